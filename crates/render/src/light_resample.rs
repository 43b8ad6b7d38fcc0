//! Resampled importance sampling (RIS) of next-event estimation's light
//! sample at a glossy vertex.
//!
//! A light's own sampler (a map ∝ texel power, a rectangle uniform in area)
//! mostly lands where a narrow lobe is ~0. Here `m` candidates are drawn
//! from it, each weighted by w = p̂/p for a target p̂ = h·p whose factor
//! `h` is a cheap stand-in for the BSDF (its sampling density, which for the
//! microfacet models is f·cos up to F·G₂/G₁), one is picked in proportion to
//! its weight, and only that one is shadow-tested and evaluated. With the
//! contribution weight W = (1/p̂(y))·(1/m)·Σ wᵢ the estimate f·L·cos·W is
//! unbiased for any h > 0 wherever f·L·cos > 0: E[Σᵢ (wᵢ/Σw) g(xᵢ)/p̂(xᵢ)
//! · Σw/m] = (1/m) Σᵢ E[g(xᵢ)/p(xᵢ)], which needs each candidate to be
//! distributed as p on its own, not the candidates to be independent. So they
//! are one stratified draw shifted by fixed offsets (a rank-1 pattern), which
//! spreads them over the light better than independent draws would; the
//! pick reads its own uniform number. Relative to the light's density p(y)
//! the weight is p(y)·W = mean(h)/h(y), the factor [`resample`] returns.

use crate::light::{LightSample, Lights};
use glam::DVec3;

/// Candidate i's offset is i·ALPHA mod 1 in (light choice, u, v): the R₃
/// sequence's generator (1/φ₃, 1/φ₃², 1/φ₃³, φ₃ the plastic number), whose
/// multiples fill the cube evenly for any count.
const ALPHA: [f64; 3] = [
    0.819_172_513_396_164_4,
    0.671_043_606_703_789_2,
    0.549_700_477_901_970_4,
];

/// The uniform numbers of candidate `i` from the vertex's draw `u`.
#[inline]
fn candidate(u: [f64; 3], i: u32) -> [f64; 3] {
    let k = f64::from(i);
    let mut out = [0.0; 3];
    for d in 0..3 {
        let x = u[d] + k * ALPHA[d];
        out[d] = x - x.floor();
    }
    out
}

/// Draws `m` light samples from point `p` with the uniform numbers `u`
/// (candidate 0 is the plain sample of `u`), picks one in proportion to
/// `h(direction, density)` with `u_pick`, and returns it with
/// mean(h)/h(pick): the factor that turns the light strategy's 1/p(y) into
/// RIS's contribution weight. `None` when every candidate has h = 0 (a
/// candidate the light cannot give still counts in the mean). A non-finite
/// or negative h counts as 0.
///
/// `u[0]` chooses one light for all candidates: each candidate is still
/// distributed as the light sampler's p on its own, which is all the
/// estimate needs. From a light at a finite distance a candidate is only a
/// direction, distance and density ([`Lights::direction`]); the pick alone
/// gets its emission and shape.
pub(crate) fn resample<'a>(
    lights: &'a Lights,
    p: DVec3,
    u: [f64; 3],
    m: u32,
    u_pick: f64,
    mut h: impl FnMut(DVec3, f64) -> f64,
) -> Option<(LightSample<'a>, f64)> {
    let idx = lights.choose(u[0])?;
    let uv = |i| {
        let c = candidate(u, i);
        [c[1], c[2]]
    };
    if lights.has_direction(idx) {
        let draw = |i| lights.direction(idx, p, uv(i));
        let (d, ratio) = pick(m, u_pick, draw, |d| h(d.wi, d.pdf))?;
        Some((lights.finish(idx, d), ratio))
    } else {
        let draw = |i| lights.sample_from(idx, p, uv(i));
        pick(m, u_pick, draw, |ls| h(ls.wi, ls.pdf))
    }
}

/// Streams candidates `draw(0..m)` and keeps one in proportion to `h`,
/// with mean(h)/h(kept) (see [`resample`]).
#[inline(always)]
fn pick<T>(
    m: u32,
    u_pick: f64,
    mut draw: impl FnMut(u32) -> Option<T>,
    mut h: impl FnMut(&T) -> f64,
) -> Option<(T, f64)> {
    let mut chosen: Option<(T, f64)> = None;
    let mut sum = 0.0;
    // One uniform number picks among a stream: candidate i replaces the
    // pick with probability hᵢ/Σ_{j≤i} h_j, and the number is rescaled to
    // stay uniform on whichever side of that threshold it fell.
    let mut r = u_pick;
    for i in 0..m {
        let Some(x) = draw(i) else {
            continue;
        };
        let w = h(&x);
        if !(w > 0.0 && w.is_finite()) {
            continue;
        }
        sum += w;
        let a = w / sum;
        if r < a {
            r /= a;
            chosen = Some((x, w));
        } else {
            r = (r - a) / (1.0 - a);
        }
        r = r.min(1.0 - f64::EPSILON);
    }
    let (x, w) = chosen?;
    let ratio = sum / (f64::from(m) * w);
    ratio.is_finite().then_some((x, ratio))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Planar, Transform};
    use crate::light::{Environment, LightKind};
    use crate::rng::Rng;
    use crate::spectrum::Spectrum;
    use std::f64::consts::PI;

    /// A von Mises–Fisher lobe about `mu` of concentration `k`: unit
    /// integral over the sphere, and as narrow as a glossy lobe (κ 50 ≈ a
    /// GGX α 0.1 lobe's width).
    fn vmf(mu: DVec3, k: f64, w: DVec3) -> f64 {
        k / (2.0 * PI * (1.0 - (-2.0 * k).exp())) * (k * (w.dot(mu) - 1.0)).exp()
    }

    /// Means over `n` resampled samples of (right, broken) estimates of
    /// ∫ g·L dω, L = 1: g(y)·W with RIS's contribution weight, and with the
    /// (1/m)Σw factor dropped (g(y)/p̂(y)); with their standard errors.
    fn estimates(
        lights: &Lights,
        p: DVec3,
        g: impl Fn(DVec3) -> f64,
        h: impl Fn(DVec3) -> f64,
        n: u32,
    ) -> [(f64, f64); 2] {
        let m = 8;
        let mut rng = Rng::for_sample(7, 0, 0);
        let mut acc = [[0.0; 2]; 2];
        for _ in 0..n {
            let u = rng.uniform3();
            let u_pick = rng.uniform();
            let x = resample(lights, p, u, m, u_pick, |wi, _| h(wi));
            let [right, broken] = match x {
                Some((ls, ratio)) => {
                    let v = g(ls.wi) / ls.pdf;
                    [v * ratio, v / (ls.pdf * h(ls.wi))]
                }
                None => [0.0, 0.0],
            };
            for (a, v) in acc.iter_mut().zip([right, broken]) {
                a[0] += v;
                a[1] += v * v;
            }
        }
        acc.map(|[s, s2]| {
            let mean = s / f64::from(n);
            (
                mean,
                ((s2 / f64::from(n) - mean * mean) / f64::from(n)).sqrt(),
            )
        })
    }

    #[test]
    fn resampling_a_constant_environment_integrates_a_narrow_lobe() {
        // ∫ vMF dω = 1 under unit radiance: the white furnace of a lobe
        // that a uniform light sample rarely meets. The proxy is off axis
        // and wider (a proxy need not be f, only positive where f is).
        let lights = Lights {
            lights: vec![LightKind::Environment(Environment::Constant(
                Spectrum::Constant(1.0),
            ))],
            environment: Some(0),
            bsdf_only_environment: false,
        };
        let mu = DVec3::new(0.3, -0.2, 1.0).normalize();
        let mu_h = DVec3::new(0.4, -0.1, 1.0).normalize();
        let [(right, se), (broken, _)] = estimates(
            &lights,
            DVec3::ZERO,
            |w| vmf(mu, 50.0, w),
            |w| vmf(mu_h, 20.0, w) + 1e-3,
            200_000,
        );
        assert!(
            (right - 1.0).abs() < 4.0 * se && se < 0.01,
            "{right} ± {se}"
        );
        // The test can fail: without (1/m)Σw the same samples miss by far.
        assert!((broken - 1.0).abs() > 50.0 * se, "{broken}");
    }

    /// A 2 × 1 rectangle 1.5 above the origin, tilted 30° about x, and a
    /// lobe (κ 30) aimed at one of its corners, so it covers part of it;
    /// with ∫ lobe dω over the rectangle by a midpoint rule on 800 × 400
    /// cells (as ∫ lobe cosθ_l / d² dA).
    fn tilted_rectangle() -> (LightKind, DVec3, f64) {
        let xf = Transform::new([210.0, 0.0, 0.0], 1.0, [0.2, 0.1, 1.5]);
        let shape = Planar::rectangle([2.0, 1.0], &xf);
        let corner = shape.center + shape.u * shape.half.0 * 0.8 + shape.v * shape.half.1 * 0.7;
        let mu = corner.normalize();
        let (na, nb) = (800, 400);
        let da = 4.0 * shape.half.0 * shape.half.1 / f64::from(na * nb);
        let mut exact = 0.0;
        for i in 0..na {
            for j in 0..nb {
                let a = (2.0 * (f64::from(i) + 0.5) / f64::from(na) - 1.0) * shape.half.0;
                let b = (2.0 * (f64::from(j) + 0.5) / f64::from(nb) - 1.0) * shape.half.1;
                let q = shape.center + shape.u * a + shape.v * b;
                let d2 = q.length_squared();
                let w = q / d2.sqrt();
                let cos_l = -w.dot(shape.n);
                if cos_l > 0.0 {
                    exact += vmf(mu, 30.0, w) * cos_l / d2 * da;
                }
            }
        }
        assert!(exact > 0.1, "{exact}");
        let light = LightKind::Rectangle {
            shape,
            spectrum: Spectrum::Constant(1.0),
            two_sided: false,
        };
        (light, mu, exact)
    }

    #[test]
    fn resampling_a_rectangle_light_matches_quadrature_at_a_glossy_lobe() {
        let (light, mu, exact) = tilted_rectangle();
        let lights = Lights {
            lights: vec![light],
            environment: None,
            bsdf_only_environment: false,
        };
        let g = |w: DVec3| vmf(mu, 30.0, w);
        let [(right, se), (broken, _)] =
            estimates(&lights, DVec3::ZERO, g, |w| g(w) + 1e-3, 100_000);
        assert!(
            (right - exact).abs() < 4.0 * se && se < 0.005 * exact,
            "{right} ± {se} vs {exact}"
        );
        assert!((broken - exact).abs() > 50.0 * se, "{broken}");
    }

    #[test]
    fn resampling_a_rectangle_beside_an_environment_counts_both() {
        // One light chosen per vertex for all its candidates: the rectangle
        // (candidates are directions, the pick finished) or the constant
        // environment (candidates are whole samples); ∫ g·L dω is the
        // rectangle's quadrature plus the lobe's unit integral, and every
        // selection density must come out right for the sum to.
        let (light, mu, exact) = tilted_rectangle();
        let lights = Lights {
            lights: vec![
                light,
                LightKind::Environment(Environment::Constant(Spectrum::Constant(1.0))),
            ],
            environment: Some(1),
            bsdf_only_environment: false,
        };
        let g = |w: DVec3| vmf(mu, 30.0, w);
        let [(right, se), _] = estimates(&lights, DVec3::ZERO, g, |w| g(w) + 1e-3, 200_000);
        let want = exact + 1.0;
        assert!(
            (right - want).abs() < 4.0 * se && se < 0.01 * want,
            "{right} ± {se} vs {want}"
        );
    }

    #[test]
    fn one_candidate_is_the_plain_light_sample() {
        let lights = Lights {
            lights: vec![LightKind::Environment(Environment::Constant(
                Spectrum::Constant(1.0),
            ))],
            environment: Some(0),
            bsdf_only_environment: false,
        };
        let u = [0.3, 0.6, 0.2];
        let plain = lights.sample(DVec3::ZERO, u).unwrap();
        let (ls, ratio) = resample(&lights, DVec3::ZERO, u, 1, 0.9, |_, _| 2.0).unwrap();
        assert_eq!((ls.wi, ls.pdf, ratio), (plain.wi, plain.pdf, 1.0));
        // No candidate with a positive proxy: no sample.
        assert!(resample(&lights, DVec3::ZERO, u, 8, 0.5, |_, _| 0.0).is_none());
        assert!(resample(&lights, DVec3::ZERO, u, 8, 0.5, |_, _| f64::NAN).is_none());
    }

    #[test]
    fn candidates_are_picked_in_proportion_to_the_proxy() {
        // Candidate i has proxy i + 1: over uniform pick numbers, candidate
        // i is returned (i + 1)/36 of the time, told by its ratio 36/8/(i+1).
        let lights = Lights {
            lights: vec![LightKind::Environment(Environment::Constant(
                Spectrum::Constant(1.0),
            ))],
            environment: Some(0),
            bsdf_only_environment: false,
        };
        let u = [0.1, 0.7, 0.4];
        let mut seen = 0;
        let mut counts = [0u32; 8];
        let n = 36_000;
        for k in 0..n {
            let u_pick = (f64::from(k) + 0.5) / f64::from(n);
            let (_, ratio) = resample(&lights, DVec3::ZERO, u, 8, u_pick, |_, _| {
                seen += 1;
                f64::from((seen - 1) % 8 + 1)
            })
            .unwrap();
            let i = (36.0 / 8.0 / ratio).round() as usize - 1;
            counts[i] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            let want = f64::from(n) * (i + 1) as f64 / 36.0;
            assert!((f64::from(c) - want).abs() <= 2.0, "{i}: {c} vs {want}");
        }
    }
}
