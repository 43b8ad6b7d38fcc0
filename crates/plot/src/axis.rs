//! Axis description (label, scale, optional fixed range) and the data → pixel mapping.

use crate::ticks::{Tick, linear_ticks, log_ticks};

/// How data values map onto an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Evenly spaced values.
    Linear,
    /// Evenly spaced decades; only values > 0 can be shown.
    Log,
}

/// One plot axis: its label (put the unit in it, e.g. `"θo [deg]"`), scale and range.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub(crate) label: String,
    pub(crate) scale: Scale,
    pub(crate) range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis labelled `label`, range fitted to the data.
    pub fn linear(label: impl Into<String>) -> Axis {
        Axis {
            label: label.into(),
            scale: Scale::Linear,
            range: None,
        }
    }

    /// A base-10 logarithmic axis labelled `label`, range fitted to the positive data.
    pub fn log(label: impl Into<String>) -> Axis {
        Axis {
            label: label.into(),
            scale: Scale::Log,
            range: None,
        }
    }

    /// Fixes the shown range to `[lo, hi]` instead of fitting it to the data. Points outside
    /// are clipped at the frame. Checked when the plot is rendered: needs finite `lo < hi`,
    /// and `lo > 0` on a log axis.
    pub fn range(mut self, lo: f64, hi: f64) -> Axis {
        self.range = Some((lo, hi));
        self
    }

    /// The axis scale.
    pub fn scale(&self) -> Scale {
        self.scale
    }

    /// The axis label.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// Whether `v` can be placed on this axis at all.
    pub(crate) fn accepts(&self, v: f64) -> bool {
        v.is_finite() && (self.scale == Scale::Linear || v > 0.0)
    }

    pub(crate) fn ticks(&self, lo: f64, hi: f64, target: usize) -> Vec<Tick> {
        match self.scale {
            Scale::Linear => linear_ticks(lo, hi, target),
            Scale::Log => log_ticks(lo, hi, target),
        }
    }
}

/// Fits a shown range to the accepted data values with a small margin. Always returns finite
/// `lo < hi` (and `lo > 0` for log), even for a single value or values near the f64 limits.
pub(crate) fn auto_range(scale: Scale, lo: f64, hi: f64) -> (f64, f64) {
    const MARGIN: f64 = 0.04;
    match scale {
        Scale::Linear => {
            let (lo, hi) = if hi > lo {
                (lo, hi)
            } else {
                let half = (lo.abs() * 0.1).max(1.0);
                // Widen towards zero when the other side would overflow.
                if !(lo - half).is_finite() {
                    (lo, hi + 2.0 * half)
                } else if !(hi + half).is_finite() {
                    (lo - 2.0 * half, hi)
                } else {
                    (lo - half, hi + half)
                }
            };
            let pad = (hi - lo) * MARGIN;
            let (a, b) = (lo - pad, hi + pad);
            if a.is_finite() && b.is_finite() {
                (a, b)
            } else {
                (lo, hi)
            }
        }
        Scale::Log => {
            // Keep 10^l finite and normal.
            const LMIN: f64 = -307.5;
            const LMAX: f64 = 308.2;
            let (l0, l1) = (lo.log10(), hi.log10());
            let (l0, l1) = if l1 - l0 > 1e-12 {
                (l0, l1)
            } else {
                (l0 - 0.5, l1 + 0.5)
            };
            let pad = (l1 - l0) * MARGIN;
            let (mut a, mut b) = ((l0 - pad).clamp(LMIN, LMAX), (l1 + pad).clamp(LMIN, LMAX));
            if b - a < 0.1 {
                (a, b) = if b >= LMAX - 0.1 {
                    (LMAX - 1.0, LMAX)
                } else {
                    (a.min(LMAX - 1.0), a.min(LMAX - 1.0) + 1.0)
                };
            }
            (10f64.powf(a), 10f64.powf(b))
        }
    }
}

/// Maps data values of one axis to pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisMap {
    /// Scale of the axis.
    pub scale: Scale,
    /// Data value at the low end of the frame.
    pub lo: f64,
    /// Data value at the high end of the frame.
    pub hi: f64,
    /// Pixel coordinate of `lo`.
    pub px_lo: f64,
    /// Pixel coordinate of `hi`.
    pub px_hi: f64,
}

impl AxisMap {
    /// Pixel coordinate of data value `v` (may lie outside the frame), or `None` when `v`
    /// cannot be shown on this axis.
    pub fn to_px(&self, v: f64) -> Option<f64> {
        let f = match self.scale {
            Scale::Linear if v.is_finite() => (v - self.lo) / (self.hi - self.lo),
            Scale::Log if v.is_finite() && v > 0.0 => {
                (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
            }
            _ => return None,
        };
        let p = self.px_lo + f * (self.px_hi - self.px_lo);
        p.is_finite().then_some(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_map_puts_decades_evenly() {
        let m = AxisMap {
            scale: Scale::Log,
            lo: 1e-2,
            hi: 1e2,
            px_lo: 0.0,
            px_hi: 400.0,
        };
        assert!((m.to_px(1.0).unwrap() - 200.0).abs() < 1e-9);
        assert!((m.to_px(10.0).unwrap() - 300.0).abs() < 1e-9);
        assert_eq!(m.to_px(0.0), None);
        assert_eq!(m.to_px(-1.0), None);
        assert_eq!(m.to_px(f64::NAN), None);
    }

    #[test]
    fn auto_range_pads_and_handles_single_values() {
        let (a, b) = auto_range(Scale::Linear, 0.0, 100.0);
        assert!((a + 4.0).abs() < 1e-12 && (b - 104.0).abs() < 1e-12);
        let (a, b) = auto_range(Scale::Linear, 5.0, 5.0);
        assert!(a < 5.0 && b > 5.0);
        let (a, b) = auto_range(Scale::Log, 1e-3, 1e3);
        assert!(a < 1e-3 && a > 1e-4 && b > 1e3 && b < 1e4);
        let (a, b) = auto_range(Scale::Log, 7.0, 7.0);
        assert!(a < 7.0 && b > 7.0 && a > 0.0);
        for (lo, hi) in [
            (-f64::MAX, f64::MAX),
            (f64::MAX, f64::MAX),
            (-f64::MAX, -f64::MAX),
            (0.0, 0.0),
        ] {
            let (a, b) = auto_range(Scale::Linear, lo, hi);
            assert!(
                a.is_finite() && b.is_finite() && b > a,
                "{lo} {hi} -> {a} {b}"
            );
        }
        for v in [f64::MAX, f64::MIN_POSITIVE, 5e-324, 1.0] {
            let (a, b) = auto_range(Scale::Log, v, v);
            assert!(a > 0.0 && b.is_finite() && b > a, "{v} -> {a} {b}");
        }
    }
}
