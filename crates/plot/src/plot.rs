//! The line-plot figure: layout, axes, series, legend, title.

use crate::axis::{AxisMap, Scale, auto_range};
use crate::color::Rgb;
use crate::raster::{Mask, PxRect, fill_rect};
use crate::text::{self, HAlign};
use crate::ticks::Tick;
use crate::{Axis, LineStyle, Marker, PlotError, Series};
use image::RgbImage;
use std::path::Path;

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

struct Sizes {
    tick: f64,
    label: f64,
    title: f64,
    legend: f64,
    pad: f64,
    frame_w: f64,
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
        let (xr, yr) = (
            self.shown_range(&self.x, "x", &paths, 0)?,
            self.shown_range(&self.y, "y", &paths, 1)?,
        );

        let base = self
            .font_px
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or_else(|| {
                (f64::from(height) / 34.0)
                    .min(f64::from(width) / 40.0)
                    .clamp(12.0, 26.0)
            });
        let sz = Sizes {
            tick: base,
            label: base * 1.1,
            title: base * 1.3,
            legend: base * 0.95,
            pad: (base * 0.6).round(),
            frame_w: (base / 14.0).max(1.0).round(),
        };
        let min_w = (base * 14.0) as u32;
        let min_h = (base * 11.0) as u32;
        if width < min_w || height < min_h {
            return Err(PlotError::TooSmall {
                width,
                height,
                min_width: min_w,
                min_height: min_h,
            });
        }
        if u64::from(width) * u64::from(height) > MAX_PIXELS {
            return Err(PlotError::TooLarge {
                width,
                height,
                max_pixels: MAX_PIXELS,
            });
        }

        // Tick density follows the space roughly available before the exact layout is known.
        let xt = self.x.ticks(
            xr.0,
            xr.1,
            ((f64::from(width) * 0.75) / (base * 6.0)).clamp(2.0, 10.0) as usize,
        );
        let yt = self.y.ticks(
            yr.0,
            yr.1,
            ((f64::from(height) * 0.7) / (base * 3.2)).clamp(2.0, 10.0) as usize,
        );

        let legend_box = self.legend_size(&sz);
        let ytick_w = yt
            .iter()
            .filter_map(|t| t.label.as_deref())
            .map(|l| text::measure(l, sz.tick).width)
            .fold(0.0, f64::max);
        let xtick_last_w = xt
            .iter()
            .rev()
            .find_map(|t| t.label.as_deref())
            .map_or(0.0, |l| text::measure(l, sz.tick).width);
        let line_h = |px: f64| text::measure("Ag", px).height;
        let tick_len = (base * 0.45).round();

        let top = sz.pad
            + if self.title.is_empty() {
                line_h(sz.tick) * 0.5
            } else {
                line_h(sz.title) + sz.pad
            };
        let bottom = sz.pad
            + line_h(sz.tick)
            + tick_len * 0.5
            + sz.pad * 0.5
            + if self.x.label.is_empty() {
                0.0
            } else {
                line_h(sz.label)
            };
        let left = sz.pad
            + if self.y.label.is_empty() {
                0.0
            } else {
                line_h(sz.label) + sz.pad * 0.5
            }
            + ytick_w
            + sz.pad * 0.6;
        let mut right = sz.pad + (xtick_last_w * 0.5).max(sz.pad);
        if self.legend == Legend::Outside {
            right = sz.pad + legend_box.0 + sz.pad;
        }
        let frame = PxRect {
            x0: left.round() as i64,
            y0: top.round() as i64,
            x1: (f64::from(width) - right).round() as i64,
            y1: (f64::from(height) - bottom).round() as i64,
        };
        if frame.width() < (base * 5.0) as i64 || frame.height() < (base * 4.0) as i64 {
            let need_w = width as i64 + (base * 5.0) as i64 - frame.width();
            let need_h = height as i64 + (base * 4.0) as i64 - frame.height();
            return Err(PlotError::TooSmall {
                width,
                height,
                min_width: need_w.max(0) as u32,
                min_height: need_h.max(0) as u32,
            });
        }
        let xmap = AxisMap {
            scale: self.x.scale,
            lo: xr.0,
            hi: xr.1,
            px_lo: frame.x0 as f64,
            px_hi: frame.x1 as f64,
        };
        let ymap = AxisMap {
            scale: self.y.scale,
            lo: yr.0,
            hi: yr.1,
            px_lo: frame.y1 as f64,
            px_hi: frame.y0 as f64,
        };

        let mut img = RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));
        if self.grid {
            draw_grid(&mut img, &frame, &xt, &yt, &xmap, &ymap);
        }
        for (i, (s, segs)) in self.series.iter().zip(&paths).enumerate() {
            let color = s.color.unwrap_or_else(|| Rgb::palette(i));
            let mut mask = Mask::new(frame);
            let width_px = s.width.unwrap_or((base / 8.0).max(1.5));
            let dash = dash_pattern(s.line, width_px, base);
            for seg in segs {
                let px: Vec<(f64, f64)> = seg
                    .iter()
                    .filter_map(|&(x, y)| Some((xmap.to_px(x)?, ymap.to_px(y)?)))
                    .collect();
                if s.line != LineStyle::None {
                    mask.stroke_polyline(&px, width_px, &dash);
                }
            }
            if s.marker != Marker::None {
                let r = s.marker_size.unwrap_or(base * 0.28);
                let pts = segs.iter().flatten().step_by(s.marker_every.max(1));
                for &(x, y) in pts {
                    if let (Some(px), Some(py)) = (xmap.to_px(x), ymap.to_px(y)) {
                        mask.stamp_marker((px, py), r, s.marker, width_px);
                    }
                }
            }
            mask.composite(&mut img, color);
        }
        draw_frame_and_ticks(&mut img, &frame, &xt, &yt, &xmap, &ymap, &sz, tick_len);

        // Axis labels and title.
        let xl_y = frame.y1 as f64 + tick_len * 0.5 + line_h(sz.tick) + sz.pad * 0.5;
        let fx_mid = (frame.x0 + frame.x1) as f64 * 0.5;
        text::draw(
            &mut img,
            &self.x.label,
            sz.label,
            fx_mid,
            xl_y,
            HAlign::Center,
            Rgb::BLACK,
        );
        let fy_mid = (frame.y0 + frame.y1) as f64 * 0.5;
        text::draw_vertical(
            &mut img,
            &self.y.label,
            sz.label,
            sz.pad,
            fy_mid,
            Rgb::BLACK,
        );
        if !self.title.is_empty() {
            text::draw(
                &mut img,
                &self.title,
                sz.title,
                fx_mid,
                sz.pad,
                HAlign::Center,
                Rgb::BLACK,
            );
        }
        if self.legend != Legend::Hidden {
            self.draw_legend(&mut img, &frame, legend_box, &sz, base, width);
        }
        Ok((
            img,
            PlotReport {
                frame,
                x: xmap,
                y: ymap,
                skipped,
            },
        ))
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

    fn legend_size(&self, sz: &Sizes) -> (f64, f64) {
        if self.legend == Legend::Hidden {
            return (0.0, 0.0);
        }
        let label_w = self
            .series
            .iter()
            .map(|s| text::measure(&s.label, sz.legend).width)
            .fold(0.0, f64::max);
        let row = text::measure("Ag", sz.legend).height * 1.15;
        let sample = sz.legend * 2.4;
        (
            sz.pad * 2.0 + sample + sz.pad * 0.6 + label_w,
            sz.pad + row * self.series.len() as f64,
        )
    }

    fn draw_legend(
        &self,
        img: &mut RgbImage,
        frame: &PxRect,
        (bw, bh): (f64, f64),
        sz: &Sizes,
        base: f64,
        width: u32,
    ) {
        let inset = sz.pad;
        let (x0, y0) = match self.legend {
            Legend::TopRight => (frame.x1 as f64 - inset - bw, frame.y0 as f64 + inset),
            Legend::TopLeft => (frame.x0 as f64 + inset, frame.y0 as f64 + inset),
            Legend::BottomRight => (frame.x1 as f64 - inset - bw, frame.y1 as f64 - inset - bh),
            Legend::BottomLeft => (frame.x0 as f64 + inset, frame.y1 as f64 - inset - bh),
            Legend::Outside => (f64::from(width) - sz.pad - bw, frame.y0 as f64),
            Legend::Hidden => return,
        };
        let r = PxRect {
            x0: x0.round() as i64,
            y0: y0.round() as i64,
            x1: (x0 + bw).round() as i64,
            y1: (y0 + bh).round() as i64,
        };
        fill_rect(img, r, Rgb(150, 150, 150));
        fill_rect(
            img,
            PxRect {
                x0: r.x0 + 1,
                y0: r.y0 + 1,
                x1: r.x1 - 1,
                y1: r.y1 - 1,
            },
            Rgb::WHITE,
        );
        let row = text::measure("Ag", sz.legend).height * 1.15;
        let sample = sz.legend * 2.4;
        for (i, s) in self.series.iter().enumerate() {
            let color = s.color.unwrap_or_else(|| Rgb::palette(i));
            let top = y0 + sz.pad * 0.5 + row * i as f64;
            let cy = top + row * 0.5;
            let sx0 = x0 + sz.pad;
            let mut mask = Mask::new(r);
            let width_px = s.width.unwrap_or((base / 8.0).max(1.5));
            if s.line != LineStyle::None {
                mask.stroke_polyline(
                    &[(sx0, cy), (sx0 + sample, cy)],
                    width_px,
                    &dash_pattern(s.line, width_px, base * 0.7),
                );
            }
            if s.marker != Marker::None {
                mask.stamp_marker(
                    (sx0 + sample * 0.5, cy),
                    s.marker_size.unwrap_or(base * 0.28),
                    s.marker,
                    width_px,
                );
            }
            mask.composite(img, color);
            let th = text::measure(&s.label, sz.legend).height;
            text::draw(
                img,
                &s.label,
                sz.legend,
                sx0 + sample + sz.pad * 0.6,
                cy - th * 0.5,
                HAlign::Left,
                Rgb::BLACK,
            );
        }
    }
}

fn dash_pattern(style: LineStyle, w: f64, base: f64) -> Vec<f64> {
    match style {
        LineStyle::Solid | LineStyle::None => Vec::new(),
        LineStyle::Dashed => vec![base * 0.7, base * 0.4],
        LineStyle::Dotted => vec![w * 1.2, w * 1.8],
        LineStyle::DashDot => vec![base * 0.7, base * 0.3, w * 1.2, base * 0.3],
    }
}

fn draw_grid(img: &mut RgbImage, f: &PxRect, xt: &[Tick], yt: &[Tick], xm: &AxisMap, ym: &AxisMap) {
    for t in xt.iter().filter(|t| t.label.is_some()) {
        if let Some(px) = xm.to_px(t.value) {
            let x = px.round() as i64;
            if x > f.x0 && x < f.x1 - 1 {
                fill_rect(
                    img,
                    PxRect {
                        x0: x,
                        y0: f.y0,
                        x1: x + 1,
                        y1: f.y1,
                    },
                    Rgb::GRID,
                );
            }
        }
    }
    for t in yt.iter().filter(|t| t.label.is_some()) {
        if let Some(py) = ym.to_px(t.value) {
            let y = py.round() as i64;
            if y > f.y0 && y < f.y1 - 1 {
                fill_rect(
                    img,
                    PxRect {
                        x0: f.x0,
                        y0: y,
                        x1: f.x1,
                        y1: y + 1,
                    },
                    Rgb::GRID,
                );
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn draw_frame_and_ticks(
    img: &mut RgbImage,
    f: &PxRect,
    xt: &[Tick],
    yt: &[Tick],
    xm: &AxisMap,
    ym: &AxisMap,
    sz: &Sizes,
    tick_len: f64,
) {
    let w = sz.frame_w as i64;
    let k = Rgb::BLACK;
    fill_rect(
        img,
        PxRect {
            x0: f.x0 - w,
            y0: f.y0 - w,
            x1: f.x1 + w,
            y1: f.y0,
        },
        k,
    );
    fill_rect(
        img,
        PxRect {
            x0: f.x0 - w,
            y0: f.y1,
            x1: f.x1 + w,
            y1: f.y1 + w,
        },
        k,
    );
    fill_rect(
        img,
        PxRect {
            x0: f.x0 - w,
            y0: f.y0,
            x1: f.x0,
            y1: f.y1,
        },
        k,
    );
    fill_rect(
        img,
        PxRect {
            x0: f.x1,
            y0: f.y0,
            x1: f.x1 + w,
            y1: f.y1,
        },
        k,
    );
    let tl = tick_len as i64;
    let line_h = text::measure("Ag", sz.tick).height;
    // Ticks point inwards on all four sides, as in most physics journals.
    for t in xt {
        let Some(px) = xm.to_px(t.value) else {
            continue;
        };
        let x = px.round() as i64;
        if x < f.x0 - 1 || x > f.x1 + 1 {
            continue;
        }
        let len = if t.label.is_some() { tl } else { tl / 2 };
        fill_rect(
            img,
            PxRect {
                x0: x - w / 2,
                y0: f.y1 - len,
                x1: x - w / 2 + w,
                y1: f.y1,
            },
            k,
        );
        fill_rect(
            img,
            PxRect {
                x0: x - w / 2,
                y0: f.y0,
                x1: x - w / 2 + w,
                y1: f.y0 + len,
            },
            k,
        );
        if let Some(l) = &t.label {
            text::draw(
                img,
                l,
                sz.tick,
                px,
                f.y1 as f64 + w as f64 + tick_len * 0.3,
                HAlign::Center,
                k,
            );
        }
    }
    for t in yt {
        let Some(py) = ym.to_px(t.value) else {
            continue;
        };
        let y = py.round() as i64;
        if y < f.y0 - 1 || y > f.y1 + 1 {
            continue;
        }
        let len = if t.label.is_some() { tl } else { tl / 2 };
        fill_rect(
            img,
            PxRect {
                x0: f.x0,
                y0: y - w / 2,
                x1: f.x0 + len,
                y1: y - w / 2 + w,
            },
            k,
        );
        fill_rect(
            img,
            PxRect {
                x0: f.x1 - len,
                y0: y - w / 2,
                x1: f.x1,
                y1: y - w / 2 + w,
            },
            k,
        );
        if let Some(l) = &t.label {
            text::draw(
                img,
                l,
                sz.tick,
                f.x0 as f64 - w as f64 - sz.pad * 0.6,
                py - line_h * 0.5,
                HAlign::Right,
                k,
            );
        }
    }
}
