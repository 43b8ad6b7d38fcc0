//! The K-correlation (ABC) power spectral density of an isotropic rough
//! surface, in the rad/µm convention of `docs/physics.md` §1–2.
//!
//! P(ζ) = Lc²(γ−1)σ² / (2π [1 + Lc²ζ²]^{(γ+1)/2}), ∫_{R²} P d²ζ = σ². Its
//! inverse transform is the Matérn covariance σ² M(r/Lc) (see
//! [`super::matern`]), so `Lc` is the Matérn range length. Conversions to the
//! cycles/µm convention (f = ζ/2π) are explicit: [`KcPsd::psd_cycles`] and
//! [`KcPsd::psd_1d_cycles`].

use core::f64::consts::PI;

use crate::BrdfError;
use crate::error::check_range;

/// Smallest accepted γ: below, the inverse CDF exponent 2/(γ−1) overflows and
/// nearly all mass sits at evanescent frequencies (physics.md §11).
pub const GAMMA_MIN: f64 = 1.0 + 1e-3;
/// Smallest γ the full GHS accepts (its table's tail exponent ν ≥ 0.025):
/// nearer γ = 1 the lobe is a stable law spanning more decades than f64
/// holds; the SSA covers [`GAMMA_MIN`, `GAMMA_MIN_FULL`).
pub const GAMMA_MIN_FULL: f64 = 1.05;
/// Largest accepted γ: beyond, the Matérn smoothness ν ≈ 50 is Gaussian to
/// far below any measurable difference and Γ(ν) approaches overflow.
pub const GAMMA_MAX: f64 = 100.0;
/// Largest accepted rms height σ, µm. The full-GHS tables hold g up to
/// (2k(360 nm)·10 µm)² = 1.2e5 < [`crate::wave::ghs_table::G_MAX`] without
/// extrapolation, and every model is validated up to here (stress tests);
/// rougher surfaces are in the geometric-optics regime: use a microfacet model.
pub const SIGMA_MAX_UM: f64 = 10.0;
/// Accepted correlation lengths Lc, µm: from 30 nm (a lobe far wider than
/// the hemisphere even at 360 nm) to 1 mm (a lobe ~1e−4 rad wide).
pub const LC_MIN_UM: f64 = 0.03;
/// See [`LC_MIN_UM`].
pub const LC_MAX_UM: f64 = 1000.0;

/// K-correlation PSD with rms height σ, correlation length Lc (µm) and
/// spectral exponent γ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KcPsd {
    sigma_um: f64,
    lc_um: f64,
    gamma: f64,
}

impl KcPsd {
    /// Validates and builds the PSD. σ ∈ [0, 10] µm, Lc ∈ [0.03, 1000] µm,
    /// γ ∈ [1.001, 100] (the full GHS needs γ ≥ 1.05).
    pub fn new(sigma_um: f64, lc_um: f64, gamma: f64) -> Result<Self, BrdfError> {
        check_range(
            "sigma_um",
            sigma_um,
            0.0,
            SIGMA_MAX_UM,
            "0 ≤ sigma_um ≤ 10 (µm); rougher surfaces scatter geometrically: use ggx or beckmann",
        )?;
        check_range(
            "lc_um",
            lc_um,
            LC_MIN_UM,
            LC_MAX_UM,
            "0.03 ≤ lc_um ≤ 1000 (µm)",
        )?;
        check_range("gamma", gamma, GAMMA_MIN, GAMMA_MAX, "1.001 ≤ gamma ≤ 100")?;
        Ok(KcPsd {
            sigma_um,
            lc_um,
            gamma,
        })
    }

    /// rms height σ, µm.
    #[inline]
    pub fn sigma_um(&self) -> f64 {
        self.sigma_um
    }

    /// Correlation (Matérn range) length Lc, µm.
    #[inline]
    pub fn lc_um(&self) -> f64 {
        self.lc_um
    }

    /// Spectral exponent γ (the Harvey C parameter).
    #[inline]
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Matérn smoothness ν = (γ − 1)/2.
    #[inline]
    pub fn nu(&self) -> f64 {
        0.5 * (self.gamma - 1.0)
    }

    /// Unit-mass PSD in u = Lc·ζ: p₁(u) = ν / (π (1+u²)^{ν+1}), ∫ p₁ d²u = 1.
    /// Evaluated through log1p so that large γ and large u underflow cleanly.
    #[inline]
    pub fn p1(&self, u: f64) -> f64 {
        p1(self.nu(), u)
    }

    /// P(ζ) in µm⁴ (per (rad/µm)²), ζ in rad/µm; ∫ P d²ζ = σ².
    #[inline]
    pub fn psd(&self, zeta_rad_per_um: f64) -> f64 {
        self.sigma_um * self.sigma_um * self.unit_psd(zeta_rad_per_um)
    }

    /// P(ζ)/σ², the unit-mass PSD in the ζ-plane (µm²); finite at σ = 0.
    #[inline]
    pub fn unit_psd(&self, zeta: f64) -> f64 {
        let l = self.lc_um;
        l * l * self.p1(l * zeta)
    }

    /// Mass of the unit PSD inside |ζ| ≤ `zeta`:
    /// F(ζ) = 1 − (1 + Lc²ζ²)^{−ν}.
    #[inline]
    pub fn cdf(&self, zeta: f64) -> f64 {
        if zeta.is_nan() || zeta <= 0.0 {
            return 0.0;
        }
        let u = self.lc_um * zeta;
        cdf_u(self.nu(), u)
    }

    /// Radial frequency |ζ| (rad/µm) at which the CDF equals `xi` ∈ [0, 1).
    ///
    /// ζ = sqrt(expm1(−log1p(−ξ)/ν))/Lc. Returns +∞ when the exponent passes
    /// 700 (the sample is certainly evanescent) or for ξ ≥ 1.
    #[inline]
    pub fn sample_zeta(&self, xi: f64) -> f64 {
        sample_u(self.nu(), xi) / self.lc_um
    }

    /// One-sided 1-D profile PSD in the cycles convention, µm³ (per cycle/µm),
    /// for a line cut through the isotropic surface:
    /// P₁(f) = 2σ²B Γ(γ/2) / (√π Γ((γ−1)/2)) · (1 + B²f²)^{−γ/2}, B = 2π·Lc,
    /// with ∫₀^∞ P₁ df = σ². This is the form fitted in
    /// `data/surfaces/README.md` (its `L` is our 2π·Lc).
    pub fn psd_1d_cycles(&self, f_cycles_per_um: f64) -> f64 {
        let f = f_cycles_per_um.abs();
        if f.is_nan() {
            return 0.0;
        }
        let b = 2.0 * PI * self.lc_um;
        let g = self.gamma;
        let log_norm = libm::lgamma(0.5 * g) - libm::lgamma(0.5 * (g - 1.0));
        let bf = b * f;
        let log_shape = -0.5 * g * libm::log1p(bf * bf);
        2.0 * self.sigma_um * self.sigma_um * b / libm::sqrt(PI)
            * crate::numerics::math::exp(log_norm + log_shape)
    }

    /// 2-D PSD in the cycles convention, µm⁴ (per (cycle/µm)²):
    /// PSD_cyc(f) = (2π)² P(2πf), ∫ PSD_cyc d²f = σ².
    #[inline]
    pub fn psd_cycles(&self, f_cycles_per_um: f64) -> f64 {
        4.0 * PI * PI * self.psd(2.0 * PI * f_cycles_per_um)
    }

    /// Total slope variance ⟨|∇h|²⟩ = 2σ²/(Lc²(γ−3)) for γ > 3; `None`
    /// (infinite) otherwise. The per-component variance is half of it.
    pub fn slope_variance(&self) -> Option<f64> {
        if self.gamma > 3.0 {
            let l = self.lc_um;
            Some(2.0 * self.sigma_um * self.sigma_um / (l * l * (self.gamma - 3.0)))
        } else {
            None
        }
    }
}

/// Unit-mass KC density in u: ν / (π (1+u²)^{ν+1}).
///
/// ln(1 + u²) rather than log1p(u²): an absolute error δ in the logarithm is
/// a relative error (ν+1)δ in the power, and rounding 1 + u² costs at most
/// δ = 1.1e−16, so log1p's relative accuracy at small u² buys nothing here;
/// the platform logarithm costs a third as much (two of these per entry of a
/// full-GHS table's columns).
#[inline]
pub(crate) fn p1(nu: f64, u: f64) -> f64 {
    let u2 = u * u;
    if !u2.is_finite() {
        return 0.0;
    }
    nu / PI * crate::numerics::math::exp(-(nu + 1.0) * crate::numerics::math::ln(1.0 + u2))
}

/// Radial CDF of p₁ in u: 1 − (1+u²)^{−ν}, via expm1 so small u keeps its
/// relative accuracy.
#[inline]
pub(crate) fn cdf_u(nu: f64, u: f64) -> f64 {
    if u.is_nan() || u <= 0.0 {
        return 0.0;
    }
    let u2 = u * u;
    if !u2.is_finite() {
        return 1.0;
    }
    (-libm::expm1(-nu * libm::log1p(u2))).clamp(0.0, 1.0)
}

/// Inverse of [`cdf_u`]: u(ξ) = sqrt(expm1(−log1p(−ξ)/ν)), +∞ beyond overflow.
#[inline]
pub(crate) fn sample_u(nu: f64, xi: f64) -> f64 {
    if xi.is_nan() || xi <= 0.0 {
        return 0.0;
    }
    if xi >= 1.0 {
        return f64::INFINITY;
    }
    let e = -libm::log1p(-xi) / nu;
    if e > 700.0 {
        return f64::INFINITY;
    }
    libm::sqrt(libm::expm1(e).max(0.0))
}

impl super::RadialPsd for KcPsd {
    fn sigma_um(&self) -> f64 {
        self.sigma_um
    }
    fn length_um(&self) -> f64 {
        self.lc_um
    }
    fn unit_psd_u(&self, u: f64) -> f64 {
        p1(self.nu(), u)
    }
    fn cdf_u(&self, u: f64) -> f64 {
        cdf_u(self.nu(), u)
    }
    fn sample_u(&self, xi: f64) -> f64 {
        sample_u(self.nu(), xi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫₀^Z g(x) dx by composite Simpson (n even) in x = sinh(s), which
    /// spreads the nodes over decades; good to 1e-10 for these smooth integrands.
    fn sinh_simpson(g: impl Fn(f64) -> f64, zmax: f64, n: usize) -> f64 {
        let smax = libm::asinh(zmax);
        let h = smax / n as f64;
        let mut acc = 0.0;
        for i in 0..=n {
            let s = i as f64 * h;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            acc += w * g(libm::sinh(s)) * libm::cosh(s);
        }
        acc * h / 3.0
    }

    /// Radial quadrature ∫₀^Z 2π ζ f(ζ) dζ.
    fn radial_mass(f: impl Fn(f64) -> f64, zmax: f64, n: usize) -> f64 {
        sinh_simpson(|z| 2.0 * PI * z * f(z), zmax, n)
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(KcPsd::new(-1.0, 1.0, 2.0).is_err());
        assert!(KcPsd::new(1.0, 0.0, 2.0).is_err());
        assert!(KcPsd::new(1.0, 1.0, 1.0).is_err());
        assert!(KcPsd::new(1.0, 1.0, f64::NAN).is_err());
        assert!(KcPsd::new(f64::INFINITY, 1.0, 2.0).is_err());
        assert!(KcPsd::new(0.0, 1.0, 1.0005).is_err());
        assert!(KcPsd::new(0.0, 1.0, 1.002).is_ok());
    }

    #[test]
    fn psd_normalised_and_cdf_matches_quadrature() {
        for &(s, l, g) in &[(0.3, 2.0, 3.5), (0.1, 0.5, 6.0), (1.0, 5.0, 4.0)] {
            let p = KcPsd::new(s, l, g).unwrap();
            for &z in &[0.1, 1.0, 3.0] {
                let m = radial_mass(|x| p.unit_psd(x), z, 4000);
                assert!(
                    (m - p.cdf(z)).abs() < 1e-9,
                    "{s} {l} {g} {z}: {m} vs {}",
                    p.cdf(z)
                );
            }
            // Whole-plane mass: the CDF tends to 1 and P = σ²·unit.
            assert!((p.cdf(1e12) - 1.0).abs() < 1e-12);
            assert!((p.psd(0.7) - s * s * p.unit_psd(0.7)).abs() < 1e-15);
        }
    }

    #[test]
    fn inverse_cdf_round_trips() {
        for &g in &[1.002, 1.2, 2.0, 3.0, 6.0, 50.0] {
            let p = KcPsd::new(0.1, 1.3, g).unwrap();
            for i in 1..100 {
                let xi = i as f64 / 100.0;
                let z = p.sample_zeta(xi);
                if z.is_finite() {
                    assert!((p.cdf(z) - xi).abs() < 1e-12, "g={g} xi={xi}");
                } else {
                    assert!(g < 1.01);
                }
            }
            assert_eq!(p.sample_zeta(0.0), 0.0);
            assert_eq!(p.sample_zeta(1.0), f64::INFINITY);
        }
    }

    #[test]
    fn cycles_conventions() {
        let p = KcPsd::new(0.2, 1.5, 2.7).unwrap();
        // 2-D cycles PSD integrates to σ² (∫ 2π f PSD_cyc df).
        let m = radial_mass(|f| p.psd_cycles(f), 1e6, 40000);
        assert!((m / 0.04 - 1.0).abs() < 2e-6, "{m}");
        // 1-D one-sided profile PSD integrates to σ² and equals the line
        // integral of the 2-D cycles PSD (×2 for one-sided).
        let (n, fmax) = (200000, 1e4);
        let acc = sinh_simpson(|f| p.psd_1d_cycles(f), fmax, n);
        assert!((acc / 0.04 - 1.0).abs() < 1e-4, "{acc}");
        let fx = 0.3;
        // Both signs of fy, one-sided in fx.
        let line = 2.0 * 2.0 * sinh_simpson(|fy| p.psd_cycles(libm::hypot(fx, fy)), fmax, n);
        assert!((line / p.psd_1d_cycles(fx) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn slope_variance_and_harvey_abc() {
        let p = KcPsd::new(0.5, 2.0, 4.0).unwrap();
        assert!((p.slope_variance().unwrap() - 2.0 * 0.25 / 4.0).abs() < 1e-15);
        assert!(
            KcPsd::new(0.5, 2.0, 3.0)
                .unwrap()
                .slope_variance()
                .is_none()
        );
        // Harvey ABC (cycles): A/(1+B²f²)^{(C+1)/2}, B = 2πLc, C = γ, A = σ²B²(C−1)/(2π).
        let b = 2.0 * PI * 2.0;
        let a = 0.25 * b * b * 3.0 / (2.0 * PI);
        let f = 0.37;
        let abc = a / libm::pow(1.0 + b * b * f * f, 2.5);
        assert!((p.psd_cycles(f) / abc - 1.0).abs() < 1e-13);
    }

    #[test]
    fn stable_at_extremes() {
        let p = KcPsd::new(0.0, LC_MIN_UM, 100.0).unwrap();
        assert_eq!(p.psd(1.0), 0.0);
        assert!(p.unit_psd(1e300).is_finite());
        let q = KcPsd::new(SIGMA_MAX_UM, LC_MAX_UM, 1.001).unwrap();
        // Outside the validated domain: refused, naming the parameter.
        for (s, l, g) in [
            (10.01, 1.0, 3.0),
            (0.1, 0.0299, 3.0),
            (0.1, 1000.1, 3.0),
            (0.1, 1.0, 100.1),
        ] {
            let e = KcPsd::new(s, l, g).unwrap_err();
            assert!(
                matches!(e, BrdfError::OutOfRange { name, .. } if ["sigma_um", "lc_um", "gamma"].contains(&name)),
                "{e:?}"
            );
        }
        for z in [0.0, 1e-300, 1.0, 1e300, f64::INFINITY] {
            assert!(q.psd(z).is_finite() && q.psd(z) >= 0.0);
            assert!((0.0..=1.0).contains(&q.cdf(z)));
        }
    }
}
