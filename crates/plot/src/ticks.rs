//! Tick positions and labels for linear and logarithmic axes.

/// One tick mark. Major ticks carry a label; minor ticks (`label == None`) are drawn shorter
/// and without text.
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    /// Data value at the tick.
    pub value: f64,
    /// Text under/next to the tick, `None` for a minor tick.
    pub label: Option<String>,
}

/// Ticks for a linear axis over `[lo, hi]` with roughly `target` labelled ticks at 1-2-2.5-5
/// multiples of a power of ten. Returns an empty list for a non-finite or empty range.
pub fn linear_ticks(lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let step = nice_step((hi - lo) / target.max(1) as f64);
    if !(step.is_finite() && step > 0.0) {
        return Vec::new();
    }
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    if last < first || last - first > 1000 {
        return Vec::new();
    }
    let scale = lo.abs().max(hi.abs());
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            // k*step can leave 1e-17 residue at zero; snap it so the label reads "0".
            let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
            Tick {
                value: v,
                label: Some(format_linear(v, step, scale)),
            }
        })
        .collect()
}

/// Ticks for a log axis over `[lo, hi]` (both > 0). Spans of two or more decades get labels
/// at powers of ten ("10⁻³"), thinned to about `target` labels, with minor ticks at 2…9 × 10ⁿ
/// when the decades are few enough to show them; shorter spans get labels at 1-2-5 multiples
/// (or, failing two of those, linear ticks) so every axis has at least two labels.
pub fn log_ticks(lo: f64, hi: f64, target: usize) -> Vec<Tick> {
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return Vec::new();
    }
    let (l0, l1) = (lo.log10(), hi.log10());
    let e0 = (l0 - 1e-9).ceil() as i64;
    let e1 = (l1 + 1e-9).floor() as i64;
    let decades = e1 - e0 + 1;
    let inside = |v: f64| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9);
    let mut ticks = Vec::new();
    if decades >= 2 {
        let stride = ((decades as f64) / target.max(1) as f64).ceil().max(1.0) as i64;
        let show_minor = stride == 1 && (l1 - l0) <= 10.0;
        for e in (e0 - 1)..=e1 {
            let p = 10f64.powi(e as i32);
            if e >= e0 {
                let label = (e.rem_euclid(stride) == 0).then(|| power_of_ten_label(e));
                ticks.push(Tick { value: p, label });
            }
            if show_minor {
                for m in 2..=9 {
                    let v = m as f64 * p;
                    if inside(v) {
                        ticks.push(Tick {
                            value: v,
                            label: None,
                        });
                    }
                }
            }
        }
    } else {
        for e in (e0 - 2)..=(e1 + 1) {
            let p = 10f64.powi(e as i32);
            for m in 1..=9 {
                let v = m as f64 * p;
                if inside(v) {
                    let label = matches!(m, 1 | 2 | 5).then(|| format_mantissa_power(m, e));
                    ticks.push(Tick { value: v, label });
                }
            }
        }
        if ticks.iter().filter(|t| t.label.is_some()).count() < 2 {
            ticks = linear_ticks(lo, hi, target.max(2));
        }
    }
    ticks.sort_by(|a, b| a.value.total_cmp(&b.value));
    ticks
}

/// Smallest 1/2/2.5/5 × 10ⁿ step not below `raw`.
fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return f64::NAN;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .find(|&n| f <= n * (1.0 + 1e-9))
        .unwrap_or(10.0);
    nice * mag
}

fn format_linear(v: f64, step: f64, scale: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    if !(1e-3..1e5).contains(&scale) {
        // Scientific: mantissa decimals follow the step relative to the value's own power.
        let e = (v.abs().log10() + 1e-9).floor() as i32;
        let m = v / 10f64.powi(e);
        let dec = decimals_for(step / 10f64.powi(e));
        let ms = trim_zeros(format!("{m:.dec$}"));
        return format!("{ms}×10{}", superscript(&e.to_string()));
    }
    let dec = decimals_for(step);
    let s = format!("{v:.dec$}");
    s.replace('-', "−")
}

/// Decimal places needed to show multiples of `step` exactly (2.5 needs one more).
fn decimals_for(step: f64) -> usize {
    let mut d = 0usize;
    let mut s = step;
    while d < 12 && (s - s.round()).abs() > 1e-6 * s.abs().max(1e-300) {
        s *= 10.0;
        d += 1;
    }
    d
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn power_of_ten_label(e: i64) -> String {
    format!("10{}", superscript(&e.to_string()))
}

fn format_mantissa_power(m: u32, e: i64) -> String {
    if (-3..=4).contains(&e) {
        let v = f64::from(m) * 10f64.powi(e as i32);
        let dec = if e < 0 { (-e) as usize } else { 0 };
        format!("{v:.dec$}")
    } else if m == 1 {
        power_of_ten_label(e)
    } else {
        format!("{m}×10{}", superscript(&e.to_string()))
    }
}

/// Unicode superscript form of an integer string ("-3" → "⁻³").
pub(crate) fn superscript(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            '-' => '⁻',
            other => other,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labelled(t: &[Tick]) -> Vec<(f64, String)> {
        t.iter()
            .filter_map(|t| t.label.clone().map(|l| (t.value, l)))
            .collect()
    }

    #[test]
    fn log_ticks_over_five_decades_label_every_power() {
        let t = log_ticks(1e-3, 1e2, 8);
        let l = labelled(&t);
        let want = ["10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹", "10²"];
        assert_eq!(l.len(), want.len(), "{l:?}");
        for ((v, s), (e, w)) in l.iter().zip((-3..=2).zip(want)) {
            assert!((v / 10f64.powi(e) - 1.0).abs() < 1e-12);
            assert_eq!(s, w);
        }
        // 8 minor ticks per full decade, 5 decades.
        assert_eq!(t.iter().filter(|t| t.label.is_none()).count(), 40);
        assert!(t.windows(2).all(|w| w[0].value < w[1].value));
    }

    #[test]
    fn log_ticks_partial_decades_stay_inside_range() {
        let t = log_ticks(3e-4, 0.7, 8);
        assert!(
            t.iter()
                .all(|t| t.value >= 3e-4 * (1.0 - 1e-9) && t.value <= 0.7 * (1.0 + 1e-9))
        );
        let l = labelled(&t);
        assert_eq!(l.first().unwrap().1, "10⁻³");
        assert_eq!(l.last().unwrap().1, "10⁻¹");
        // Minor ticks 4e-4..9e-4 below the first decade are present.
        assert!(t.iter().any(|t| (t.value - 4e-4).abs() < 1e-15));
    }

    #[test]
    fn log_ticks_thin_huge_ranges() {
        let t = log_ticks(1e-30, 1e30, 6);
        let l = labelled(&t);
        assert!(l.len() >= 4 && l.len() <= 7, "{l:?}");
        assert!(
            t.iter()
                .all(|t| t.label.is_some() || t.value.log10().fract().abs() < 1e-9)
        );
        // No minor 2..9 ticks when decades are strided.
        assert!(
            t.iter()
                .all(|t| (t.value.log10() - t.value.log10().round()).abs() < 1e-9)
        );
    }

    #[test]
    fn log_ticks_within_one_decade_use_1_2_5() {
        let l = labelled(&log_ticks(1.5, 30.0, 6));
        let vals: Vec<f64> = l.iter().map(|p| p.0).collect();
        assert_eq!(vals, vec![2.0, 5.0, 10.0, 20.0]);
        assert_eq!(l[0].1, "2");
        assert_eq!(l[2].1, "10");
        let small = labelled(&log_ticks(1.5e-6, 3e-5, 6));
        assert_eq!(small[0].1, "2×10⁻⁶");
        assert_eq!(small[2].1, "10⁻⁵");
    }

    #[test]
    fn log_ticks_narrow_range_falls_back_to_linear() {
        let l = labelled(&log_ticks(2.1, 2.9, 5));
        assert!(l.len() >= 2, "{l:?}");
        assert!(l.iter().all(|(v, _)| *v >= 2.1 && *v <= 2.9));
    }

    #[test]
    fn log_ticks_reject_bad_ranges() {
        assert!(log_ticks(0.0, 1.0, 5).is_empty());
        assert!(log_ticks(-1.0, 1.0, 5).is_empty());
        assert!(log_ticks(1.0, f64::INFINITY, 5).is_empty());
        assert!(log_ticks(2.0, 1.0, 5).is_empty());
        assert!(log_ticks(f64::NAN, 1.0, 5).is_empty());
    }

    #[test]
    fn linear_ticks_are_nice_and_exact() {
        let l = labelled(&linear_ticks(0.0, 90.0, 6));
        let s: Vec<&str> = l.iter().map(|p| p.1.as_str()).collect();
        assert_eq!(s, ["0", "20", "40", "60", "80"]);
        let l = labelled(&linear_ticks(-1.0, 1.0, 4));
        let s: Vec<&str> = l.iter().map(|p| p.1.as_str()).collect();
        assert_eq!(s, ["−1.0", "−0.5", "0", "0.5", "1.0"]);
        let l = labelled(&linear_ticks(0.0, 0.01, 4));
        assert_eq!(l[1].1, "0.0025");
    }

    #[test]
    fn linear_ticks_use_scientific_labels_for_tiny_values() {
        let l = labelled(&linear_ticks(0.0, 4e-6, 4));
        assert_eq!(l[1].1, "1×10⁻⁶");
        let l = labelled(&linear_ticks(0.0, 3e6, 3));
        assert_eq!(l[1].1, "1×10⁶");
    }

    #[test]
    fn nice_step_picks_1_2_2p5_5() {
        assert_eq!(nice_step(0.9), 1.0);
        assert_eq!(nice_step(1.1), 2.0);
        assert_eq!(nice_step(2.2), 2.5);
        assert_eq!(nice_step(3.0), 5.0);
        assert_eq!(nice_step(7.0), 10.0);
        assert!((nice_step(0.013) - 0.02).abs() < 1e-15);
    }
}
