//! The outputs of `lustre judge`: JSON, Markdown table, points CSV and figures.

use std::fmt::Write as _;
use std::path::Path;

use fit::explicit_brdf::{ExplicitBrdf, Validity};
use fit::pipeline::Analysis;
use plot::{Axis, ImageGrid, Legend, LineStyle, Marker, Plot, Rgb, Series};
use serde_json::{Map, Value, json};

use crate::JudgeError;
use crate::compare::{AngleSet, Judged, Point, Score, SliceKind, dvec, excess, ln10_floor};
use crate::reference::ReferenceResult;

/// Everything the outputs are made from.
pub(crate) struct Report<'a> {
    pub(crate) scan: &'a str,
    pub(crate) crop: Option<usize>,
    pub(crate) upsample: usize,
    pub(crate) analysis: &'a Analysis,
    pub(crate) explicit: &'a ExplicitBrdf,
    pub(crate) sets: &'a [AngleSet],
    pub(crate) judged: &'a [Judged],
    pub(crate) skipped: &'a [(String, String)],
    pub(crate) reference: Option<&'a ReferenceResult>,
    pub(crate) fresnel: &'a str,
}

pub(crate) fn num(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

impl Report<'_> {
    pub(crate) fn valid_counts(set: &AngleSet) -> Map<String, Value> {
        let mut m = Map::new();
        for v in [
            Validity::Valid,
            Validity::NearSpecular,
            Validity::BeyondNyquist,
            Validity::Aliased,
            Validity::Shadowed,
            Validity::BelowHorizon,
        ] {
            let n = set.points.iter().filter(|p| p.validity == v).count();
            m.insert(v.name().into(), json!(n));
        }
        m
    }

    /// rms of the explicit estimate's own log10 standard error over the valid points.
    pub(crate) fn noise(&self) -> (f64, Vec<f64>) {
        let (mut all, mut n_all) = (0.0, 0usize);
        let per = self
            .sets
            .iter()
            .map(|s| {
                let (mut a, mut n) = (0.0, 0usize);
                for p in s.points.iter().filter(|p| p.validity == Validity::Valid) {
                    let r = std::f64::consts::LOG10_E * p.explicit.relative_se().min(10.0);
                    a += r * r;
                    n += 1;
                }
                all += a;
                n_all += n;
                if n > 0 {
                    (a / n as f64).sqrt()
                } else {
                    f64::NAN
                }
            })
            .collect();
        let overall = if n_all > 0 {
            (all / n_all as f64).sqrt()
        } else {
            f64::NAN
        };
        (overall, per)
    }

    /// rms log10 distance of the Gaussian surrogate's explicit BRDF from the map's.
    pub(crate) fn surrogate_score(&self) -> Option<(Score, Vec<Score>)> {
        self.sets.first()?.points.first()?.surrogate?;
        let mut all = Score::default();
        let per = self
            .sets
            .iter()
            .map(|s| {
                let mut sc = Score::default();
                for p in s.points.iter().filter(|p| p.validity == Validity::Valid) {
                    if let Some(v) = p.surrogate {
                        sc.add(ln10_floor(v, s.floor) - ln10_floor(p.explicit.value, s.floor));
                    }
                }
                all.merge(&sc);
                sc
            })
            .collect();
        Some((all, per))
    }

    pub(crate) fn find(&self, key: &str) -> Option<&Judged> {
        self.judged.iter().find(|j| j.c.key == key)
    }

    /// (assumption, from, to, Δ of the log10 error in excess of the reference's noise).
    pub(crate) fn costs(&self) -> Vec<(String, String, String, f64)> {
        let mut out = Vec::new();
        let (noise, _) = self.noise();
        if let Some((s, _)) = self.surrogate_score() {
            // Both sides of this comparison carry the tile noise.
            out.push((
                "Gaussian heights (explicit BRDF of a Gaussian surrogate with the map's spectrum)"
                    .to_string(),
                "explicit".to_string(),
                "surrogate".to_string(),
                excess(s.rms(), std::f64::consts::SQRT_2 * noise),
            ));
        }
        use fit::candidates::Family;
        let best = format!("{}_best", Family::TwoScale.name());
        let pairs = [
            (
                "K-correlation shape instead of the measured PSD",
                Family::MeasuredPsd.name(),
                Family::Ghs.name(),
            ),
            (
                "first-order (SSA) lobe instead of all orders",
                Family::Ghs.name(),
                Family::GhsSsa.name(),
            ),
            (
                "two-scale split (best cutoff) instead of one KC spectrum",
                Family::Ghs.name(),
                best.as_str(),
            ),
            (
                "scalar Fresnel R instead of the polarisation factor Q (full GHS)",
                Family::GhsQ.name(),
                Family::Ghs.name(),
            ),
            (
                "first-order Rayleigh–Rice instead of the full GHS with Q",
                Family::GhsQ.name(),
                Family::RayleighRice.name(),
            ),
            (
                "microfacet GGX (NDF fit) instead of full GHS",
                Family::Ghs.name(),
                Family::Ggx.name(),
            ),
        ];
        for (what, a, b) in pairs {
            if let (Some(x), Some(y)) = (self.find(a), self.find(b)) {
                out.push((
                    what.to_string(),
                    a.to_string(),
                    b.to_string(),
                    excess(y.overall.rms(), noise) - excess(x.overall.rms(), noise),
                ));
            }
        }
        out
    }

    pub(crate) fn json(&self) -> Value {
        let e = self.explicit;
        let (noise, noise_per) = self.noise();
        let windows: Vec<Value> = self
            .sets
            .iter()
            .map(|s| {
                let w = &s.window;
                json!({
                    "theta_i_deg": s.theta_i, "lambda_nm": s.lambda_nm,
                    "resolution_dsin": w.resolution,
                    "nyquist_dsin": [w.nyquist.0, w.nyquist.1],
                    "max_dsin": [w.max_offset.0, w.max_offset.1],
                    "alias_floor": num(w.alias_floor),
                    "phase_step_rad": w.phase_step,
                    "smith_g1_incidence": w.g1_incidence,
                    "points": s.points.len(),
                    "by_validity": Value::Object(Self::valid_counts(s)),
                    "coherent_explicit": num(s.coherent.value),
                    "coherent_explicit_se": num(s.coherent.se),
                })
            })
            .collect();
        let models: Vec<Value> = self
            .judged
            .iter()
            .map(|j| {
                let per: Vec<Value> = self
                    .sets
                    .iter()
                    .zip(&j.per_angle)
                    .map(|(s, sc)| {
                        let spec = j.c.bxdf.specular(dvec(s.wi), s.lambda_nm).weight;
                        json!({"theta_i_deg": s.theta_i, "lambda_nm": s.lambda_nm,
                               "log10_rms_error": num(sc.rms()), "points": sc.n,
                               "specular_weight": num(spec),
                               "coherent_explicit": num(s.coherent.value)})
                    })
                    .collect();
                json!({
                    "model": j.c.model, "key": j.c.key, "label": j.c.label,
                    "assumes": j.c.assumes,
                    "log10_rms_error": num(j.overall.rms()),
                    "log10_excess_over_noise": num(excess(j.overall.rms(), noise)),
                    "points": j.overall.n,
                    "params": Value::Object(j.c.params.clone()),
                    "per_angle": per,
                })
            })
            .collect();
        let skipped: Vec<Value> = self
            .skipped
            .iter()
            .map(|(l, r)| json!({"label": l, "reason": r}))
            .collect();
        let costs: Vec<Value> = self
            .costs()
            .into_iter()
            .map(|(a, f, t, d)| json!({"assumption": a, "from": f, "to": t, "delta_log10_rms": num(d)}))
            .collect();
        let surrogate = self.surrogate_score().map(|(s, per)| {
            json!({"log10_rms_distance": num(s.rms()), "points": s.n,
                   "per_angle": per.iter().map(|x| num(x.rms())).collect::<Vec<_>>()})
        });
        let reference = self.reference.map(|r| {
            json!({"file": r.file, "rows": r.rows, "skipped_rows": r.skipped_rows,
                   "models": r.scores.iter().map(|(k, l, s)| json!({
                       "key": k, "label": l, "log10_rms_error": num(s.rms()), "points": s.n
                   })).collect::<Vec<_>>()})
        });
        let (tx, ty) = e.tile_size();
        let (dx, dy) = e.pixel();
        let a = self.analysis;
        json!({
            "scan": self.scan.to_string(),
            "grid": [a.scan.nx, a.scan.ny],
            "fresnel": self.fresnel,
            "window": {
                "crop_px": self.crop,
                "upsample": self.upsample,
                "pixel_um": [dx * 1e6, dy * 1e6],
                "tile_px": [e.tile_pixels().0, e.tile_pixels().1],
                "tile_um": [tx * 1e6, ty * 1e6],
                "tiles": e.tiles(),
                "overlap_variance_factor": e.overlap_factor(),
                "rms_slope": e.rms_slope(),
                "shadowing": "directions with Smith G1(θi)·G1(θo) < 0.9 (Beckmann, α = rms slope) are excluded",
                "per_angle": windows,
                "noise_floor_log10": num(noise),
                "noise_floor_log10_per_angle": noise_per.into_iter().map(num).collect::<Vec<_>>(),
            },
            "models": models,
            "skipped": skipped,
            "gaussian_surrogate": surrogate,
            "assumption_costs_note": "differences of the log10 rms error in excess of the reference's own noise floor (in quadrature); the surrogate row has the noise of both estimates",
            "assumption_costs": costs,
            "reference": reference,
            "fit": {
                "sq_um": a.stats.sq * 1e6, "rms_slope": a.stats.rms_slope(),
                "kc": {"sigma_um": a.kc.params.sigma * 1e6, "lc_um": a.kc.params.lc * 1e6,
                       "gamma": a.kc.params.gamma, "degenerate": a.kc.degenerate},
            },
        })
    }

    pub(crate) fn markdown(&self) -> String {
        let mut s = String::new();
        let e = self.explicit;
        let a = self.analysis;
        let _ = writeln!(
            s,
            "# lustre judge: {}\n\n{} × {} points, pixel {:.4} µm, Sq {:.4} µm, rms slope {:.4}; \
             KC fit σ {:.4} µm, Lc {:.4} µm, γ {:.3}{}; Fresnel: {}.\n\
             Reference: explicit Kirchhoff BRDF of the map{}, {} tiles of {} × {} px (Hann, 50 % overlap).\n",
            self.scan,
            a.scan.nx,
            a.scan.ny,
            a.scan.dx * 1e6,
            a.stats.sq * 1e6,
            a.stats.rms_slope(),
            a.kc.params.sigma * 1e6,
            a.kc.params.lc * 1e6,
            a.kc.params.gamma,
            if a.kc.degenerate { " (degenerate)" } else { "" },
            if self.fresnel == "none" {
                "none (R ≡ 1)"
            } else {
                self.fresnel
            },
            match (self.crop, self.upsample) {
                (None, 1) => String::new(),
                (c, u) => format!(
                    " ({}upsampled ×{u}, pixel {:.4} µm)",
                    c.map(|c| format!("central {c} px, ")).unwrap_or_default(),
                    e.pixel().0 * 1e6
                ),
            },
            e.tiles(),
            e.tile_pixels().0,
            e.tile_pixels().1
        );
        let _ = writeln!(
            s,
            "## Valid window\n\n| θi | λ nm | resolution Δsinθ | max Δsinθ (x, y) | phase step/px rad | G1(θi) | coherent | valid / points |\n|---|---|---|---|---|---|---|---|"
        );
        for set in self.sets {
            let w = &set.window;
            let valid = set
                .points
                .iter()
                .filter(|p| p.validity == Validity::Valid)
                .count();
            let _ = writeln!(
                s,
                "| {} | {} | {:.2e} | {:.3}, {:.3} | {:.2} | {:.3} | {:.3e} ± {:.1e} | {} / {} |",
                set.theta_i,
                set.lambda_nm,
                w.resolution,
                w.max_offset.0,
                w.max_offset.1,
                w.phase_step,
                w.g1_incidence,
                set.coherent.value,
                set.coherent.se,
                valid,
                set.points.len()
            );
        }
        let (noise, noise_per) = self.noise();
        let _ = write!(
            s,
            "\n## Log10 rms error against the explicit BRDF (best first)\n\n| rank | model | overall | excess over noise |"
        );
        for set in self.sets {
            let _ = write!(s, " {}°/{} |", set.theta_i, set.lambda_nm);
        }
        let _ = write!(s, "\n|---|---|---|---|");
        for _ in self.sets {
            s.push_str("---|");
        }
        s.push('\n');
        let cell = |x: f64| {
            if x.is_finite() {
                format!("{x:.3}")
            } else {
                "–".into()
            }
        };
        for (r, j) in self.judged.iter().enumerate() {
            let _ = write!(
                s,
                "| {} | {} | {} | {} |",
                r + 1,
                j.c.label,
                cell(j.overall.rms()),
                cell(excess(j.overall.rms(), noise))
            );
            for sc in &j.per_angle {
                let _ = write!(s, " {} |", cell(sc.rms()));
            }
            s.push('\n');
        }
        if let Some((sc, per)) = self.surrogate_score() {
            let _ = write!(
                s,
                "| – | Gaussian surrogate (explicit) | {} | {} |",
                cell(sc.rms()),
                cell(excess(sc.rms(), std::f64::consts::SQRT_2 * noise))
            );
            for p in per {
                let _ = write!(s, " {} |", cell(p.rms()));
            }
            s.push('\n');
        }
        let _ = write!(
            s,
            "| – | noise floor of the reference | {} | – |",
            cell(noise)
        );
        for p in noise_per {
            let _ = write!(s, " {} |", cell(p));
        }
        s.push('\n');
        let _ = writeln!(
            s,
            "\n## What each assumption costs (change in the log10 error in excess of the noise)\n\n| assumption | from → to | Δ |\n|---|---|---|"
        );
        for (what, f, t, d) in self.costs() {
            let _ = writeln!(s, "| {what} | {f} → {t} | {} |", cell(d));
        }
        if !self.skipped.is_empty() {
            let _ = writeln!(s, "\nNot judged:\n");
            for (l, r) in self.skipped {
                let _ = writeln!(s, "* {l}: {r}");
            }
        }
        if let Some(r) = self.reference {
            let _ = writeln!(
                s,
                "\n## Against the measured BRDF {} ({} rows, {} without a positive value)\n\n| rank | model | log10 rms error | points |\n|---|---|---|---|",
                r.file, r.rows, r.skipped_rows
            );
            for (i, (_, l, sc)) in r.scores.iter().enumerate() {
                let _ = writeln!(s, "| {} | {l} | {} | {} |", i + 1, cell(sc.rms()), sc.n);
            }
        }
        s
    }

    pub(crate) fn csv(&self) -> String {
        let mut s = String::from(
            "theta_i_deg,lambda_nm,slice,coord,ox,oy,oz,validity,explicit,explicit_se,surrogate",
        );
        for j in self.judged {
            let _ = write!(s, ",{}", j.c.key);
        }
        s.push('\n');
        for (k, set) in self.sets.iter().enumerate() {
            for (i, p) in set.points.iter().enumerate() {
                let _ = write!(
                    s,
                    "{},{},{},{},{},{},{},{},{},{},{}",
                    set.theta_i,
                    set.lambda_nm,
                    match p.kind {
                        SliceKind::InPlane => "in_plane",
                        SliceKind::CrossPlane => "cross_plane",
                    },
                    p.coord,
                    p.wo[0],
                    p.wo[1],
                    p.wo[2],
                    p.validity.name(),
                    p.explicit.value,
                    p.explicit.se,
                    p.surrogate.map(|v| v.to_string()).unwrap_or_default()
                );
                for j in self.judged {
                    let _ = write!(s, ",{}", j.values[k][i]);
                }
                s.push('\n');
            }
        }
        s
    }

    pub(crate) fn plots(&self, out: &Path) -> Result<(), JudgeError> {
        let thetas: Vec<f64> = dedup(self.sets.iter().map(|s| s.theta_i));
        let lambdas: Vec<f64> = dedup(self.sets.iter().map(|s| s.lambda_nm));
        let name = Path::new(self.scan).file_name().map_or_else(
            || self.scan.to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let mut grid = ImageGrid::new(thetas.len(), lambdas.len()).title(format!(
            "{name}: in-plane BRDF slices, the scan's explicit BRDF against the best models \
             (rows θi, columns λ)"
        ));
        // Best few models only, so the slices stay readable.
        let shown: Vec<usize> = (0..self.judged.len().min(6)).collect();
        for (k, set) in self.sets.iter().enumerate() {
            let r = thetas.iter().position(|t| *t == set.theta_i).unwrap_or(0);
            let c = lambdas
                .iter()
                .position(|l| *l == set.lambda_nm)
                .unwrap_or(0);
            let img = self.slice_plot(k, set, &shown, k == 0)?;
            grid.set(r, c, img)?;
        }
        grid.save_png(out.join("judge_slices.png"))?;
        self.error_plot(out, &thetas)?;
        Ok(())
    }

    pub(crate) fn slice_plot(
        &self,
        k: usize,
        set: &AngleSet,
        shown: &[usize],
        legend: bool,
    ) -> Result<plot::RgbImage, JudgeError> {
        let pts: Vec<(usize, &Point)> = set
            .points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.kind == SliceKind::InPlane)
            .collect();
        let xs: Vec<f64> = pts.iter().map(|(_, p)| p.coord).collect();
        let valid = |p: &Point| p.validity == Validity::Valid;
        let y_of = |f: &dyn Fn(&Point) -> f64, only_valid: bool| -> Vec<f64> {
            pts.iter()
                .map(|(_, p)| {
                    if valid(p) == only_valid {
                        f(p)
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        };
        let top = pts
            .iter()
            .map(|(_, p)| p.explicit.value)
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        if top <= 0.0 {
            return Err(crate::invalid!(
                "θi {}° λ {} nm: the explicit BRDF is zero on the whole slice",
                set.theta_i,
                set.lambda_nm
            ));
        }
        let bottom = pts
            .iter()
            .filter(|(_, p)| valid(p))
            .map(|(_, p)| p.explicit.value)
            .filter(|v| *v > 0.0)
            .fold(top, f64::min);
        let mut p = Plot::new(format!("θi {}°, {} nm", set.theta_i, set.lambda_nm))
            .x_axis(Axis::linear("θo [deg] (< 0: backscatter)").range(-90.0, 90.0))
            .y_axis(Axis::log("BRDF [sr⁻¹]").range((bottom / 30.0).max(top * 1e-6), top * 5.0))
            .legend(if legend {
                Legend::BottomLeft
            } else {
                Legend::Hidden
            })
            .font_px(11.0);
        // The scan's own values, drawn apart inside and outside the validity window.
        let scan = |label: &str, inside: bool, color: Rgb, marker: Marker| {
            Series::points(label, &xs, &y_of(&|p: &Point| p.explicit.value, inside))
                .color(color)
                .marker(marker)
                .marker_size(3.0)
        };
        p = add(
            p,
            scan("scan (explicit)", true, Rgb(0, 0, 0), Marker::Circle),
        );
        for sign in [-2.0, 2.0] {
            p = add(
                p,
                Series::line(
                    if sign > 0.0 { "±2 se" } else { "" },
                    &xs,
                    &y_of(&|q: &Point| q.explicit.value + sign * q.explicit.se, true),
                )
                .color(Rgb(120, 120, 120))
                .style(LineStyle::Dotted)
                .width(1.0),
            );
        }
        p = add(
            p,
            scan("outside window", false, Rgb(190, 190, 190), Marker::Cross),
        );
        for &m in shown {
            let j = &self.judged[m];
            let ys: Vec<f64> = pts.iter().map(|(i, _)| j.values[k][*i]).collect();
            p = add(
                p,
                Series::line(j.c.label.clone(), &xs, &ys)
                    .color(Rgb::palette(m))
                    .width(1.5),
            );
        }
        let (img, _) = p.render(560, 400)?;
        Ok(img)
    }

    pub(crate) fn error_plot(&self, out: &Path, thetas: &[f64]) -> Result<(), JudgeError> {
        let mut p = Plot::new(format!(
            "{}: log10 rms error against the scan's explicit BRDF",
            Path::new(self.scan)
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default()
        ))
        .x_axis(Axis::linear("θi [deg]"))
        .y_axis(Axis::log("log10 rms error (all λ)"))
        .legend(Legend::Outside)
        .font_px(12.0);
        let per_theta = |per: &dyn Fn(usize) -> Option<f64>| -> Vec<f64> {
            thetas
                .iter()
                .map(|t| {
                    let (mut a, mut n) = (0.0, 0usize);
                    for (i, s) in self.sets.iter().enumerate() {
                        if s.theta_i == *t
                            && let Some(v) = per(i)
                            && v.is_finite()
                        {
                            a += v * v;
                            n += 1;
                        }
                    }
                    if n > 0 {
                        (a / n as f64).sqrt()
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        };
        let (_, noise_per) = self.noise();
        p = add(
            p,
            Series::line(
                "noise floor of the reference",
                thetas,
                &per_theta(&|i| Some(noise_per[i])),
            )
            .color(Rgb(0, 0, 0))
            .style(LineStyle::Dashed),
        );
        if let Some((_, sur)) = self.surrogate_score() {
            p = add(
                p,
                Series::line(
                    "Gaussian surrogate (explicit)",
                    thetas,
                    &per_theta(&|i| Some(sur[i].rms())),
                )
                .color(Rgb(120, 120, 120))
                .style(LineStyle::Dotted)
                .marker(Marker::Diamond),
            );
        }
        for (m, j) in self.judged.iter().enumerate() {
            let ys: Vec<f64> = thetas
                .iter()
                .map(|t| {
                    let mut acc = Score::default();
                    for (s, sc) in self.sets.iter().zip(&j.per_angle) {
                        if s.theta_i == *t {
                            acc.merge(sc);
                        }
                    }
                    acc.rms()
                })
                .collect();
            p = add(
                p,
                Series::line(j.c.label.clone(), thetas, &ys)
                    .color(Rgb::palette(m))
                    .marker(Marker::Circle),
            );
        }
        let (img, _) = p.render(760, 380)?;
        plot::save_png(&img, out.join("judge_errors.png"))?;
        Ok(())
    }
}

/// Adds `s` unless it has no point a log axis can show (the plot crate rejects such series).
pub(crate) fn add(p: Plot, s: Series) -> Plot {
    if s.ys().iter().any(|y| y.is_finite() && *y > 0.0) {
        p.series(s)
    } else {
        p
    }
}

pub(crate) fn dedup(it: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = Vec::new();
    for x in it {
        if !v.contains(&x) {
            v.push(x);
        }
    }
    v
}
