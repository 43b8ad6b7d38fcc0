//! Text set in the bundled DejaVu Sans (see `fonts/LICENSE-DejaVu.txt`): measuring, the line
//! box, word wrapping, glyph rasterising for [`crate::backend::Canvas`], and drawing
//! (multi-line) labels through plotters' text elements.

use crate::PlotError;
use crate::color::Rgb;
use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend, IntoFont, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontFamily, FontTransform, RGBColor, TextStyle};
use std::sync::OnceLock;

static FONT_BYTES: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// Top of the line box above the baseline, in font sizes: DejaVu's ascenders, θ, ⁻¹ and
/// brackets reach 0.65 of the size (`ab_glyph` scales ascent − descent to the size).
const ASCENT: f64 = 0.66;
/// Bottom of the line box below the baseline (descenders reach 0.18 of the size).
const DESCENT: f64 = 0.19;
/// Baseline-to-baseline distance of stacked lines, in font sizes.
pub(crate) const LINE_PITCH: f64 = 1.2;

fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).ok())
        .as_ref()
}

/// Checks that the bundled font can be used; called before anything is laid out.
pub(crate) fn ensure_font() -> Result<(), PlotError> {
    font().map(|_| ()).ok_or_else(|| {
        PlotError::Drawing("the bundled font fonts/DejaVuSans.ttf does not parse".into())
    })
}

/// Height of one line's box (ink of ascenders to descenders) in px.
pub(crate) fn line_box(px: f64) -> f64 {
    (ASCENT + DESCENT) * px
}

/// Advance width of one line in pixels, with kerning.
pub(crate) fn width(text: &str, px: f64) -> f64 {
    let Some(f) = font() else { return 0.0 };
    let f = f.as_scaled(PxScale::from(px as f32));
    let (mut caret, mut prev) = (0.0f32, None);
    for ch in text.chars() {
        let id = f.glyph_id(ch);
        if let Some(p) = prev {
            caret += f.kern(p, id);
        }
        caret += f.h_advance(id);
        prev = Some(id);
    }
    f64::from(caret)
}

/// Calls `put(x, y, coverage)` for every pixel of `text` set with its line box's top-left
/// corner at `origin` (pixel offsets, relative to the anchor the caller adds).
pub(crate) fn rasterise(
    text: &str,
    px: f64,
    origin: (f64, f64),
    mut put: impl FnMut(i32, i32, f32),
) {
    let Some(font) = font() else { return };
    let scale = PxScale::from(px as f32);
    let f = font.as_scaled(scale);
    let baseline = (origin.1 + ASCENT * px) as f32;
    let (mut caret, mut prev) = (origin.0 as f32, None);
    for ch in text.chars() {
        let id = f.glyph_id(ch);
        if let Some(p) = prev {
            caret += f.kern(p, id);
        }
        let glyph = id.with_scale_and_position(scale, point(caret, baseline));
        caret += f.h_advance(id);
        prev = Some(id);
        if let Some(outline) = font.outline_glyph(glyph) {
            let b = outline.px_bounds();
            outline.draw(|gx, gy, c| {
                put(b.min.x as i32 + gx as i32, b.min.y as i32 + gy as i32, c);
            });
        }
    }
}

/// Height of `lines` stacked lines.
pub(crate) fn block_height(lines: usize, px: f64) -> f64 {
    if lines == 0 {
        return 0.0;
    }
    (lines - 1) as f64 * LINE_PITCH * px + line_box(px)
}

/// Widest line of a `\n`-separated text.
pub(crate) fn block_width(text: &str, px: f64) -> f64 {
    text.split('\n').map(|l| width(l, px)).fold(0.0, f64::max)
}

/// Splits `text` into lines no wider than `max_w` px: at its `\n`s, then between words, and
/// inside a word only when the word alone is too wide.
pub(crate) fn wrap(text: &str, px: f64, max_w: f64) -> Vec<String> {
    let mut out = Vec::new();
    for para in text.split('\n') {
        let mut line = String::new();
        for word in para.split(' ').filter(|w| !w.is_empty()) {
            let candidate = if line.is_empty() {
                word.to_string()
            } else {
                format!("{line} {word}")
            };
            if width(&candidate, px) <= max_w {
                line = candidate;
                continue;
            }
            if !line.is_empty() {
                out.push(std::mem::take(&mut line));
            }
            line = break_word(word, px, max_w, &mut out);
        }
        out.push(line);
    }
    out
}

/// Pushes full-width pieces of an over-long word to `out` and returns its remainder.
fn break_word(word: &str, px: f64, max_w: f64, out: &mut Vec<String>) -> String {
    let mut piece = String::new();
    for ch in word.chars() {
        piece.push(ch);
        if width(&piece, px) > max_w && piece.chars().count() > 1 {
            piece.pop();
            out.push(std::mem::take(&mut piece));
            piece.push(ch);
        }
    }
    piece
}

/// Plotters text style of the bundled font (the family name is not looked up: the
/// [`crate::backend::Canvas`] sets all text itself).
pub(crate) fn style(px: f64, color: Rgb) -> TextStyle<'static> {
    (FontFamily::SansSerif, px)
        .into_font()
        .color(&RGBColor(color.0, color.1, color.2))
}

/// Horizontal anchor of a text line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HAlign {
    Left,
    Center,
    Right,
}

/// Draws `text` (`\n` splits lines) with the top of the first line box at `y_top`.
pub(crate) fn draw_lines<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    px: f64,
    (x, y_top): (f64, f64),
    align: HAlign,
    color: Rgb,
) -> Result<(), PlotError> {
    let h = match align {
        HAlign::Left => HPos::Left,
        HAlign::Center => HPos::Center,
        HAlign::Right => HPos::Right,
    };
    let st = style(px, color).pos(Pos::new(h, VPos::Top));
    for (k, line) in text.split('\n').enumerate() {
        let y = y_top + k as f64 * LINE_PITCH * px;
        area.draw(&Text::new(line, (x.round() as i32, y.round() as i32), &st))
            .map_err(crate::error::drawing)?;
    }
    Ok(())
}

/// Draws one line reading bottom to top, centred on `cy`, the line box's top (the glyph
/// tops) at `x_left`.
pub(crate) fn draw_vertical<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    px: f64,
    (x_left, cy): (f64, f64),
    color: Rgb,
) -> Result<(), PlotError> {
    let st = style(px, color)
        .transform(FontTransform::Rotate270)
        .pos(Pos::new(HPos::Center, VPos::Top));
    area.draw(&Text::new(
        text,
        (x_left.round() as i32, cy.round() as i32),
        &st,
    ))
    .map_err(crate::error::drawing)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::Canvas;
    use plotters::prelude::{BitMapBackend, IntoDrawingArea};

    /// Bounding box (x0, y0, x1, y1) of the dark pixels after drawing with `draw`.
    fn ink_box(w: u32, h: u32, draw: impl Fn(&DrawingArea<Canvas<'_>, Shift>)) -> [i32; 4] {
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let area = Canvas(BitMapBackend::with_buffer(&mut buf, (w, h))).into_drawing_area();
            draw(&area);
            area.present().unwrap();
        }
        let mut b = [i32::MAX, i32::MAX, -1, -1];
        for y in 0..h as i32 {
            for x in 0..w as i32 {
                if buf[((y * w as i32 + x) * 3) as usize] < 160 {
                    b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
                }
            }
        }
        b
    }

    #[test]
    fn bundled_font_has_the_symbols_plots_use() {
        let f = font().expect("bundled font parses");
        for ch in [
            'β', '−', '₀', '⁻', '¹', '°', 'θ', 'λ', 'µ', '×', '²', 'σ', '·',
        ] {
            assert_ne!(f.glyph_id(ch).0, 0, "glyph for {ch:?} missing");
        }
    }

    #[test]
    fn ink_fills_the_line_box() {
        let px = 40.0;
        let [x0, y0, x1, y1] = ink_box(400, 200, |a| {
            draw_lines(a, "Bgθ[⁻¹]", px, (20.0, 60.0), HAlign::Left, Rgb::BLACK).unwrap()
        });
        let bottom = 60.0 + line_box(px);
        assert!((f64::from(y0) - 60.0).abs() <= 2.0, "top {y0}");
        assert!(
            (f64::from(y1) - bottom).abs() <= 2.0,
            "bottom {y1} vs {bottom}"
        );
        // The first glyph starts at its side bearing (a few px), not left of the anchor.
        assert!((21..=26).contains(&x0), "left {x0}");
        assert!(f64::from(x1) <= 20.0 + width("Bgθ[⁻¹]", px), "right {x1}");
        // Rotated: glyph tops face left, the text is centred on cy.
        let [x0, y0, x1, y1] = ink_box(200, 400, |a| {
            draw_vertical(a, "BRDF [sr⁻¹]", px, (50.0, 200.0), Rgb::BLACK).unwrap()
        });
        assert!((x0 - 50).abs() <= 2, "left {x0}");
        assert!(f64::from(x1) <= 50.0 + line_box(px) + 1.0, "right {x1}");
        assert!(
            (f64::from(y0 + y1) / 2.0 - 200.0).abs() <= 4.0,
            "centre {y0}..{y1}"
        );
        let w = width("BRDF [sr⁻¹]", px);
        assert!(
            (f64::from(y1 - y0) - w).abs() < 0.1 * w,
            "{} vs {w}",
            y1 - y0
        );
    }

    #[test]
    fn glyphs_keep_their_spacing() {
        // "1" has a wide left side bearing; ignoring it (as plotters' own text path does)
        // puts the digits of "0.012" at uneven gaps. Here each glyph's ink starts where the
        // caret plus its bearing says, so the gap "0"→"1" equals the gap "1"→"1".
        let px = 40.0;
        let ink_columns = |s: &str| {
            let mut buf = vec![255u8; 400 * 80 * 3];
            {
                let area =
                    Canvas(BitMapBackend::with_buffer(&mut buf, (400, 80))).into_drawing_area();
                draw_lines(&area, s, px, (10.0, 10.0), HAlign::Left, Rgb::BLACK).unwrap();
            }
            (0..400)
                .filter(|x| (0..80).any(|y| buf[(y * 400 + x) * 3] < 128))
                .collect::<Vec<usize>>()
        };
        let first_ink = |s: &str| ink_columns(s)[0] as f64;
        for s in ["1", "01", "011", ".1"] {
            let prefix = &s[..s.len() - 1];
            let want = 10.0 + width(prefix, px) + first_ink("1") - 10.0;
            let cols = ink_columns(s);
            // The last glyph's first ink column.
            let got = cols
                .iter()
                .copied()
                .filter(|&c| c as f64 >= 10.0 + width(prefix, px) - 1.0)
                .min()
                .unwrap() as f64;
            assert!((got - want).abs() <= 1.0, "{s}: {got} vs {want}");
        }
    }

    #[test]
    fn width_grows_with_text_and_size() {
        let a = width("10", 16.0);
        assert!(width("1000", 16.0) > a * 1.8);
        assert!((width("10", 32.0) / a - 2.0).abs() < 0.05);
    }

    #[test]
    fn wrap_breaks_at_words_and_inside_over_long_words() {
        let px = 20.0;
        let title = "S280: brass, σ 0.28 µm, Lc 9.1 µm, in-plane BRDF";
        let max_w = width(title, px) * 0.45;
        let lines = wrap(title, px, max_w);
        assert!(lines.len() >= 3, "{lines:?}");
        assert!(lines.iter().all(|l| width(l, px) <= max_w), "{lines:?}");
        assert_eq!(lines.join(" "), title);
        let long = "x".repeat(60);
        let lines = wrap(&long, px, width("xxxxxxxxxx", px));
        assert_eq!(lines.len(), 6, "{lines:?}");
        assert_eq!(lines.concat(), long);
        assert_eq!(wrap("a\nb", px, 1000.0), ["a", "b"]);
        // Narrower than one glyph: one glyph a line, never an empty loop.
        assert_eq!(wrap("abc", px, 1.0), ["a", "b", "c"]);
    }
}
