//! Pixel-space geometry plotters does not do for us: clipping polylines to the plot frame
//! (plotters draws anything anywhere on the image, and a value far outside a fixed range would
//! otherwise send the rasteriser across billions of pixels) and dash patterns of any length.

use crate::LineStyle;

/// A point in image pixels.
pub(crate) type Pt = (f64, f64);

/// Axis-aligned box (x0, y0, x1, y1) in pixels.
pub(crate) type Box2 = (f64, f64, f64, f64);

/// Liang–Barsky clip of segment a→b to `bx`; returns the parameter range kept, or None when
/// the segment misses the box.
pub(crate) fn clip_segment(a: Pt, b: Pt, bx: Box2) -> Option<(f64, f64)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
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

/// Pixel coordinates beyond this are pulled in before clipping so that differences of far
/// points stay finite; for frames below 10⁵ px this moves the drawn line by < 10⁻⁶ px.
const FAR_PX: f64 = 1e12;

/// The parts of polyline `pts` inside `bx`, each a polyline of its own (a part ends where the
/// line leaves the box). A single point inside the box is kept as a one-point part.
pub(crate) fn clip_polyline(pts: &[Pt], bx: Box2) -> Vec<Vec<Pt>> {
    let pts: Vec<Pt> = pts
        .iter()
        .map(|p| (p.0.clamp(-FAR_PX, FAR_PX), p.1.clamp(-FAR_PX, FAR_PX)))
        .collect();
    let inside = |p: Pt| p.0 >= bx.0 && p.0 <= bx.2 && p.1 >= bx.1 && p.1 <= bx.3;
    let mut parts: Vec<Vec<Pt>> = Vec::new();
    let mut cur: Vec<Pt> = Vec::new();
    if let [p] = pts[..] {
        if inside(p) {
            parts.push(vec![p]);
        }
        return parts;
    }
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let Some((t0, t1)) = clip_segment(a, b, bx) else {
            if !cur.is_empty() {
                parts.push(std::mem::take(&mut cur));
            }
            continue;
        };
        let at = |t: f64| (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        let (p, q) = (
            if t0 > 0.0 { at(t0) } else { a },
            if t1 < 1.0 { at(t1) } else { b },
        );
        if cur.is_empty() || t0 > 0.0 {
            if !cur.is_empty() {
                parts.push(std::mem::take(&mut cur));
            }
            cur.push(p);
        }
        cur.push(q);
        if t1 < 1.0 {
            parts.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        parts.push(cur);
    }
    parts
}

/// On/off lengths in px of a line style (empty = solid), for line width `w` at font size
/// `base`.
pub(crate) fn dash_pattern(style: LineStyle, w: f64, base: f64) -> Vec<f64> {
    match style {
        LineStyle::Solid | LineStyle::None => Vec::new(),
        LineStyle::Dashed => vec![base * 0.7, base * 0.4],
        LineStyle::Dotted => vec![w * 1.2, w * 1.8],
        LineStyle::DashDot => vec![base * 0.7, base * 0.3, w * 1.2, base * 0.3],
    }
}

/// The "on" pieces of polyline `pts` under `dash` (alternating on/off lengths along the arc
/// length, starting with on). An empty or degenerate pattern gives the whole line.
pub(crate) fn dash_polyline(pts: &[Pt], dash: &[f64]) -> Vec<Vec<Pt>> {
    let period: f64 = dash.iter().sum();
    if dash.is_empty() || !(period.is_finite() && period > 0.0) || dash.iter().any(|d| *d < 0.0) {
        return vec![pts.to_vec()];
    }
    let mut out: Vec<Vec<Pt>> = Vec::new();
    let (mut k, mut left) = (0usize, dash[0]);
    let mut cur: Vec<Pt> = pts.first().map(|p| vec![*p]).unwrap_or_default();
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let mut done = 0.0;
        while len - done > left {
            done += left;
            let t = done / len;
            let p = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            if k % 2 == 0 {
                cur.push(p);
                out.push(std::mem::take(&mut cur));
            } else {
                cur = vec![p];
            }
            k = (k + 1) % dash.len();
            left = dash[k];
        }
        left -= len - done;
        if k % 2 == 0 {
            cur.push(b);
        }
    }
    if k % 2 == 0 && cur.len() > 1 {
        out.push(cur);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn length(p: &[Pt]) -> f64 {
        p.windows(2)
            .map(|w| ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt())
            .sum()
    }

    #[test]
    fn clip_keeps_the_inside_part() {
        let (t0, t1) = clip_segment((-10.0, 5.0), (20.0, 5.0), (0.0, 0.0, 10.0, 10.0)).unwrap();
        assert!((t0 - 10.0 / 30.0).abs() < 1e-12 && (t1 - 20.0 / 30.0).abs() < 1e-12);
        assert!(clip_segment((-10.0, -5.0), (20.0, -5.0), (0.0, 0.0, 10.0, 10.0)).is_none());
        // A line that leaves and re-enters the box becomes two parts.
        let parts = clip_polyline(
            &[(1.0, 5.0), (5.0, 5.0), (5.0, 50.0), (8.0, 5.0), (9.0, 5.0)],
            (0.0, 0.0, 10.0, 10.0),
        );
        let near = |p: Pt, q: Pt| (p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9;
        assert_eq!(parts.len(), 2, "{parts:?}");
        assert_eq!(parts[0].len(), 3, "{parts:?}");
        assert!(near(parts[0][2], (5.0, 10.0)), "{parts:?}");
        assert!(
            near(parts[1][0], (5.0 + 3.0 * 40.0 / 45.0, 10.0)),
            "{parts:?}"
        );
        assert_eq!(parts[1].last(), Some(&(9.0, 5.0)));
        // Values at the f64 limits clip to finite points on the box.
        let parts = clip_polyline(&[(5.0, -1e308), (5.0, 1e308)], (0.0, 0.0, 10.0, 10.0));
        assert_eq!(parts.len(), 1);
        assert!(near(parts[0][0], (5.0, 0.0)) && (parts[0][1].1 - 10.0).abs() < 1e-3);
    }

    #[test]
    fn dash_pattern_alternates_along_the_arc_length() {
        // A bent line 0..30 px long with 4 on / 2 off: on at [0,4), [6,10), …
        let pts = [(0.0, 0.0), (15.0, 0.0), (15.0, 15.0)];
        let on = dash_polyline(&pts, &[4.0, 2.0]);
        assert_eq!(on.len(), 5, "{on:?}");
        for piece in &on {
            assert!((length(piece) - 4.0).abs() < 1e-9, "{piece:?}");
        }
        // The piece across the corner keeps the corner point.
        assert_eq!(on[2], vec![(12.0, 0.0), (15.0, 0.0), (15.0, 1.0)]);
        assert_eq!(dash_polyline(&pts, &[]), vec![pts.to_vec()]);
    }

    proptest! {
        #[test]
        fn dashes_cover_their_share_of_the_line(
            pts in prop::collection::vec((-500.0..500.0f64, -500.0..500.0f64), 2..20),
            on in 0.5..30.0f64,
            off in 0.5..30.0f64,
        ) {
            let total = length(&pts);
            let drawn: f64 = dash_polyline(&pts, &[on, off]).iter().map(|p| length(p)).sum();
            let periods = (total / (on + off)).floor();
            // Whole periods give exactly `on` each; the last partial one between 0 and `on`.
            prop_assert!(drawn >= periods * on - 1e-6 && drawn <= (periods + 1.0) * on + 1e-6,
                "{drawn} of {total}");
        }

        #[test]
        fn clipped_parts_stay_in_the_box_and_keep_inside_length(
            pts in prop::collection::vec((-300.0..300.0f64, -300.0..300.0f64), 1..20),
        ) {
            let bx = (-100.0, -50.0, 120.0, 80.0);
            let parts = clip_polyline(&pts, bx);
            for p in parts.iter().flatten() {
                prop_assert!(p.0 >= bx.0 - 1e-9 && p.0 <= bx.2 + 1e-9);
                prop_assert!(p.1 >= bx.1 - 1e-9 && p.1 <= bx.3 + 1e-9);
            }
            // The kept length equals the summed clipped length of each segment.
            let want: f64 = pts.windows(2).filter_map(|w| {
                clip_segment(w[0], w[1], bx).map(|(t0, t1)| length(&[w[0], w[1]]) * (t1 - t0))
            }).sum();
            let got: f64 = parts.iter().map(|p| length(p)).sum();
            prop_assert!((got - want).abs() < 1e-6 * want.max(1.0), "{got} vs {want}");
        }
    }
}
