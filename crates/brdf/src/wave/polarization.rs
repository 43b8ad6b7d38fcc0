//! The polarisation factor of first-order vector perturbation theory
//! (Rayleigh–Rice; physics.md §13), and the polarised Fresnel reflectances
//! of the specular lobe.
//!
//! For a rough interface between air and a medium of relative permittivity
//! ε = (n + iκ)², Rayleigh–Rice scattering from incident polarisation a into
//! detected polarisation b has the amplitude factors (Germer, Appl. Opt. 36,
//! 8798 (1997), Eq. 2, with φ the scattering azimuth measured from the
//! mirror direction and A_x = sqrt(ε − sin²θx), principal branch):
//!
//! ```text
//! q_ss =  (ε−1) cosφ / ((cosθi + A_i)(cosθo + A_o))
//! q_sp = −(ε−1) A_o sinφ / ((cosθi + A_i)(ε cosθo + A_o))       s in, p out
//! q_ps = −(ε−1) A_i sinφ / ((ε cosθi + A_i)(cosθo + A_o))       p in, s out
//! q_pp =  (ε−1)(ε sinθi sinθo − A_i A_o cosφ) / ((ε cosθi + A_i)(ε cosθo + A_o))
//! ```
//!
//! and Q = |q_ss|² + |q_sp|² (s incident, both polarisations detected),
//! |q_pp|² + |q_ps|² (p incident), or their mean (unpolarised). At the mirror
//! direction Q is the Fresnel reflectance of the incident polarisation.
//! `Fresnel::One` (R ≡ 1) is read as the perfect conductor, ε → −∞, where
//! q_ss → cosφ, q_sp → −sinφ/cosθo, q_ps → −sinφ/cosθi and
//! q_pp → (sinθi sinθo − cosφ)/(cosθi cosθo).

use glam::DVec3;

use crate::fresnel::Fresnel;

/// Polarisation of the incident light. The detector sums both scattered
/// polarisations in every case.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Polarization {
    /// The mean of s and p (the Mueller element M₀₀). Default.
    #[default]
    #[cfg_attr(feature = "serde", serde(alias = "unpolarised"))]
    Unpolarized,
    /// Electric field perpendicular to the plane of incidence.
    S,
    /// Electric field in the plane of incidence.
    P,
}

/// Which reflectance factor multiplies the GHS scattered lobe.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum PolarizationFactor {
    /// The scalar Fresnel reflectance R (at the angle `fresnel_angle` says).
    /// Default.
    #[default]
    R,
    /// The Rayleigh–Rice polarisation factor Q times the obliquity ratio
    /// 4 cosθi cosθo/(cosθi + cosθo)², so that the lobe tends to
    /// Rayleigh–Rice as g → 0 (physics.md §13.2).
    Q,
}

/// A complex number: just what the Fresnel and Q factors need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct C {
    re: f64,
    im: f64,
}

impl C {
    const fn new(re: f64, im: f64) -> C {
        C { re, im }
    }
    fn real(re: f64) -> C {
        C { re, im: 0.0 }
    }
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, s: f64) -> C {
        C::new(self.re * s, self.im * s)
    }
    /// |z|²
    fn norm2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    /// The principal square root (Re ≥ 0), without overflow or cancellation.
    fn sqrt(self) -> C {
        if self.re == 0.0 && self.im == 0.0 {
            return C::real(0.0);
        }
        let r = libm::hypot(self.re, self.im);
        if self.re >= 0.0 {
            let t = libm::sqrt(0.5 * (r + self.re));
            C::new(t, 0.5 * self.im / t)
        } else {
            let t = libm::sqrt(0.5 * (r - self.re));
            C::new(0.5 * libm::fabs(self.im) / t, t.copysign(self.im))
        }
    }
}

/// |a/b|² without forming the quotient.
fn ratio2(a: C, b: C) -> f64 {
    a.norm2() / b.norm2()
}

/// The reflecting medium at one wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Medium {
    /// The perfect conductor (`Fresnel::One`).
    Pec,
    /// Relative permittivity ε = (n + iκ)².
    Eps(C),
}

impl Medium {
    /// The medium of `fresnel` at `lambda_nm`.
    pub fn of(fresnel: &Fresnel, lambda_nm: f64) -> Medium {
        match fresnel {
            Fresnel::One => Medium::Pec,
            Fresnel::Conductor(ior) => {
                let (n, k) = ior.at(lambda_nm);
                Medium::Eps(C::new(n * n - k * k, 2.0 * n * k))
            }
        }
    }

    /// (|r_s|², |r_p|²) at incidence cosine `c` ∈ [0, 1].
    pub fn fresnel_sp(self, c: f64) -> (f64, f64) {
        let c = if c > 0.0 { c.min(1.0) } else { 0.0 };
        match self {
            Medium::Pec => (1.0, 1.0),
            Medium::Eps(e) => {
                let a = e.sub(C::real((1.0 - c) * (1.0 + c))).sqrt();
                let cc = C::real(c);
                let rs = ratio2(cc.sub(a), cc.add(a));
                let ec = e.scale(c);
                let rp = ratio2(ec.sub(a), ec.add(a));
                let fix = |r: f64| {
                    if r.is_finite() {
                        r.clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                };
                (fix(rs), fix(rp))
            }
        }
    }

    /// The Fresnel reflectance of `pol` at incidence cosine `c`.
    pub fn reflectance(self, c: f64, pol: Polarization) -> f64 {
        let (s, p) = self.fresnel_sp(c);
        match pol {
            Polarization::Unpolarized => 0.5 * (s + p),
            Polarization::S => s,
            Polarization::P => p,
        }
    }

    /// The Rayleigh–Rice factor Q(wi, wo) of `pol` (both scattered
    /// polarisations summed); 0 below either horizon.
    pub fn q_factor(self, wi: DVec3, wo: DVec3, pol: Polarization) -> f64 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let (ci, co) = (wi.z.min(1.0), wo.z.min(1.0));
        let (si2, so2) = (
            (wi.x * wi.x + wi.y * wi.y).min(1.0),
            (wo.x * wo.x + wo.y * wo.y).min(1.0),
        );
        let (si, so) = (libm::sqrt(si2), libm::sqrt(so2));
        // Scattering azimuth from the mirror direction s⊥ = −i⊥; at normal
        // incidence the plane of incidence is the x–z plane (i⊥ along +x).
        let (ex, ey) = if si > 0.0 {
            (wi.x / si, wi.y / si)
        } else {
            (1.0, 0.0)
        };
        // (cosφ, sinφ, 1 − cosφ), the last as |m − ô⊥|²/2 with m = −e the
        // mirror's azimuth, without cancellation near the plane of incidence.
        let (cos_phi, sin_phi, one_minus_cos) = if so > 0.0 {
            let (ux, uy) = (wo.x / so, wo.y / so);
            let (dx, dy) = (-ex - ux, -ey - uy);
            (
                -(ux * ex + uy * ey),
                uy * ex - ux * ey,
                0.5 * (dx * dx + dy * dy),
            )
        } else {
            (1.0, 0.0, 0.0)
        };
        let (qs, qp) = match self {
            Medium::Pec => {
                let ss = cos_phi * cos_phi;
                let sp = sin_phi * sin_phi / (co * co);
                let ps = sin_phi * sin_phi / (ci * ci);
                // sinθi sinθo − cosφ = (1 − cosφ) − (1 − sinθi sinθo), with
                // 1 − sinθi sinθo = (cos²θi + cos²θo + (sinθi − sinθo)²)/2:
                // exactly −1 at the mirror, whatever the grazing angle.
                let dsin = (co * co - ci * ci) / (si + so).max(f64::MIN_POSITIVE);
                let pp = (one_minus_cos - 0.5 * (ci * ci + co * co + dsin * dsin)) / (ci * co);
                (ss + sp, pp * pp + ps)
            }
            Medium::Eps(e) => {
                let em1 = e.sub(C::real(1.0));
                if em1.norm2() == 0.0 {
                    return 0.0;
                }
                let ai = e.sub(C::real(si2)).sqrt();
                let ao = e.sub(C::real(so2)).sqrt();
                let di_s = C::real(ci).add(ai);
                let do_s = C::real(co).add(ao);
                let di_p = e.scale(ci).add(ai);
                let do_p = e.scale(co).add(ao);
                let e2 = em1.norm2();
                let ss = e2 * cos_phi * cos_phi / (di_s.mul(do_s)).norm2();
                let sp = e2 * ao.norm2() * sin_phi * sin_phi / (di_s.mul(do_p)).norm2();
                let ps = e2 * ai.norm2() * sin_phi * sin_phi / (di_p.mul(do_s)).norm2();
                let pp_num = em1.mul(e.scale(si * so).sub(ai.mul(ao).scale(cos_phi)));
                let pp = pp_num.norm2() / (di_p.mul(do_p)).norm2();
                (ss + sp, pp + ps)
            }
        };
        let q = match pol {
            Polarization::Unpolarized => 0.5 * (qs + qp),
            Polarization::S => qs,
            Polarization::P => qp,
        };
        if q.is_finite() { q.max(0.0) } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use crate::ior::{Ior, Metal};
    use core::f64::consts::PI;

    fn metal(m: Metal) -> Fresnel {
        Fresnel::conductor(Ior::metal(m))
    }

    #[test]
    fn q_at_the_mirror_is_the_fresnel_reflectance() {
        for f in [metal(Metal::Au), metal(Metal::Al), Fresnel::One] {
            for lam in [380.0, 550.0, 780.0] {
                let m = Medium::of(&f, lam);
                for t in [0.0, 0.3, 1.0, 1.4, 1.55] {
                    let wi = spherical(t, 0.7);
                    let wo = spherical(t, 0.7 + PI);
                    for pol in [Polarization::Unpolarized, Polarization::S, Polarization::P] {
                        let q = m.q_factor(wi, wo, pol);
                        let r = m.reflectance(libm::cos(t), pol);
                        assert!(
                            (q - r).abs() < 1e-13 * r.max(1.0),
                            "{f:?} {lam} {t} {pol:?}"
                        );
                    }
                    let unpol = f.reflectance(libm::cos(t), lam);
                    let r = m.reflectance(libm::cos(t), Polarization::Unpolarized);
                    assert!((unpol - r).abs() < 1e-13, "{f:?} {lam} {t}: {unpol} vs {r}");
                }
            }
        }
    }

    #[test]
    fn q_is_reciprocal_and_tends_to_the_perfect_conductor() {
        let wi = spherical(0.9, 0.2);
        for wo in [
            spherical(0.3, 2.0),
            spherical(1.3, 4.0),
            spherical(0.0, 0.0),
        ] {
            for f in [metal(Metal::Cu), Fresnel::One] {
                let m = Medium::of(&f, 600.0);
                let a = m.q_factor(wi, wo, Polarization::Unpolarized);
                let b = m.q_factor(wo, wi, Polarization::Unpolarized);
                assert!((a - b).abs() < 1e-13 * a, "{f:?}: {a} vs {b}");
            }
            // |ε| → ∞ along a metal-like direction.
            let pec = Medium::Pec.q_factor(wi, wo, Polarization::P);
            let big = Medium::Eps(C::new(-1e12, 1e10)).q_factor(wi, wo, Polarization::P);
            assert!((pec - big).abs() < 1e-5 * pec, "{pec} vs {big}");
        }
        assert_eq!(
            Medium::Eps(C::real(1.0)).q_factor(wi, spherical(0.1, 1.0), Polarization::S),
            0.0
        );
    }

    #[test]
    fn complex_square_root_is_the_principal_branch() {
        for (re, im) in [
            (4.0, 0.0),
            (-4.0, 0.0),
            (-4.0, -0.0),
            (3.0, 4.0),
            (-3.0, 4.0),
            (-3.0, -4.0),
        ] {
            let z = C::new(re, im);
            let r = z.sqrt();
            assert!(r.re >= 0.0);
            let back = r.mul(r);
            assert!(
                (back.re - re).abs() < 1e-14 && (back.im - im).abs() < 1e-14,
                "{z:?}"
            );
        }
    }
}
