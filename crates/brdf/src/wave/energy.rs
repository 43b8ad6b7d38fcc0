//! Energy handling and Fresnel-angle switches of the GHS models
//! (physics.md §5, §3.2), the (θi, λ) tables they need, and the
//! deterministic hemispherical quadrature those tables are built with.

use core::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use crate::model::{WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::quadrature::gauss_legendre;
pub use crate::wave::polarization::{Polarization, PolarizationFactor};

/// How the scattered part is normalised (physics.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Energy {
    /// The physics as written: the evanescent part is lost and, at grazing
    /// incidence, the total can exceed 1. Reciprocal. Default.
    #[default]
    Raw,
    /// Krywonos renormalisation f_s → K(θi) f_s with K = (1 − A_s)/a_s(θi),
    /// so that A_s + scattered = 1 (× R). The raw albedo a_s is tabulated
    /// per material over (θi, λ) when the model is built, and K formed from
    /// it and the exact 1 − A_s at each query. Not reciprocal. Where the raw
    /// scattered albedo is below 1e−6·(1 − A_s) the lobe is treated as
    /// absorbed (K = 0) rather than amplified.
    Krywonos,
    /// Band-limited roughness: σ is replaced by σ_rel(θi, λ) with
    /// σ_rel² = σ² × (in-disk fraction of the unit PSD about the mirror
    /// direction), in A_s and in g. Tabulated over (θi, λ). Not reciprocal.
    /// σ_rel alone can still leave A_s + scattered > 1 at grazing incidence
    /// (g gains where cosθo > cosθi); there the scattered part is scaled
    /// down to 1 − A_s, from a second (θi, λ) table of the scattered albedo
    /// with σ_rel (a cap that only reduces).
    SigmaRel,
}

/// Which angle the Fresnel factor of the scattered part uses (physics.md §3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum FresnelAngle {
    /// R(cosθd), cosθd = i·h = sqrt((1 + i·o)/2): reciprocal, equals
    /// R(θi) at the mirror direction. Default.
    #[default]
    Halfway,
    /// R(θi) everywhere (Krywonos-style); breaks reciprocity.
    Incident,
}

/// Options shared by the GHS models.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GhsOptions {
    /// Energy handling.
    pub energy: Energy,
    /// Fresnel angle of the scattered part (with [`PolarizationFactor::R`]).
    pub fresnel_angle: FresnelAngle,
    /// Polarisation of the incident light (the specular lobe's reflectance
    /// and the scattered part's factor are those of this polarisation).
    pub polarization: Polarization,
    /// The scattered part's reflectance factor: scalar R or the
    /// Rayleigh–Rice Q.
    pub polarization_factor: PolarizationFactor,
}

/// Nodes in θi of the energy tables (graded towards grazing, see
/// [`EnergyTable`]).
pub(crate) const TABLE_THETA_NODES: usize = 96;
/// Nodes in λ of the energy tables (uniform over 360–830 nm).
pub(crate) const TABLE_LAMBDA_NODES: usize = 16;
/// The last θi node: 90° − 1e−3 rad; beyond it the table is clamped.
const X_FIRST: f64 = 1e-3;
/// Scale of the grading near grazing, rad (see [`grade`]).
const X_SCALE: f64 = 2e-3;
/// Weight of the uniform part of the grading, per rad (see [`grade`]).
const X_UNIFORM: f64 = 1.2;

/// A smooth function of (θi, λ) on a fixed grid, 4×4-point Lagrange
/// interpolation, clamped to the grid. Fixed size: no allocation.
///
/// The θi nodes are uniform in v = [`grade`](x), x = 90° − θi: 2.9° apart at
/// normal incidence, 1e−3 rad at x = 0.01 and 2e−4 rad at the last node,
/// x = 1e−3. Near grazing the tabulated albedos change over x ~ sqrt(2/(kL))
/// (where the rim of the propagating disk reaches the lobe), 0.011 rad for
/// the narrowest lobe of the domain, which nodes uniform in θi (1.4° apart)
/// do not resolve.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EnergyTable {
    data: [f64; TABLE_THETA_NODES * TABLE_LAMBDA_NODES],
}

/// v(x) = asinh(x/X_SCALE) + X_UNIFORM·x: logarithmic in x near grazing,
/// close to uniform in θ near normal incidence; increasing.
fn grade(x: f64) -> f64 {
    libm::asinh(x / X_SCALE) + X_UNIFORM * x
}

/// x with [`grade`](x) = v, for v in [grade(0), grade(π/2)], by bisection
/// (build time only).
fn ungrade(v: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, FRAC_PI_2);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if grade(mid) < v {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-16 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

impl EnergyTable {
    /// θ of node `j` (node 0 at normal incidence).
    pub fn theta_node(j: usize) -> f64 {
        if j == 0 {
            return 0.0;
        }
        let (v0, v1) = (grade(FRAC_PI_2), grade(X_FIRST));
        let v = v0 + (v1 - v0) * j as f64 / (TABLE_THETA_NODES - 1) as f64;
        FRAC_PI_2 - ungrade(v)
    }

    /// λ (nm) of node `l`.
    pub fn lambda_node(l: usize) -> f64 {
        WAVELENGTH_MIN_NM
            + (WAVELENGTH_MAX_NM - WAVELENGTH_MIN_NM) * l as f64 / (TABLE_LAMBDA_NODES - 1) as f64
    }

    /// Tabulates `f(θi, λ_nm)`.
    pub fn build(mut f: impl FnMut(f64, f64) -> f64) -> Self {
        let mut data = [0.0; TABLE_THETA_NODES * TABLE_LAMBDA_NODES];
        for j in 0..TABLE_THETA_NODES {
            for l in 0..TABLE_LAMBDA_NODES {
                data[j * TABLE_LAMBDA_NODES + l] = f(Self::theta_node(j), Self::lambda_node(l));
            }
        }
        EnergyTable { data }
    }

    /// Interpolated value at cosθi, λ (clamped to the grid).
    pub fn at(&self, cos_i: f64, lambda_nm: f64) -> f64 {
        // x = 90° − θi = asin(cosθi), without the cancellation of π/2 − acos.
        let x = libm::asin(cos_i.clamp(0.0, 1.0));
        let (v0, v1) = (grade(FRAC_PI_2), grade(X_FIRST));
        let ft = ((grade(x) - v0) / (v1 - v0) * (TABLE_THETA_NODES - 1) as f64)
            .clamp(0.0, (TABLE_THETA_NODES - 1) as f64);
        let fl = ((lambda_nm - WAVELENGTH_MIN_NM) / (WAVELENGTH_MAX_NM - WAVELENGTH_MIN_NM)
            * (TABLE_LAMBDA_NODES - 1) as f64)
            .clamp(0.0, (TABLE_LAMBDA_NODES - 1) as f64);
        let (j, wt) = weights(ft, TABLE_THETA_NODES);
        let (l, wl) = weights(fl, TABLE_LAMBDA_NODES);
        let mut acc = 0.0;
        for (a, wa) in wt.iter().enumerate() {
            let row = &self.data[(j - 1 + a) * TABLE_LAMBDA_NODES + l - 1..][..4];
            acc += wa * (wl[0] * row[0] + wl[1] * row[1] + wl[2] * row[2] + wl[3] * row[3]);
        }
        acc
    }
}

fn weights(f: f64, n: usize) -> (usize, [f64; 4]) {
    let i = (libm::floor(f) as usize).clamp(1, n - 3);
    let t = f - i as f64;
    let tm1 = t - 1.0;
    let tm2 = t - 2.0;
    let tp1 = t + 1.0;
    (
        i,
        [
            -t * tm1 * tm2 / 6.0,
            tp1 * tm1 * tm2 * 0.5,
            -tp1 * t * tm2 * 0.5,
            tp1 * t * tm1 / 6.0,
        ],
    )
}

/// ∫_{H²} f(o) cosθo dω_o = ∫_{|o⊥|<1} f d²o⊥ for a lobe peaked at the
/// mirror direction of `wi`, by the scheme of physics.md §4.3: polar
/// coordinates about the mirror point, geometric panels in ρ from
/// `lobe_rho`·1e−3 (the lobe's width in o⊥ units), a τ² substitution at the
/// rim that removes the sqrt(1 − |o⊥|²) singularity, cosθo formed without
/// cancellation, and 2×16-point Gauss–Legendre in φ ∈ [0, π] (doubled by
/// symmetry). 8-point Gauss–Legendre per radial panel.
pub fn hemispherical_integral(wi: DVec3, lobe_rho: f64, mut f: impl FnMut(DVec3) -> f64) -> f64 {
    let (gx8, gw8) = gauss_legendre::<4>();
    let (gx16, gw16) = gauss_legendre::<8>();
    let sin_i = libm::sqrt((wi.x * wi.x + wi.y * wi.y).min(1.0));
    // Frame: mirror point s⊥ = −i⊥; φ measured from the direction of −s⊥ = i⊥.
    let (ex, ey) = if sin_i > 0.0 {
        (wi.x / sin_i, wi.y / sin_i)
    } else {
        (1.0, 0.0)
    };
    let mut total = 0.0;
    let rho0 = (1e-3 * lobe_rho).clamp(1e-12, 1e-2);
    for half in 0..2 {
        for k in 0..16 {
            let (node, w) = if k < 8 {
                (-gx16[k], gw16[k])
            } else {
                (gx16[k - 8], gw16[k - 8])
            };
            let phi = FRAC_PI_2 * (half as f64 + 0.5 + 0.5 * node);
            let wphi = FRAC_PI_2 * 0.5 * w;
            let (sp, cp) = libm::sincos(phi);
            // direction of the offset in the surface plane
            let dx = cp * ex - sp * ey;
            let dy = cp * ey + sp * ex;
            // b = s⊥·e = −sinθi cosφ
            let b = -sin_i * cp;
            let rmax = -b + libm::sqrt((1.0 - sin_i * sin_i * sp * sp).max(0.0));
            if !(rmax > 0.0) {
                continue;
            }
            let mut eval_at = |rho: f64| -> f64 {
                let oz2 = (rmax - rho) * (rho + rmax + 2.0 * b);
                if !(oz2 > 0.0) {
                    return 0.0;
                }
                let o = DVec3::new(-wi.x + rho * dx, -wi.y + rho * dy, libm::sqrt(oz2));
                f(o) * rho
            };
            let mut panel = |lo: f64, hi: f64| -> f64 {
                let h = 0.5 * (hi - lo);
                let m = 0.5 * (hi + lo);
                let mut s = 0.0;
                for i in 0..4 {
                    s += gw8[i] * (eval_at(m - h * gx8[i]) + eval_at(m + h * gx8[i]));
                }
                s * h
            };
            let split = 0.5 * rmax;
            let mut acc = 0.0;
            let mut lo = 0.0;
            let mut hi = rho0.min(split);
            while lo < split {
                acc += panel(lo, hi);
                lo = hi;
                hi = (2.0 * hi).min(split);
            }
            // ρ = rmax(1 − τ²/2), τ ∈ [0, 1]: dρ = rmax·τ dτ
            for (t0, t1) in [(0.0, 0.5), (0.5, 1.0)] {
                let h = 0.5 * (t1 - t0);
                let m = 0.5 * (t1 + t0);
                let mut s = 0.0;
                for i in 0..4 {
                    for tau in [m - h * gx8[i], m + h * gx8[i]] {
                        s += gw8[i] * eval_at(rmax * (1.0 - 0.5 * tau * tau)) * rmax * tau;
                    }
                }
                acc += s * h;
            }
            total += wphi * acc;
        }
    }
    2.0 * total
}

/// Fraction of a unit-mass radial density (given by its radial CDF in u)
/// that falls inside the propagating disk, for a lobe centred on the mirror
/// direction: (1/π)∫₀^π F(kL·ρmax(φ)) dφ.
pub(crate) fn in_disk_fraction(sin_i: f64, kl: f64, cdf_u: impl Fn(f64) -> f64) -> f64 {
    let (gx, gw) = gauss_legendre::<16>();
    let mut acc = 0.0;
    for k in 0..32 {
        let (node, w) = if k < 16 {
            (-gx[k], gw[k])
        } else {
            (gx[k - 16], gw[k - 16])
        };
        let phi = 0.5 * PI * (1.0 + node);
        let (sp, cp) = libm::sincos(phi);
        let rmax = sin_i * cp + libm::sqrt((1.0 - sin_i * sin_i * sp * sp).max(0.0));
        acc += 0.5 * PI * w * cdf_u(kl * rmax);
    }
    (acc / PI).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrature_of_cosine_and_constant() {
        // ∫ cosθo dω = π (f = 1), ∫ cos² dω = 2π/3 (f = cosθo).
        for &t in &[0.0, 0.5, 1.2, 1.55] {
            let wi = DVec3::new(libm::sin(t), 0.0, libm::cos(t));
            let a = hemispherical_integral(wi, 0.01, |_| 1.0);
            assert!((a - PI).abs() < 1e-9, "{t}: {a}");
            let b = hemispherical_integral(wi, 0.01, |o| o.z);
            assert!((b - 2.0 * PI / 3.0).abs() < 1e-6, "{t}: {b}");
        }
    }

    #[test]
    fn in_disk_fraction_normal_incidence_closed_form() {
        // KC: F = 1 − (1 + k²Lc²)^{−ν} at normal incidence.
        let nu = 0.75;
        let kl = 3.0;
        let got = in_disk_fraction(0.0, kl, |u| crate::statistics::kc::cdf_u(nu, u));
        let want = 1.0 - libm::pow(1.0 + kl * kl, -nu);
        assert!((got - want).abs() < 1e-14);
    }

    #[test]
    fn theta_nodes_are_graded_towards_grazing() {
        let x = |j| FRAC_PI_2 - EnergyTable::theta_node(j);
        assert_eq!(EnergyTable::theta_node(0), 0.0);
        assert!((x(TABLE_THETA_NODES - 1) - X_FIRST).abs() < 1e-15);
        assert!(EnergyTable::theta_node(1) < 3f64.to_radians());
        for j in 1..TABLE_THETA_NODES {
            let (a, b) = (x(j - 1), x(j));
            assert!(b < a, "node {j}");
            // From 0.3° to 3° of grazing the nodes are < 10 % of x apart.
            if (0.005..0.05).contains(&a) {
                assert!(a - b < 0.1 * a, "node {j}: {a} − {b}");
            }
            assert!((grade(ungrade(grade(b))) - grade(b)).abs() < 1e-12);
        }
    }

    #[test]
    fn table_interpolates_smooth_functions() {
        let t = EnergyTable::build(|th, l| libm::cos(th) + 1e-3 * l);
        for &(th, l) in &[(0.3, 500.0), (1.0, 777.0), (0.05, 361.0)] {
            let v = t.at(libm::cos(th), l);
            assert!(
                (v - (libm::cos(th) + 1e-3 * l)).abs() < 1e-5,
                "{th} {l}: {v}"
            );
        }
    }
}
