//! The whole analysis of `lustre fit`: prepare the scan (fill, plane-level), statistics,
//! PSDs, K-correlation fits, NDF fits, two-scale splits and the tabulated PSD.

use crate::kc::{self, KcFit};
use crate::ndf::{self, Ndf};
use crate::psd::{self, Psd1d, RadialPsd, WelchOptions};
use crate::stats::{self, Stats};
use crate::two_scale::{self, TwoScale};
use crate::{FitError, Topography, fill, level};
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
    /// The prepared (filled, plane-levelled) scan.
    pub scan: Topography,
    /// Number of invalid points filled in the scan.
    pub filled: usize,
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
    pub radial: Option<RadialPsd>,
    /// Tabulated isotropic 2D PSD for the measured-PSD model, and how it was made.
    pub table: (RadialPsd, &'static str),
    /// NDF fits.
    pub ndf: NdfFits,
    /// Two-scale splits, one per cutoff.
    pub two_scale: Vec<TwoScale>,
}

/// Fill invalid points and subtract the least-squares plane.
pub fn prepare(mut t: Topography) -> Result<(Topography, usize), FitError> {
    let filled = fill::harmonic(&mut t)?;
    level::plane(&mut t)?;
    Ok((t, filled))
}

/// Run the analysis on a scan and an optional stylus profile.
pub fn analyse(
    scan: Topography,
    stylus: Option<Topography>,
    opts: &Options,
) -> Result<Analysis, FitError> {
    let (scan, filled) = prepare(scan)?;
    let stats = stats::compute(&scan);
    let line_psd = psd::welch(&scan, &opts.welch)?;
    let nseg = line_psd.f.len().saturating_sub(1) * 2;
    let k_hi = (nseg / 4).max(4);
    let f_hi = line_psd.f[k_hi.min(line_psd.f.len() - 1)];
    let f_merge = opts.merge_cutoff / (2.0 * PI);

    let (stylus_psd, fit_psd, f_lo) = match stylus {
        Some(st) => {
            let (st, _) = prepare(st)?;
            let nperseg = (st.nx / opts.stylus_segments.max(1)).max(8).min(st.nx);
            let sp = psd::welch(
                &st,
                &WelchOptions {
                    nperseg: Some(nperseg),
                    noverlap: None,
                },
            )?;
            let f_lo = sp.f.get(3).copied().unwrap_or(0.0);
            let merged = psd::merge(&sp, &line_psd, f_merge);
            (Some(sp), merged, f_lo)
        }
        None => (
            None,
            line_psd.clone(),
            line_psd.f.get(3).copied().unwrap_or(0.0),
        ),
    };
    let kc = kc::fit(
        kc::Form::Profile1d,
        &fit_psd.f,
        &fit_psd.p,
        f_lo * (1.0 - 1e-9),
        f_hi * (1.0 + 1e-9),
    )?;

    let radial = if scan.is_profile() {
        None
    } else {
        Some(psd::radial(&scan)?)
    };
    let kc_2d = match &radial {
        Some(r) if r.zeta.len() > 8 => {
            let zmax = r.zeta[r.zeta.len() - 1];
            kc::fit_weighted(
                kc::Form::Radial2d,
                &r.zeta,
                &r.p,
                Some(&r.count),
                r.zeta[2] * (1.0 - 1e-9),
                zmax / 2.0,
            )
            .ok()
        }
        _ => None,
    };

    let table = match (&radial, &stylus_psd) {
        (Some(r), None) => (r.clone(), "radially averaged 2D PSD of the map"),
        (Some(r), Some(sp)) => {
            let low = psd::radial_from_profile(sp, 4);
            let mut t = RadialPsd {
                zeta: Vec::new(),
                p: Vec::new(),
                count: Vec::new(),
            };
            for (z, p) in low
                .zeta
                .iter()
                .zip(&low.p)
                .filter(|(z, _)| **z < opts.merge_cutoff)
            {
                t.zeta.push(*z);
                t.p.push(*p);
            }
            for (z, p) in r
                .zeta
                .iter()
                .zip(&r.p)
                .filter(|(z, _)| **z >= opts.merge_cutoff)
            {
                t.zeta.push(*z);
                t.p.push(*p);
            }
            (
                t,
                "stylus 1D PSD converted by the local power-law relation below the merge cutoff, radial 2D PSD of the map above",
            )
        }
        (None, _) => (
            psd::radial_from_profile(&fit_psd, 4),
            "1D PSD converted to 2D by the local power-law relation (approximate near roll-offs)",
        ),
    };

    let (sx, sy) = ndf::slopes(&scan);
    let ndf = if scan.is_profile() {
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
    };

    let mut splits = Vec::new();
    for &m in &opts.cutoff_multiples {
        splits.push(two_scale::split(
            &scan,
            &fit_psd,
            m,
            opts.wavelength,
            (f_lo * (1.0 - 1e-9), f_hi * (1.0 + 1e-9)),
        )?);
    }
    Ok(Analysis {
        scan,
        filled,
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
    })
}
