//! Anti-aliased coverage masks: lines, dashes, marker shapes and text are first rasterised
//! into a mask (max-combined), then composited once, so overlapping pieces of one series do
//! not darken each other at joints.

use crate::color::Rgb;
use image::RgbImage;

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
}

/// Per-pixel coverage in [0, 1] over a rectangle of the target image.
pub(crate) struct Mask {
    rect: PxRect,
    cov: Vec<f32>,
}

impl Mask {
    pub(crate) fn new(rect: PxRect) -> Mask {
        let n = (rect.width().max(0) * rect.height().max(0)) as usize;
        Mask {
            rect,
            cov: vec![0.0; n],
        }
    }

    fn add(&mut self, x: i64, y: i64, c: f32) {
        let r = self.rect;
        if x < r.x0 || x >= r.x1 || y < r.y0 || y >= r.y1 || c <= 0.0 {
            return;
        }
        let i = ((y - r.y0) * r.width() + (x - r.x0)) as usize;
        if self.cov[i] < c {
            self.cov[i] = c.min(1.0);
        }
    }

    /// Rasterises a glyph-coverage callback positioned at integer offset (ox, oy).
    pub(crate) fn add_at(&mut self, x: i64, y: i64, c: f32) {
        self.add(x, y, c);
    }

    pub(crate) fn composite(&self, img: &mut RgbImage, color: Rgb) {
        let r = self.rect;
        for y in r.y0.max(0)..r.y1.min(i64::from(img.height())) {
            for x in r.x0.max(0)..r.x1.min(i64::from(img.width())) {
                let c = self.cov[((y - r.y0) * r.width() + (x - r.x0)) as usize];
                if c > 0.0 {
                    let p = img.get_pixel_mut(x as u32, y as u32);
                    p.0 = color.blend_over(p.0, c);
                }
            }
        }
    }

    /// Composites the mask turned 90° counter-clockwise, its new top-left corner at (dx, dy).
    pub(crate) fn composite_rotated_ccw(&self, img: &mut RgbImage, dx: i64, dy: i64, color: Rgb) {
        let (w, h) = (self.rect.width(), self.rect.height());
        for sy in 0..h {
            for sx in 0..w {
                let c = self.cov[(sy * w + sx) as usize];
                if c <= 0.0 {
                    continue;
                }
                // CCW rotation: source column becomes destination row counted from the bottom.
                let tx = dx + sy;
                let ty = dy + (w - 1 - sx);
                if tx >= 0 && ty >= 0 && tx < i64::from(img.width()) && ty < i64::from(img.height())
                {
                    let p = img.get_pixel_mut(tx as u32, ty as u32);
                    p.0 = color.blend_over(p.0, c);
                }
            }
        }
    }

    /// Strokes a polyline of `width` px. `dash` lists alternating on/off lengths in px (empty =
    /// solid); the pattern runs continuously along the polyline's arc length.
    pub(crate) fn stroke_polyline(&mut self, pts: &[(f64, f64)], width: f64, dash: &[f64]) {
        let hw = (width * 0.5).max(0.5);
        let mut arc = 0.0;
        if pts.len() == 1 {
            self.stroke_segment(pts[0], pts[0], hw, 0.0, dash);
        }
        for w in pts.windows(2) {
            let len = seg_len(w[0], w[1]);
            self.stroke_segment(w[0], w[1], hw, arc, dash);
            arc += len;
        }
    }

    fn stroke_segment(&mut self, a: (f64, f64), b: (f64, f64), hw: f64, arc0: f64, dash: &[f64]) {
        let pad = hw + 1.5;
        let clip = (
            self.rect.x0 as f64 - pad,
            self.rect.y0 as f64 - pad,
            self.rect.x1 as f64 + pad,
            self.rect.y1 as f64 + pad,
        );
        let Some((t0, t1)) = clip_segment(a, b, clip) else {
            return;
        };
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = (dx * dx + dy * dy).sqrt();
        let p = (a.0 + dx * t0, a.1 + dy * t0);
        let q = (a.0 + dx * t1, a.1 + dy * t1);
        let shallow = dx.abs() >= dy.abs();
        // Walk the major axis; on each step only a short band across the line can be covered.
        let (m0, m1) = if shallow {
            (p.0.min(q.0), p.0.max(q.0))
        } else {
            (p.1.min(q.1), p.1.max(q.1))
        };
        let lo = (m0 - pad).floor() as i64;
        let hi = (m1 + pad).ceil() as i64;
        let (rlo, rhi) = if shallow {
            (self.rect.x0, self.rect.x1)
        } else {
            (self.rect.y0, self.rect.y1)
        };
        let slope = if shallow {
            if dx != 0.0 { dy / dx } else { 0.0 }
        } else if dy != 0.0 {
            dx / dy
        } else {
            0.0
        };
        let band = pad * (1.0 + slope * slope).sqrt() + 1.0;
        for major in lo.max(rlo)..hi.min(rhi) {
            let mc = major as f64 + 0.5;
            // Minor coordinate of the (clamped) segment at this major position.
            let centre = if shallow {
                let t = if dx != 0.0 {
                    ((mc - a.0) / dx).clamp(t0, t1)
                } else {
                    t0
                };
                a.1 + dy * t
            } else {
                let t = if dy != 0.0 {
                    ((mc - a.1) / dy).clamp(t0, t1)
                } else {
                    t0
                };
                a.0 + dx * t
            };
            let mlo = (centre - band).floor() as i64;
            let mhi = (centre + band).ceil() as i64;
            for minor in mlo..=mhi {
                let (x, y) = if shallow {
                    (major, minor)
                } else {
                    (minor, major)
                };
                let c = (x as f64 + 0.5, y as f64 + 0.5);
                let (d, t) = dist_to_segment(c, a, b);
                let mut cov = (hw + 0.5 - d).clamp(0.0, 1.0);
                if cov > 0.0 && !dash.is_empty() && len > 0.0 {
                    let s = arc0 + t.clamp(0.0, 1.0) * len;
                    if !dash_on(s, dash) {
                        cov = 0.0;
                    }
                }
                self.add(x, y, cov as f32);
            }
        }
    }

    /// Stamps a filled marker of radius `r` px centred at `c`.
    pub(crate) fn stamp_marker(&mut self, c: (f64, f64), r: f64, shape: crate::Marker, lw: f64) {
        use crate::Marker;
        if shape == Marker::None {
            return;
        }
        if matches!(shape, Marker::Cross | Marker::Plus) {
            let k = if shape == Marker::Cross {
                r * std::f64::consts::FRAC_1_SQRT_2
            } else {
                r
            };
            let (s1, s2) = if shape == Marker::Cross {
                (
                    ((c.0 - k, c.1 - k), (c.0 + k, c.1 + k)),
                    ((c.0 - k, c.1 + k), (c.0 + k, c.1 - k)),
                )
            } else {
                (
                    ((c.0 - k, c.1), (c.0 + k, c.1)),
                    ((c.0, c.1 - k), (c.0, c.1 + k)),
                )
            };
            // Thin strokes would leave the marker centre pixel only partly covered.
            let hw = (lw * 0.6).max(1.25);
            self.stroke_segment(s1.0, s1.1, hw, 0.0, &[]);
            self.stroke_segment(s2.0, s2.1, hw, 0.0, &[]);
            return;
        }
        let ext = r * 1.5 + 2.0;
        for y in (c.1 - ext).floor() as i64..=(c.1 + ext).ceil() as i64 {
            for x in (c.0 - ext).floor() as i64..=(c.0 + ext).ceil() as i64 {
                let (px, py) = (x as f64 + 0.5 - c.0, y as f64 + 0.5 - c.1);
                let sdf = match shape {
                    Marker::Circle => (px * px + py * py).sqrt() - r,
                    Marker::Square => px.abs().max(py.abs()) - r * 0.85,
                    Marker::Diamond => {
                        (px.abs() + py.abs()) * std::f64::consts::FRAC_1_SQRT_2 - r * 0.8
                    }
                    Marker::Triangle => triangle_sdf(px, py, r * 1.15),
                    Marker::None | Marker::Cross | Marker::Plus => f64::INFINITY,
                };
                self.add(x, y, (0.5 - sdf).clamp(0.0, 1.0) as f32);
            }
        }
    }
}

/// Signed distance (approximate outside, exact enough for 1 px anti-aliasing) to an
/// upward-pointing equilateral triangle with circumradius `r` centred at the origin.
fn triangle_sdf(x: f64, y: f64, r: f64) -> f64 {
    // Three half-planes; image y grows downwards so "up" is -y.
    let s3 = 3f64.sqrt() * 0.5;
    let d_bottom = y - r * 0.5;
    let d_right = s3 * x - 0.5 * y - r * 0.5;
    let d_left = -s3 * x - 0.5 * y - r * 0.5;
    d_bottom.max(d_right).max(d_left)
}

fn seg_len(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt()
}

fn dist_to_segment(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t_raw = if l2 > 0.0 {
        ((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2
    } else {
        0.0
    };
    let t = t_raw.clamp(0.0, 1.0);
    let (cx, cy) = (a.0 + dx * t, a.1 + dy * t);
    (((p.0 - cx).powi(2) + (p.1 - cy).powi(2)).sqrt(), t_raw)
}

fn dash_on(s: f64, dash: &[f64]) -> bool {
    let period: f64 = dash.iter().sum();
    if period.is_nan() || period <= 0.0 {
        return true;
    }
    let mut m = s.rem_euclid(period);
    for (i, &len) in dash.iter().enumerate() {
        if m < len {
            return i % 2 == 0;
        }
        m -= len;
    }
    true
}

/// Liang–Barsky clip of segment a→b to the box (x0, y0, x1, y1); returns the parameter range
/// kept, or None when the segment misses the box.
fn clip_segment(a: (f64, f64), b: (f64, f64), bx: (f64, f64, f64, f64)) -> Option<(f64, f64)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let mut t0: f64 = 0.0;
    let mut t1: f64 = 1.0;
    for (p, q) in [
        (-dx, a.0 - bx.0),
        (dx, bx.2 - a.0),
        (-dy, a.1 - bx.1),
        (dy, bx.3 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
}

/// Fills an axis-aligned rectangle with a solid colour (clipped to the image).
pub(crate) fn fill_rect(img: &mut RgbImage, r: PxRect, color: Rgb) {
    for y in r.y0.max(0)..r.y1.min(i64::from(img.height())) {
        for x in r.x0.max(0)..r.x1.min(i64::from(img.width())) {
            img.put_pixel(x as u32, y as u32, image::Rgb([color.0, color.1, color.2]));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_keeps_inside_part() {
        let (t0, t1) = clip_segment((-10.0, 5.0), (20.0, 5.0), (0.0, 0.0, 10.0, 10.0)).unwrap();
        assert!((t0 - 10.0 / 30.0).abs() < 1e-12 && (t1 - 20.0 / 30.0).abs() < 1e-12);
        assert!(clip_segment((-10.0, -5.0), (20.0, -5.0), (0.0, 0.0, 10.0, 10.0)).is_none());
    }

    #[test]
    fn dash_pattern_alternates() {
        let d = [4.0, 2.0];
        assert!(dash_on(0.5, &d) && dash_on(3.9, &d));
        assert!(!dash_on(4.5, &d) && !dash_on(5.9, &d));
        assert!(dash_on(6.1, &d));
    }

    #[test]
    fn horizontal_stroke_covers_its_row_only() {
        let rect = PxRect {
            x0: 0,
            y0: 0,
            x1: 20,
            y1: 20,
        };
        let mut m = Mask::new(rect);
        m.stroke_polyline(&[(2.0, 10.5), (18.0, 10.5)], 1.0, &[]);
        let at = |x: i64, y: i64| m.cov[(y * 20 + x) as usize];
        assert!(at(10, 10) > 0.99);
        assert_eq!(at(10, 12), 0.0);
        assert_eq!(at(10, 8), 0.0);
        assert_eq!(at(0, 10), 0.0);
    }
}
