//! The microfacet distribution that parameterises an RGL table.
//!
//! The format stores a BRDF relative to a microfacet normal distribution D
//! and its projected area σ(ω) = ∫ D(m) max(0, ω·m) dm: a reader returns
//! f·cosθo = S · D(m) / (4 σ(ωi)) with S the tabulated spectra, and samples
//! m from the distribution of visible normals D_ωi(m) = D(m) max(0, ωi·m) /
//! σ(ωi). For a microfacet model S is then F·G2/G1, smooth and of order 1.
//!
//! * GGX and Beckmann use their own D and σ(ω) = cosθ (1 + Λ(ω)) (Smith).
//! * Any other model gets the distribution the RGL acquisition pipeline
//!   derives from a measurement (Dupuy & Jakob 2018, §4): in the
//!   retro-reflection configuration ωo = ωi = ω a microfacet BRDF is
//!   f(ω, ω) = F(0) D(ω) / (4 cosθ σ(ω)), so D ∝ cosθ f(ω, ω) σ[D](ω), the
//!   dominant eigenvector of a positive linear operator, found by power
//!   iteration. The backscatter is weighted over the export's wavelengths by
//!   luminance. For the wave-optical models this D is the lobe of f(ω, ω)
//!   about the normal; their lobe at other configurations differs from the
//!   microfacet prediction (see the README), which the spectra S carry.

use brdf::{Bxdf, DVec3, Distribution};

use crate::ExportError;
use crate::param::{azimuthal_cosine_integral, direction, node, u_to_phi, u_to_theta};
use core::f64::consts::PI;

/// Where the table's microfacet distribution comes from.
#[derive(Clone, Debug)]
pub enum NdfSource {
    /// A microfacet model's own distribution (GGX, Beckmann; anisotropic
    /// allowed) and the angle φ (radians, from the tangent x towards y) its
    /// αx axis is turned by, as `brdf::microfacet::Rotated` turns the model.
    Microfacet(Distribution, f64),
    /// Derived from the model's retro-reflection, as the RGL acquisition
    /// pipeline does from a measurement (isotropic models only).
    Backscatter,
}

/// D on the grid of the file's `ndf` field (rows u_φ, columns u_θ).
pub struct NdfGrid {
    /// Nodes along u_θ.
    pub n_theta: usize,
    /// Nodes along u_φ.
    pub n_phi: usize,
    /// D (sr⁻¹, ∫ D cosθ dω = 1), row-major.
    pub values: Vec<f64>,
}

/// Gauss–Legendre nodes and weights on [−1, 1], 8 points.
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// ∫ g(θm) D(θm) dω over the upper hemisphere for an isotropic D given at
/// `n` nodes evenly spaced in u and interpolated linearly in u (as the
/// readers interpolate the `ndf` field), with `g` receiving θm.
fn hemisphere_integral(d: &[f64], g: impl Fn(f64) -> f64) -> f64 {
    let n = d.len();
    let mut sum = 0.0;
    for k in 0..n - 1 {
        let (u0, u1) = (node(k, n), node(k + 1, n));
        for &(x, wt) in &GL8 {
            let t = 0.5 * (x + 1.0);
            let u = u0 + (u1 - u0) * t;
            let theta = u_to_theta(u);
            let dv = d[k] + (d[k + 1] - d[k]) * t;
            // dω = sinθ dθ dφ and dθ = π u du; the φ integral is in `g`.
            sum += 0.5 * wt * (u1 - u0) * dv * g(theta) * theta.sin() * PI * u;
        }
    }
    sum
}

/// σ(θ) of an isotropic tabulated D: its area projected onto the plane
/// normal to a direction at elevation `theta`.
pub fn projected_area_iso(d: &[f64], theta: f64) -> f64 {
    hemisphere_integral(d, |tm| azimuthal_cosine_integral(theta, tm))
}

/// ∫ D cosθ dω of an isotropic tabulated D (1 for a normalised one).
fn normalisation_iso(d: &[f64]) -> f64 {
    hemisphere_integral(d, |tm| 2.0 * PI * tm.cos())
}

/// The D of `source` on an `n_theta × n_phi` grid. `weights` are the
/// luminance weights of `lambdas_nm` (for the backscatter).
pub fn ndf_grid(
    source: &NdfSource,
    model: &dyn Bxdf,
    n_theta: usize,
    n_phi: usize,
    lambdas_nm: &[f64],
    weights: &[f64],
) -> Result<NdfGrid, ExportError> {
    let values = match source {
        NdfSource::Microfacet(dist, angle_rad) => {
            let mut v = Vec::with_capacity(n_theta * n_phi);
            for r in 0..n_phi {
                for k in 0..n_theta {
                    let m = direction(u_to_theta(node(k, n_theta)), u_to_phi(node(r, n_phi)));
                    v.push(dist.d(turned_back(m, *angle_rad)));
                }
            }
            v
        }
        NdfSource::Backscatter => {
            let d = backscatter_ndf(model, n_theta, lambdas_nm, weights)?;
            (0..n_phi).flat_map(|_| d.iter().copied()).collect()
        }
    };
    Ok(NdfGrid {
        n_theta,
        n_phi,
        values,
    })
}

/// Iterations of the power method; it converges geometrically, to 1e-10
/// within a few dozen steps for every model tried.
const POWER_STEPS: usize = 200;

/// The isotropic D (at `n` nodes in u) whose microfacet retro-reflection is
/// the model's, by power iteration on D ← cosθ f(ω, ω) σ[D].
pub fn backscatter_ndf(
    model: &dyn Bxdf,
    n: usize,
    lambdas_nm: &[f64],
    weights: &[f64],
) -> Result<Vec<f64>, ExportError> {
    let thetas: Vec<f64> = (0..n).map(|k| u_to_theta(node(k, n))).collect();
    let c: Vec<f64> = thetas
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let w = direction(t, 0.0);
            // The horizon node: no microfacet there reflects anything, and a
            // model's retro-reflection at exactly 90° is a limit it may not
            // keep finite (two-scale's grows without bound).
            if k + 1 == n || w.z <= 0.0 {
                return 0.0;
            }
            let f: f64 = lambdas_nm
                .iter()
                .zip(weights)
                .map(|(&l, &wt)| wt * model.eval(w, w, l))
                .sum();
            (w.z * f).max(0.0)
        })
        .collect();
    if !c.iter().any(|&v| v > 0.0) || !c.iter().all(|v| v.is_finite()) {
        return Err(ExportError::Model(
            "the model reflects nothing back along the incident direction, so no \
             microfacet distribution can be derived from its retro-reflection"
                .into(),
        ));
    }
    let mut d = c.clone();
    normalise(&mut d);
    for _ in 0..POWER_STEPS {
        let mut next: Vec<f64> = thetas
            .iter()
            .zip(&c)
            .map(|(&t, &ck)| ck * projected_area_iso(&d, t))
            .collect();
        normalise(&mut next);
        let change = next
            .iter()
            .zip(&d)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let peak = next.iter().copied().fold(0.0, f64::max);
        d = next;
        if change <= 1e-12 * peak {
            break;
        }
    }
    Ok(d)
}

fn normalise(d: &mut [f64]) {
    let s = normalisation_iso(d);
    if s > 0.0 {
        d.iter_mut().for_each(|v| *v /= s);
    }
}

/// R(−φ) v: a direction of the tangent frame in the frame of a distribution
/// turned by φ about the normal (cosθ and solid angle are kept).
fn turned_back(v: DVec3, angle_rad: f64) -> DVec3 {
    if angle_rad == 0.0 {
        return v;
    }
    let (s, c) = angle_rad.sin_cos();
    DVec3::new(c * v.x + s * v.y, c * v.y - s * v.x, v.z)
}

/// σ(ω) of `source` at `w` (upper hemisphere): Smith's cosθ (1 + Λ) for a
/// microfacet distribution, the quadrature of the tabulated isotropic D
/// otherwise (`iso` is that D at its u nodes).
pub fn projected_area(source: &NdfSource, iso: &[f64], w: DVec3) -> f64 {
    match source {
        NdfSource::Microfacet(dist, angle_rad) => {
            // At the horizon cosθ Λ tends to a finite limit; stay just above it.
            let z = w.z.max(1e-9);
            let w = DVec3::new(w.x, w.y, z).normalize();
            w.z * (1.0 + dist.lambda(turned_back(w, *angle_rad)))
        }
        NdfSource::Backscatter => projected_area_iso(iso, crate::param::elevation(w)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::{Fresnel, MicrofacetConductor};

    #[test]
    fn projected_area_of_tabulated_ggx_matches_smith() {
        let dist = Distribution::ggx(0.3, 0.3).unwrap();
        let n = 512;
        let d: Vec<f64> = (0..n)
            .map(|k| dist.d(direction(u_to_theta(node(k, n)), 0.0)))
            .collect();
        assert!(
            (normalisation_iso(&d) - 1.0).abs() < 1e-4,
            "{}",
            normalisation_iso(&d)
        );
        for &t in &[0.0, 0.4, 1.0, 1.4, 1.55] {
            let w = direction(t, 0.0);
            let smith = projected_area(&NdfSource::Microfacet(dist, 0.0), &[], w);
            let quad = projected_area_iso(&d, t);
            assert!(
                (quad - smith).abs() < 1e-4 * smith,
                "θ {t}: {quad} vs {smith}"
            );
        }
    }

    #[test]
    fn backscatter_of_a_microfacet_model_recovers_its_distribution() {
        // With height-correlated Smith, G2(ω, ω) = 1/(1 + 2Λ) instead of
        // G1 = 1/(1 + Λ): the recovered D is exact at the normal and within
        // the (1 + Λ)/(1 + 2Λ) ratio elsewhere (a few % inside the lobe).
        let dist = Distribution::ggx(0.2, 0.2).unwrap();
        let model = MicrofacetConductor::new(dist, Fresnel::One).unwrap();
        let n = 256;
        let d = backscatter_ndf(&model, n, &[550.0], &[1.0]).unwrap();
        for k in (0..n).step_by(16) {
            let t = u_to_theta(node(k, n));
            if t > 1.2 {
                break;
            }
            let w = direction(t, 0.0);
            let truth = dist.d(w);
            let l = dist.lambda(w);
            let bound = (1.0 + l) / (1.0 + 2.0 * l);
            let ratio = d[k] / truth;
            assert!(
                ratio > 0.97 * bound && ratio < 1.03,
                "θ {t}: D ratio {ratio}, bound {bound}"
            );
        }
    }
}
