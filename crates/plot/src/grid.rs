//! Labelled image grids (rows = models, columns = views), like the paper's Fig. 1 and 4.

use crate::PlotError;
use crate::color::Rgb;
use crate::plot::MAX_PIXELS;
use crate::raster::{PxRect, fill_rect};
use crate::text::{self, HAlign};
use image::RgbImage;
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
        let cw = self
            .cells
            .iter()
            .flatten()
            .map(|c| u64::from(c.width()))
            .max()
            .unwrap_or(0);
        let ch = self
            .cells
            .iter()
            .flatten()
            .map(|c| u64::from(c.height()))
            .max()
            .unwrap_or(0);
        let base = self
            .font_px
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or_else(|| (ch as f64 / 12.0).clamp(12.0, 24.0));
        let title_px = base * 1.25;
        let pad = (base * 0.6).round();
        let gap = (base * 0.35).round().max(2.0);
        let lines_h =
            |s: &str, px: f64| s.split('\n').count() as f64 * text::measure("Ag", px).height;
        let lines_w = |s: &str, px: f64| {
            s.split('\n')
                .map(|l| text::measure(l, px).width)
                .fold(0.0, f64::max)
        };

        let row_w = self
            .row_labels
            .iter()
            .take(self.rows)
            .map(|l| lines_w(l, base))
            .fold(0.0, f64::max);
        let row_col = if row_w > 0.0 { row_w + pad } else { 0.0 };
        let col_h = self
            .col_labels
            .iter()
            .take(self.cols)
            .map(|l| lines_h(l, base))
            .fold(0.0, f64::max);
        let col_row = if col_h > 0.0 { col_h + gap } else { 0.0 };
        let title_h = if self.title.is_empty() {
            0.0
        } else {
            lines_h(&self.title, title_px) + pad * 0.5
        };
        let cap_h = self
            .captions
            .iter()
            .flatten()
            .map(|c| lines_h(c, base * 0.9))
            .fold(0.0, f64::max);
        let cap_row = if cap_h > 0.0 { cap_h + gap * 0.5 } else { 0.0 };

        let (cols, rows) = (self.cols as u64, self.rows as u64);
        let (gap_u, pad_u) = (gap as u64, pad as u64);
        let width = pad_u * 2 + row_col.ceil() as u64 + cols * cw + (cols - 1) * gap_u;
        let height = pad_u * 2
            + (title_h + col_row).ceil() as u64
            + rows * (ch + cap_row.ceil() as u64)
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
        let (width, height) = (width as u32, height as u32);
        let mut img = RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));

        if !self.title.is_empty() {
            draw_lines(
                &mut img,
                &self.title,
                title_px,
                f64::from(width) * 0.5,
                pad,
                HAlign::Center,
            );
        }
        let x_cells = pad + row_col.ceil();
        let y_cells = pad + (title_h + col_row).ceil();
        let mut slots = Vec::with_capacity(self.cells.len());
        for r in 0..self.rows {
            for c in 0..self.cols {
                let x0 = x_cells as i64 + c as i64 * (cw + gap_u) as i64;
                let y0 = y_cells as i64 + r as i64 * (ch + cap_row.ceil() as u64 + gap_u) as i64;
                let slot = PxRect {
                    x0,
                    y0,
                    x1: x0 + cw as i64,
                    y1: y0 + ch as i64,
                };
                let i = r * self.cols + c;
                match &self.cells[i] {
                    Some(cell) => {
                        let ox = x0 + (cw as i64 - i64::from(cell.width())) / 2;
                        let oy = y0 + (ch as i64 - i64::from(cell.height())) / 2;
                        image::imageops::replace(&mut img, cell, ox, oy);
                    }
                    None => fill_rect(&mut img, slot, Rgb(235, 235, 235)),
                }
                if let Some(cap) = &self.captions[i] {
                    draw_lines(
                        &mut img,
                        cap,
                        base * 0.9,
                        (slot.x0 + slot.x1) as f64 * 0.5,
                        slot.y1 as f64 + gap * 0.5,
                        HAlign::Center,
                    );
                }
                slots.push(slot);
            }
        }
        for (c, label) in self.col_labels.iter().take(self.cols).enumerate() {
            let s = slots[c];
            let h = lines_h(label, base);
            draw_lines(
                &mut img,
                label,
                base,
                (s.x0 + s.x1) as f64 * 0.5,
                y_cells - gap - h,
                HAlign::Center,
            );
        }
        for (r, label) in self.row_labels.iter().take(self.rows).enumerate() {
            let s = slots[r * self.cols];
            let h = lines_h(label, base);
            draw_lines(
                &mut img,
                label,
                base,
                x_cells - pad,
                (s.y0 + s.y1) as f64 * 0.5 - h * 0.5,
                HAlign::Right,
            );
        }
        Ok((
            img,
            GridLayout {
                slots,
                width,
                height,
            },
        ))
    }
}

fn draw_lines(img: &mut RgbImage, s: &str, px: f64, x: f64, y: f64, align: HAlign) {
    let lh = text::measure("Ag", px).height;
    for (k, line) in s.split('\n').enumerate() {
        text::draw(img, line, px, x, y + lh * k as f64, align, Rgb::BLACK);
    }
}
