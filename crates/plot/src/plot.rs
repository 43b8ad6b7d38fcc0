//! The line-plot figure. The layout (where frame, labels, title and legend go) and the tick
//! choice are ours; plotters draws the axes, grid, tick marks and labels, series, markers and
//! text into the bitmap.

use crate::axis::{AxisMap, Scale, auto_range};
use crate::backend::Canvas;
use crate::color::Rgb;
use crate::stroke::{Pt, clip_polyline, dash_pattern, dash_polyline};
use crate::text::{self, HAlign, LINE_PITCH};
use crate::ticks::Tick;
use crate::{Axis, LineStyle, Marker, PlotError, Series, error::drawing};
use image::RgbImage;
use plotters::coord::Shift;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::prelude::{
    BitMapBackend, ChartBuilder, Circle, Color, DrawingArea, IntoDrawingArea, PathElement, Polygon,
    Rectangle,
};
use plotters::style::{RGBColor, ShapeStyle};
use std::path::Path;

/// A rectangle in pixel coordinates, `x0 <= x < x1`, `y0 <= y < y1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PxRect {
    /// Left edge (inclusive).
    pub x0: i64,
    /// Top edge (inclusive).
    pub y0: i64,
    /// Right edge (exclusive).
    pub x1: i64,
    /// Bottom edge (exclusive).
    pub y1: i64,
}

impl PxRect {
    pub(crate) fn width(&self) -> i64 {
        self.x1 - self.x0
    }
    pub(crate) fn height(&self) -> i64 {
        self.y1 - self.y0
    }
    fn contains(&self, x: i64, y: i64) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }
}

/// Largest image a plot or grid may produce (pixels), so bad sizes fail instead of
/// exhausting memory.
pub(crate) const MAX_PIXELS: u64 = 1 << 28;

/// Where the legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legend {
    /// Inside the frame, top right corner (default).
    TopRight,
    /// Inside the frame, top left corner.
    TopLeft,
    /// Inside the frame, bottom right corner.
    BottomRight,
    /// Inside the frame, bottom left corner.
    BottomLeft,
    /// To the right of the frame (the frame shrinks to make room).
    Outside,
    /// No legend.
    Hidden,
}

/// A 2-D line plot. See the crate docs for an example.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    title: String,
    x: Axis,
    y: Axis,
    series: Vec<Series>,
    legend: Legend,
    font_px: Option<f64>,
    grid: bool,
}

/// Points a render left out, per series.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Skipped {
    /// Series label.
    pub label: String,
    /// Number of points that were NaN, infinite or non-positive on a log axis.
    pub count: usize,
}

/// Where things ended up in a rendered plot, plus what was skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotReport {
    /// The plot frame (data area) in pixels.
    pub frame: PxRect,
    /// Horizontal data → pixel mapping.
    pub x: AxisMap,
    /// Vertical data → pixel mapping (pixel y grows downwards).
    pub y: AxisMap,
    /// Series that had points left out, with counts (series with none are not listed).
    pub skipped: Vec<Skipped>,
}

impl PlotReport {
    /// Pixel position of data point (x, y), or `None` if either value cannot be shown.
    pub fn to_px(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        Some((self.x.to_px(x)?, self.y.to_px(y)?))
    }
}

/// Text sizes and spacings, all following the tick-label font size `tick`.
struct Sizes {
    tick: f64,
    label: f64,
    title: f64,
    legend: f64,
    pad: f64,
    frame_w: f64,
    tick_len: f64,
}

impl Sizes {
    fn new(base: f64) -> Sizes {
        Sizes {
            tick: base,
            label: base * 1.1,
            title: base * 1.3,
            legend: base * 0.95,
            pad: (base * 0.6).round(),
            frame_w: (base / 14.0).max(1.0).round(),
            tick_len: (base * 0.45).round(),
        }
    }

    /// Distance from the frame to the top of a tick label's anchor (plotters puts labels
    /// twice the tick length away from the axis).
    fn label_dist(&self) -> f64 {
        2.0 * self.tick_len
    }
}

/// Where everything goes, decided before anything is drawn.
struct Layout {
    frame: PxRect,
    xmap: AxisMap,
    ymap: AxisMap,
    xt: Vec<Tick>,
    yt: Vec<Tick>,
    title: Vec<String>,
    /// Legend box size in px, if there is a legend.
    legend: Option<(f64, f64)>,
    /// Margins handed to plotters: (top, bottom, left, right, x label area, y label area).
    margins: [u32; 6],
}

/// One axis as plotters' mesh sees it: our data → pixel mapping, our ticks and labels.
struct TickAxis {
    map: AxisMap,
    major: Vec<(f64, String)>,
    minor: Vec<f64>,
}

impl TickAxis {
    fn new(map: AxisMap, ticks: &[Tick]) -> TickAxis {
        let (mut major, mut minor) = (Vec::new(), Vec::new());
        for t in ticks {
            match &t.label {
                Some(l) => major.push((t.value, l.clone())),
                None => minor.push(t.value),
            }
        }
        TickAxis { map, major, minor }
    }
}

impl Ranged for TickAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    /// The pixel holding the value, as for the series, so grid lines and data agree.
    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let m = AxisMap {
            px_lo: f64::from(limit.0),
            px_hi: f64::from(limit.1),
            ..self.map
        };
        m.to_px(*v).map_or(limit.0, |p| {
            p.floor().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
        })
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.iter().map(|t| t.0).collect()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.map.lo..self.map.hi
    }
}

impl ValueFormatter<f64> for TickAxis {
    fn format_ext(&self, v: &f64) -> String {
        self.major
            .iter()
            .find(|t| t.0 == *v)
            .map(|t| t.1.clone())
            .unwrap_or_default()
    }
}
impl Plot {
    /// An empty plot with a title (may be empty) and linear axes labelled "x" and "y".
    pub fn new(title: impl Into<String>) -> Plot {
        Plot {
            title: title.into(),
            x: Axis::linear("x"),
            y: Axis::linear("y"),
            series: Vec::new(),
            legend: Legend::TopRight,
            font_px: None,
            grid: true,
        }
    }

    /// Sets the horizontal axis.
    pub fn x_axis(mut self, a: Axis) -> Plot {
        self.x = a;
        self
    }

    /// Sets the vertical axis.
    pub fn y_axis(mut self, a: Axis) -> Plot {
        self.y = a;
        self
    }

    /// Adds a series (drawn in the order added; later ones on top).
    pub fn series(mut self, s: Series) -> Plot {
        self.series.push(s);
        self
    }

    /// Legend placement.
    pub fn legend(mut self, l: Legend) -> Plot {
        self.legend = l;
        self
    }

    /// Tick-label font size in px (other text scales from it). Default: min(height / 34,
    /// width / 40), clamped to 12..26 px (≈ 17.6 px at 800×600).
    pub fn font_px(mut self, px: f64) -> Plot {
        self.font_px = Some(px);
        self
    }

    /// Light grid lines at the labelled ticks (default on).
    pub fn grid(mut self, on: bool) -> Plot {
        self.grid = on;
        self
    }

    /// The series added so far.
    pub fn series_list(&self) -> &[Series] {
        &self.series
    }

    /// Renders to a PNG file, atomically. Returns where the frame is and what was skipped.
    pub fn save_png(
        &self,
        path: impl AsRef<Path>,
        width: u32,
        height: u32,
    ) -> Result<PlotReport, PlotError> {
        let (img, report) = self.render(width, height)?;
        crate::io::save_png(&img, path)?;
        Ok(report)
    }

    /// Writes the plotted data as CSV (see [`crate::write_series_csv`]), atomically.
    pub fn save_csv(&self, path: impl AsRef<Path>) -> Result<(), PlotError> {
        crate::write_series_csv(path, &self.x.label, &self.y.label, &self.series)
    }

    /// Renders to an in-memory RGB image.
    pub fn render(&self, width: u32, height: u32) -> Result<(RgbImage, PlotReport), PlotError> {
        if self.series.is_empty() {
            return Err(PlotError::NoSeries {
                title: self.title.clone(),
            });
        }
        let (paths, skipped) = self.valid_paths()?;
        let xr = self.shown_range(&self.x, "x", &paths, 0)?;
        let yr = self.shown_range(&self.y, "y", &paths, 1)?;
        if u64::from(width) * u64::from(height) > MAX_PIXELS {
            return Err(PlotError::TooLarge {
                width,
                height,
                max_pixels: MAX_PIXELS,
            });
        }
        text::ensure_font()?;
        let (sz, lay) = match self.try_layout(width, height, xr, yr) {
            Ok(v) => v,
            Err(need) => return Err(self.too_small(width, height, need, xr, yr)),
        };
        let base = sz.tick;
        let mut buf = vec![255u8; width as usize * height as usize * 3];
        {
            let root =
                Canvas(BitMapBackend::with_buffer(&mut buf, (width, height))).into_drawing_area();
            self.draw_axes(&root, &lay, &sz)?;
            for (i, (s, runs)) in self.series.iter().zip(&paths).enumerate() {
                draw_series(&root, &lay, s, i, runs, base)?;
            }
            draw_frame(&root, &lay.frame, sz.frame_w as i32)?;
            self.draw_texts(&root, &lay, &sz, width)?;
            if let Some(size) = lay.legend {
                self.draw_legend(&root, &lay.frame, size, &sz, base, width)?;
            }
            root.present().map_err(drawing)?;
        }
        let img = RgbImage::from_raw(width, height, buf)
            .ok_or_else(|| PlotError::Drawing("pixel buffer of the wrong size".into()))?;
        let report = PlotReport {
            frame: lay.frame,
            x: lay.xmap,
            y: lay.ymap,
            skipped,
        };
        Ok((img, report))
    }

    /// Tick-label font size for a `width` × `height` image.
    fn base_px(&self, width: u32, height: u32) -> f64 {
        self.font_px
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or_else(|| {
                (f64::from(height) / 34.0)
                    .min(f64::from(width) / 40.0)
                    .clamp(12.0, 26.0)
            })
    }

    /// The layout at this size, or (when the plot does not fit) a size it needs at least.
    fn try_layout(
        &self,
        width: u32,
        height: u32,
        xr: (f64, f64),
        yr: (f64, f64),
    ) -> Result<(Sizes, Layout), (u32, u32)> {
        let base = self.base_px(width, height);
        let (min_w, min_h) = ((base * 14.0) as u32, (base * 11.0) as u32);
        if width < min_w || height < min_h {
            return Err((min_w.max(width), min_h.max(height)));
        }
        let sz = Sizes::new(base);
        let lay = self.layout(width, height, xr, yr, &sz)?;
        Ok((sz, lay))
    }

    /// The `TooSmall` error for a request, naming a size at which the plot does render (the
    /// needs grow with the default font size, which follows the image size, so iterate).
    fn too_small(
        &self,
        width: u32,
        height: u32,
        mut need: (u32, u32),
        xr: (f64, f64),
        yr: (f64, f64),
    ) -> PlotError {
        for _ in 0..32 {
            match self.try_layout(need.0, need.1, xr, yr) {
                Ok(_) => break,
                Err(more) => {
                    need = (
                        more.0.max(need.0.saturating_add(1)),
                        more.1.max(need.1.saturating_add(1)),
                    )
                }
            }
        }
        PlotError::TooSmall {
            width,
            height,
            min_width: need.0,
            min_height: need.1,
        }
    }

    /// Places frame, title, labels and legend for a `width` × `height` image; when the frame
    /// would be too small, the size that would give it enough room.
    fn layout(
        &self,
        width: u32,
        height: u32,
        xr: (f64, f64),
        yr: (f64, f64),
        sz: &Sizes,
    ) -> Result<Layout, (u32, u32)> {
        let (w, h) = (f64::from(width), f64::from(height));
        // Tick density follows the space roughly available before the exact layout is known.
        let xt = self.x.ticks(
            xr.0,
            xr.1,
            (w * 0.75 / (sz.tick * 6.0)).clamp(2.0, 10.0) as usize,
        );
        let yt = self.y.ticks(
            yr.0,
            yr.1,
            (h * 0.7 / (sz.tick * 3.2)).clamp(2.0, 10.0) as usize,
        );
        let title = if self.title.is_empty() {
            Vec::new()
        } else {
            text::wrap(&self.title, sz.title, w - 2.0 * sz.pad)
        };
        let legend = self.legend_size(sz);
        let label_w = |t: &[Tick]| -> Vec<f64> {
            t.iter()
                .filter_map(|t| t.label.as_deref())
                .map(|l| text::width(l, sz.tick))
                .collect()
        };
        let ytick_w = label_w(&yt).into_iter().fold(0.0, f64::max);
        let xtick_last_w = label_w(&xt).last().copied().unwrap_or(0.0);
        let axis_label_h = |l: &str| {
            if l.is_empty() {
                0.0
            } else {
                text::block_height(1, sz.label) + sz.pad * 0.5
            }
        };
        let top = sz.pad
            + if title.is_empty() {
                0.5 * sz.tick
            } else {
                text::block_height(title.len(), sz.title) + sz.tick * 0.6
            };
        let x_area = sz.label_dist() + text::line_box(sz.tick) + axis_label_h(&self.x.label);
        let y_area = sz.label_dist() + ytick_w + axis_label_h(&self.y.label);
        let right = match (self.legend, legend) {
            (Legend::Outside, Some((bw, _))) => 2.0 * sz.pad + bw,
            _ => sz.pad + (xtick_last_w * 0.5).max(sz.pad),
        };
        let px = |v: f64| v.ceil().max(0.0) as u32;
        let margins = [
            px(top),
            px(sz.pad),
            px(sz.pad),
            px(right),
            px(x_area),
            px(y_area),
        ];
        let frame = PxRect {
            x0: i64::from(margins[2]) + i64::from(margins[5]),
            y0: i64::from(margins[0]),
            x1: i64::from(width) - i64::from(margins[3]),
            y1: i64::from(height) - i64::from(margins[1]) - i64::from(margins[4]),
        };
        let (need_w, need_h) = ((sz.tick * 5.0) as i64, (sz.tick * 4.0) as i64);
        if frame.width() < need_w || frame.height() < need_h {
            let grow = |have: u32, short: i64| {
                (i64::from(have) + short.max(0)).clamp(0, i64::from(u32::MAX)) as u32
            };
            return Err((
                grow(width, need_w - frame.width()),
                grow(height, need_h - frame.height()),
            ));
        }
        // The pixel range plotters maps the axis onto: first to last pixel of the frame.
        let xmap = AxisMap {
            scale: self.x.scale,
            lo: xr.0,
            hi: xr.1,
            px_lo: frame.x0 as f64,
            px_hi: (frame.x1 - 1) as f64,
        };
        let ymap = AxisMap {
            scale: self.y.scale,
            lo: yr.0,
            hi: yr.1,
            px_lo: (frame.y1 - 1) as f64,
            px_hi: frame.y0 as f64,
        };
        Ok(Layout {
            frame,
            xmap,
            ymap,
            xt,
            yt,
            title,
            legend,
            margins,
        })
    }

    /// Grid lines, axis lines, tick marks and tick labels, through a plotters chart whose
    /// coordinates are the axes' linear coordinates (log10 of the value on log axes).
    fn draw_axes<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        lay: &Layout,
        sz: &Sizes,
    ) -> Result<(), PlotError> {
        let [top, bottom, left, right, x_area, y_area] = lay.margins;
        let mut chart = ChartBuilder::on(root)
            .margin_top(top)
            .margin_bottom(bottom)
            .margin_left(left)
            .margin_right(right)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(
                TickAxis::new(lay.xmap, &lay.xt),
                TickAxis::new(lay.ymap, &lay.yt),
            )
            .map_err(drawing)?;
        let black = ShapeStyle {
            color: RGBColor(0, 0, 0).to_rgba(),
            filled: false,
            stroke_width: sz.frame_w as u32,
        };
        let mut mesh = chart.configure_mesh();
        mesh.label_style(text::style(sz.tick, Rgb::BLACK))
            .axis_style(black)
            .set_all_tick_mark_size(sz.tick_len as i32)
            .bold_line_style(rgb(Rgb::GRID))
            .light_line_style(rgb(Rgb(240, 240, 240)));
        if !self.grid {
            mesh.disable_mesh();
        }
        mesh.draw().map_err(drawing)
    }

    /// Axis labels and the (wrapped) title.
    fn draw_texts<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        lay: &Layout,
        sz: &Sizes,
        width: u32,
    ) -> Result<(), PlotError> {
        let f = &lay.frame;
        let fx_mid = (f.x0 + f.x1) as f64 * 0.5;
        let fy_mid = (f.y0 + f.y1) as f64 * 0.5;
        if !self.x.label.is_empty() {
            let y = f.y1 as f64 + sz.label_dist() + text::line_box(sz.tick) + sz.pad * 0.5;
            let st = (fx_mid, y);
            text::draw_lines(
                root,
                &self.x.label,
                sz.label,
                st,
                HAlign::Center,
                Rgb::BLACK,
            )?;
        }
        if !self.y.label.is_empty() {
            text::draw_vertical(root, &self.y.label, sz.label, (sz.pad, fy_mid), Rgb::BLACK)?;
        }
        if !lay.title.is_empty() {
            let at = (f64::from(width) * 0.5, sz.pad);
            text::draw_lines(
                root,
                &lay.title.join("\n"),
                sz.title,
                at,
                HAlign::Center,
                Rgb::BLACK,
            )?;
        }
        Ok(())
    }

    /// Splits each series into runs of showable points; a bad point ends a run.
    #[allow(clippy::type_complexity)]
    fn valid_paths(&self) -> Result<(Vec<Vec<Vec<(f64, f64)>>>, Vec<Skipped>), PlotError> {
        let mut all = Vec::with_capacity(self.series.len());
        let mut skipped = Vec::new();
        for s in &self.series {
            if s.xs.len() != s.ys.len() {
                return Err(PlotError::LengthMismatch {
                    label: s.label.clone(),
                    xs: s.xs.len(),
                    ys: s.ys.len(),
                });
            }
            if s.xs.is_empty() {
                return Err(PlotError::EmptySeries {
                    label: s.label.clone(),
                });
            }
            let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
            let mut cur = Vec::new();
            let mut bad = 0;
            for (&x, &y) in s.xs.iter().zip(&s.ys) {
                if self.x.accepts(x) && self.y.accepts(y) {
                    cur.push((x, y));
                } else {
                    bad += 1;
                    if !cur.is_empty() {
                        runs.push(std::mem::take(&mut cur));
                    }
                }
            }
            if !cur.is_empty() {
                runs.push(cur);
            }
            if runs.is_empty() {
                let detail = format!(
                    "x axis {}, y axis {}",
                    if self.x.scale == Scale::Log {
                        "log"
                    } else {
                        "linear"
                    },
                    if self.y.scale == Scale::Log {
                        "log"
                    } else {
                        "linear"
                    }
                );
                return Err(PlotError::NoPlottablePoints {
                    label: s.label.clone(),
                    points: s.xs.len(),
                    detail,
                });
            }
            if bad > 0 {
                skipped.push(Skipped {
                    label: s.label.clone(),
                    count: bad,
                });
            }
            all.push(runs);
        }
        Ok((all, skipped))
    }

    fn shown_range(
        &self,
        axis: &Axis,
        name: &'static str,
        paths: &[Vec<Vec<(f64, f64)>>],
        k: usize,
    ) -> Result<(f64, f64), PlotError> {
        if let Some((lo, hi)) = axis.range {
            let reason = if !(lo.is_finite() && hi.is_finite()) {
                Some("bounds must be finite")
            } else if lo >= hi {
                Some("the lower bound must be below the upper bound")
            } else if axis.scale == Scale::Log && lo <= 0.0 {
                Some("a log axis needs a positive lower bound")
            } else {
                None
            };
            return match reason {
                Some(reason) => Err(PlotError::InvalidRange {
                    axis: name,
                    lo,
                    hi,
                    reason,
                }),
                None => Ok((lo, hi)),
            };
        }
        let vals = paths
            .iter()
            .flatten()
            .flatten()
            .map(|p| if k == 0 { p.0 } else { p.1 });
        let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        Ok(auto_range(axis.scale, lo, hi))
    }

    /// Series shown in the legend: those with a label.
    fn legend_entries(&self) -> impl Iterator<Item = (usize, &Series)> {
        self.series
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.label.is_empty())
    }

    /// Legend box size in px, or None when there is no legend to draw.
    fn legend_size(&self, sz: &Sizes) -> Option<(f64, f64)> {
        if self.legend == Legend::Hidden {
            return None;
        }
        let (n, label_w) = self
            .legend_entries()
            .fold((0usize, 0.0f64), |(n, w), (_, s)| {
                (n + 1, w.max(text::width(&s.label, sz.legend)))
            });
        (n > 0).then_some((
            sz.pad * 2.6 + sz.legend * 2.4 + label_w,
            sz.pad + LINE_PITCH * sz.legend * n as f64,
        ))
    }

    fn draw_legend<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        frame: &PxRect,
        (bw, bh): (f64, f64),
        sz: &Sizes,
        base: f64,
        width: u32,
    ) -> Result<(), PlotError> {
        let inset = sz.pad;
        let (x0, y0) = match self.legend {
            Legend::TopRight => (frame.x1 as f64 - inset - bw, frame.y0 as f64 + inset),
            Legend::TopLeft => (frame.x0 as f64 + inset, frame.y0 as f64 + inset),
            Legend::BottomRight => (frame.x1 as f64 - inset - bw, frame.y1 as f64 - inset - bh),
            Legend::BottomLeft => (frame.x0 as f64 + inset, frame.y1 as f64 - inset - bh),
            Legend::Outside => (f64::from(width) - sz.pad - bw, frame.y0 as f64),
            Legend::Hidden => return Ok(()),
        };
        let corners = [
            (x0.round() as i32, y0.round() as i32),
            ((x0 + bw).round() as i32, (y0 + bh).round() as i32),
        ];
        let draw = |e: &Rectangle<(i32, i32)>| root.draw(e).map_err(drawing);
        draw(&Rectangle::new(corners, rgb(Rgb::WHITE).filled()))?;
        draw(&Rectangle::new(corners, rgb(Rgb(150, 150, 150))))?;
        let row = LINE_PITCH * sz.legend;
        let sample = sz.legend * 2.4;
        for (k, (i, s)) in self.legend_entries().enumerate() {
            let color = s.color.unwrap_or_else(|| Rgb::palette(i));
            let cy = y0 + sz.pad * 0.5 + row * (k as f64 + 0.5);
            let sx0 = x0 + sz.pad;
            let lw = line_width(s, base);
            if s.line != LineStyle::None {
                let dash = dash_pattern(s.line, lw, base * 0.7);
                for piece in dash_polyline(&[(sx0, cy), (sx0 + sample, cy)], &dash) {
                    draw_piece(root, &piece, color, lw)?;
                }
            }
            draw_marker(root, s, (sx0 + sample * 0.5, cy), color, base)?;
            let at = (
                sx0 + sample + sz.pad * 0.6,
                cy - 0.5 * text::line_box(sz.legend),
            );
            text::draw_lines(root, &s.label, sz.legend, at, HAlign::Left, Rgb::BLACK)?;
        }
        Ok(())
    }
}

fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

/// Line width in px: as given (kept to 0.5…50 px), else following the font size.
fn line_width(s: &Series, base: f64) -> f64 {
    s.width
        .filter(|w| w.is_finite())
        .map_or((base / 8.0).max(1.5), |w| w.clamp(0.5, 50.0))
}

/// One series: its runs mapped to pixels, clipped to the frame, dashed, then its markers.
fn draw_series<DB: plotters::prelude::DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lay: &Layout,
    s: &Series,
    index: usize,
    runs: &[Vec<(f64, f64)>],
    base: f64,
) -> Result<(), PlotError> {
    let color = s.color.unwrap_or_else(|| Rgb::palette(index));
    let to_px = |&(x, y): &(f64, f64)| Some((lay.xmap.to_px(x)?, lay.ymap.to_px(y)?));
    let f = &lay.frame;
    // Last pixel's far edge: a point mapped onto the last pixel is inside.
    let bx = (
        f.x0 as f64,
        f.y0 as f64,
        f.x1 as f64 - 1e-9,
        f.y1 as f64 - 1e-9,
    );
    let lw = line_width(s, base);
    if s.line != LineStyle::None {
        let dash = dash_pattern(s.line, lw, base);
        for run in runs {
            let px: Vec<Pt> = run.iter().filter_map(to_px).collect();
            for part in clip_polyline(&px, bx) {
                for piece in dash_polyline(&part, &dash) {
                    draw_piece(root, &piece, color, lw)?;
                }
            }
        }
    }
    if s.marker != Marker::None {
        for p in runs
            .iter()
            .flatten()
            .step_by(s.marker_every.max(1))
            .filter_map(to_px)
        {
            if f.contains(p.0.floor() as i64, p.1.floor() as i64) {
                draw_marker(root, s, p, color, base)?;
            }
        }
    }
    Ok(())
}

/// Strokes a polyline given in pixels (each point stands for the pixel it falls in).
fn draw_piece<DB: plotters::prelude::DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    pts: &[Pt],
    color: Rgb,
    width_px: f64,
) -> Result<(), PlotError> {
    let mut ip: Vec<(i32, i32)> = Vec::with_capacity(pts.len());
    for p in pts {
        let q = (p.0.floor() as i32, p.1.floor() as i32);
        if ip.last() != Some(&q) {
            ip.push(q);
        }
    }
    let stroke = width_px.round().max(1.0) as u32;
    let dot = |c: (i32, i32), r: u32| root.draw(&Circle::new(c, r, rgb(color).filled()));
    if let [c] = ip[..] {
        // A lone point (or a piece shorter than a pixel) is a dot as wide as the line.
        return dot(c, stroke / 2).map_err(drawing);
    }
    let style = ShapeStyle {
        color: rgb(color).to_rgba(),
        filled: false,
        stroke_width: stroke,
    };
    // Plotters outlines a thick polyline with mitred joins; at a turn sharper than 120° the
    // inner offset lines meet far away and the outline spikes across the image (noisy data
    // does this), so the line is cut there and the pieces meet in a round dot.
    let mut start = 0;
    for k in 1..ip.len() {
        let sharp = k + 1 < ip.len() && sharp_turn(ip[k - 1], ip[k], ip[k + 1]);
        if sharp || k + 1 == ip.len() {
            root.draw(&PathElement::new(ip[start..=k].to_vec(), style))
                .map_err(drawing)?;
            if sharp && stroke >= 2 {
                dot(ip[k], stroke / 2).map_err(drawing)?;
            }
            start = k;
        }
    }
    Ok(())
}

/// Whether the polyline a → b → c turns by more than 120° at b.
fn sharp_turn(a: (i32, i32), b: (i32, i32), c: (i32, i32)) -> bool {
    let (u, v) = (
        (f64::from(b.0 - a.0), f64::from(b.1 - a.1)),
        (f64::from(c.0 - b.0), f64::from(c.1 - b.1)),
    );
    let dot = u.0 * v.0 + u.1 * v.1;
    dot < -0.5 * (u.0.hypot(u.1) * v.0.hypot(v.1))
}

/// The series' marker centred at pixel position `c`.
fn draw_marker<DB: plotters::prelude::DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &Series,
    c: Pt,
    color: Rgb,
    base: f64,
) -> Result<(), PlotError> {
    let r = s
        .marker_size
        .filter(|r| r.is_finite())
        .map_or(base * 0.28, |r| r.clamp(1.0, 100.0));
    let (cx, cy) = (c.0.floor(), c.1.floor());
    let at = |dx: f64, dy: f64| ((cx + dx).round() as i32, (cy + dy).round() as i32);
    let fill = rgb(color).filled();
    let poly = |pts: Vec<(i32, i32)>| root.draw(&Polygon::new(pts, fill)).map_err(drawing);
    let bar_w = (line_width(s, base) * 1.2).max(2.0);
    let bars = |a: [Pt; 2], b: [Pt; 2]| -> Result<(), PlotError> {
        for seg in [a, b] {
            let pts = seg.map(|(dx, dy)| (cx + dx + 0.5, cy + dy + 0.5));
            draw_piece(root, &pts, color, bar_w)?;
        }
        Ok(())
    };
    match s.marker {
        Marker::None => Ok(()),
        Marker::Circle => root
            .draw(&Circle::new(at(0.0, 0.0), r.round() as u32, fill))
            .map_err(drawing),
        Marker::Square => {
            // Filled rectangles end before their second corner.
            let (h, (x1, y1)) = (r * 0.85, at(r * 0.85, r * 0.85));
            root.draw(&Rectangle::new([at(-h, -h), (x1 + 1, y1 + 1)], fill))
                .map_err(drawing)
        }
        Marker::Triangle => {
            let (rr, s3) = (r * 1.15, 3f64.sqrt() * 0.5);
            poly(vec![
                at(0.0, -rr),
                at(rr * s3, rr * 0.5),
                at(-rr * s3, rr * 0.5),
            ])
        }
        Marker::Diamond => {
            let d = r * 1.13;
            poly(vec![at(0.0, -d), at(d, 0.0), at(0.0, d), at(-d, 0.0)])
        }
        Marker::Cross => {
            let k = r * std::f64::consts::FRAC_1_SQRT_2;
            bars([(-k, -k), (k, k)], [(-k, k), (k, -k)])
        }
        Marker::Plus => bars([(-r, 0.0), (r, 0.0)], [(0.0, -r), (0.0, r)]),
    }
}

/// Black frame `w` px wide just outside the plot area, on all four sides.
fn draw_frame<DB: plotters::prelude::DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    f: &PxRect,
    w: i32,
) -> Result<(), PlotError> {
    let style = ShapeStyle {
        color: RGBColor(0, 0, 0).to_rgba(),
        filled: false,
        stroke_width: w.max(1) as u32,
    };
    let (x0, y0, x1, y1) = (f.x0 as i32, f.y0 as i32, f.x1 as i32, f.y1 as i32);
    root.draw(&Rectangle::new([(x0 - 1, y0 - 1), (x1, y1)], style))
        .map_err(drawing)
}
