//! The anisotropic K-correlation surface (physics.md §15): the isotropic KC
//! stretched along two perpendicular axes,
//!
//! ```text
//! P(ζ) = Lx Ly (γ−1) σ² / (2π [1 + Lx² ζ_a² + Ly² ζ_b²]^{(γ+1)/2}),
//! ζ_a = ζ·a,  ζ_b = ζ·b,  a = (cos φ₀, sin φ₀),  b = (−sin φ₀, cos φ₀),
//! ```
//!
//! with ∫ P d²ζ = σ² and covariance C(r) = σ² M(|(r·a/Lx, r·b/Ly)|) (M the
//! Matérn function of [`super::matern`]). Lx is the correlation length along
//! the axis a at angle φ₀ from the tangent x towards y, Ly along b: a surface
//! brushed along b (grooves along b) has Lx < Ly. With u = (Lx ζ_a, Ly ζ_b) the
//! PSD is σ² Lx Ly p₁(|u|), p₁ the unit isotropic KC of [`KcPsd::p1`]: every
//! statement about the isotropic surface in u carries over with Lc² → Lx Ly.

use crate::BrdfError;
use crate::error::check_range;

use super::kc::{GAMMA_MAX, GAMMA_MIN, KcPsd, LC_MAX_UM, LC_MIN_UM, SIGMA_MAX_UM};

/// Checks an axis angle (radians from the tangent x towards y): finite, as
/// `angle_deg` in a material.
pub(crate) fn check_angle(angle_rad: f64) -> Result<(), BrdfError> {
    // Reported in degrees, as the key is given; the bound is ±1e6 rad.
    const MAX_DEG: f64 = 1e6 * 180.0 / core::f64::consts::PI;
    check_range(
        "angle_deg",
        angle_rad.to_degrees(),
        -MAX_DEG,
        MAX_DEG,
        "a finite angle (degrees from the tangent x towards y)",
    )?;
    Ok(())
}

/// Checks the two correlation lengths of a stretched surface (each in
/// [0.03, 1000] µm) and its axis angle.
pub(crate) fn check_axes(lx_um: f64, ly_um: f64, angle_rad: f64) -> Result<(), BrdfError> {
    check_range(
        "lx_um",
        lx_um,
        LC_MIN_UM,
        LC_MAX_UM,
        "0.03 ≤ lx_um ≤ 1000 (µm)",
    )?;
    check_range(
        "ly_um",
        ly_um,
        LC_MIN_UM,
        LC_MAX_UM,
        "0.03 ≤ ly_um ≤ 1000 (µm)",
    )?;
    check_angle(angle_rad)
}

/// An anisotropic K-correlation PSD: σ, Lx, Ly (µm), the axis angle φ₀
/// (radians) and γ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnisotropicKc {
    sigma_um: f64,
    lx_um: f64,
    ly_um: f64,
    angle_rad: f64,
    gamma: f64,
    /// cos φ₀, sin φ₀
    cs: (f64, f64),
}

impl AnisotropicKc {
    /// Validates and builds the PSD: σ ∈ [0, 10] µm, Lx and Ly ∈ [0.03,
    /// 1000] µm (as the isotropic Lc), φ₀ finite, γ ∈ [1.001, 100].
    pub fn new(
        sigma_um: f64,
        lx_um: f64,
        ly_um: f64,
        angle_rad: f64,
        gamma: f64,
    ) -> Result<Self, BrdfError> {
        check_range(
            "sigma_um",
            sigma_um,
            0.0,
            SIGMA_MAX_UM,
            "0 ≤ sigma_um ≤ 10 (µm); rougher surfaces scatter geometrically: use ggx or beckmann",
        )?;
        check_axes(lx_um, ly_um, angle_rad)?;
        check_range("gamma", gamma, GAMMA_MIN, GAMMA_MAX, "1.001 ≤ gamma ≤ 100")?;
        Ok(AnisotropicKc {
            sigma_um,
            lx_um,
            ly_um,
            angle_rad,
            gamma,
            cs: (libm::cos(angle_rad), libm::sin(angle_rad)),
        })
    }

    /// rms height σ, µm.
    pub fn sigma_um(&self) -> f64 {
        self.sigma_um
    }

    /// Correlation length along the axis a (at φ₀), µm.
    pub fn lx_um(&self) -> f64 {
        self.lx_um
    }

    /// Correlation length along the axis b (at φ₀ + 90°), µm.
    pub fn ly_um(&self) -> f64 {
        self.ly_um
    }

    /// φ₀, radians from the tangent x towards y.
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// Spectral exponent γ.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Matérn smoothness ν = (γ − 1)/2.
    pub fn nu(&self) -> f64 {
        0.5 * (self.gamma - 1.0)
    }

    /// The isotropic KC of the same σ and γ with Lc = `lc_um`: the radial
    /// law in u (its p₁, CDF and sampler do not depend on Lc).
    pub fn radial(&self, lc_um: f64) -> Result<KcPsd, BrdfError> {
        KcPsd::new(self.sigma_um, lc_um, self.gamma)
    }

    /// u = (Lx ζ·a, Ly ζ·b) of a frequency ζ = (ζx, ζy), rad/µm.
    #[inline]
    pub fn to_u(&self, zx: f64, zy: f64) -> (f64, f64) {
        let (c, s) = self.cs;
        (
            self.lx_um * (c * zx + s * zy),
            self.ly_um * (c * zy - s * zx),
        )
    }

    /// ζ of a u (the inverse of [`to_u`](Self::to_u)).
    #[inline]
    pub fn from_u(&self, ux: f64, uy: f64) -> (f64, f64) {
        let (c, s) = self.cs;
        let (za, zb) = (ux / self.lx_um, uy / self.ly_um);
        (c * za - s * zb, s * za + c * zb)
    }

    /// P(ζ), µm⁴; ∫ P d²ζ = σ².
    pub fn psd(&self, zx: f64, zy: f64) -> f64 {
        let (ux, uy) = self.to_u(zx, zy);
        self.sigma_um
            * self.sigma_um
            * self.lx_um
            * self.ly_um
            * super::kc::p1(self.nu(), libm::hypot(ux, uy))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    #[test]
    fn psd_integrates_to_sigma2_and_stretches_the_isotropic_one() {
        let a = AnisotropicKc::new(0.3, 0.5, 4.0, 0.7, 3.5).unwrap();
        // ∫ P d²ζ in polar coordinates on a log-radial grid.
        let (nr, nphi) = (4000, 256);
        let mut acc = 0.0;
        let (lo, hi) = (1e-4f64.ln(), 1e4f64.ln());
        for i in 0..nr {
            let r = (lo + (hi - lo) * (i as f64 + 0.5) / nr as f64).exp();
            let dr = r * (hi - lo) / nr as f64;
            for j in 0..nphi {
                let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
                acc +=
                    a.psd(r * libm::cos(phi), r * libm::sin(phi)) * r * dr * 2.0 * PI / nphi as f64;
            }
        }
        assert!((acc / 0.09 - 1.0).abs() < 1e-4, "{acc}");
        // Along the axes it is the isotropic KC with Lx, resp. Ly, rescaled.
        let (c, s) = (libm::cos(0.7), libm::sin(0.7));
        let iso = |l: f64, z: f64| KcPsd::new(0.3, l, 3.5).unwrap().p1(l * z) * 0.09 * 0.5 * 4.0;
        for z in [0.01, 0.3, 2.0] {
            assert!((a.psd(c * z, s * z) / iso(0.5, z) - 1.0).abs() < 1e-13);
            assert!((a.psd(-s * z, c * z) / iso(4.0, z) - 1.0).abs() < 1e-13);
        }
        let (ux, uy) = a.to_u(0.3, -1.2);
        let (zx, zy) = a.from_u(ux, uy);
        assert!((zx - 0.3).abs() < 1e-15 && (zy + 1.2).abs() < 1e-15);
    }

    #[test]
    fn out_of_range_names_the_parameter() {
        let e = |r: Result<AnisotropicKc, BrdfError>| match r {
            Err(BrdfError::OutOfRange { name, .. }) => name,
            other => panic!("{other:?}"),
        };
        assert_eq!(e(AnisotropicKc::new(0.1, 0.01, 1.0, 0.0, 3.0)), "lx_um");
        assert_eq!(e(AnisotropicKc::new(0.1, 1.0, 2000.0, 0.0, 3.0)), "ly_um");
        assert_eq!(
            e(AnisotropicKc::new(0.1, 1.0, 1.0, f64::NAN, 3.0)),
            "angle_deg"
        );
        assert_eq!(e(AnisotropicKc::new(0.1, 1.0, 1.0, 0.0, 1.0)), "gamma");
    }
}
