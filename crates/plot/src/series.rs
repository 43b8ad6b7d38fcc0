//! A data series: points plus how to draw them.

use crate::color::Rgb;

/// Stroke pattern of a series' connecting line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineStyle {
    /// Continuous line.
    Solid,
    /// Long dashes.
    Dashed,
    /// Short dots.
    Dotted,
    /// Dash, dot, dash…
    DashDot,
    /// No line (markers only).
    None,
}

/// Symbol drawn at each data point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// No symbol.
    None,
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled upward triangle.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Diagonal cross (×).
    Cross,
    /// Upright cross (+).
    Plus,
}

/// One labelled data series. Build with [`Series::line`] or [`Series::points`], then adjust
/// with the builder methods.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub(crate) label: String,
    pub(crate) xs: Vec<f64>,
    pub(crate) ys: Vec<f64>,
    pub(crate) color: Option<Rgb>,
    pub(crate) line: LineStyle,
    pub(crate) marker: Marker,
    pub(crate) width: Option<f64>,
    pub(crate) marker_size: Option<f64>,
    pub(crate) marker_every: usize,
}

impl Series {
    /// A solid line through `(xs[i], ys[i])` in the given order. Points that cannot be shown
    /// (NaN, ±∞, ≤ 0 on a log axis) are skipped and break the line there.
    pub fn line(label: impl Into<String>, xs: &[f64], ys: &[f64]) -> Series {
        Series {
            label: label.into(),
            xs: xs.to_vec(),
            ys: ys.to_vec(),
            color: None,
            line: LineStyle::Solid,
            marker: Marker::None,
            width: None,
            marker_size: None,
            marker_every: 1,
        }
    }

    /// Markers only (circles by default), no connecting line.
    pub fn points(label: impl Into<String>, xs: &[f64], ys: &[f64]) -> Series {
        Series {
            line: LineStyle::None,
            marker: Marker::Circle,
            ..Series::line(label, xs, ys)
        }
    }

    /// Colour (default: the palette colour of the series' position in the plot).
    pub fn color(mut self, c: Rgb) -> Series {
        self.color = Some(c);
        self
    }

    /// Line pattern.
    pub fn style(mut self, s: LineStyle) -> Series {
        self.line = s;
        self
    }

    /// Marker symbol.
    pub fn marker(mut self, m: Marker) -> Series {
        self.marker = m;
        self
    }

    /// Line width in pixels (default scales with the font size, ≈ 2 px at 800×600).
    pub fn width(mut self, px: f64) -> Series {
        self.width = Some(px);
        self
    }

    /// Marker radius in pixels (default scales with the font size, ≈ 4.5 px at 800×600).
    pub fn marker_size(mut self, px: f64) -> Series {
        self.marker_size = Some(px);
        self
    }

    /// Draw a marker only at every `n`-th point (n ≥ 1), for dense curves.
    pub fn marker_every(mut self, n: usize) -> Series {
        self.marker_every = n.max(1);
        self
    }

    /// Legend label.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The x values as given.
    pub fn xs(&self) -> &[f64] {
        &self.xs
    }

    /// The y values as given.
    pub fn ys(&self) -> &[f64] {
        &self.ys
    }
}
