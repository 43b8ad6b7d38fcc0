//! What can make a readable scan's numbers wrong, found before they are trusted: most of the
//! map invalid (refused, or cropped to its largest valid rectangle, or filled and flagged),
//! spikes far outside the height distribution (corrupted bytes, instrument glitches), and
//! heights or lengths in the wrong unit (an Sq below one atom, a slope no metal has).

use crate::Topography;
use crate::io::{Units, units};

/// What to do with a scan whose invalid points exceed
/// [`crate::pipeline::MAX_INVALID_FRACTION`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InvalidPolicy {
    /// Refuse the scan (filling would invent most of the surface).
    #[default]
    Refuse,
    /// Analyse the largest rectangle (a profile: the longest run) of valid points.
    Crop,
    /// Fill anyway, and flag it in `[reliability].invalid`.
    Fill,
}

impl InvalidPolicy {
    /// `refuse`, `crop` or `fill`.
    pub fn from_name(s: &str) -> Option<InvalidPolicy> {
        match s.trim().to_ascii_lowercase().as_str() {
            "refuse" => Some(InvalidPolicy::Refuse),
            "crop" => Some(InvalidPolicy::Crop),
            "fill" => Some(InvalidPolicy::Fill),
            _ => None,
        }
    }
}

/// The largest axis-aligned rectangle of valid (finite) points, `(x0, y0, width, height)`
/// by area, or `None` when no point is valid. Row by row, the run of valid points above
/// each column is a histogram whose largest rectangle a stack finds in one pass.
pub fn largest_valid_rectangle(t: &Topography) -> Option<(usize, usize, usize, usize)> {
    let (nx, ny) = (t.nx, t.ny);
    let mut run = vec![0usize; nx];
    let mut best: Option<(usize, (usize, usize, usize, usize))> = None;
    let mut stack: Vec<(usize, usize)> = Vec::with_capacity(nx + 1);
    for y in 0..ny {
        for (r, h) in run.iter_mut().zip(&t.heights[y * nx..(y + 1) * nx]) {
            *r = if h.is_finite() { *r + 1 } else { 0 };
        }
        stack.clear();
        for x in 0..=nx {
            let h = run.get(x).copied().unwrap_or(0);
            let mut start = x;
            while let Some(&(s, sh)) = stack.last() {
                if sh < h {
                    break;
                }
                stack.pop();
                let area = sh * (x - s);
                if sh > 0 && best.is_none_or(|(b, _)| area > b) {
                    best = Some((area, (s, y + 1 - sh, x - s, sh)));
                }
                start = s;
            }
            stack.push((start, h));
        }
    }
    best.map(|(_, r)| r)
}

/// The part `(x0, y0, width, height)` of a map.
pub fn crop(t: &Topography, (x0, y0, w, h): (usize, usize, usize, usize)) -> Topography {
    let mut heights = Vec::with_capacity(w * h);
    for y in y0..y0 + h {
        heights.extend_from_slice(&t.heights[y * t.nx + x0..y * t.nx + x0 + w]);
    }
    Topography {
        nx: w,
        ny: h,
        heights,
        ..t.clone()
    }
}

/// Points this many robust standard deviations (1.4826 · median absolute deviation) from
/// the median height are outliers. Gaussian heights reach 12 σ with probability ~10⁻³³, and
/// the most skewed real scans here (deep pits, Ssk −15) keep almost all their points inside
/// it, while a corrupted float or a stuck sensor lands thousands of σ away.
pub const OUTLIER_MADS: f64 = 12.0;

/// Heights far outside the distribution of a (levelled) scan.
#[derive(Debug, Clone, PartialEq)]
pub struct Outliers {
    /// Indices (`y·nx + x`) of the outlying points.
    pub indices: Vec<usize>,
    /// The robust standard deviation, 1.4826 · MAD [m].
    pub robust_sigma: f64,
    /// The median height [m].
    pub median: f64,
    /// Share of the height variance (Sq²) the outliers carry.
    pub variance_share: f64,
    /// Sq without the outliers [m].
    pub sq_without: f64,
}

impl Outliers {
    /// One line for messages: how many, where (the first few as x, y), what they do to Sq.
    pub fn describe(&self, t: &Topography, sq: f64) -> String {
        let shown: Vec<String> = self
            .indices
            .iter()
            .take(5)
            .map(|&i| format!("({}, {})", i % t.nx, i / t.nx))
            .collect();
        let more = if self.indices.len() > shown.len() {
            ", …"
        } else {
            ""
        };
        format!(
            "{} point{} lie more than {OUTLIER_MADS} robust σ ({:.3e} m, from the median \
             absolute deviation) from the median height, at (x, y) {}{more}; they carry \
             {:.1} % of the height variance (Sq {:.4e} m, {:.4e} m without them): spikes, \
             dropouts or corrupted values. Fix: re-export or re-measure, or pass \
             --outliers mask to treat them as invalid",
            self.indices.len(),
            if self.indices.len() == 1 { "" } else { "s" },
            self.robust_sigma,
            shown.join(", "),
            100.0 * self.variance_share,
            sq,
            self.sq_without,
        )
    }
}

/// The outliers of a scan (NaN points skipped); `None` when there are none or the heights
/// have no spread to measure them against (more than half the points equal).
pub fn outliers(t: &Topography) -> Option<Outliers> {
    let mut v: Vec<f64> = t
        .heights
        .iter()
        .copied()
        .filter(|h| h.is_finite())
        .collect();
    if v.len() < 8 {
        return None;
    }
    let median = select_median(&mut v);
    let mut dev: Vec<f64> = v.iter().map(|h| (h - median).abs()).collect();
    let robust_sigma = 1.4826 * select_median(&mut dev);
    if robust_sigma <= 0.0 || !robust_sigma.is_finite() {
        return None;
    }
    let limit = OUTLIER_MADS * robust_sigma;
    let indices: Vec<usize> = (0..t.heights.len())
        .filter(|&i| {
            let h = t.heights[i];
            h.is_finite() && (h - median).abs() > limit
        })
        .collect();
    if indices.is_empty() {
        return None;
    }
    let moments = |skip: bool| {
        let mut is_out = indices.iter().peekable();
        let (mut s, mut s2, mut n) = (0.0, 0.0, 0.0);
        for (i, &h) in t.heights.iter().enumerate() {
            if is_out.peek() == Some(&&i) {
                is_out.next();
                if skip {
                    continue;
                }
            }
            if h.is_finite() {
                s += h;
                s2 += h * h;
                n += 1.0;
            }
        }
        let m = s / n;
        (s2 / n - m * m).max(0.0)
    };
    let (all, without) = (moments(false), moments(true));
    Some(Outliers {
        variance_share: if all > 0.0 {
            (1.0 - without / all).clamp(0.0, 1.0)
        } else {
            0.0
        },
        sq_without: without.sqrt(),
        indices,
        robust_sigma,
        median,
    })
}

fn select_median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// An Sq below this is below one atomic step (≈ 0.05 nm): no measured surface is that
/// smooth, and heights read in the wrong unit land here first.
pub const SQ_MIN_M: f64 = 5e-11;
/// An Sq above this (1 mm) is no surface finish.
pub const SQ_MAX_M: f64 = 1e-3;
/// An RMS slope above 10 (84° average facets) is no metal surface.
pub const SLOPE_MAX: f64 = 10.0;

/// A loud explanation when Sq or the RMS slope of a scan is implausible for a metal
/// surface, with the factors and the `--units lateral,height` that would make both
/// plausible (`given`: the `--units` the scan was read with, if any); `None` when they are.
pub fn implausible_units(sq: f64, slope: f64, dx: f64, given: Option<Units>) -> Option<String> {
    let sq_ok = |s: f64| (SQ_MIN_M..=SQ_MAX_M).contains(&s);
    let slope_ok = |s: f64| s <= SLOPE_MAX;
    if !(sq.is_finite() && slope.is_finite()) || sq == 0.0 || (sq_ok(sq) && slope_ok(slope)) {
        return None;
    }
    let what = if sq < SQ_MIN_M {
        format!("Sq {sq:.3e} m is below one atom (0.05 nm)")
    } else if sq > SQ_MAX_M {
        format!("Sq {sq:.3e} m is above 1 mm, no surface finish")
    } else {
        format!("the RMS slope {slope:.3e} is above {SLOPE_MAX}, steeper than any metal surface")
    };
    // Height and lateral rescalings by powers of 1000 (nm, µm, mm, m): of those that make
    // Sq, the slope and the pixel size plausible, the one landing nearest a typical finish
    // (Sq 0.1 µm, slope 0.1; in decades), lateral changes counting as a third more: a unit
    // error is a factor of 1000ⁿ, so the edge of the window (×1e3 to 0.056 nm) is no answer.
    let steps = [1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6, 1e9];
    let mut best: Option<(f64, f64, f64)> = None;
    for &fh in &steps {
        for &fl in &steps {
            let (s, k, d) = (sq * fh, slope * fh / fl, dx * fl);
            if !(sq_ok(s) && slope_ok(k) && (1e-10..=1e-2).contains(&d)) {
                continue;
            }
            let cost = (s / 1e-7).log10().abs()
                + 0.5 * (k.max(1e-12) / 0.1).log10().abs()
                + fl.log10().abs() / 3.0;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, fh, fl));
            }
        }
    }
    let Some((_, fh, fl)) = best else {
        return Some(format!(
            "{what}: implausible for a metal surface, and no rescaling of heights and lengths \
             by powers of 1000 makes it plausible; check the height channel and the pixel size"
        ));
    };
    let flag = |m: f64| units::name_of(m).replace('µ', "u");
    let fix = match given {
        Some(u) => format!(
            "pass --units {},{} instead",
            flag(u.lateral * fl),
            flag(u.height * fh)
        ),
        None => "if the file states no unit, pass the right --units; if it states one, its \
                 height scale or unit is wrong (re-export the scan)"
            .to_string(),
    };
    Some(format!(
        "{what}: implausible for a metal surface, so a unit is probably wrong: heights ×{fh:e} \
         and lengths ×{fl:e} would give Sq {:.3e} m and RMS slope {:.3e}; {fix}",
        sq * fh,
        slope * fh / fl
    ))
}
