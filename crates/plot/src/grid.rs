//! Labelled image grids (rows = models, columns = views), like the paper's Fig. 1 and 4.

use crate::backend::Canvas;
use crate::color::Rgb;
use crate::plot::MAX_PIXELS;
use crate::text::{self, HAlign};
use crate::{PlotError, PxRect};
use image::RgbImage;
use plotters::prelude::{BitMapBackend, IntoDrawingArea};
use std::path::Path;

/// A grid of images with an optional title, row labels (left), column labels (top) and
/// per-cell captions (below each cell). Cells of different sizes are centred in slots as large
/// as the largest cell; empty cells are drawn light grey.
#[derive(Debug, Clone)]
pub struct ImageGrid {
    rows: usize,
    cols: usize,
    cells: Vec<Option<RgbImage>>,
    captions: Vec<Option<String>>,
    row_labels: Vec<String>,
    col_labels: Vec<String>,
    title: String,
    font_px: Option<f64>,
}

/// Where a rendered grid put each cell.
#[derive(Debug, Clone, PartialEq)]
pub struct GridLayout {
    /// Slot of each cell in row-major order (the image is centred inside its slot).
    pub slots: Vec<PxRect>,
    /// Total image width.
    pub width: u32,
    /// Total image height.
    pub height: u32,
}

impl ImageGrid {
    /// An empty `rows` × `cols` grid.
    pub fn new(rows: usize, cols: usize) -> ImageGrid {
        let n = rows.saturating_mul(cols);
        ImageGrid {
            rows,
            cols,
            cells: vec![None; n],
            captions: vec![None; n],
            row_labels: Vec::new(),
            col_labels: Vec::new(),
            title: String::new(),
            font_px: None,
        }
    }

    /// Title drawn centred above everything.
    pub fn title(mut self, t: impl Into<String>) -> ImageGrid {
        self.title = t.into();
        self
    }

    /// Labels left of each row (missing ones are blank; extra ones ignored). `\n` splits lines.
    pub fn row_labels<S: Into<String>>(mut self, labels: impl IntoIterator<Item = S>) -> ImageGrid {
        self.row_labels = labels.into_iter().map(Into::into).collect();
        self
    }

    /// Labels above each column (missing ones are blank; extra ones ignored). `\n` splits lines.
    pub fn col_labels<S: Into<String>>(mut self, labels: impl IntoIterator<Item = S>) -> ImageGrid {
        self.col_labels = labels.into_iter().map(Into::into).collect();
        self
    }

    /// Label font size in px (default: cell height / 12, clamped to 12..24 px).
    pub fn font_px(mut self, px: f64) -> ImageGrid {
        self.font_px = Some(px);
        self
    }

    fn index(&self, row: usize, col: usize) -> Result<usize, PlotError> {
        if row < self.rows && col < self.cols {
            Ok(row * self.cols + col)
        } else {
            Err(PlotError::CellOutOfRange {
                row,
                col,
                rows: self.rows,
                cols: self.cols,
            })
        }
    }

    /// Puts an image into cell (row, col), replacing any earlier one.
    pub fn set(&mut self, row: usize, col: usize, img: RgbImage) -> Result<(), PlotError> {
        let i = self.index(row, col)?;
        self.cells[i] = Some(img);
        Ok(())
    }

    /// Puts raw 8-bit sRGB pixels (row-major, 3 bytes per pixel) into cell (row, col).
    pub fn set_rgb8(
        &mut self,
        row: usize,
        col: usize,
        width: u32,
        height: u32,
        pixels: Vec<u8>,
    ) -> Result<(), PlotError> {
        let expected = (width as usize)
            .saturating_mul(height as usize)
            .saturating_mul(3);
        let got = pixels.len();
        match RgbImage::from_raw(width, height, pixels) {
            Some(img) if got == expected => self.set(row, col, img),
            _ => Err(PlotError::BadPixelBuffer {
                width,
                height,
                expected,
                got,
            }),
        }
    }

    /// Loads a PNG file into cell (row, col).
    pub fn load(
        &mut self,
        row: usize,
        col: usize,
        path: impl AsRef<Path>,
    ) -> Result<(), PlotError> {
        self.index(row, col)?;
        let img = crate::io::load_rgb(path)?;
        self.set(row, col, img)
    }

    /// Caption drawn under cell (row, col).
    pub fn caption(
        &mut self,
        row: usize,
        col: usize,
        text: impl Into<String>,
    ) -> Result<(), PlotError> {
        let i = self.index(row, col)?;
        self.captions[i] = Some(text.into());
        Ok(())
    }

    /// Renders and saves as PNG, atomically.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<GridLayout, PlotError> {
        let (img, layout) = self.render()?;
        crate::io::save_png(&img, path)?;
        Ok(layout)
    }

    /// Renders to an in-memory image.
    pub fn render(&self) -> Result<(RgbImage, GridLayout), PlotError> {
        if self.rows == 0 || self.cols == 0 {
            return Err(PlotError::EmptyGrid("it has zero rows or columns"));
        }
        if self.cells.iter().all(Option::is_none) {
            return Err(PlotError::EmptyGrid("no cell holds an image"));
        }
        text::ensure_font()?;
        let g = self.geometry()?;
        let (width, height) = (g.width, g.height);
        let mut img = RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));
        let mut slots = Vec::with_capacity(self.cells.len());
        for r in 0..self.rows {
            for c in 0..self.cols {
                let x0 = g.x_cells as i64 + c as i64 * (g.cw + g.gap) as i64;
                let y0 = g.y_cells as i64 + r as i64 * (g.ch + g.cap_row + g.gap) as i64;
                let slot = PxRect {
                    x0,
                    y0,
                    x1: x0 + g.cw as i64,
                    y1: y0 + g.ch as i64,
                };
                match &self.cells[r * self.cols + c] {
                    Some(cell) => {
                        let ox = x0 + (g.cw as i64 - i64::from(cell.width())) / 2;
                        let oy = y0 + (g.ch as i64 - i64::from(cell.height())) / 2;
                        image::imageops::replace(&mut img, cell, ox, oy);
                    }
                    None => {
                        let grey = RgbImage::from_pixel(g.cw as u32, g.ch as u32, rgb8(EMPTY));
                        image::imageops::replace(&mut img, &grey, x0, y0);
                    }
                }
                slots.push(slot);
            }
        }
        let mut raw = img.into_raw();
        {
            let area =
                Canvas(BitMapBackend::with_buffer(&mut raw, (width, height))).into_drawing_area();
            self.draw_labels(&area, &g, &slots)?;
            area.present().map_err(crate::error::drawing)?;
        }
        let img = RgbImage::from_raw(width, height, raw)
            .ok_or_else(|| PlotError::Drawing("pixel buffer of the wrong size".into()))?;
        Ok((
            img,
            GridLayout {
                slots,
                width,
                height,
            },
        ))
    }

    /// Sizes of slots, label bands and the whole image.
    fn geometry(&self) -> Result<Geometry, PlotError> {
        let max_dim = |f: fn(&RgbImage) -> u32| {
            self.cells
                .iter()
                .flatten()
                .map(|c| u64::from(f(c)))
                .max()
                .unwrap_or(0)
        };
        let (cw, ch) = (max_dim(RgbImage::width), max_dim(RgbImage::height));
        let base = self
            .font_px
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or_else(|| (ch as f64 / 12.0).clamp(12.0, 24.0));
        let title_px = base * 1.25;
        let pad = (base * 0.6).round();
        let gap = (base * 0.35).round().max(2.0);
        let lines_h = |s: &str, px: f64| text::block_height(s.split('\n').count(), px);
        let widest = |labels: &[String], n: usize, f: &dyn Fn(&str) -> f64| {
            labels.iter().take(n).map(|l| f(l)).fold(0.0, f64::max)
        };
        let row_w = widest(&self.row_labels, self.rows, &|l| text::block_width(l, base));
        let row_col = if row_w > 0.0 { row_w + pad } else { 0.0 };
        let col_h = widest(&self.col_labels, self.cols, &|l| lines_h(l, base));
        let col_row = if col_h > 0.0 { col_h + gap } else { 0.0 };
        let cap_h = widest(
            &self.captions.iter().flatten().cloned().collect::<Vec<_>>(),
            self.cells.len(),
            &|l| lines_h(l, base * 0.9),
        );
        let cap_row = if cap_h > 0.0 {
            (cap_h + gap * 0.5).ceil() as u64
        } else {
            0
        };
        let (cols, rows) = (self.cols as u64, self.rows as u64);
        let (gap_u, pad_u) = (gap as u64, pad as u64);
        let width = pad_u * 2 + row_col.ceil() as u64 + cols * cw + (cols - 1) * gap_u;
        // The title wraps to the grid's width, so a long one adds lines instead of being cut.
        let title = if self.title.is_empty() {
            Vec::new()
        } else {
            text::wrap(&self.title, title_px, (width as f64 - 2.0 * pad).max(1.0))
        };
        let title_h = if title.is_empty() {
            0.0
        } else {
            text::block_height(title.len(), title_px) + pad * 0.5
        };
        let height = pad_u * 2
            + (title_h + col_row).ceil() as u64
            + rows * (ch + cap_row)
            + (rows - 1) * gap_u;
        if width > u64::from(u32::MAX)
            || height > u64::from(u32::MAX)
            || width.saturating_mul(height) > MAX_PIXELS
        {
            return Err(PlotError::TooLarge {
                width: width.min(u64::from(u32::MAX)) as u32,
                height: height.min(u64::from(u32::MAX)) as u32,
                max_pixels: MAX_PIXELS,
            });
        }
        Ok(Geometry {
            width: width as u32,
            height: height as u32,
            cw,
            ch,
            cap_row,
            gap: gap_u,
            base,
            pad,
            title,
            title_px,
            x_cells: pad + row_col.ceil(),
            y_cells: pad + (title_h + col_row).ceil(),
        })
    }

    /// Title, column and row labels and captions.
    fn draw_labels<DB: plotters::prelude::DrawingBackend>(
        &self,
        area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
        g: &Geometry,
        slots: &[PxRect],
    ) -> Result<(), PlotError> {
        let (base, gap) = (g.base, g.gap as f64);
        let black = Rgb::BLACK;
        let lines_h = |s: &str, px: f64| text::block_height(s.split('\n').count(), px);
        let mid = |s: &PxRect| ((s.x0 + s.x1) as f64 * 0.5, (s.y0 + s.y1) as f64 * 0.5);
        if !g.title.is_empty() {
            let at = (f64::from(g.width) * 0.5, g.pad);
            text::draw_lines(
                area,
                &g.title.join("\n"),
                g.title_px,
                at,
                HAlign::Center,
                black,
            )?;
        }
        for (i, slot) in slots.iter().enumerate() {
            if let Some(cap) = &self.captions[i] {
                let at = (mid(slot).0, slot.y1 as f64 + gap * 0.5);
                text::draw_lines(area, cap, base * 0.9, at, HAlign::Center, black)?;
            }
        }
        for (c, label) in self.col_labels.iter().take(self.cols).enumerate() {
            let at = (mid(&slots[c]).0, g.y_cells - gap - lines_h(label, base));
            text::draw_lines(area, label, base, at, HAlign::Center, black)?;
        }
        for (r, label) in self.row_labels.iter().take(self.rows).enumerate() {
            let s = &slots[r * self.cols];
            let at = (g.x_cells - g.pad, mid(s).1 - lines_h(label, base) * 0.5);
            text::draw_lines(area, label, base, at, HAlign::Right, black)?;
        }
        Ok(())
    }
}

/// Colour of a slot no image was put in.
const EMPTY: Rgb = Rgb(235, 235, 235);

fn rgb8(c: Rgb) -> image::Rgb<u8> {
    image::Rgb([c.0, c.1, c.2])
}

/// Grid sizes in pixels, decided before anything is drawn.
struct Geometry {
    width: u32,
    height: u32,
    /// Slot (largest cell) width and height.
    cw: u64,
    ch: u64,
    /// Height of the caption band under each row.
    cap_row: u64,
    gap: u64,
    base: f64,
    pad: f64,
    title: Vec<String>,
    title_px: f64,
    /// Left and top edge of the first slot.
    x_cells: f64,
    y_cells: f64,
}
