//! The material-preview assets, generated here so that their licence is the
//! project's: a curved object and a checkered floor, written as OBJ text.
//!
//! The object is a surface of revolution about +y whose profile is a chain
//! of line segments and circular arcs joined with matching tangents (so the
//! surface normal is continuous): a rounded foot, a concave flare into a
//! short stem, a concave neck fillet, a spherical bulb, a rounded lip and a
//! spherical dish sunk into the top. It has convex parts (bulb, foot rim,
//! lip), saddle-shaped parts (the two fillets, the inside of the lip) and a
//! fully concave part (the dish), so one image shows a lobe on convex
//! curvature, inter-reflection in a cavity and grazing angles at the
//! silhouette. Every point and normal of the profile is exact (arcs and
//! lines), so the OBJ's vertex normals are the analytic normals, and a test
//! can check any vertex against [`PreviewObject::closest`].
//!
//! Sizes: the object stands on y = 0, 1.0 high and 0.72 wide (the bulb); the
//! floor is a square checkerboard in the y = 0 plane.

use glam::{DVec2, DVec3};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// One piece of the profile in the (ρ, y) half-plane, traversed from the
/// bottom of the axis to the top; the solid is on the left, so the outward
/// normal is the tangent turned clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Piece {
    /// A straight segment from `a` to `b`.
    Line {
        /// Start.
        a: DVec2,
        /// End.
        b: DVec2,
    },
    /// A circular arc: centre `c`, radius `r`, angle from `a0` to `a1` (rad);
    /// increasing angle (counter-clockwise) is convex, decreasing is concave.
    Arc {
        /// Centre.
        c: DVec2,
        /// Radius.
        r: f64,
        /// Start angle.
        a0: f64,
        /// End angle.
        a1: f64,
    },
}

impl Piece {
    /// Point at parameter `t` ∈ [0, 1].
    pub fn point(&self, t: f64) -> DVec2 {
        match *self {
            Piece::Line { a, b } => a + (b - a) * t,
            Piece::Arc { c, r, a0, a1 } => {
                let a = a0 + (a1 - a0) * t;
                c + r * DVec2::new(a.cos(), a.sin())
            }
        }
    }

    /// Unit tangent (direction of travel) at `t`.
    pub fn tangent(&self, t: f64) -> DVec2 {
        match *self {
            Piece::Line { a, b } => (b - a).normalize(),
            Piece::Arc { a0, a1, .. } => {
                let a = a0 + (a1 - a0) * t;
                (a1 - a0).signum() * DVec2::new(-a.sin(), a.cos())
            }
        }
    }

    /// Outward unit normal at `t` (the tangent turned clockwise).
    pub fn normal(&self, t: f64) -> DVec2 {
        let d = self.tangent(t);
        DVec2::new(d.y, -d.x)
    }

    /// Length of the piece.
    pub fn length(&self) -> f64 {
        match *self {
            Piece::Line { a, b } => (b - a).length(),
            Piece::Arc { r, a0, a1, .. } => r * (a1 - a0).abs(),
        }
    }

    /// Parameter of the point of this piece closest to `p`, and its distance.
    pub fn closest(&self, p: DVec2) -> (f64, f64) {
        let t = match *self {
            Piece::Line { a, b } => ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0),
            Piece::Arc { c, a0, a1, .. } => {
                let q = p - c;
                // The angle of p, unwrapped into the arc's range when possible.
                let ang = q.y.atan2(q.x);
                let (lo, hi) = (a0.min(a1), a0.max(a1));
                let mut best = None;
                for k in -2..=2 {
                    let a = ang + 2.0 * PI * k as f64;
                    if (lo..=hi).contains(&a) {
                        best = Some((a - a0) / (a1 - a0));
                    }
                }
                best.unwrap_or_else(|| {
                    let d0 = (self.point(0.0) - p).length();
                    let d1 = (self.point(1.0) - p).length();
                    if d0 <= d1 { 0.0 } else { 1.0 }
                })
            }
        };
        (t, (self.point(t) - p).length())
    }

    /// Turning angle (rad) of the tangent over the piece.
    pub fn turning(&self) -> f64 {
        match *self {
            Piece::Line { .. } => 0.0,
            Piece::Arc { a0, a1, .. } => (a1 - a0).abs(),
        }
    }
}

/// The preview object: its profile and tessellation settings.
#[derive(Clone, Debug)]
pub struct PreviewObject {
    /// Profile pieces from the bottom centre to the top centre.
    pub pieces: Vec<Piece>,
    /// Segments around the axis.
    pub segments: usize,
    /// Largest tangent turn per profile step, radians.
    pub max_turn: f64,
}

fn deg(a: f64) -> f64 {
    a.to_radians()
}

impl Default for PreviewObject {
    fn default() -> Self {
        PreviewObject::new()
    }
}

impl PreviewObject {
    /// The bundled object (dimensions in the module docs).
    pub fn new() -> PreviewObject {
        let v = DVec2::new;
        // Foot: flat bottom, rounded rim (r 0.04), concave flare (r 0.16) into the stem.
        let foot_r = 0.30;
        let rim_r = 0.04;
        let flare_r = 0.16;
        let stem = foot_r - flare_r; // stem radius 0.14
        let flare_c = v(foot_r, 2.0 * rim_r + flare_r);
        // Bulb: sphere of radius 0.36; the neck fillet (r 0.08) meets it at −60°.
        let bulb_r = 0.36;
        let neck_r = 0.08;
        let meet = deg(-60.0);
        // Fillet centre c_f = P + r_f·(−cos 120°, −sin 120°) with P on the bulb at `meet`;
        // its ρ must be stem + r_f: bulb_r·cos(meet) − r_f·cos(120°) = stem + r_f.
        let neck_c_rho = stem + neck_r;
        debug_assert!((bulb_r * meet.cos() + neck_r * 0.5 - neck_c_rho).abs() < 1e-12);
        let stem_top = 0.28;
        let neck_c = v(neck_c_rho, stem_top);
        let p_meet = neck_c + neck_r * v(deg(120.0).cos(), deg(120.0).sin());
        let bulb_c = p_meet - bulb_r * v(meet.cos(), meet.sin());
        // Lip: a small convex arc (r 0.03) inside the bulb, tangent to it at +50°,
        // turning over to 150°; then the dish, a concave sphere reaching the axis.
        let lip_at = deg(50.0);
        let lip_r = 0.03;
        let lip_c = bulb_c + (bulb_r - lip_r) * v(lip_at.cos(), lip_at.sin());
        let lip_end = deg(150.0);
        let j = lip_c + lip_r * v(lip_end.cos(), lip_end.sin());
        // Dish: concave arc with centre on the axis, from −30° down to −90°.
        let dish_start = deg(-30.0);
        let dish_r = j.x / dish_start.cos();
        let dish_c = v(0.0, j.y - dish_r * dish_start.sin());
        let pieces = vec![
            Piece::Line {
                a: v(0.0, 0.0),
                b: v(foot_r, 0.0),
            },
            Piece::Arc {
                c: v(foot_r, rim_r),
                r: rim_r,
                a0: deg(-90.0),
                a1: deg(90.0),
            },
            Piece::Arc {
                c: flare_c,
                r: flare_r,
                a0: deg(-90.0),
                a1: deg(-180.0),
            },
            Piece::Line {
                a: v(stem, flare_c.y),
                b: v(stem, stem_top),
            },
            Piece::Arc {
                c: neck_c,
                r: neck_r,
                a0: deg(180.0),
                a1: deg(120.0),
            },
            Piece::Arc {
                c: bulb_c,
                r: bulb_r,
                a0: meet,
                a1: lip_at,
            },
            Piece::Arc {
                c: lip_c,
                r: lip_r,
                a0: lip_at,
                a1: lip_end,
            },
            Piece::Arc {
                c: dish_c,
                r: dish_r,
                a0: dish_start,
                a1: deg(-90.0),
            },
        ];
        PreviewObject {
            pieces,
            segments: 48,
            max_turn: deg(12.0),
        }
    }

    /// Profile samples: (point, outward normal) from the bottom to the top
    /// centre; arcs get a step per `max_turn` of tangent turn, lines one.
    pub fn profile(&self) -> Vec<(DVec2, DVec2)> {
        let mut out = vec![(self.pieces[0].point(0.0), self.pieces[0].normal(0.0))];
        for p in &self.pieces {
            let n = ((p.turning() / self.max_turn).ceil() as usize).max(1);
            for k in 1..=n {
                let t = k as f64 / n as f64;
                out.push((p.point(t), p.normal(t)));
            }
        }
        out
    }

    /// The point of the surface closest to `p` (world, the object at the
    /// origin) and the analytic outward normal there, with the distance.
    pub fn closest(&self, p: DVec3) -> (DVec3, DVec3, f64) {
        let rho = (p.x * p.x + p.z * p.z).sqrt();
        let q = DVec2::new(rho, p.y);
        let (piece, t, dist) = self
            .pieces
            .iter()
            .map(|pc| {
                let (t, d) = pc.closest(q);
                (pc, t, d)
            })
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .expect("the profile has pieces");
        let (cphi, sphi) = if rho > 0.0 {
            (p.x / rho, p.z / rho)
        } else {
            (1.0, 0.0)
        };
        let pt = piece.point(t);
        let n = piece.normal(t);
        (
            DVec3::new(pt.x * cphi, pt.y, pt.x * sphi),
            DVec3::new(n.x * cphi, n.y, n.x * sphi),
            dist,
        )
    }

    /// The tessellated surface as OBJ text (`v`, `vn`, `f v//vn`), faces
    /// wound counter-clockwise seen from outside; the two profile ends on
    /// the axis become single pole vertices.
    pub fn obj(&self) -> String {
        let prof = self.profile();
        let m = self.segments;
        let mut s = String::from(
            "# lustre material-preview object (generated by `lustre scenes`,\n\
             # crates/render/src/preview_mesh.rs): a surface of revolution about +y, 1.0 high.\n\
             # Vertex normals are the analytic normals of the profile's arcs and lines.\n\
             o preview_object\n",
        );
        // Vertex index (1-based) of profile point k at segment j.
        let last = prof.len() - 1;
        let mut index = vec![vec![0usize; m]; prof.len()];
        let mut next = 1;
        for (k, (p, n)) in prof.iter().enumerate() {
            let pole = k == 0 || k == last;
            let ring = if pole { 1 } else { m };
            for (j, slot) in index[k].iter_mut().enumerate().take(ring) {
                let phi = 2.0 * PI * j as f64 / m as f64;
                let (c, sn) = if pole {
                    (0.0, 0.0)
                } else {
                    (phi.cos(), phi.sin())
                };
                let _ = writeln!(s, "v {} {} {}", f6(p.x * c), f6(p.y), f6(p.x * sn));
                let _ = writeln!(s, "vn {} {} {}", f6(n.x * c), f6(n.y), f6(n.x * sn));
                *slot = next;
                next += 1;
            }
            if pole {
                let v = index[k][0];
                index[k].iter_mut().for_each(|x| *x = v);
            }
        }
        let mut face = |a: usize, b: usize, c: usize| {
            let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
        };
        for k in 0..last {
            for j in 0..m {
                let j1 = (j + 1) % m;
                let (a, b) = (index[k][j], index[k][j1]);
                let (c, d) = (index[k + 1][j], index[k + 1][j1]);
                // Going up the profile with φ increasing toward +z from +x, the
                // outward side sees (a, c, b) counter-clockwise (see the test).
                if k == 0 {
                    face(a, c, d);
                } else if k + 1 == last {
                    face(a, c, b);
                } else {
                    face(a, c, d);
                    face(a, d, b);
                }
            }
        }
        s
    }
}

/// Six decimals, without a negative zero (so regenerated files compare as text).
fn f6(v: f64) -> String {
    let s = format!("{v:.6}");
    if s == "-0.000000" {
        "0.000000".into()
    } else {
        s
    }
}

/// A checkerboard floor in the y = 0 plane, `n` × `n` squares of side
/// `square`, centred on the origin, normal +y; returns the OBJ text of the
/// squares of one colour (`parity` 0 includes the square at the −x, −z corner).
pub fn checker_floor_obj(n: usize, square: f64, parity: usize) -> String {
    let mut s = format!(
        "# lustre preview floor: {n}×{n} checkerboard of {square} squares in y = 0, colour {parity}\n\
         # (generated by `lustre scenes`, crates/render/src/preview_mesh.rs)\n\
         o floor_{parity}\n"
    );
    let half = n as f64 * square / 2.0;
    let mut v = 1;
    for i in 0..n {
        for k in 0..n {
            if (i + k) % 2 != parity % 2 {
                continue;
            }
            let (x0, z0) = (-half + i as f64 * square, -half + k as f64 * square);
            let (x1, z1) = (x0 + square, z0 + square);
            for (x, z) in [(x0, z0), (x1, z0), (x1, z1), (x0, z1)] {
                let _ = writeln!(s, "v {} 0.000000 {}", f6(x), f6(z));
            }
            // (x0,z0) → (x0,z1) → (x1,z1) is counter-clockwise seen from +y.
            let _ = writeln!(s, "f {} {} {}", v, v + 3, v + 2);
            let _ = writeln!(s, "f {} {} {}", v, v + 2, v + 1);
            v += 4;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_join_with_matching_tangents() {
        let o = PreviewObject::new();
        for w in o.pieces.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                (a.point(1.0) - b.point(0.0)).length() < 1e-12,
                "{a:?} → {b:?}"
            );
            assert!(
                (a.tangent(1.0) - b.tangent(0.0)).length() < 1e-12,
                "{a:?} → {b:?}"
            );
        }
        let first = o.pieces[0].point(0.0);
        let last = o.pieces.last().unwrap().point(1.0);
        assert!(
            first.x.abs() < 1e-12 && last.x.abs() < 1e-12,
            "ends on the axis"
        );
    }
}
