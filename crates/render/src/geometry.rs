//! Rays and the analytic shapes (rectangle, disk, sphere), in f64.

use glam::{DQuat, DVec3};

/// A ray `o + t·d`, `d` unit length.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub o: DVec3,
    /// Unit direction.
    pub d: DVec3,
}

impl Ray {
    /// Point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.o + t * self.d
    }
}

/// The point of a surface a ray hit: ray parameter, position, normal and tangent.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Ray parameter.
    pub t: f64,
    /// Hit point.
    pub p: DVec3,
    /// Unit geometric normal (the shape's outward / +z side).
    pub n: DVec3,
    /// Unit tangent, orthogonal to `n`: the anisotropy x axis.
    pub tangent: DVec3,
}

/// Rotation, uniform scale, then translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Rotation.
    pub rotation: DQuat,
    /// Uniform scale factor (> 0).
    pub scale: f64,
    /// Translation.
    pub translation: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            rotation: DQuat::IDENTITY,
            scale: 1.0,
            translation: DVec3::ZERO,
        }
    }
}

impl Transform {
    /// Rotation by `deg[0]` about x, then `deg[1]` about y, then `deg[2]` about z.
    pub fn new(rotate_deg: [f64; 3], scale: f64, translate: [f64; 3]) -> Transform {
        let r = rotate_deg.map(f64::to_radians);
        let rotation = DQuat::from_rotation_z(r[2])
            * DQuat::from_rotation_y(r[1])
            * DQuat::from_rotation_x(r[0]);
        Transform {
            rotation,
            scale,
            translation: DVec3::from(translate),
        }
    }

    /// Maps a point.
    #[inline]
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.rotation * (p * self.scale) + self.translation
    }

    /// Maps a direction (rotation only).
    #[inline]
    pub fn direction(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }
}

/// Where a ray meets a [`Planar`] shape.
#[derive(Clone, Copy, Debug)]
pub struct PlanarHit {
    /// Ray parameter.
    pub t: f64,
    /// In-plane coordinate of the hit along the shape's `u` axis, from its centre.
    pub a: f64,
    /// In-plane coordinate along `v`.
    pub b: f64,
}

/// A planar shape: a rectangle or disk in the plane through `center`
/// spanned by `u`, `v` with normal `n = u × v`.
#[derive(Clone, Copy, Debug)]
pub struct Planar {
    /// Centre.
    pub center: DVec3,
    /// Unit in-plane axis (tangent).
    pub u: DVec3,
    /// Unit in-plane axis.
    pub v: DVec3,
    /// Unit normal.
    pub n: DVec3,
    /// Half extents along `u`, `v` (rectangle) or radius in `.0` (disk).
    pub half: (f64, f64),
    /// Whether this is a disk.
    pub disk: bool,
}

impl Planar {
    /// A `width × height` rectangle in the local xy plane (normal +z), transformed.
    pub fn rectangle(size: [f64; 2], xf: &Transform) -> Planar {
        Planar::build(
            xf,
            (0.5 * size[0] * xf.scale, 0.5 * size[1] * xf.scale),
            false,
        )
    }

    /// A disk of `radius` in the local xy plane (normal +z), transformed.
    pub fn disk(radius: f64, xf: &Transform) -> Planar {
        Planar::build(xf, (radius * xf.scale, radius * xf.scale), true)
    }

    fn build(xf: &Transform, half: (f64, f64), disk: bool) -> Planar {
        let u = xf.direction(DVec3::X).normalize();
        let v = xf.direction(DVec3::Y).normalize();
        Planar {
            center: xf.translation,
            u,
            v,
            n: u.cross(v),
            half,
            disk,
        }
    }

    /// Area.
    pub fn area(&self) -> f64 {
        if self.disk {
            std::f64::consts::PI * self.half.0 * self.half.0
        } else {
            4.0 * self.half.0 * self.half.1
        }
    }

    /// Nearest hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SurfacePoint> {
        let h = self.hit(ray, t_min, t_max)?;
        Some(self.point_at(ray, h.t))
    }

    /// The `t` of [`Planar::intersect`] and the hit's in-plane coordinates,
    /// without the surface point: what a shadow test, or a search for the
    /// nearest of several shapes, needs.
    #[inline]
    pub fn hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<PlanarHit> {
        let denom = ray.d.dot(self.n);
        if denom.abs() < 1e-14 {
            return None;
        }
        let t = (self.center - ray.o).dot(self.n) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let r = ray.at(t) - self.center;
        let (a, b) = (r.dot(self.u), r.dot(self.v));
        let inside = if self.disk {
            a * a + b * b <= self.half.0 * self.half.0
        } else {
            a.abs() <= self.half.0 && b.abs() <= self.half.1
        };
        inside.then_some(PlanarHit { t, a, b })
    }

    /// The surface point at distance `t` along `ray` (a `t` from [`Planar::hit`]).
    #[inline]
    pub fn point_at(&self, ray: &Ray, t: f64) -> SurfacePoint {
        SurfacePoint {
            t,
            p: ray.at(t),
            n: self.n,
            tangent: self.u,
        }
    }

    /// Texture coordinates of a point on the shape, as Mitsuba's: a rectangle's
    /// (u, v) run from 0 to 1 along its `u` and `v` axes; a disk's are (r/R, φ/2π),
    /// φ from `u` towards `v` in [0, 2π).
    pub fn uv(&self, p: DVec3) -> [f64; 2] {
        let r = p - self.center;
        self.uv_in_plane(r.dot(self.u), r.dot(self.v))
    }

    /// [`Planar::uv`] of the point at in-plane coordinates (`a`, `b`) (along
    /// `u` and `v` from the centre; a [`PlanarHit`]'s).
    #[inline]
    pub fn uv_in_plane(&self, a: f64, b: f64) -> [f64; 2] {
        if self.disk {
            [a.hypot(b) / self.half.0, turn_fraction(b.atan2(a))]
        } else {
            [0.5 * (a / self.half.0 + 1.0), 0.5 * (b / self.half.1 + 1.0)]
        }
    }

    /// The square (⌊u·tiles₀⌋, ⌊v·tiles₁⌋) of a checkerboard over the
    /// [`Planar::uv_in_plane`] of in-plane coordinates (`a`, `b`), or `None`
    /// where a disk's point lies too close to a square's edge to decide it
    /// without that rule's `hypot` and `atan2` (about one point in 10⁵).
    /// A rectangle's square is the rule's own.
    #[inline]
    pub fn checker_square(&self, a: f64, b: f64, tiles: [f64; 2]) -> Option<[f64; 2]> {
        if !self.disk {
            let uv = self.uv_in_plane(a, b);
            return Some([(uv[0] * tiles[0]).floor(), (uv[1] * tiles[1]).floor()]);
        }
        // √(a² + b²) is within a few ulps of `hypot` while a² + b² is a
        // normal number.
        let q = a * a + b * b;
        if q.is_nan() || q < f64::MIN_POSITIVE {
            return None;
        }
        let r = q.sqrt() / self.half.0 * tiles[0];
        let i = floor_clear_of(r, 1e-12 * r.max(1.0))?;
        let j = turn_square(approx_atan2(b, a), tiles[1])?;
        Some([i, j])
    }

    /// A uniformly distributed point on the shape.
    pub fn sample_point(&self, u: [f64; 2]) -> DVec3 {
        if self.disk {
            // Concentric mapping keeps strata compact (Shirley & Chiu 1997).
            let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
            let (r, phi) = if a == 0.0 && b == 0.0 {
                (0.0, 0.0)
            } else if a.abs() > b.abs() {
                (a, std::f64::consts::FRAC_PI_4 * (b / a))
            } else {
                (
                    b,
                    std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b),
                )
            };
            let r = r * self.half.0;
            self.center + r * phi.cos() * self.u + r * phi.sin() * self.v
        } else {
            self.center
                + (2.0 * u[0] - 1.0) * self.half.0 * self.u
                + (2.0 * u[1] - 1.0) * self.half.1 * self.v
        }
    }
}

/// atan t ≈ t·P(t²) on [0, 1]: the coefficients of P (odd degree 15 in t,
/// least squares reweighted toward equal ripple), off by at most 3.8·10⁻⁸ rad.
const ATAN_P: [f64; 8] = [
    0.999_999_335_560_249_4,
    -0.333_298_607_124_270_23,
    0.199_465_648_327_723_23,
    -0.139_086_254_699_082_62,
    0.096_421_869_398_986_31,
    -0.055_912_185_655_117_35,
    0.021_862_860_538_373_996,
    -0.004_054_540_420_073_152,
];

/// How far [`approx_atan2`] may be from `atan2`, in radians: 26 times the
/// polynomial's error, which leaves round-off far behind
/// (`approx_atan2_is_within_its_tolerance`).
const ATAN_TOLERANCE: f64 = 1e-6;

/// atan2(`y`, `x`) in [−π, π] to within [`ATAN_TOLERANCE`], without libm:
/// a polynomial on [0, 1] and the octant's reflections. NaN at the origin.
/// Where a checkerboard's square is all that is wanted, this decides it
/// for all but the points within the tolerance of an edge.
#[inline]
fn approx_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let t = ax.min(ay) / ax.max(ay);
    let s = t * t;
    let p = ATAN_P.iter().rev().fold(0.0, |acc, &c| acc * s + c);
    let mut a = t * p;
    if ay > ax {
        a = std::f64::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = std::f64::consts::PI - a;
    }
    if y < 0.0 { -a } else { a }
}

/// ⌊`s`⌋ if `s` is farther than `margin` from every integer (and not NaN).
#[inline]
fn floor_clear_of(s: f64, margin: f64) -> Option<f64> {
    let i = s.floor();
    (s - i > margin && i + 1.0 - s > margin).then_some(i)
}

/// ⌊turn_fraction(φ)·`tiles`⌋ from an [`approx_atan2`] angle `phi`: `None`
/// within its tolerance of a square's edge or of the turn's wrap at φ = 0.
#[inline]
fn turn_square(phi: f64, tiles: f64) -> Option<f64> {
    let m = ATAN_TOLERANCE / std::f64::consts::TAU;
    let f = phi / std::f64::consts::TAU;
    let f = if f < 0.0 { f + 1.0 } else { f };
    if !(f > m && f < 1.0 - m) {
        return None;
    }
    floor_clear_of(f * tiles, m * tiles)
}

/// An angle from `atan2` (in [−π, π]) as a fraction of a turn in [0, 1).
fn turn_fraction(phi: f64) -> f64 {
    let f = phi / std::f64::consts::TAU;
    if f < 0.0 {
        (f + 1.0).min(1.0 - f64::EPSILON)
    } else {
        f
    }
}

/// A sphere.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius (> 0).
    pub radius: f64,
}

impl Sphere {
    /// Nearest hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SurfacePoint> {
        let t = self.hit_distance(ray, t_min, t_max)?;
        Some(self.point_at(ray, t))
    }

    /// The surface point at distance `t` along `ray` (a `t` from
    /// [`Sphere::hit_distance`]).
    #[inline]
    pub fn point_at(&self, ray: &Ray, t: f64) -> SurfacePoint {
        let p = ray.at(t);
        let n = (p - self.center) / self.radius;
        let n = n.normalize();
        // dp/dφ about the sphere's z axis; at the poles fall back to x.
        let tangent = DVec3::new(-n.y, n.x, 0.0)
            .try_normalize()
            .unwrap_or(DVec3::X);
        SurfacePoint { t, p, n, tangent }
    }

    /// Texture coordinates of a point on the sphere, as Mitsuba's: (φ/2π, θ/π) with θ
    /// from the +z axis through the centre and φ from +x towards +y in [0, 2π).
    pub fn uv(&self, p: DVec3) -> [f64; 2] {
        let d = (p - self.center) / self.radius;
        let theta = d.z.clamp(-1.0, 1.0).acos();
        [turn_fraction(d.y.atan2(d.x)), theta / std::f64::consts::PI]
    }

    /// The square (⌊u·tiles₀⌋, ⌊v·tiles₁⌋) of a checkerboard over the
    /// [`Sphere::uv`] of point `p`, or `None` where `p` lies too close to a
    /// square's edge or a pole to decide it without that rule's `atan2` and
    /// `acos` (about one point in 10⁵).
    #[inline]
    pub fn checker_square(&self, p: DVec3, tiles: [f64; 2]) -> Option<[f64; 2]> {
        let d = (p - self.center) / self.radius;
        let i = turn_square(approx_atan2(d.y, d.x), tiles[0])?;
        // acos z = atan2(√((1 − z)(1 + z)), z): a function of z alone, as the
        // rule's is, whether or not d is of unit length.
        let z = d.z.clamp(-1.0, 1.0);
        let theta = approx_atan2(((1.0 - z) * (1.0 + z)).sqrt(), z);
        let m = ATAN_TOLERANCE / std::f64::consts::PI;
        let v = theta / std::f64::consts::PI;
        if v.is_nan() || v <= m {
            return None;
        }
        let j = floor_clear_of(v * tiles[1], m * tiles[1])?;
        Some([i, j])
    }

    /// The `t` of [`Sphere::intersect`] alone (no point, normal or tangent):
    /// what a light sample or a shadow test needs.
    #[inline]
    pub fn hit_distance(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let oc = ray.o - self.center;
        let b = oc.dot(ray.d);
        // Discriminant from the perpendicular distance (Haines et al., Ray Tracing Gems ch. 7).
        let perp = oc - b * ray.d;
        let disc = self.radius * self.radius - perp.length_squared();
        if disc < 0.0 {
            return None;
        }
        // c via (|oc| − r)(|oc| + r) avoids cancellation for far origins;
        // its square root only for rays that meet the sphere.
        let len = oc.length();
        let c = (len - self.radius) * (len + self.radius);
        let sq = disc.sqrt();
        let q = -b - sq.copysign(b);
        let (t0, t1) = {
            let a0 = c / q;
            let a1 = q;
            if a0 < a1 { (a0, a1) } else { (a1, a0) }
        };
        if t0 > t_min && t0 < t_max {
            Some(t0)
        } else if t1 > t_min && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_coordinates_follow_mitsubas_shapes() {
        let close =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12;
        // A 2 × 1 rectangle turned 90° about z: its u axis is +y, v is −x.
        let xf = Transform::new([0.0, 0.0, 90.0], 1.0, [1.0, 2.0, 3.0]);
        let r = Planar::rectangle([2.0, 1.0], &xf);
        let at = |a: f64, b: f64| xf.translation + a * r.u + b * r.v;
        assert!(close(r.uv(at(-1.0, -0.5)), [0.0, 0.0]));
        assert!(close(r.uv(at(1.0, 0.5)), [1.0, 1.0]));
        assert!(close(r.uv(at(0.5, 0.0)), [0.75, 0.5]));
        assert!((r.u - DVec3::Y).length() < 1e-12);
        // A disk: (r/R, φ/2π), φ from u towards v.
        let d = Planar::disk(2.0, &Transform::new([0.0; 3], 1.0, [0.0; 3]));
        assert!(close(d.uv(DVec3::new(1.0, 0.0, 0.0)), [0.5, 0.0]));
        assert!(close(d.uv(DVec3::new(0.0, 2.0, 0.0)), [1.0, 0.25]));
        assert!(close(d.uv(DVec3::new(0.0, -1.0, 0.0)), [0.5, 0.75]));
        // A sphere: (φ/2π, θ/π) about +z through its centre.
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, 1.0),
            radius: 2.0,
        };
        assert!(close(s.uv(DVec3::new(0.0, 0.0, 3.0)), [0.0, 0.0]));
        assert!(close(s.uv(DVec3::new(-2.0, 0.0, 1.0)), [0.5, 0.5]));
        assert!(close(s.uv(DVec3::new(0.0, -2.0, 1.0)), [0.75, 0.5]));
        assert!(close(s.uv(DVec3::new(0.0, 0.0, -1.0)), [0.0, 1.0]));
        // Just below the −x axis the turn is just below 1, never 1 or above.
        let u = s.uv(DVec3::new(-2.0, -1e-300, 1.0))[0];
        assert!((0.5..1.0).contains(&u), "{u}");
    }

    #[test]
    fn approx_atan2_is_within_its_tolerance() {
        // Every direction around the circle (a million, at lengths from
        // 1e−3 to 1e3), the axes and the octants' edges.
        let mut worst: f64 = 0.0;
        let n = 1_000_000;
        for k in 0..=n {
            let phi = -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / n as f64;
            let len = 10f64.powi(k % 7 - 3);
            let (y, x) = (len * phi.sin(), len * phi.cos());
            worst = worst.max((approx_atan2(y, x) - y.atan2(x)).abs());
        }
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (1.0, 1.0),
            (-1.0, -1.0),
        ] {
            worst = worst.max((approx_atan2(y, x) - f64::atan2(y, x)).abs());
        }
        // The polynomial's own error, which the tolerance is 26 times.
        assert!(worst < 3.9e-8, "{worst:e}");
        assert!(worst * 25.0 < ATAN_TOLERANCE);
        assert!(approx_atan2(0.0, 0.0).is_nan());
    }

    /// Where `checker_square` decides a square it is the square of the
    /// texture coordinates' rule, ⌊uv·tiles⌋, for points all over disks and
    /// spheres and at every square's edges (at and within 1e−15…1e−5 rad or
    /// relative of them), and it decides nearly every point.
    #[test]
    fn checker_squares_are_the_texture_coordinates_squares() {
        use std::f64::consts::{PI, TAU};
        let rule = |uv: [f64; 2], tiles: [f64; 2]| {
            [(uv[0] * tiles[0]).floor(), (uv[1] * tiles[1]).floor()]
        };
        let mut rng = brdf::numerics::splitmix::SplitMix64::new(11);
        let offsets = [
            0.0, 1e-15, -1e-15, 1e-12, -1e-12, 1e-9, -1e-9, 3e-8, -3e-8, 1e-7, -1e-7, 1e-6, -1e-6,
            1e-5, -1e-5,
        ];
        let (mut decided, mut random) = (0usize, 0usize);
        for tiles in [
            [4.0, 6.0],
            [8.0, 4.0],
            [6.0, 4.0],
            [3.7, 12.5],
            [1.0, 7.0],
            [16.0, 9.3],
        ] {
            let xf = Transform::new([30.0, -70.0, 10.0], 1.3, [0.2, -0.4, 0.1]);
            let disk = Planar::disk(0.7, &xf);
            let sphere = Sphere {
                center: DVec3::new(0.3, 0.35, -0.2),
                radius: 0.35,
            };
            let mut check = |r: f64, phi: f64, theta: f64, count: bool| {
                // The disk at polar (r, φ), through the same arithmetic as a hit.
                let p = disk.center + r * phi.cos() * disk.u + r * phi.sin() * disk.v;
                let q = p - disk.center;
                let (a, b) = (q.dot(disk.u), q.dot(disk.v));
                if let Some(sq) = disk.checker_square(a, b, tiles) {
                    assert_eq!(
                        sq,
                        rule(disk.uv_in_plane(a, b), tiles),
                        "disk {tiles:?} {r} {phi}"
                    );
                    decided += usize::from(count);
                }
                let dir = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let p = sphere.center + sphere.radius * dir;
                if let Some(sq) = sphere.checker_square(p, tiles) {
                    assert_eq!(
                        sq,
                        rule(sphere.uv(p), tiles),
                        "sphere {tiles:?} {phi} {theta}"
                    );
                    decided += usize::from(count);
                }
                random += 2 * usize::from(count);
            };
            for _ in 0..50_000 {
                let (r, phi, theta) = (
                    0.7 * rng.uniform().sqrt(),
                    TAU * rng.uniform(),
                    PI * rng.uniform(),
                );
                check(r, phi, theta, true);
            }
            // The edges: φ = 2πk/tiles, r = 0.7k/tiles₀, θ = πk/tiles₁.
            for k in 0..=tiles[0].max(tiles[1]).ceil() as i32 {
                for &e in &offsets {
                    let phi_u = TAU * k as f64 / tiles[0] + e;
                    let phi_v = TAU * k as f64 / tiles[1] + e;
                    let r = 0.7 * (k as f64 / tiles[0]).min(1.0) * (1.0 - e.abs());
                    let theta = (PI * k as f64 / tiles[1] + e).clamp(0.0, PI);
                    let (r0, t0) = (0.7 * rng.uniform(), PI * rng.uniform());
                    check(r, TAU * rng.uniform(), t0, false);
                    check(r0, phi_v, t0, false);
                    check(r0, phi_u, theta, false);
                    check(r0 * (1.0 + e), -phi_v, PI - theta, false);
                }
            }
        }
        assert!(
            decided as f64 > 0.9995 * random as f64,
            "{decided} of {random}"
        );
    }

    #[test]
    fn rectangle_hit_and_miss() {
        let r = Planar::rectangle(
            [2.0, 1.0],
            &Transform::new([0.0, 0.0, 0.0], 1.0, [0.0, 0.0, 1.0]),
        );
        let ray = Ray {
            o: DVec3::new(0.9, 0.4, 5.0),
            d: DVec3::NEG_Z,
        };
        let h = r.intersect(&ray, 0.0, f64::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-12 && h.n == DVec3::Z);
        let miss = Ray {
            o: DVec3::new(0.9, 0.6, 5.0),
            d: DVec3::NEG_Z,
        };
        assert!(r.intersect(&miss, 0.0, f64::INFINITY).is_none());
        assert!((r.area() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn rotation_order_is_x_then_y_then_z() {
        let xf = Transform::new([90.0, 0.0, 90.0], 1.0, [0.0; 3]);
        // x-rotation maps +z to −y; the z-rotation then maps −y to +x.
        assert!((xf.direction(DVec3::Z) - DVec3::X).length() < 1e-12);
    }

    #[test]
    fn sphere_hits_from_outside_and_inside() {
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, -10.0),
            radius: 2.0,
        };
        let h = s
            .intersect(
                &Ray {
                    o: DVec3::ZERO,
                    d: DVec3::NEG_Z,
                },
                1e-9,
                f64::INFINITY,
            )
            .unwrap();
        assert!((h.t - 8.0).abs() < 1e-12 && (h.n - DVec3::Z).length() < 1e-12);
        let inside = s
            .intersect(
                &Ray {
                    o: s.center,
                    d: DVec3::X,
                },
                1e-9,
                f64::INFINITY,
            )
            .unwrap();
        assert!((inside.t - 2.0).abs() < 1e-12);
        assert!(
            s.intersect(
                &Ray {
                    o: DVec3::ZERO,
                    d: DVec3::X
                },
                1e-9,
                f64::INFINITY
            )
            .is_none()
        );
    }

    #[test]
    fn sphere_distance_is_the_hit_distance_and_the_hit_lies_on_the_sphere() {
        // Rays from outside, inside and on the surface, toward and away from
        // the sphere, with windows that include and exclude either root.
        let s = Sphere {
            center: DVec3::new(0.3, -1.0, 4.0),
            radius: 1.5,
        };
        let (mut hits, mut misses) = (0, 0);
        for i in 0..2000u32 {
            let f = |k: u32| (((i.wrapping_mul(2_654_435_761) >> k) & 1023) as f64) / 1023.0;
            let o = s.center + DVec3::new(f(0) - 0.5, f(3) - 0.5, f(6) - 0.5) * (6.0 * f(9));
            let d = DVec3::new(f(12) - 0.5, f(15) - 0.5, f(18) - 0.5 + 1e-3).normalize();
            let ray = Ray { o, d };
            for (t_min, t_max) in [(0.0, f64::INFINITY), (1e-9, 2.0), (1.0, 10.0)] {
                let t = s.hit_distance(&ray, t_min, t_max);
                let h = s.intersect(&ray, t_min, t_max);
                assert_eq!(t, h.as_ref().map(|h| h.t), "ray {i}");
                if let (Some(t), Some(h)) = (t, h) {
                    hits += 1;
                    assert!(t > t_min && t < t_max);
                    assert!(((h.p - s.center).length() - s.radius).abs() < 1e-12);
                    let g = s.point_at(&ray, t);
                    assert!(g.p == h.p && g.n == h.n && g.tangent == h.tangent);
                } else {
                    misses += 1;
                }
            }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses");
    }

    /// The contract the integrator's shading frame relies on for analytic
    /// shapes (it skips Gram–Schmidt there): a unit tangent orthogonal to
    /// the unit normal, to round-off, at every hit, near a sphere's poles
    /// and for planes under any rotation and scale.
    #[test]
    fn analytic_hit_tangents_are_orthonormal() {
        let check = |g: &SurfacePoint, what: &str| {
            assert!(
                (g.n.length() - 1.0).abs() < 1e-15,
                "{what}: |n| = {}",
                g.n.length()
            );
            let t = g.tangent;
            assert!(
                (t.length() - 1.0).abs() < 1e-15,
                "{what}: |t| = {}",
                t.length()
            );
            assert!(t.dot(g.n).abs() < 1e-15, "{what}: t·n = {}", t.dot(g.n));
        };
        let mut rng = brdf::numerics::splitmix::SplitMix64::new(5);
        let mut hits = 0;
        for i in 0..2000 {
            let mut u = || rng.uniform();
            let rotate = [360.0 * u(), 360.0 * u(), 360.0 * u()];
            let scale = 10f64.powf(8.0 * u() - 4.0);
            let xf = Transform::new(rotate, scale, [u() - 0.5, u() - 0.5, u() - 0.5]);
            let plane = if i % 2 == 0 {
                Planar::rectangle([2.0, 1.0], &xf)
            } else {
                Planar::disk(1.0, &xf)
            };
            // A ray from off the plane through a point inside it.
            let target = plane.center + 0.4 * plane.half.0 * plane.u + 0.3 * plane.half.1 * plane.v;
            let o = target + scale * (plane.n + 0.5 * plane.u);
            let ray = Ray {
                o,
                d: (target - o).normalize(),
            };
            if let Some(g) = plane.intersect(&ray, 0.0, f64::INFINITY) {
                check(&g, "plane");
                hits += 1;
            }
            // Sphere hits all over, and within 1e−12 rad of the poles.
            let s = Sphere {
                center: DVec3::new(u(), u(), u()),
                radius: 10f64.powf(6.0 * u() - 3.0),
            };
            let pole = if i % 2 == 0 { 1.0 } else { -1.0 };
            for dir in [
                DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize(),
                DVec3::new(1e-12 * (u() - 0.5), 1e-12 * (u() - 0.5), pole).normalize(),
            ] {
                let o = s.center + 3.0 * s.radius * dir;
                let ray = Ray { o, d: -dir };
                let g = s
                    .intersect(&ray, 0.0, f64::INFINITY)
                    .expect("aimed at the centre");
                check(&g, "sphere");
                hits += 1;
            }
        }
        assert!(hits > 5000, "{hits}");
    }

    #[test]
    fn disk_samples_stay_inside() {
        let d = Planar::disk(0.5, &Transform::default());
        for i in 0..100 {
            let p = d.sample_point([i as f64 / 100.0, (i * 37 % 100) as f64 / 100.0]);
            assert!(p.length() <= 0.5 + 1e-12 && p.z == 0.0);
        }
    }
}
