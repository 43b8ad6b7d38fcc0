//! Exact unpolarised Fresnel reflectance of a conductor, R = ½(|r_s|² + |r_p|²).

use crate::ior::Ior;

/// How a model weights reflection by the surface's optical constants.
#[derive(Clone, Debug, PartialEq)]
pub enum Fresnel {
    /// R ≡ 1: a perfect mirror material (white furnace tests, reference values).
    One,
    /// Conductor with complex index n + iκ relative to the outer medium (air).
    Conductor(Ior),
}

impl Fresnel {
    /// Conductor Fresnel for the given index.
    pub fn conductor(ior: Ior) -> Fresnel {
        Fresnel::Conductor(ior)
    }

    /// Reflectance for the cosine between the incident direction and the
    /// reflecting normal, at `lambda_nm`. `cos_theta` is clamped to [0, 1].
    #[inline]
    pub fn reflectance(&self, cos_theta: f64, lambda_nm: f64) -> f64 {
        match self {
            Fresnel::One => 1.0,
            Fresnel::Conductor(ior) => {
                let (n, k) = ior.at(lambda_nm);
                conductor_reflectance(cos_theta, n, k)
            }
        }
    }

    /// Checks that the data cover `[lo, hi]` nm (always true for [`Fresnel::One`]).
    pub fn check_covers(&self, lo_nm: f64, hi_nm: f64) -> Result<(), crate::BrdfError> {
        match self {
            Fresnel::One => Ok(()),
            Fresnel::Conductor(ior) => ior.check_covers(lo_nm, hi_nm),
        }
    }
}

/// Unpolarised reflectance of an interface from air into a medium of index
/// n + iκ, for incidence cosine `cos_theta`.
///
/// Uses the real-arithmetic form of the complex Fresnel equations: with
/// a² + b² = |η² − sin²θ| it needs two square roots and no complex division,
/// and both ratios tend to 1 (not 0/0) as cosθ → 0, which keeps grazing
/// incidence exact. Equal to the complex form to round-off (tested).
#[inline]
pub fn conductor_reflectance(cos_theta: f64, n: f64, k: f64) -> f64 {
    let c = if cos_theta > 0.0 {
        cos_theta.min(1.0)
    } else {
        0.0
    };
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let n2 = n * n;
    let k2 = k * k;
    let t0 = n2 - k2 - s2;
    let a2b2 = libm::sqrt(t0 * t0 + 4.0 * n2 * k2);
    let a = libm::sqrt((0.5 * (a2b2 + t0)).max(0.0));
    let t1 = a2b2 + c2;
    let t2 = 2.0 * c * a;
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    // R_s = (t1 − t2)/(t1 + t2) and R_p = R_s (t3 − t4)/(t3 + t4), so
    // ½(R_s + R_p) = (t1 − t2) t3 / ((t1 + t2)(t3 + t4)): one division.
    let r = (t1 - t2) * t3 / ((t1 + t2) * (t3 + t4));
    // n = 1, κ = 0 at normal incidence is 0/0; a matched interface reflects nothing.
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ior::Metal;

    /// Minimal complex arithmetic for the textbook form of the Fresnel equations.
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    impl C {
        fn mul(self, o: C) -> C {
            C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
        }
        fn div(self, o: C) -> C {
            let d = o.0 * o.0 + o.1 * o.1;
            C(
                (self.0 * o.0 + self.1 * o.1) / d,
                (self.1 * o.0 - self.0 * o.1) / d,
            )
        }
        fn add(self, o: C) -> C {
            C(self.0 + o.0, self.1 + o.1)
        }
        fn sub(self, o: C) -> C {
            C(self.0 - o.0, self.1 - o.1)
        }
        fn norm2(self) -> f64 {
            self.0 * self.0 + self.1 * self.1
        }
        fn sqrt(self) -> C {
            let r = libm::hypot(self.0, self.1);
            let re = libm::sqrt(0.5 * (r + self.0));
            let im = libm::sqrt(0.5 * (r - self.0)).copysign(self.1);
            C(re, im)
        }
    }

    fn complex_form(c: f64, n: f64, k: f64) -> f64 {
        let eta = C(n, k);
        let eta2 = eta.mul(eta);
        let ct = C(1.0, 0.0).sub(C(1.0 - c * c, 0.0).div(eta2)).sqrt();
        let cc = C(c, 0.0);
        let rs = cc.sub(eta.mul(ct)).div(cc.add(eta.mul(ct)));
        let rp = eta.mul(cc).sub(ct).div(eta.mul(cc).add(ct));
        0.5 * (rs.norm2() + rp.norm2())
    }

    #[test]
    fn matches_complex_form() {
        for &(n, k) in &[
            (0.27, 2.77),
            (1.5, 0.0),
            (2.9, 3.1),
            (0.05, 4.0),
            (1.0, 0.5),
        ] {
            for i in 0..=100 {
                let c = i as f64 / 100.0;
                let a = conductor_reflectance(c, n, k);
                let b = if c == 0.0 { 1.0 } else { complex_form(c, n, k) };
                assert!((a - b).abs() < 1e-13, "n={n} k={k} c={c}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn normal_incidence_closed_form_and_grazing_limit() {
        let (n, k) = (0.27, 2.77);
        let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((conductor_reflectance(1.0, n, k) - want).abs() < 1e-15);
        assert_eq!(conductor_reflectance(0.0, n, k), 1.0);
        assert!(conductor_reflectance(1e-9, n, k) > 0.999_999);
        assert_eq!(conductor_reflectance(-0.5, n, k), 1.0);
        assert_eq!(conductor_reflectance(1.0, 1.0, 0.0), 0.0);
    }

    #[test]
    fn measured_metals_match_data_readme() {
        // data/spectra/README.md "Normal-incidence reflectance" table.
        let cases = [
            (Metal::Cu, 550.0, 0.624),
            (Metal::Al, 550.0, 0.915),
            (Metal::Au, 650.0, 0.957),
            (Metal::Ag, 400.0, 0.964),
            (Metal::Fe, 450.0, 0.496),
            (Metal::Cr, 700.0, 0.562),
            (Metal::BrassCu70Zn30, 550.0, 0.789),
            (Metal::StainlessSteel, 400.0, 0.570),
        ];
        for (m, l, want) in cases {
            let r = Fresnel::conductor(Ior::metal(m)).reflectance(1.0, l);
            assert!((r - want).abs() < 6e-4, "{m:?} at {l} nm: {r} vs {want}");
        }
    }
}
