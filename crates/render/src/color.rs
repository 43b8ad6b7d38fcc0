//! CIE XYZ to linear sRGB, and the sRGB transfer curve for 8-bit output.

/// XYZ → linear sRGB (IEC 61966-2-1, D65 white).
pub const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
];

/// Linear sRGB → XYZ (inverse of [`XYZ_TO_SRGB`]).
pub const SRGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.0721750],
    [0.0193339, 0.1191920, 0.9503041],
];

/// 3×3 matrix times vector.
#[inline]
pub fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// Linear sRGB from XYZ.
#[inline]
pub fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    mul(&XYZ_TO_SRGB, xyz)
}

/// The sRGB opto-electronic transfer function, input clamped to [0, 1].
#[inline]
pub fn srgb_encode(linear: f64) -> f64 {
    let x = if linear.is_finite() {
        linear.clamp(0.0, 1.0)
    } else {
        0.0
    };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB code value of a linear intensity.
#[inline]
pub fn to_u8(linear: f64) -> u8 {
    (srgb_encode(linear) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_are_inverse() {
        for i in 0..3 {
            let mut e = [0.0; 3];
            e[i] = 1.0;
            let back = mul(&XYZ_TO_SRGB, mul(&SRGB_TO_XYZ, e));
            for j in 0..3 {
                assert!((back[j] - e[j]).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn transfer_curve_endpoints() {
        assert_eq!(to_u8(0.0), 0);
        assert_eq!(to_u8(1.0), 255);
        assert_eq!(to_u8(f64::NAN), 0);
        assert_eq!(to_u8(0.5), 188); // 1.055·0.5^(1/2.4) − 0.055 = 0.73536 → 187.5 + 0.5
    }
}
