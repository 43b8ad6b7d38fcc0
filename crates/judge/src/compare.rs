//! Directions, the explicit reference per (θi, λ), model values as that reference sees
//! them (smoothed by the tile kernel; integrated over o_y for profiles) and log-space scores.

use brdf::{Bxdf, DVec3, Fresnel};
use fit::explicit_brdf::{AngularWindow, Estimate, ExplicitBrdf, Validity};

use crate::LOG_FLOOR;
use crate::recipes::Candidate;

/// Which slice a direction belongs to.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum SliceKind {
    InPlane,
    CrossPlane,
}

/// One evaluated direction.
pub(crate) struct Point {
    pub(crate) kind: SliceKind,
    /// Signed θo [deg] (in-plane, > 0 on the specular side) or o_y (cross-plane).
    pub(crate) coord: f64,
    pub(crate) wo: [f64; 3],
    pub(crate) explicit: Estimate,
    pub(crate) surrogate: Option<f64>,
    pub(crate) validity: Validity,
}

/// Everything computed for one (θi, λ).
pub(crate) struct AngleSet {
    pub(crate) theta_i: f64,
    pub(crate) lambda_nm: f64,
    pub(crate) wi: [f64; 3],
    pub(crate) window: AngularWindow,
    pub(crate) coherent: Estimate,
    pub(crate) points: Vec<Point>,
    pub(crate) floor: f64,
}

/// In-plane exits: half uniform in signed θo over ±88°, half at geometric offsets from
/// the mirror direction (resolution … 1 in direction cosine).
pub(crate) fn in_plane_dirs(theta_i: f64, n: usize, res: f64) -> Vec<(f64, [f64; 3])> {
    let s_max = 88f64.to_radians().sin();
    let mirror = -theta_i.to_radians().sin();
    let mut ox: Vec<f64> = Vec::new();
    let n_uni = (n / 2).max(2);
    for j in 0..n_uni {
        let t = (-88.0 + 176.0 * j as f64 / (n_uni - 1) as f64).to_radians();
        ox.push(-t.sin());
    }
    let n_side = ((n - n / 2) / 2).max(1);
    let lo = res.max(1e-5);
    for j in 0..n_side {
        let d = lo * (1.0 / lo).powf(j as f64 / (n_side.max(2) - 1) as f64);
        ox.extend([mirror - d, mirror + d]);
    }
    ox.retain(|v| v.abs() <= s_max);
    ox.sort_by(|a, b| b.total_cmp(a));
    ox.dedup();
    ox.iter()
        .map(|&x| ((-x).asin().to_degrees(), [x, 0.0, (1.0 - x * x).sqrt()]))
        .collect()
}

/// Cross-plane exits through the mirror direction: o = (−sinθi, o_y, ·).
pub(crate) fn cross_plane_dirs(theta_i: f64, n: usize, res: f64) -> Vec<(f64, [f64; 3])> {
    let sx = -theta_i.to_radians().sin();
    let y_max = (1.0 - sx * sx).sqrt() * 88f64.to_radians().sin();
    let mut oy: Vec<f64> = Vec::new();
    let n_uni = (n / 2).max(2);
    for j in 0..n_uni {
        oy.push(-y_max + 2.0 * y_max * j as f64 / (n_uni - 1) as f64);
    }
    let n_side = ((n - n / 2) / 2).max(1);
    let lo = res.max(1e-5);
    for j in 0..n_side {
        let d = lo * (y_max / lo).powf(j as f64 / (n_side.max(2) - 1) as f64);
        oy.extend([-d, d]);
    }
    oy.retain(|v| v.abs() <= y_max);
    oy.sort_by(f64::total_cmp);
    oy.dedup();
    oy.iter()
        .map(|&y| (y, [sx, y, (1.0 - sx * sx - y * y).max(0.0).sqrt()]))
        .collect()
}

/// cosθd = i·h = sqrt((1 + i·o)/2), the Fresnel angle of the scattered part.
pub(crate) fn cos_d(wi: [f64; 3], wo: [f64; 3]) -> f64 {
    (0.5 * (1.0 + wi[0] * wo[0] + wi[1] * wo[1] + wi[2] * wo[2]))
        .max(0.0)
        .sqrt()
}

pub(crate) fn dvec(v: [f64; 3]) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

/// `f` integrated over the out-of-plane direction cosine at in-plane `ox` (profiles):
/// 2∫₀^Y f do_y (isotropic models are even in o_y when i is in the x–z plane), on geometric
/// panels from 1e−5·Y with 4-point Gauss–Legendre.
pub(crate) fn marginal(m: &dyn Bxdf, wi: DVec3, ox: f64, lambda_nm: f64) -> f64 {
    let y_max = (1.0 - ox * ox).max(0.0).sqrt();
    if y_max <= 0.0 {
        return 0.0;
    }
    let (x, w) = brdf::numerics::quadrature::gauss_legendre::<2>();
    let mut edges = vec![0.0];
    let mut e = 1e-5 * y_max;
    while e < y_max {
        edges.push(e);
        e *= 2.0;
    }
    edges.push(y_max);
    let mut s = 0.0;
    for p in edges.windows(2) {
        let (a, b) = (p[0], p[1]);
        let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
        for (xi, wi_) in x.iter().zip(&w) {
            for oy in [c - h * xi, c + h * xi] {
                let oz2 = 1.0 - ox * ox - oy * oy;
                if oz2 > 0.0 {
                    s += wi_ * h * m.eval(wi, DVec3::new(ox, oy, oz2.sqrt()), lambda_nm);
                }
            }
        }
    }
    2.0 * s
}

/// A model value as the explicit estimate sees it: smoothed by the tile kernel (`nodes`, ξ in
/// rad/m, k in rad/m), and for profiles integrated over o_y.
pub(crate) fn model_value(
    m: &dyn Bxdf,
    wi: [f64; 3],
    wo: [f64; 3],
    lambda_nm: f64,
    k: f64,
    nodes: &[(f64, f64, f64)],
    profile: bool,
) -> f64 {
    let wi_v = dvec(wi);
    let mut s = 0.0;
    for &(xx, xy, w) in nodes {
        let ox = wo[0] + xx / k;
        if profile {
            if ox.abs() < 1.0 {
                s += w * marginal(m, wi_v, ox, lambda_nm);
            }
            continue;
        }
        let oy = wo[1] + xy / k;
        let r2 = ox * ox + oy * oy;
        if r2 < 1.0 {
            s += w * m.eval(wi_v, DVec3::new(ox, oy, (1.0 - r2).sqrt()), lambda_nm);
        }
    }
    s
}

/// The part of an rms log error not explained by `noise` (both rms, in quadrature).
pub(crate) fn excess(rms: f64, noise: f64) -> f64 {
    if rms.is_finite() && noise.is_finite() {
        (rms * rms - noise * noise).max(0.0).sqrt()
    } else {
        f64::NAN
    }
}

pub(crate) fn ln10_floor(v: f64, floor: f64) -> f64 {
    v.max(floor).log10()
}

/// Log-space comparison of one model with the explicit reference over the valid points.
#[derive(Clone, Debug, Default)]
pub(crate) struct Score {
    sum2: f64,
    pub(crate) n: usize,
}

impl Score {
    pub(crate) fn add(&mut self, d: f64) {
        self.sum2 += d * d;
        self.n += 1;
    }
    pub(crate) fn merge(&mut self, o: &Score) {
        self.sum2 += o.sum2;
        self.n += o.n;
    }
    pub(crate) fn rms(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            (self.sum2 / self.n as f64).sqrt()
        }
    }
}

pub(crate) fn score_model(set: &AngleSet, values: &[f64]) -> Score {
    let mut s = Score::default();
    for (p, v) in set.points.iter().zip(values) {
        if p.validity == Validity::Valid {
            s.add(ln10_floor(*v, set.floor) - ln10_floor(p.explicit.value, set.floor));
        }
    }
    s
}

/// Model values at every point of every angle set.
pub(crate) fn evaluate(
    c: &Candidate,
    sets: &[AngleSet],
    nodes: &[(f64, f64, f64)],
    profile: bool,
) -> Vec<Vec<f64>> {
    sets.iter()
        .map(|set| {
            let k = 2.0 * std::f64::consts::PI / (set.lambda_nm * 1e-9);
            set.points
                .iter()
                .map(|p| {
                    model_value(
                        c.bxdf.as_ref(),
                        set.wi,
                        p.wo,
                        set.lambda_nm,
                        k,
                        nodes,
                        profile,
                    )
                })
                .collect()
        })
        .collect()
}

/// A judged model: the candidate, its values and its scores.
pub(crate) struct Judged {
    pub(crate) c: Candidate,
    pub(crate) values: Vec<Vec<f64>>,
    pub(crate) per_angle: Vec<Score>,
    pub(crate) overall: Score,
}

pub(crate) fn judge(
    c: Candidate,
    sets: &[AngleSet],
    nodes: &[(f64, f64, f64)],
    profile: bool,
) -> Judged {
    let values = evaluate(&c, sets, nodes, profile);
    let per_angle: Vec<Score> = sets
        .iter()
        .zip(&values)
        .map(|(s, v)| score_model(s, v))
        .collect();
    let mut overall = Score::default();
    for s in &per_angle {
        overall.merge(s);
    }
    Judged {
        c,
        values,
        per_angle,
        overall,
    }
}

pub(crate) fn angle_set(
    e: &ExplicitBrdf,
    surrogate: Option<&ExplicitBrdf>,
    fresnel: &Fresnel,
    theta_i: f64,
    lambda_nm: f64,
    n: usize,
) -> AngleSet {
    let lambda = lambda_nm * 1e-9;
    let t = theta_i.to_radians();
    let wi = [t.sin(), 0.0, t.cos()];
    let window = e.angular_window(wi, lambda);
    let mut dirs: Vec<(SliceKind, f64, [f64; 3])> = in_plane_dirs(theta_i, n, window.resolution)
        .into_iter()
        .map(|(c, w)| (SliceKind::InPlane, c, w))
        .collect();
    if !e.is_profile() {
        dirs.extend(
            cross_plane_dirs(theta_i, n / 2, window.resolution)
                .into_iter()
                .map(|(c, w)| (SliceKind::CrossPlane, c, w)),
        );
    }
    let wos: Vec<[f64; 3]> = dirs.iter().map(|d| d.2).collect();
    let raw = e.scattered_many(wi, &wos, lambda);
    let sur = surrogate.map(|s| s.scattered_many(wi, &wos, lambda));
    let mut points = Vec::with_capacity(dirs.len());
    for (j, (kind, coord, wo)) in dirs.into_iter().enumerate() {
        let spectrum = raw[j].value
            / if e.is_profile() {
                2.0 * std::f64::consts::PI / lambda
            } else {
                (2.0 * std::f64::consts::PI / lambda).powi(2)
            };
        let validity = window.classify(wi, wo, spectrum);
        let r = fresnel.reflectance(cos_d(wi, wo), lambda_nm);
        points.push(Point {
            kind,
            coord,
            wo,
            explicit: Estimate {
                value: raw[j].value * r,
                se: raw[j].se * r,
                n: raw[j].n,
            },
            surrogate: sur.as_ref().map(|s| s[j].value * r),
            validity,
        });
    }
    let c = e.coherent(wi, lambda);
    let rs = fresnel.reflectance(wi[2], lambda_nm);
    let top = points
        .iter()
        .filter(|p| p.validity == Validity::Valid)
        .map(|p| p.explicit.value)
        .fold(0.0, f64::max);
    AngleSet {
        theta_i,
        lambda_nm,
        wi,
        window,
        coherent: Estimate {
            value: c.value * rs,
            se: c.se * rs,
            n: c.n,
        },
        points,
        floor: LOG_FLOOR * if top > 0.0 { top } else { 1.0 },
    }
}
