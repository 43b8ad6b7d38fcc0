//! Building an RGL file from a model.

use brdf::{Bxdf, DVec3};
use core::f64::consts::PI;

use super::{Colour, RglOptions, RglTable};
use crate::check::{self, CheckPoint, Rng, Sides};
use crate::color::{luminance_weights, srgb_weights};
use crate::marginal::Marginal2D;
use crate::ndf::{NdfSource, ndf_grid, projected_area};
use crate::param::{direction, node, u_to_phi, u_to_theta};
use crate::tensor::{self, Field};
use crate::{ExportError, Exported, Report, par_map};

fn opt(field: &'static str, message: String) -> ExportError {
    ExportError::Option { field, message }
}

fn check_nodes(field: &'static str, n: usize, lo: usize, hi: usize) -> Result<(), ExportError> {
    if (lo..=hi).contains(&n) {
        Ok(())
    } else {
        Err(opt(field, format!("{n} nodes: must lie in {lo}..={hi}")))
    }
}

/// Refuses options no reader (or no model) can take.
fn validate(o: &RglOptions) -> Result<(), ExportError> {
    let t = &o.theta_i_deg;
    if t.is_empty() || t.len() > 1024 {
        return Err(opt(
            "theta_i_deg",
            format!("{} angles: give 1 to 1024", t.len()),
        ));
    }
    if t.iter().any(|v| !(0.0..=90.0).contains(v)) || t.windows(2).any(|w| w[1] <= w[0]) {
        return Err(opt(
            "theta_i_deg",
            "angles must be strictly increasing degrees in [0, 90]".into(),
        ));
    }
    check_nodes("phi_i_nodes", o.phi_i_nodes, 3, 256)?;
    check_nodes("sample_nodes", o.sample_nodes, 2, 1024)?;
    for (f, v) in [
        ("vndf_nodes", o.vndf_nodes),
        ("ndf_nodes", o.ndf_nodes),
        ("sigma_nodes", o.sigma_nodes),
    ] {
        check_nodes(f, v[0], 2, 2048)?;
        check_nodes(f, v[1], 2, 2048)?;
    }
    check_nodes(
        "check_samples",
        o.check_samples,
        0,
        crate::MAX_CHECK_SAMPLES,
    )?;
    let l = &o.wavelengths_nm;
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    if l.is_empty() || l.len() > 1024 {
        return Err(opt(
            "wavelengths_nm",
            format!("{} wavelengths: give 1 to 1024", l.len()),
        ));
    }
    if l.iter().any(|v| !(lo..=hi).contains(v)) || l.windows(2).any(|w| w[1] <= w[0]) {
        return Err(opt(
            "wavelengths_nm",
            format!("wavelengths must be strictly increasing within the models' {lo}–{hi} nm"),
        ));
    }
    if !(0.0..90.0).contains(&o.check_theta_max_deg) {
        return Err(opt(
            "check_theta_max_deg",
            "must lie in [0, 90) degrees".into(),
        ));
    }
    Ok(())
}

/// Refuses a table whose spectra would pass 2^28 f32 values (1 GiB), or
/// whose warps 2^25 (each of their nodes costs an evaluation of the model
/// at a dozen wavelengths).
fn check_size(o: &RglOptions, phi_slices: usize) -> Result<(), ExportError> {
    let slices = o.theta_i_deg.len() * phi_slices;
    let per = o.sample_nodes * o.sample_nodes * o.wavelengths_nm.len().max(3);
    if slices.saturating_mul(per) > 1 << 28 {
        return Err(opt(
            "sample_nodes",
            format!(
                "{slices} slices × {per} values exceed 2^28 (1 GiB of f32): lower the \
                 resolution (sample nodes, wavelengths, incidence or azimuth slices)"
            ),
        ));
    }
    let warp = o.vndf_nodes[0] * o.vndf_nodes[1];
    if slices.saturating_mul(warp) > 1 << 25 {
        return Err(opt(
            "vndf_nodes",
            format!("{slices} slices × {warp} warp nodes exceed 2^25: lower the VNDF grid"),
        ));
    }
    Ok(())
}

/// Largest coherent (delta) reflectance over the table's incidences up to
/// the checked angle, and where: an error unless the options drop it.
fn delta_lobe(model: &dyn Bxdf, o: &RglOptions) -> Result<f64, ExportError> {
    let mut worst = (0.0, 0.0, 0.0);
    for &t in o
        .theta_i_deg
        .iter()
        .filter(|&&t| t <= o.check_theta_max_deg)
    {
        let wi = direction(t.to_radians(), 0.0);
        for &l in &o.wavelengths_nm {
            let w = model.specular(wi, l).weight;
            if w > worst.0 {
                worst = (w, t, l);
            }
        }
    }
    if worst.0 > crate::DELTA_TOLERANCE && !o.drop_specular {
        return Err(ExportError::Specular {
            weight: worst.0,
            theta_i_deg: worst.1,
            lambda_nm: worst.2,
        });
    }
    Ok(worst.0)
}

/// Everything of a build the slices need.
struct Frame<'a> {
    model: &'a (dyn Bxdf + Sync),
    o: &'a RglOptions,
    iso: bool,
    theta_i: Vec<f32>,
    phi_i: Vec<f32>,
    ndf: Marginal2D,
    sigma: Marginal2D,
}

impl Frame<'_> {
    fn slices(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.phi_i.len()).flat_map(move |a| (0..self.theta_i.len()).map(move |j| (a, j)))
    }

    fn wi(&self, a: usize, j: usize) -> DVec3 {
        direction(self.theta_i[j] as f64, self.phi_i[a] as f64)
    }

    /// The half vector at u = (u_θ, u_φ) of slice azimuth `phi_i`.
    fn half_vector(&self, u: [f64; 2], phi_i: f64) -> DVec3 {
        let rel = if self.iso { phi_i } else { 0.0 };
        direction(u_to_theta(u[0]), u_to_phi(u[1]) + rel)
    }

    /// The warp of each slice on the (u_φ, u_θ) grid of half vectors. The
    /// readers use the `vndf` field only as a warp (S is looked up where it
    /// sends the half vector), so it need not be the RGL acquisition's
    /// density of visible normals D_ωi(m): it is that density mixed half
    /// and half with the model's own reflected lobe at the slice's incidence
    /// raised to the power [`LOBE_TEMPER`], which spreads S's nodes into the
    /// lobe's tails and over a lobe wider than D predicts (the wave-optical
    /// models at oblique incidence). See the README for the errors of each
    /// choice.
    fn vndf_data(&self, w: &Weights) -> Vec<f32> {
        let [nt, np] = self.o.vndf_nodes;
        let slices: Vec<(usize, usize)> = self.slices().collect();
        let per = par_map(slices.len(), |i| {
            let (a, j) = slices[i];
            let wi = self.wi(a, j);
            let mut vis = Vec::with_capacity(nt * np);
            let mut own = Vec::with_capacity(nt * np);
            let (lam, wl) = w.warp_lambdas(&self.o.wavelengths_nm);
            let mut fp = vec![(0.0, 0.0); lam.len()];
            for r in 0..np {
                for k in 0..nt {
                    let u = [node(k, nt), node(r, np)];
                    let m = self.half_vector(u, self.phi_i[a] as f64);
                    let d = self.ndf.eval(u, &[]);
                    let cos_d = wi.dot(m).max(0.0);
                    // |∂ωm/∂u| = 2π² u sinθm; constants dropped.
                    let jac = u[0] * (m.x * m.x + m.y * m.y).sqrt();
                    let wo = 2.0 * cos_d * m - wi;
                    vis.push(d * cos_d * jac);
                    let mut v = 0.0;
                    if wo.z > 0.0 && cos_d > 0.0 {
                        self.model.eval_pdf_many(wi, wo, &lam, &mut fp);
                        let f: f64 = wl.iter().zip(&fp).map(|(a, b)| a * b.0).sum();
                        // f cosθo |∂ωo/∂ωm| |∂ωm/∂u|, |∂ωo/∂ωm| = 4 (ωi·m).
                        v = f.max(0.0) * wo.z * 4.0 * cos_d * jac;
                    }
                    own.push(if v.is_finite() { v } else { 0.0 });
                }
            }
            mix(&vis, &own)
        });
        per.into_iter().flatten().collect()
    }

    /// S (per wavelength or RGB channel) and its luminance along row `iy`
    /// of slice (a, j)'s sample grid.
    fn spectra_row(&self, vndf: &Marginal2D, a: usize, j: usize, iy: usize, w: &Weights) -> Row {
        let n = self.o.sample_nodes;
        let lambdas = &self.o.wavelengths_nm;
        let channels = w.channels();
        let (phi, theta) = (self.phi_i[a] as f64, self.theta_i[j] as f64);
        let wi = self.wi(a, j);
        let u_wi = [crate::param::theta_to_u(theta), crate::param::phi_to_u(phi)];
        let sigma = self.sigma.eval(u_wi, &[]);
        let mut s = vec![0.0f32; channels * n];
        let mut lum = vec![0.0f64; n];
        let mut fp = vec![(0.0, 0.0); lambdas.len()];
        let mut lost = 0usize;
        for ix in 0..n {
            let (u_m, _) = vndf.sample([node(ix, n), node(iy, n)], &[phi, theta]);
            let m = self.half_vector(u_m, phi);
            let cos_d = wi.dot(m);
            let wo = 2.0 * cos_d * m - wi;
            if wo.z <= 0.0 || cos_d <= 0.0 {
                continue;
            }
            let d = self.ndf.eval(u_m, &[]);
            self.model.eval_pdf_many(wi, wo, lambdas, &mut fp);
            if d.is_nan() || d <= 0.0 {
                lost += fp.iter().any(|p| p.0 > 0.0) as usize;
                continue;
            }
            let k = wo.z * 4.0 * sigma / d;
            let spec: Vec<f64> = fp.iter().map(|p| p.0 * k).collect();
            if spec.iter().any(|v| !v.is_finite() || *v > f32::MAX as f64) {
                lost += 1;
                continue;
            }
            lum[ix] = w.lum.iter().zip(&spec).map(|(a, b)| a * b).sum();
            for c in 0..channels {
                s[c * n + ix] = match &w.rgb {
                    None => spec[c],
                    Some(rgb) => rgb.iter().zip(&spec).map(|(wk, v)| wk[c] * v).sum(),
                } as f32;
            }
        }
        Row { s, lum, lost }
    }
}

/// Colour weights of the export's wavelengths.
struct Weights {
    lum: Vec<f64>,
    rgb: Option<Vec<[f64; 3]>>,
    n_lambda: usize,
}

impl Weights {
    fn channels(&self) -> usize {
        if self.rgb.is_some() { 3 } else { self.n_lambda }
    }

    /// At most 12 of the export's wavelengths, evenly picked, with their
    /// luminance weights summed onto them: enough to place a warp's nodes.
    fn warp_lambdas(&self, lambdas: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let step = lambdas.len().div_ceil(12);
        let mut l = Vec::new();
        let mut wt: Vec<f64> = Vec::new();
        for (k, (&lk, &wk)) in lambdas.iter().zip(&self.lum).enumerate() {
            if k % step == 0 {
                l.push(lk);
                wt.push(0.0);
            }
            if let Some(last) = wt.last_mut() {
                *last += wk;
            }
        }
        (l, wt)
    }
}

/// Exponent of the lobe's density in the warp. With 1 (the lobe itself)
/// a tail holding 1 % of the light gets 1 % of the nodes and S, which grows
/// there as f/D, is interpolated across one cell; 1/3 gave the smallest
/// read-back errors of 1, 0.7, 0.5, 1/3 and 1/4 on GGX α 0.05 and 0.2,
/// Beckmann, GHS-SSA and two-scale (README).
const LOBE_TEMPER: f64 = 1.0 / 3.0;

/// Half of `a`'s normalised mass and half of `b`^[`LOBE_TEMPER`]'s (just
/// `a` if `b` has no mass), as f32.
fn mix(a: &[f64], b: &[f64]) -> Vec<f32> {
    let sa: f64 = a.iter().sum();
    let bp: Vec<f64> = b.iter().map(|v| v.powf(LOBE_TEMPER)).collect();
    let sb: f64 = bp.iter().sum();
    if !(sb > 0.0 && sb.is_finite() && sa > 0.0 && sa.is_finite()) {
        return a.iter().map(|&v| v as f32).collect();
    }
    a.iter()
        .zip(&bp)
        .map(|(&x, &y)| (0.5 * x / sa + 0.5 * y / sb) as f32)
        .collect()
}

struct Row {
    /// Channel-major: `s[c·n + ix]`.
    s: Vec<f32>,
    lum: Vec<f64>,
    lost: usize,
}

fn f32s(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// The RGL file of `model`, parameterised by `source`'s distribution, with
/// its error estimate.
pub fn build(
    model: &(dyn Bxdf + Sync),
    source: &NdfSource,
    o: &RglOptions,
) -> Result<Exported, ExportError> {
    validate(o)?;
    let dropped = delta_lobe(model, o)?;
    let iso = match source {
        NdfSource::Microfacet(d, _) => d.alpha_x() == d.alpha_y(),
        NdfSource::Backscatter => true,
    };
    check_size(o, if iso { 1 } else { o.phi_i_nodes })?;
    if matches!(source, NdfSource::Backscatter) && !crate::is_isotropic(model) {
        return Err(ExportError::Model(
            "the model is anisotropic, and the distribution derived from its retro-reflection \
             is isotropic: only GGX and Beckmann, through their own distribution, export \
             anisotropic tables"
                .into(),
        ));
    }
    let lambdas = &o.wavelengths_nm;
    let w = Weights {
        lum: luminance_weights(lambdas, o.illuminant),
        rgb: (o.colour == Colour::Rgb).then(|| srgb_weights(lambdas, o.illuminant)),
        n_lambda: lambdas.len(),
    };
    let rows_of = |n: [usize; 2]| if iso { 2 } else { n[1] };
    let [nt_ndf, np_ndf] = [o.ndf_nodes[0], rows_of(o.ndf_nodes)];
    let ndf = ndf_grid(source, model, nt_ndf, np_ndf, lambdas, &w.lum)?;
    let ndf32 = f32s(&ndf.values);
    let iso_d: Vec<f64> = ndf32[..nt_ndf].iter().map(|&v| v as f64).collect();
    let ndf_i = Marginal2D::new(&ndf32, nt_ndf, np_ndf, vec![], false, false)
        .ok_or_else(|| ExportError::Model("the NDF table is empty".into()))?;
    let [st, sp] = [o.sigma_nodes[0], rows_of(o.sigma_nodes)];
    let mut sigma = Vec::with_capacity(st * sp);
    for r in 0..sp {
        for k in 0..st {
            let wdir = direction(u_to_theta(node(k, st)), u_to_phi(node(r, sp)));
            sigma.push(projected_area(source, &iso_d, wdir));
        }
    }
    let sigma32 = f32s(&sigma);
    let phi_i: Vec<f32> = if iso {
        vec![0.0]
    } else {
        (0..o.phi_i_nodes)
            .map(|k| (-PI + 2.0 * PI * node(k, o.phi_i_nodes)) as f32)
            .collect()
    };
    let frame = Frame {
        model,
        o,
        iso,
        theta_i: o
            .theta_i_deg
            .iter()
            .map(|t| t.to_radians() as f32)
            .collect(),
        phi_i,
        ndf: ndf_i,
        sigma: Marginal2D::new(&sigma32, st, sp, vec![], false, false)
            .ok_or_else(|| ExportError::Model("the σ table is empty".into()))?,
    };
    let angles = vec![
        frame.phi_i.iter().map(|&v| v as f64).collect(),
        frame.theta_i.iter().map(|&v| v as f64).collect(),
    ];
    let vndf32 = frame.vndf_data(&w);
    let [vt, vp] = o.vndf_nodes;
    let vndf = Marginal2D::new(&vndf32, vt, vp, angles, true, true).ok_or_else(|| {
        ExportError::Model(
            "a slice of visible normals is empty: the NDF vanishes everywhere its microfacets \
             face the incident direction"
                .into(),
        )
    })?;
    let (spectra, lum, lost) = spectra_and_luminance(&frame, &vndf, &w);
    let mut fields = vec![
        Field::u8("description", o.description.as_bytes()),
        Field::u8("jacobian", &[1]),
        Field::f32("theta_i", &[frame.theta_i.len()], &frame.theta_i),
        Field::f32("phi_i", &[frame.phi_i.len()], &frame.phi_i),
        Field::f32("ndf", &[np_ndf, nt_ndf], &ndf32),
        Field::f32("sigma", &[sp, st], &sigma32),
        Field::f32(
            "vndf",
            &[frame.phi_i.len(), frame.theta_i.len(), vp, vt],
            &vndf32,
        ),
    ];
    let (na, nj, n) = (frame.phi_i.len(), frame.theta_i.len(), o.sample_nodes);
    fields.push(Field::f32("luminance", &[na, nj, n, n], &lum));
    let channels = w.channels();
    if o.colour == Colour::Spectral {
        fields.push(Field::f32("wavelengths", &[lambdas.len()], &f32s(lambdas)));
        fields.push(Field::f32("spectra", &[na, nj, channels, n, n], &spectra));
    } else {
        fields.push(Field::f32("rgb", &[na, nj, 3, n, n], &spectra));
    }
    let bytes = tensor::write(&fields);
    let table = RglTable::parse(&bytes)?;
    let checks = check_table(model, &table, o, &w, &frame.phi_i);
    let report = Report {
        format: match o.colour {
            Colour::Spectral => "RGL measured BSDF (spectral)",
            Colour::Rgb => "RGL measured BSDF (linear sRGB)",
        },
        resolution: format!(
            "{na} φi × {nj} θi slices ({:.1}–{:.1}°), {} {} × {n}² sample grid, VNDF {vt}×{vp}, \
             NDF {nt_ndf}×{np_ndf}, σ {st}×{sp}",
            o.theta_i_deg[0],
            o.theta_i_deg[nj - 1],
            channels,
            if o.colour == Colour::Spectral {
                "wavelengths"
            } else {
                "channels"
            },
        ),
        ndf: match source {
            NdfSource::Microfacet(..) => "the model's own microfacet distribution",
            NdfSource::Backscatter => "derived from the model's retro-reflection (power iteration)",
        },
        bytes: bytes.len(),
        dropped_specular: dropped,
        unrepresented_nodes: lost,
        check_theta_max_deg: o.check_theta_max_deg,
        checks,
    };
    Ok(Exported { bytes, report })
}

/// The `spectra` (or `rgb`) and `luminance` fields, the slices' rows
/// computed in parallel; and the count of nodes whose S could not be stored.
fn spectra_and_luminance(
    frame: &Frame,
    vndf: &Marginal2D,
    w: &Weights,
) -> (Vec<f32>, Vec<f32>, usize) {
    let n = frame.o.sample_nodes;
    let channels = w.channels();
    let slices: Vec<(usize, usize)> = frame.slices().collect();
    let rows = par_map(slices.len() * n, |i| {
        let (a, j) = slices[i / n];
        frame.spectra_row(vndf, a, j, i % n, w)
    });
    let mut spectra = vec![0.0f32; slices.len() * channels * n * n];
    let mut lum = vec![0.0f32; slices.len() * n * n];
    let mut lost = 0;
    for (si, chunk) in rows.chunks(n).enumerate() {
        let peak = chunk
            .iter()
            .flat_map(|r| r.lum.iter())
            .copied()
            .fold(0.0, f64::max);
        // A floor keeps every node reachable by the luminance warp.
        let floor = if peak > 0.0 { 1e-3 * peak } else { 1.0 };
        for (iy, row) in chunk.iter().enumerate() {
            lost += row.lost;
            for ix in 0..n {
                lum[(si * n + iy) * n + ix] = row.lum[ix].max(floor) as f32;
                for c in 0..channels {
                    spectra[((si * channels + c) * n + iy) * n + ix] = row.s[c * n + ix];
                }
            }
        }
    }
    (spectra, lum, lost)
}

/// Where the spectral error is estimated: near these wavelengths, ...
const CHECK_LAMBDAS_NM: [f64; 4] = [450.0, 550.0, 650.0, 750.0];

/// ... at the midpoint of the table's wavelength interval holding each (at
/// a node the wavelength interpolation would be exact), or at the table's
/// only wavelength.
fn check_wavelengths(nodes: &[f64]) -> Vec<f64> {
    if nodes.len() == 1 {
        return nodes.to_vec();
    }
    let mut out: Vec<f64> = CHECK_LAMBDAS_NM
        .iter()
        .map(|&l| {
            let j = nodes.partition_point(|&x| x <= l).clamp(1, nodes.len() - 1);
            0.5 * (nodes[j - 1] + nodes[j])
        })
        .collect();
    out.dedup();
    out
}

/// The error estimate at the table's incidences and midpoints up to the
/// checked angle, per azimuth node of an anisotropic table.
fn check_table(
    model: &(dyn Bxdf + Sync),
    table: &RglTable,
    o: &RglOptions,
    w: &Weights,
    phi_i: &[f32],
) -> Vec<CheckPoint> {
    if o.check_samples == 0 {
        return Vec::new();
    }
    let angles = check::check_angles(&o.theta_i_deg, o.check_theta_max_deg);
    let phis: Vec<f64> = if phi_i.len() == 1 {
        vec![0.0]
    } else {
        // Node and midpoint azimuths of the first half-turn.
        (0..phi_i.len() / 2)
            .flat_map(|k| [phi_i[k] as f64, 0.5 * (phi_i[k] + phi_i[k + 1]) as f64])
            .collect()
    };
    let lambdas: Vec<f64> = if o.colour == Colour::Rgb {
        vec![0.0, 1.0, 2.0]
    } else {
        check_wavelengths(&o.wavelengths_nm)
    };
    let jobs: Vec<(f64, f64)> = phis
        .iter()
        .flat_map(|&p| angles.iter().map(move |&t| (t, p)))
        .collect();
    let per = par_map(jobs.len(), |i| {
        let (t, p) = jobs[i];
        let wi = direction(t.to_radians(), p);
        let mut rng = Rng::new(0x5eed ^ i as u64);
        check_one(model, table, o, w, wi, &lambdas, &mut rng)
            .into_iter()
            .map(|(l, r)| CheckPoint {
                theta_i_deg: t,
                phi_i_deg: p.to_degrees(),
                lambda: l,
                albedo_model: r[0],
                albedo_table: r[1],
                rel_l1: r[2],
                rel_l1_se: r[3],
            })
            .collect::<Vec<_>>()
    });
    per.into_iter().flatten().collect()
}

fn check_one(
    model: &(dyn Bxdf + Sync),
    table: &RglTable,
    o: &RglOptions,
    w: &Weights,
    wi: DVec3,
    lambdas: &[f64],
    rng: &mut Rng,
) -> Vec<(f64, [f64; 4])> {
    let table_sample = |u: [f64; 2]| table.sample(wi, u).map(|s| s.wo);
    let table_pdf = |wo: DVec3| table.pdf(wi, wo);
    if w.rgb.is_some() {
        let fine = crate::color::FineRgb::new(o.illuminant);
        let truth = |wo: DVec3, out: &mut [f64]| {
            out.copy_from_slice(&fine.rgb(|l| model.eval(wi, wo, l)));
        };
        let approx = |wo: DVec3, out: &mut [f64]| {
            for (c, v) in out.iter_mut().enumerate() {
                *v = table.eval(wi, wo, c as f64);
            }
        };
        let sides = Sides {
            model,
            sample_lambda_nm: 550.0,
            table_sample: &table_sample,
            table_pdf: &table_pdf,
            truth: &truth,
            approx: &approx,
        };
        let r = check::estimate(wi, &sides, 3, o.check_samples, rng);
        return r
            .into_iter()
            .enumerate()
            .map(|(c, v)| (c as f64, v))
            .collect();
    }
    lambdas
        .iter()
        .map(|&l| {
            let truth = |wo: DVec3, out: &mut [f64]| out[0] = model.eval(wi, wo, l);
            let approx = |wo: DVec3, out: &mut [f64]| out[0] = table.eval(wi, wo, l);
            let sides = Sides {
                model,
                sample_lambda_nm: l,
                table_sample: &table_sample,
                table_pdf: &table_pdf,
                truth: &truth,
                approx: &approx,
            };
            (l, check::estimate(wi, &sides, 1, o.check_samples, rng)[0])
        })
        .collect()
}
