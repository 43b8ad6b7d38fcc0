//! Text rendering with the bundled DejaVu Sans font (see `fonts/LICENSE-DejaVu.txt`).

use crate::color::Rgb;
use crate::raster::{Mask, PxRect};
use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use image::RgbImage;
use std::sync::OnceLock;

static FONT_BYTES: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    FONT.get_or_init(|| {
        // The font is compiled in and checked by a unit test, so this cannot fail at run time.
        FontRef::try_from_slice(FONT_BYTES).expect("bundled DejaVuSans.ttf parses")
    })
}

/// Size of a laid-out line of text in pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TextSize {
    pub width: f64,
    /// Ascent + |descent|: the line box height.
    pub height: f64,
    pub ascent: f64,
}

pub(crate) fn measure(text: &str, px: f64) -> TextSize {
    let f = font().as_scaled(PxScale::from(px as f32));
    let mut caret = 0.0f32;
    let mut prev = None;
    for ch in text.chars() {
        let id = f.glyph_id(ch);
        if let Some(p) = prev {
            caret += f.kern(p, id);
        }
        caret += f.h_advance(id);
        prev = Some(id);
    }
    TextSize {
        width: f64::from(caret),
        height: f64::from(f.ascent() - f.descent()),
        ascent: f64::from(f.ascent()),
    }
}

/// Rasterises `text` with its line box's top-left corner at (x, y) into a fresh mask.
fn rasterise(text: &str, px: f64, x: f64, y: f64) -> Mask {
    let size = measure(text, px);
    let rect = PxRect {
        x0: x.floor() as i64 - 1,
        y0: y.floor() as i64 - 1,
        x1: (x + size.width).ceil() as i64 + 2,
        y1: (y + size.height).ceil() as i64 + 2,
    };
    let mut mask = Mask::new(rect);
    let scale = PxScale::from(px as f32);
    let f = font().as_scaled(scale);
    let mut caret = x as f32;
    let baseline = (y + size.ascent) as f32;
    let mut prev = None;
    for ch in text.chars() {
        let id = f.glyph_id(ch);
        if let Some(p) = prev {
            caret += f.kern(p, id);
        }
        let glyph = id.with_scale_and_position(scale, point(caret, baseline));
        caret += f.h_advance(id);
        prev = Some(id);
        if let Some(outline) = font().outline_glyph(glyph) {
            let b = outline.px_bounds();
            outline.draw(|gx, gy, c| {
                mask.add_at(
                    b.min.x as i64 + i64::from(gx),
                    b.min.y as i64 + i64::from(gy),
                    c,
                );
            });
        }
    }
    mask
}

/// Horizontal anchor of a text line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HAlign {
    Left,
    Center,
    Right,
}

/// Draws one line of text; (x, y) is the anchor point on the line box's top edge.
pub(crate) fn draw(
    img: &mut RgbImage,
    text: &str,
    px: f64,
    x: f64,
    y: f64,
    align: HAlign,
    color: Rgb,
) {
    let w = measure(text, px).width;
    let left = match align {
        HAlign::Left => x,
        HAlign::Center => x - w * 0.5,
        HAlign::Right => x - w,
    };
    rasterise(text, px, left.round(), y.round()).composite(img, color);
}

/// Draws text rotated 90° counter-clockwise (reading bottom to top), centred vertically on
/// `cy`, with the line box's left edge (the glyph tops) at `x`.
pub(crate) fn draw_vertical(img: &mut RgbImage, text: &str, px: f64, x: f64, cy: f64, color: Rgb) {
    let size = measure(text, px);
    let mask = rasterise(text, px, 0.0, 0.0);
    let top = (cy - size.width * 0.5).round() as i64 - 1;
    mask.composite_rotated_ccw(img, x.round() as i64 - 1, top, color);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_font_has_the_symbols_plots_use() {
        for ch in ['β', '−', '₀', '⁻', '¹', '°', 'θ', 'λ', 'µ', '×', '²'] {
            assert_ne!(font().glyph_id(ch).0, 0, "glyph for {ch:?} missing");
        }
    }

    #[test]
    fn measure_grows_with_text_and_size() {
        let a = measure("10", 16.0);
        let b = measure("1000", 16.0);
        let c = measure("10", 32.0);
        assert!(b.width > a.width * 1.8);
        assert!((c.width / a.width - 2.0).abs() < 0.05);
        // ab_glyph scales so that ascent − descent equals the pixel size.
        assert!((a.height - 16.0).abs() < 0.5, "{}", a.height);
    }
}
