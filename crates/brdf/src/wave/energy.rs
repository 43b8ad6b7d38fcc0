//! Energy handling and Fresnel-angle switches of the GHS models
//! (physics.md §5, §3.2), the (θi, λ) tables they need, and the
//! deterministic hemispherical quadrature those tables are built with.

use core::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

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
///
/// An albedo table ([`EnergyTable::build_log`]) holds and interpolates ln a:
/// near the rim a steep surface's raw albedo changes by 10× per degree of θi
/// (σ 3 µm, Lc 1 µm, γ 1.1: 1.4e−7 at 84°, 1.2e−6 at 85°, 7.4e−6 at 86°,
/// 700 nm), which a cubic in a does not follow (the Krywonos albedo was
/// 1.0014 at 85°) and a cubic in ln a does.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EnergyTable {
    data: [f64; TABLE_THETA_NODES * TABLE_LAMBDA_NODES],
    log: bool,
}

/// Least value an albedo table takes the logarithm of (exact zeros, σ = 0).
const LOG_FLOOR: f64 = 1e-300;

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

    /// Tabulates `f(θi, λ_nm)`, its θ rows spread over the cores with
    /// `std` ([`crate::parallel::map_rows`]; the table is the same either
    /// way: each value is computed by the same call).
    pub fn build(f: impl Fn(f64, f64) -> f64 + Sync) -> Self {
        let row = |j: usize| {
            let th = Self::theta_node(j);
            let mut row = [0.0; TABLE_LAMBDA_NODES];
            for (l, v) in row.iter_mut().enumerate() {
                *v = f(th, Self::lambda_node(l));
            }
            row
        };
        let mut data = [0.0; TABLE_THETA_NODES * TABLE_LAMBDA_NODES];
        let chunks = data.chunks_exact_mut(TABLE_LAMBDA_NODES);
        #[cfg(feature = "alloc")]
        for (chunk, r) in chunks.zip(crate::parallel::map_rows(TABLE_THETA_NODES, row)) {
            chunk.copy_from_slice(&r);
        }
        #[cfg(not(feature = "alloc"))]
        for (j, chunk) in chunks.enumerate() {
            chunk.copy_from_slice(&row(j));
        }
        EnergyTable { data, log: false }
    }

    /// Tabulates a positive `f(θi, λ_nm)` (an albedo) by its logarithm, so
    /// that [`at`](Self::at) interpolates ln f.
    pub fn build_log(f: impl Fn(f64, f64) -> f64 + Sync) -> Self {
        let mut t = Self::build(f);
        for v in &mut t.data {
            *v = libm::log(v.max(LOG_FLOOR));
        }
        t.log = true;
        t
    }

    /// Interpolated value at cosθi, λ (clamped to the grid); of ln f for a
    /// table from [`build_log`](Self::build_log).
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
        if self.log { libm::exp(acc) } else { acc }
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

/// First φ panel about the rim tangent, in units of cosθi (see
/// [`hemispherical_integral`]).
const PHI_FIRST: f64 = 3.0;
/// First τ panel at the rim, in units of cosθi/sqrt(ρmax·w) (see
/// [`hemispherical_integral`]).
const TAU_FIRST: f64 = 0.25;
/// Growth of the φ and τ panels away from the rim.
const RIM_PANEL_GROWTH: f64 = 4.0;

/// ∫_{H²} f(o) cosθo dω_o = ∫_{|o⊥|<1} f d²o⊥ for a lobe peaked at the
/// mirror direction of `wi`, by the scheme of physics.md §4.3: polar
/// coordinates about the mirror point, geometric panels in ρ from
/// `lobe_rho`·1e−3 (the lobe's width in o⊥ units), a τ² substitution at the
/// rim that removes the sqrt(1 − |o⊥|²) singularity, cosθo formed without
/// cancellation. 8-point Gauss–Legendre per panel.
///
/// The rim is resolved too, because a steep surface's full-GHS lobe is not
/// peaked at the mirror direction alone: at large g, S̃ ∝ g^{−p} and
/// g ∝ (cosθi + cosθo)², so the lobe also peaks all along the horizon, over
/// cosθo ~ cosθi. Near grazing incidence that is a thin band which the
/// mirror point itself lies in, and the rays from the mirror point cross it
/// over φ within ~cosθi of the rim tangent (φ = ±90°). So the φ panels grow
/// geometrically (×4) from 3·cosθi either side of the tangent (at most 45°,
/// so ≥ 32 nodes in φ), and the rim's τ panels grow (×4) from
/// 0.25·cosθi/sqrt(ρmax·w), the band's width in τ along that ray. With the
/// two fixed panels of each before, the raw albedo of σ 6.51 µm, Lc 1 µm,
/// γ 2 was 0.4 % low at 86.8°, 830 nm (the Krywonos albedo 1.0039) and up
/// to 20 % off for σ 3 µm, Lc 1 µm, γ 1.1.
pub fn hemispherical_integral(wi: DVec3, lobe_rho: f64, mut f: impl FnMut(DVec3) -> f64) -> f64 {
    let sin_i = libm::sqrt((wi.x * wi.x + wi.y * wi.y).min(1.0));
    let cos_i = wi.z.clamp(0.0, 1.0);
    // Frame: mirror point s⊥ = −i⊥; φ measured from the direction of −s⊥ = i⊥.
    let e = if sin_i > 0.0 {
        (wi.x / sin_i, wi.y / sin_i)
    } else {
        (1.0, 0.0)
    };
    let rho0 = (1e-3 * lobe_rho).clamp(1e-12, 1e-2);
    let psi0 = (PHI_FIRST * cos_i).clamp(1e-6, FRAC_PI_4);
    // Made once: Newton's iteration for the nodes costs more than a panel.
    let rule = gauss_legendre::<4>();
    let mut total = 0.0;
    // φ = 90° ∓ ψ, ψ ∈ [0, 90°]: the two sides of the rim tangent.
    for side in [-1.0, 1.0] {
        geometric_panels(psi0, FRAC_PI_2, |lo, hi| {
            total += gauss8(&rule, lo, hi, |psi| {
                let phi = FRAC_PI_2 + side * psi;
                ray_integral(&rule, wi, e, sin_i, cos_i, phi, rho0, &mut f)
            });
        });
    }
    2.0 * total
}

/// Calls `panel(lo, hi)` over [0, end] in panels [0, first], then growing
/// by [`RIM_PANEL_GROWTH`].
fn geometric_panels(first: f64, end: f64, mut panel: impl FnMut(f64, f64)) {
    let (mut lo, mut hi) = (0.0, first.min(end));
    while lo < end {
        panel(lo, hi);
        lo = hi;
        hi = (RIM_PANEL_GROWTH * hi).min(end);
    }
}

/// The positive half of the 8-point Gauss–Legendre rule ([`gauss_legendre`]).
type Rule8 = ([f64; 4], [f64; 4]);

/// 8-point Gauss–Legendre of `g` over [lo, hi].
fn gauss8((gx, gw): &Rule8, lo: f64, hi: f64, mut g: impl FnMut(f64) -> f64) -> f64 {
    let (h, m) = (0.5 * (hi - lo), 0.5 * (hi + lo));
    let mut s = 0.0;
    for i in 0..4 {
        s += gw[i] * (g(m - h * gx[i]) + g(m + h * gx[i]));
    }
    s * h
}

/// ∫ f ρ dρ along the ray from the mirror point at angle `phi` (see
/// [`hemispherical_integral`]) to the rim.
#[allow(clippy::too_many_arguments)]
fn ray_integral(
    rule: &Rule8,
    wi: DVec3,
    (ex, ey): (f64, f64),
    sin_i: f64,
    cos_i: f64,
    phi: f64,
    rho0: f64,
    f: &mut impl FnMut(DVec3) -> f64,
) -> f64 {
    let (sp, cp) = libm::sincos(phi);
    // direction of the offset in the surface plane
    let (dx, dy) = (cp * ex - sp * ey, cp * ey + sp * ex);
    // b = s⊥·e = −sinθi cosφ; w = ρmax + b ≥ cosθi
    let b = -sin_i * cp;
    let w = libm::sqrt((1.0 - sin_i * sin_i * sp * sp).max(0.0));
    let rmax = -b + w;
    if !(rmax > 0.0) {
        return 0.0;
    }
    let mut eval_at = |rho: f64| -> f64 {
        let oz2 = (rmax - rho) * (rho + rmax + 2.0 * b);
        if !(oz2 > 0.0) {
            return 0.0;
        }
        let o = DVec3::new(-wi.x + rho * dx, -wi.y + rho * dy, libm::sqrt(oz2));
        f(o) * rho
    };
    let split = 0.5 * rmax;
    let mut acc = 0.0;
    let (mut lo, mut hi) = (0.0, rho0.min(split));
    while lo < split {
        acc += gauss8(rule, lo, hi, &mut eval_at);
        lo = hi;
        hi = (2.0 * hi).min(split);
    }
    // ρ = rmax(1 − τ²/2), τ ∈ [0, 1]: dρ = rmax·τ dτ, cosθo ≈ τ sqrt(rmax·w)
    let tau0 = (TAU_FIRST * cos_i / libm::sqrt(rmax * w)).clamp(1e-6, 0.5);
    geometric_panels(tau0, 1.0, |t0, t1| {
        acc += gauss8(rule, t0, t1, |tau| {
            eval_at(rmax * (1.0 - 0.5 * tau * tau)) * rmax * tau
        });
    });
    acc
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
    fn quadrature_of_a_band_along_the_horizon() {
        // f = (cosθi + cosθo)^−4, the large-g shape of a steep surface's
        // full-GHS lobe: ∫ f cosθo dω = 2π ∫₀¹ μ/(c + μ)⁴ dμ
        // = 2π [1/(6c²) − 1/(2(1 + c)²) + c/(3(1 + c)³)], c = cosθi.
        for &t in &[0.0f64, 60.0, 80.0, 86.8, 88.0, 89.0, 89.5, 89.9] {
            let wi = DVec3::new(libm::sin(t.to_radians()), 0.0, libm::cos(t.to_radians()));
            let c = wi.z;
            let want = 2.0
                * PI
                * (1.0 / (6.0 * c * c) - 0.5 / ((1.0 + c) * (1.0 + c))
                    + c / (3.0 * (1.0 + c) * (1.0 + c) * (1.0 + c)));
            let got = hemispherical_integral(wi, 0.13, |o| libm::pow(c + o.z, -4.0));
            assert!((got / want - 1.0).abs() < 1e-6, "{t}°: {got} vs {want}");
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
    fn log_table_follows_an_albedo_over_decades() {
        // 10^(−40 cosθ): 7 decades from 80° to 90°, like a steep surface's
        // raw albedo near the rim.
        let f = |th: f64, _l: f64| libm::pow(10.0, -40.0 * libm::cos(th));
        let (t, plain) = (EnergyTable::build_log(f), EnergyTable::build(f));
        let mut worst = (0.0f64, 0.0f64);
        for &deg in &[80.3f64, 84.7, 85.2, 87.9, 89.6] {
            let th = deg.to_radians();
            let v = t.at(libm::cos(th), 600.0) / f(th, 600.0) - 1.0;
            let p = plain.at(libm::cos(th), 600.0) / f(th, 600.0) - 1.0;
            worst = (worst.0.max(v.abs()), worst.1.max(p.abs()));
        }
        // ln f is smooth in the node grade: 5.4e−6; a cubic in f: 3.4 %.
        assert!(worst.0 < 2e-5 && worst.1 > 1e-2, "(log, plain): {worst:?}");
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
