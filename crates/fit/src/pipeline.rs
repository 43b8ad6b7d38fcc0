//! The whole analysis of `lustre fit`: prepare the scan (fill, level), statistics, PSDs,
//! K-correlation fits, NDF fits, anisotropy, two-scale splits and the tabulated PSD.
//!
//! The analysis degrades instead of failing: statistics are always computed; a
//! K-correlation fit that does not converge or ends on a bound is kept as a bounded,
//! degenerate estimate; a map too small for a fit gets parameters estimated from Sq and
//! Sdq (marked as such); optional parts (2D PSD fit, two-scale splits) that cannot be
//! computed are skipped with a note.

use crate::anisotropy::{self, Anisotropy};
use crate::io::Units;
use crate::kc::{self, KcFit};
use crate::level::{self, Form, Level};
use crate::ndf::{self, Ndf};
use crate::psd::{self, Psd1d, RadialPsdTable, WelchOptions};
use crate::quality::{self, InvalidPolicy};
use crate::stats::{self, Stats};
use crate::two_scale;
use crate::{FitError, Topography, fill};
use std::f64::consts::PI;

/// Options of the analysis.
#[derive(Debug, Clone)]
pub struct Options {
    /// Two-scale cutoffs as multiples of `wavelength`.
    pub cutoff_multiples: Vec<f64>,
    /// Wavelength for the cutoffs [m] (default 550 nm).
    pub wavelength: f64,
    /// AFM/stylus merge cutoff [rad/m] (default 1 rad/µm).
    pub merge_cutoff: f64,
    /// Welch segment options of the scan.
    pub welch: WelchOptions,
    /// The stylus profile is split into this many Welch segments (50 % overlap) to tame the
    /// variance of a single-profile periodogram; 1 = whole profile.
    pub stylus_segments: usize,
    /// NDF bins and Gaussian smoothing [rad].
    pub ndf_bins: usize,
    /// NDF smoothing standard deviation in bin widths.
    pub ndf_smooth_bins: f64,
    /// Levelling; `None`: a plane for maps, a line for profiles.
    pub level: Option<Level>,
    /// Invalid points, outliers and units: what to check and do before the analysis.
    pub checks: Checks,
}

/// What is checked in a scan before its numbers are trusted (see [`crate::quality`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Checks {
    /// A scan with more than [`MAX_INVALID_FRACTION`] invalid points: refuse, crop or fill.
    pub invalid: InvalidPolicy,
    /// Treat outliers (see [`quality::outliers`]) as invalid points instead of flagging them.
    pub mask_outliers: bool,
    /// The `--units` the scan was read with, for the fix an implausible Sq or slope names.
    pub units: Option<Units>,
}

/// What the checks found: each `Some` is flagged in `[reliability]` and on stderr.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Quality {
    /// The scan was cropped to its valid part, or filled past the limit.
    pub invalid: Option<String>,
    /// Outliers found (flagged or masked).
    pub outliers: Option<String>,
    /// Outlying points found.
    pub outlier_count: usize,
    /// Sq or the RMS slope is implausible for a metal surface.
    pub units: Option<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            cutoff_multiples: vec![50.0, 100.0, 150.0],
            wavelength: 550e-9,
            merge_cutoff: 1e6,
            welch: WelchOptions::default(),
            stylus_segments: 4,
            ndf_bins: 90,
            ndf_smooth_bins: 1.0,
            level: None,
            checks: Checks::default(),
        }
    }
}

/// NDF results.
#[derive(Debug, Clone)]
pub struct NdfFits {
    /// Tabulated NDF (maps only).
    pub ndf: Option<Ndf>,
    /// GGX α and its rms log residual.
    pub alpha_ggx: (f64, f64),
    /// Beckmann α and its rms log residual.
    pub alpha_beckmann: (f64, f64),
    /// Beckmann α from the slope second moment (`= Sdq`, or `√2·Rdq` for profiles).
    pub alpha_beckmann_moment: f64,
}

/// Everything the material file and plots need.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// The prepared (filled, levelled) scan.
    pub scan: Topography,
    /// Number of invalid points filled in the scan.
    pub filled: usize,
    /// What levelling removed.
    pub form: Form,
    /// Statistics of the scan.
    pub stats: Stats,
    /// Welch PSD of the scan lines.
    pub line_psd: Psd1d,
    /// Welch PSD of the stylus profile, if any.
    pub stylus_psd: Option<Psd1d>,
    /// PSD used for the K-correlation fit (merged when a stylus profile is given).
    pub fit_psd: Psd1d,
    /// 1D K-correlation fit (material parameters).
    pub kc: KcFit,
    /// 2D K-correlation fit to the radial PSD (maps only).
    pub kc_2d: Option<KcFit>,
    /// Radially averaged 2D PSD of the map.
    pub radial: Option<RadialPsdTable>,
    /// Tabulated isotropic 2D PSD for the measured-PSD model, and how it was made.
    pub table: (RadialPsdTable, &'static str),
    /// NDF fits.
    pub ndf: NdfFits,
    /// Two-scale splits, one per cutoff that could be computed.
    pub two_scale: Vec<two_scale::Split>,
    /// Direction dependence (maps only).
    pub anisotropy: Option<Anisotropy>,
    /// Parts skipped or degraded, in words.
    pub notes: Vec<String>,
    /// What the checks of the scan found.
    pub quality: Quality,
}

/// A scan ready for analysis.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Filled and levelled.
    pub scan: Topography,
    /// Invalid points filled.
    pub filled: usize,
    /// What levelling removed.
    pub form: Form,
}

/// Largest fraction of invalid points that is filled. Harmonic filling is smooth, so filled
/// points carry no roughness: Sq falls roughly as `√(1 − fraction)` on a rough surface (a
/// 91 % invalid map gives half the true Sq) and the fit is of the filling, not of the
/// surface. Past one half the invented part would outweigh the measured one, which no
/// warning can repair, so the map is refused.
pub const MAX_INVALID_FRACTION: f64 = 0.5;

/// Invalid fraction above which the result is kept but flagged in the notes: the
/// √(1 − fraction) bias of Sq then exceeds a few per cent.
pub const NOTE_INVALID_FRACTION: f64 = 0.1;

/// Residual rms, relative to the largest height, below which the heights are taken as
/// constant: f64 rounding of a levelled map is ~1e-16 of its values and float32 storage
/// ~1e-8, while any roughness worth fitting is orders of magnitude above either.
pub const CONSTANT_RELATIVE_RMS: f64 = 1e-10;

/// Fill invalid points and level (`None`: a plane for maps, a line for profiles).
///
/// Refuses a single point, a map with more than [`MAX_INVALID_FRACTION`] invalid points,
/// and heights that are constant (to rounding) once the form is removed.
pub fn prepare_with(t: Topography, level: Option<Level>) -> Result<Prepared, FitError> {
    let (prepared, flat) = prepare_unchecked_flat(t, level)?;
    match flat {
        Some(problem) => Err(FitError::data("constant heights", problem)),
        None => Ok(prepared),
    }
}

/// [`prepare_with`], but heights constant to rounding are returned with the reason instead
/// of refused: their statistics (Sq ≈ 0) are true, only fits to them are meaningless.
fn prepare_unchecked_flat(
    t: Topography,
    level: Option<Level>,
) -> Result<(Prepared, Option<String>), FitError> {
    let mut t = t.column_as_profile();
    if t.nx * t.ny < 2 {
        return Err(FitError::data(
            "reading the scan",
            "the scan holds a single point; a roughness fit needs a profile or a map. Fix: \
             export the whole profile or map, not one value",
        ));
    }
    let n = t.heights.len();
    let invalid = t.invalid_count();
    let fraction = invalid as f64 / n as f64;
    if invalid < n && fraction > MAX_INVALID_FRACTION {
        let rect = match quality::largest_valid_rectangle(&t) {
            Some((_, _, w, h)) => format!(
                " ({w} × {h} points, {:.1} % of the scan)",
                100.0 * (w * h) as f64 / n as f64
            ),
            None => String::new(),
        };
        return Err(FitError::data(
            "invalid points",
            format!(
                "{:.1} % of the {n} points ({invalid}) are invalid (NaN/masked); filling more \
                 than {:.0} % would invent most of the surface and bias Sq and the PSD low. \
                 Fix: pass --invalid crop to analyse the largest valid rectangle{rect}, or \
                 --invalid fill to fill anyway (flagged in [reliability].invalid); or crop the \
                 scan to its valid region, or re-measure with fewer dropouts",
                100.0 * fraction,
                100.0 * MAX_INVALID_FRACTION
            ),
        ));
    }
    let filled = fill::harmonic(&mut t)?;
    let scale = t.heights.iter().fold(0.0f64, |m, h| m.max(h.abs()));
    let l = level.unwrap_or_else(|| Level::default_for(&t));
    let form = level::apply(&mut t, l)?;
    let mean = t.heights.iter().sum::<f64>() / n as f64;
    let rms = (t.heights.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
    let flat = if n <= form.terms.len() {
        Some(format!(
            "only {n} points, no more than the {} terms of the {} form removed, so nothing is \
             left to fit. Fix: export the whole profile or map (or pass --level none)",
            form.terms.len(),
            l.name()
        ))
    } else if rms <= CONSTANT_RELATIVE_RMS * scale {
        let removed = match l {
            Level::None => String::new(),
            l => format!(" once the {} form is removed", l.name()),
        };
        Some(format!(
            "the heights are constant (to rounding){removed}: rms {rms:.3e} m for values up \
             to {scale:.3e} m, so there is no roughness to fit. Fix: check that the height \
             channel was exported (--channel; `lustre fit channels FILE` lists them) and that \
             the scan is not a blank or placeholder"
        ))
    } else {
        None
    };
    Ok((
        Prepared {
            scan: t,
            filled,
            form,
        },
        flat,
    ))
}

/// [`prepare_unchecked_flat`] after the [`Checks`]: a scan mostly invalid is cropped or
/// filled when asked (else refused), and outliers are found on the prepared scan and
/// masked (then the scan is prepared again) when asked, flagged otherwise.
fn prepare_checked(
    t: Topography,
    level: Option<Level>,
    checks: &Checks,
) -> Result<(Prepared, Option<String>, Quality), FitError> {
    let mut t = t.column_as_profile();
    let mut q = Quality::default();
    let n = t.heights.len();
    let invalid = t.invalid_count();
    let fraction = invalid as f64 / n.max(1) as f64;
    if invalid < n && fraction > MAX_INVALID_FRACTION {
        match checks.invalid {
            InvalidPolicy::Refuse => {}
            InvalidPolicy::Crop => {
                let (x0, y0, w, h) = quality::largest_valid_rectangle(&t)
                    .filter(|&(_, _, w, h)| w * h >= 2)
                    .ok_or_else(|| {
                        FitError::data(
                            "invalid points",
                            "no two neighbouring points are valid: nothing to crop to",
                        )
                    })?;
                q.invalid = Some(format!(
                    "{:.1} % of the points were invalid: analysed the largest valid rectangle \
                     (--invalid crop), {w} × {h} points from (x, y) = ({x0}, {y0}), {:.1} % of \
                     the scan; statistics of the rest are unknown",
                    100.0 * fraction,
                    100.0 * (w * h) as f64 / n as f64
                ));
                t = quality::crop(&t, (x0, y0, w, h));
            }
            InvalidPolicy::Fill => {
                q.invalid = Some(format!(
                    "{:.1} % of the points were invalid and filled anyway (--invalid fill): \
                     most of the map is smooth interpolation, so Sq, the slopes and the PSD \
                     describe the filling as much as the surface",
                    100.0 * fraction
                ));
                // Past the refusal in prepare_unchecked_flat: fill here.
                fill::harmonic(&mut t)?;
            }
        }
    }
    let original = checks.mask_outliers.then(|| t.clone());
    let (mut prepared, mut flat) = prepare_unchecked_flat(t, level)?;
    if let Some(o) = quality::outliers(&prepared.scan) {
        let sq = stats::compute(&prepared.scan).sq;
        let text = o.describe(&prepared.scan, sq);
        q.outlier_count = o.indices.len();
        match original {
            Some(mut t) if t.nx * t.ny == prepared.scan.heights.len() => {
                for &i in &o.indices {
                    t.heights[i] = f64::NAN;
                }
                (prepared, flat) = prepare_unchecked_flat(t, level)?;
                q.outliers = Some(format!("masked (--outliers mask) and filled: {text}"));
            }
            _ => q.outliers = Some(text),
        }
    }
    Ok((prepared, flat, q))
}

/// Flag an implausible Sq or slope in `q`.
fn check_units(q: &mut Quality, stats: &Stats, t: &Topography, checks: &Checks) {
    q.units = quality::implausible_units(stats.sq, stats.rms_slope(), t.dx, checks.units);
}

/// The note for a scan with more than [`NOTE_INVALID_FRACTION`] of its points filled.
fn filled_note(t: &Topography, filled: usize) -> Option<String> {
    let fraction = filled as f64 / t.heights.len().max(1) as f64;
    (fraction > NOTE_INVALID_FRACTION).then(|| {
        format!(
            "{:.1} % of the points were invalid and filled by smooth interpolation: Sq, the \
             slopes and the PSD may be low by up to {:.0} % (√(1 − fraction)); crop to the \
             valid region for unbiased numbers",
            100.0 * fraction,
            100.0 * (1.0 - (1.0 - fraction).sqrt())
        )
    })
}

/// Fill invalid points and subtract the least-squares plane (a line for profiles).
pub fn prepare(t: Topography) -> Result<(Topography, usize), FitError> {
    let p = prepare_with(t, None)?;
    Ok((p.scan, p.filled))
}

/// The material K-correlation fit of a line PSD on bins 3 ..= n/4 (the data README's
/// convention), degrading to a bounded estimate or to one from Sq and Sdq.
pub fn kc_of(t: &Topography, stats: &Stats, p: &Psd1d) -> KcFit {
    let nseg = p.f.len().saturating_sub(1) * 2;
    let k_hi = (nseg / 4).max(4).min(p.f.len().saturating_sub(1));
    let f_lo = p.f.get(3).copied().unwrap_or(f64::NAN);
    let f_hi = p.f.get(k_hi).copied().unwrap_or(f64::NAN);
    kc::fit(
        kc::PsdForm::Profile1d,
        &p.f,
        &p.p,
        f_lo * (1.0 - 1e-9),
        f_hi * (1.0 + 1e-9),
    )
    .unwrap_or_else(|_| {
        kc::estimate_from_stats(
            stats.sq,
            stats.rms_slope(),
            t.size_x(),
            kc::PsdForm::Profile1d,
        )
    })
}

/// Run the analysis on a scan and an optional stylus profile.
pub fn analyse(
    scan: Topography,
    stylus: Option<Topography>,
    opts: &Options,
) -> Result<Analysis, FitError> {
    let (prepared, flat, mut quality) = prepare_checked(scan, opts.level, &opts.checks)?;
    if let Some(problem) = flat {
        return Err(FitError::data("constant heights", problem));
    }
    let Prepared { scan, filled, form } = prepared;
    let mut notes = Vec::new();
    if let Some(n) = filled_note(&scan, filled) {
        notes.push(n);
    }
    let stats = stats::compute(&scan);
    check_units(&mut quality, &stats, &scan, &opts.checks);
    let line_psd = psd::welch(&scan, &opts.welch)?;
    let nseg = line_psd.f.len().saturating_sub(1) * 2;
    let k_hi = (nseg / 4).max(4);
    let f_hi = line_psd.f[k_hi.min(line_psd.f.len() - 1)];
    let (stylus_psd, fit_psd, f_lo) = fit_psd(&line_psd, stylus, opts)?;
    // The band every K-correlation fit of the line PSD uses, widened by rounding so that
    // its end bins are inside.
    let band = (f_lo * (1.0 - 1e-9), f_hi * (1.0 + 1e-9));
    let kc = kc::fit(
        kc::PsdForm::Profile1d,
        &fit_psd.f,
        &fit_psd.p,
        band.0,
        band.1,
    )
    .unwrap_or_else(|e| {
        notes.push(format!("{e}"));
        kc::estimate_from_stats(
            stats.sq,
            stats.rms_slope(),
            scan.size_x(),
            kc::PsdForm::Profile1d,
        )
    });
    let radial = if scan.is_profile() || scan.nx < 8 || scan.ny < 8 {
        if !scan.is_profile() {
            notes.push("map smaller than 8 × 8: no radial 2D PSD".into());
        }
        None
    } else {
        Some(psd::radial(&scan)?)
    };
    let kc_2d = radial.as_ref().and_then(kc_2d_of);
    let table = psd_table(
        radial.as_ref(),
        stylus_psd.as_ref(),
        &fit_psd,
        opts.merge_cutoff,
    );
    let ndf = ndf_fits(&scan, &stats, opts);
    let mut splits = Vec::new();
    for &m in &opts.cutoff_multiples {
        match two_scale::split(&scan, &fit_psd, m, opts.wavelength, band) {
            Ok(t) => splits.push(t),
            Err(e) => notes.push(format!("two-scale split at {m} λ skipped: {e}")),
        }
    }
    let anisotropy = anisotropy_of(&scan, &line_psd, &mut notes);
    Ok(Analysis {
        scan,
        filled,
        form,
        stats,
        line_psd,
        stylus_psd,
        fit_psd,
        kc,
        kc_2d,
        radial,
        table,
        ndf,
        two_scale: splits,
        anisotropy,
        notes,
        quality,
    })
}

/// The PSD the material is fitted to, with the stylus PSD it was merged from if any, and
/// the low end of the fit band [cycles/m]: the scan's line PSD, or the stylus profile's
/// Welch PSD below the merge cutoff joined to it.
fn fit_psd(
    line_psd: &Psd1d,
    stylus: Option<Topography>,
    opts: &Options,
) -> Result<(Option<Psd1d>, Psd1d, f64), FitError> {
    let Some(st) = stylus else {
        return Ok((
            None,
            line_psd.clone(),
            line_psd.f.get(3).copied().unwrap_or(0.0),
        ));
    };
    let f_merge = opts.merge_cutoff / (2.0 * PI);
    let stylus_err = |e| FitError::Stylus(Box::new(e));
    let st = prepare_with(st, None).map_err(stylus_err)?.scan;
    let nperseg = (st.nx / opts.stylus_segments.max(1)).max(8).min(st.nx);
    let sp = psd::welch(
        &st,
        &WelchOptions {
            nperseg: Some(nperseg),
            noverlap: None,
        },
    )
    .map_err(stylus_err)?;
    let f_lo = sp.f.get(3).copied().unwrap_or(0.0);
    let merged = psd::merge(&sp, line_psd, f_merge);
    Ok((Some(sp), merged, f_lo))
}

/// The 2D K-correlation fit to the radial PSD, on bins 2 up to half the largest frequency;
/// `None` for fewer than nine bins or a fit that fails.
fn kc_2d_of(r: &RadialPsdTable) -> Option<KcFit> {
    if r.zeta.len() <= 8 {
        return None;
    }
    let zmax = r.zeta[r.zeta.len() - 1];
    kc::fit_weighted(
        kc::PsdForm::Radial2d,
        &r.zeta,
        &r.p,
        Some(&r.count),
        r.zeta[2] * (1.0 - 1e-9),
        zmax / 2.0,
    )
    .ok()
}

/// The tabulated isotropic 2D PSD of the measured-PSD model, and how it was made: the
/// map's radial PSD, joined at `merge_cutoff` [rad/m] to the converted stylus PSD below
/// it when there is one; the converted line PSD for a profile.
fn psd_table(
    radial: Option<&RadialPsdTable>,
    stylus_psd: Option<&Psd1d>,
    fit_psd: &Psd1d,
    merge_cutoff: f64,
) -> (RadialPsdTable, &'static str) {
    match (radial, stylus_psd) {
        (Some(r), None) => (r.clone(), "radially averaged 2D PSD of the map"),
        (Some(r), Some(sp)) => {
            let low = psd::radial_from_profile(sp, 4);
            let mut t = RadialPsdTable {
                zeta: Vec::new(),
                p: Vec::new(),
                count: Vec::new(),
            };
            for (z, p) in low
                .zeta
                .iter()
                .zip(&low.p)
                .filter(|(z, _)| **z < merge_cutoff)
            {
                t.zeta.push(*z);
                t.p.push(*p);
            }
            for (z, p) in r.zeta.iter().zip(&r.p).filter(|(z, _)| **z >= merge_cutoff) {
                t.zeta.push(*z);
                t.p.push(*p);
            }
            (
                t,
                "stylus 1D PSD converted by the local power-law relation below the merge cutoff, radial 2D PSD of the map above",
            )
        }
        (None, _) => (
            psd::radial_from_profile(fit_psd, 4),
            "1D PSD converted to 2D by the local power-law relation (approximate near roll-offs)",
        ),
    }
}

/// GGX and Beckmann α fitted to the slope distribution: the 2D NDF of a map, the slope
/// marginal of a profile.
fn ndf_fits(scan: &Topography, stats: &Stats, opts: &Options) -> NdfFits {
    // The slopes are two map-sized arrays, freed on return before the two-scale splits.
    let (sx, sy) = ndf::slopes(scan);
    if scan.is_profile() {
        let smax = 6.0 * stats.rdq_x.max(1e-9);
        NdfFits {
            ndf: None,
            alpha_ggx: ndf::fit_alpha_marginal(&sx, 2 * opts.ndf_bins, smax, ndf::ggx_marginal),
            alpha_beckmann: ndf::fit_alpha_marginal(
                &sx,
                2 * opts.ndf_bins,
                smax,
                ndf::beckmann_marginal,
            ),
            alpha_beckmann_moment: 2f64.sqrt() * stats.rdq_x,
        }
    } else {
        let tmax = ndf::theta_max_for(&sx, &sy);
        let bin = tmax / opts.ndf_bins as f64;
        let h = ndf::histogram(&sx, &sy, opts.ndf_bins, tmax, opts.ndf_smooth_bins * bin);
        NdfFits {
            alpha_ggx: ndf::fit_alpha(&h, ndf::ggx),
            alpha_beckmann: ndf::fit_alpha(&h, ndf::beckmann),
            alpha_beckmann_moment: stats.sdq,
            ndf: Some(h),
        }
    }
}

/// The direction dependence of a map (`None` for a profile, or with a note when it
/// cannot be computed).
fn anisotropy_of(
    scan: &Topography,
    line_psd: &Psd1d,
    notes: &mut Vec<String>,
) -> Option<Anisotropy> {
    if scan.is_profile() {
        return None;
    }
    anisotropy::analyse(scan, line_psd.clone())
        .map_err(|e| notes.push(e.to_string()))
        .ok()
}

/// What `lustre fit stats` reports: statistics, the line PSD, the material
/// K-correlation fit and the anisotropy, without the NDF, 2D and two-scale work.
#[derive(Debug, Clone)]
pub struct Summary {
    /// The prepared scan and its levelling.
    pub prepared: Prepared,
    /// Statistics of the prepared scan.
    pub stats: Stats,
    /// Welch PSD of the x-lines (full-length segments).
    pub line_psd: Psd1d,
    /// K-correlation fit on bins 3 ..= n/4 (degrades, never fails).
    pub kc: KcFit,
    /// Direction dependence (maps of at least 2 × 2).
    pub anisotropy: Option<Anisotropy>,
    /// Parts skipped, in words.
    pub notes: Vec<String>,
    /// Why the heights are constant to rounding, when they are: the statistics stand
    /// (Sq ≈ 0, as reference tools report it) but the K-correlation fit is of rounding
    /// noise, so [`analyse`] refuses such a scan.
    pub flat: Option<String>,
    /// What the checks of the scan found.
    pub quality: Quality,
}

/// The `fit stats` analysis of one scan.
pub fn summarise(scan: Topography, level: Option<Level>) -> Result<Summary, FitError> {
    summarise_checked(scan, level, &Checks::default())
}

/// [`summarise`] with the [`Checks`] the user chose.
pub fn summarise_checked(
    scan: Topography,
    level: Option<Level>,
    checks: &Checks,
) -> Result<Summary, FitError> {
    let (prepared, flat, mut quality) = prepare_checked(scan, level, checks)?;
    let t = &prepared.scan;
    let stats = stats::compute(t);
    check_units(&mut quality, &stats, t, checks);
    let line_psd = psd::welch(t, &WelchOptions::default())?;
    let kc = kc_of(t, &stats, &line_psd);
    let mut notes = Vec::new();
    if let Some(n) = filled_note(t, prepared.filled) {
        notes.push(n);
    }
    if kc.reason == Some(kc::Degeneracy::TooFewPoints) {
        notes.push(format!(
            "the line PSD has only {} bins: K-correlation parameters estimated from Sq and Sdq",
            line_psd.f.len()
        ));
    }
    let anisotropy = anisotropy_of(t, &line_psd, &mut notes);
    Ok(Summary {
        prepared,
        stats,
        line_psd,
        kc,
        anisotropy,
        notes,
        flat,
        quality,
    })
}
