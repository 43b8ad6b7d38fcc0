//! The pixels a directly seen emitter's outline may cross.
//!
//! A small bright light seen by the camera is a disk (or polygon) of
//! radiance tens of times the rest of the image, and a pixel on its
//! outline is a coin toss per camera sample: on an open room lit by a
//! sphere light in view, its ≈ 100 outline pixels held 61 % of the 64-spp
//! squared error (`docs/error_vs_time.md`, 2026-12-07 fourth section). There
//! the integrator averages the emission seen directly over several positions
//! in the pixel (`integrator::emission_over_pixel`), each a camera ray and
//! nothing else. Everywhere else it would only cost rays, so this mask
//! marks where an outline can be: a conservative test per light from the
//! camera's geometry alone, no rays. A pixel left unmarked keeps the plain
//! estimate, so the mask decides cost and variance, never the expectation.

use crate::camera::Camera;
use crate::geometry::{Planar, Sphere};
use crate::light::{LightKind, Lights};
use glam::{DVec2, DVec3};

/// Default `[integrator] emitter_pixel_samples`.
pub const DEFAULT_SAMPLES: usize = 16;
/// Most `[integrator] emitter_pixel_samples`.
pub const MAX_SAMPLES: u32 = 64;

/// Pixels whose footprint an emitter's outline may cross (the positions
/// per camera sample averaged there are `Settings::emitter_pixel_samples`).
#[derive(Clone, Debug)]
pub struct EmitterEdges {
    width: u32,
    height: u32,
    bits: Vec<u64>,
}

impl EmitterEdges {
    /// The mask for `camera` and the sphere and rectangle lights of
    /// `lights`; `None` when `samples` ≤ 1 or no outline is in view.
    pub fn build(camera: &Camera, lights: &Lights, samples: usize) -> Option<EmitterEdges> {
        if samples <= 1 {
            return None;
        }
        let (width, height) = (camera.width, camera.height);
        let words = (width as usize * height as usize).div_ceil(64);
        let mut mask = EmitterEdges {
            width,
            height,
            bits: vec![0; words],
        };
        let reach = pixel_reach(camera);
        // Pixel tests, at most 16 image areas in all (a scene of many large
        // lights in view stops marking, which only forgoes some averaging):
        // load time stays a few hundred milliseconds at 4096².
        let mut budget = 16 * width as u64 * height as u64;
        for light in &lights.lights {
            match light {
                LightKind::Sphere { sphere, .. } => {
                    mask.mark_sphere(camera, sphere, reach, &mut budget)
                }
                LightKind::Rectangle { shape, .. } => {
                    mask.mark_rectangle(camera, shape, &mut budget)
                }
                LightKind::Point { .. } | LightKind::Environment(_) => {}
            }
        }
        mask.bits.iter().any(|&w| w != 0).then_some(mask)
    }

    /// Whether pixel (`x`, `y`) is marked.
    #[inline]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        if x >= self.width || y >= self.height {
            return false;
        }
        let i = y as usize * self.width as usize + x as usize;
        self.bits[i / 64] >> (i % 64) & 1 == 1
    }

    /// Number of marked pixels.
    pub fn count(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
    }

    fn mark(&mut self, x: u32, y: u32) {
        let i = y as usize * self.width as usize + x as usize;
        self.bits[i / 64] |= 1 << (i % 64);
    }

    /// Pixels whose centre ray is within `reach` (rad) of the sphere's
    /// silhouette cone: every direction of such a pixel's footprint is
    /// within `reach` of its centre's, so an unmarked pixel is wholly
    /// inside or wholly outside the silhouette.
    fn mark_sphere(&mut self, camera: &Camera, sphere: &Sphere, reach: f64, budget: &mut u64) {
        let oc = sphere.center - camera.origin();
        let d = oc.length();
        // From inside (or on) the light every direction sees it: no outline.
        if !(d.is_finite() && d > sphere.radius * (1.0 + 1e-9)) {
            return;
        }
        let axis = oc / d;
        let half = (sphere.radius / d).asin();
        let cos_out = (half + reach).min(core::f64::consts::PI).cos();
        let cos_in = (half - reach).max(0.0).cos();
        let Some((x0, x1, y0, y1)) = self.cone_box(camera, axis, half + reach) else {
            return;
        };
        if !spend(budget, x0, x1, y0, y1) {
            return;
        }
        for y in y0..y1 {
            for x in x0..x1 {
                let c = camera.ray(x as f64 + 0.5, y as f64 + 0.5).d.dot(axis);
                if c >= cos_out && c <= cos_in {
                    self.mark(x, y);
                }
            }
        }
    }

    /// The pixel range (x0..x1, y0..y1) holding the directions within
    /// `angle` of `axis`: the whole image unless the cone lies in front of
    /// the camera, else the box of its rim's projections plus two pixels.
    fn cone_box(&self, camera: &Camera, axis: DVec3, angle: f64) -> Option<(u32, u32, u32, u32)> {
        let full = Some((0, self.width, 0, self.height));
        if angle >= core::f64::consts::FRAC_PI_2 {
            return full;
        }
        let (t, b) = brdf::frame::orthonormal_basis(axis);
        let (s, c) = angle.sin_cos();
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        // The rim's projection is a conic; 256 points on it and a two-pixel
        // margin cover the chords' sag for any cone narrower than 90°
        // that projects in front of the camera.
        const RIM: usize = 256;
        for i in 0..RIM {
            let (si, ci) = (core::f64::consts::TAU * i as f64 / RIM as f64).sin_cos();
            let dir = c * axis + s * (ci * t + si * b);
            let Some((px, py)) = camera.project(camera.origin() + dir) else {
                return full;
            };
            lo = lo.min(DVec2::new(px, py));
            hi = hi.max(DVec2::new(px, py));
        }
        self.pixel_box(lo, hi)
    }

    /// The pixels (x0..x1, y0..y1) within two of the image-plane box
    /// `lo`–`hi`, clipped to the image; `None` if none are.
    fn pixel_box(&self, lo: DVec2, hi: DVec2) -> Option<(u32, u32, u32, u32)> {
        let clamp = |v: f64, n: u32| (v.max(0.0).min(n as f64)) as u32;
        let (x0, x1) = (clamp(lo.x - 2.0, self.width), clamp(hi.x + 3.0, self.width));
        let (y0, y1) = (
            clamp(lo.y - 2.0, self.height),
            clamp(hi.y + 3.0, self.height),
        );
        (x0 < x1 && y0 < y1).then_some((x0, x1, y0, y1))
    }

    /// Pixels whose centre is within one pixel of a rectangle's projected
    /// edge (a pixel's footprint reaches 0.71 px from its centre). A
    /// rectangle reaching behind the camera's plane is left unmarked.
    fn mark_rectangle(&mut self, camera: &Camera, shape: &Planar, budget: &mut u64) {
        let (hu, hv) = shape.half;
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(a, b)| camera.project(shape.center + a * hu * shape.u + b * hv * shape.v));
        let Some(p) = corners
            .iter()
            .map(|c| c.map(|(x, y)| DVec2::new(x, y)))
            .collect::<Option<Vec<_>>>()
        else {
            return;
        };
        for i in 0..4 {
            let (a, b) = (p[i], p[(i + 1) % 4]);
            let Some((x0, x1, y0, y1)) = self.pixel_box(a.min(b), a.max(b)) else {
                continue;
            };
            if !spend(budget, x0, x1, y0, y1) {
                return;
            }
            for y in y0..y1 {
                for x in x0..x1 {
                    let q = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    if segment_distance(q, a, b) <= 1.0 {
                        self.mark(x, y);
                    }
                }
            }
        }
    }
}

/// An upper bound on the angle between a pixel's centre ray and any ray
/// through its footprint: the half-diagonal's angle at the image centre,
/// where a pinhole camera's pixels subtend the most, with 50 % margin.
fn pixel_reach(camera: &Camera) -> f64 {
    let (cx, cy) = (0.5 * camera.width as f64, 0.5 * camera.height as f64);
    let a = camera.ray(cx, cy).d;
    let b = camera.ray(cx + 0.5, cy + 0.5).d;
    1.5 * a.dot(b).clamp(-1.0, 1.0).acos()
}

/// Takes the pixel box's area from `budget` if it holds that much.
fn spend(budget: &mut u64, x0: u32, x1: u32, y0: u32, y1: u32) -> bool {
    let area = x1.saturating_sub(x0) as u64 * y1.saturating_sub(y0) as u64;
    let ok = area <= *budget;
    if ok {
        *budget -= area;
    }
    ok
}

/// Distance from `q` to the segment `ab`.
fn segment_distance(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((q - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + t * ab - q).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Transform;
    use crate::spectrum::Spectrum;
    use brdf::numerics::splitmix::SplitMix64;

    fn lights(kinds: Vec<LightKind>) -> Lights {
        Lights {
            lights: kinds,
            environment: None,
            bsdf_only_environment: false,
        }
    }

    /// Which of an 12 × 12 grid of rays through pixel (x, y) see the
    /// emitter (`hits`: a ray's origin and direction to "meets it").
    fn coverage(camera: &Camera, x: u32, y: u32, hits: &dyn Fn(DVec3, DVec3) -> bool) -> usize {
        let n = 12;
        let mut k = 0;
        for i in 0..=n {
            for j in 0..=n {
                let r = camera.ray(
                    x as f64 + i as f64 / n as f64,
                    y as f64 + j as f64 / n as f64,
                );
                k += usize::from(hits(r.o, r.d));
            }
        }
        k
    }

    /// Every pixel whose footprint holds rays that meet the emitter and
    /// rays that miss it is marked; and the marks are few, a band along
    /// the outline rather than the whole image.
    fn check(camera: &Camera, mask: Option<&EmitterEdges>, hits: &dyn Fn(DVec3, DVec3) -> bool) {
        check_band(camera, mask, hits, true);
    }

    /// [`check`], with the band's width checked only if `band`.
    fn check_band(
        camera: &Camera,
        mask: Option<&EmitterEdges>,
        hits: &dyn Fn(DVec3, DVec3) -> bool,
        band: bool,
    ) {
        let (mut mixed, mut marked) = (0, 0);
        for y in 0..camera.height {
            for x in 0..camera.width {
                let k = coverage(camera, x, y, hits);
                let on = mask.is_some_and(|m| m.contains(x, y));
                marked += usize::from(on);
                if k > 0 && k < 169 {
                    mixed += 1;
                    assert!(
                        on,
                        "pixel ({x}, {y}) has {k}/169 rays on the emitter, unmarked"
                    );
                }
            }
        }
        // An outline just outside the image marks a strip along its border.
        let border = (camera.width + camera.height) as usize;
        assert!(
            !band || marked <= 4 * mixed + border,
            "{marked} marked for {mixed} outline pixels"
        );
    }

    fn camera(rng: &mut SplitMix64) -> Camera {
        let from = DVec3::new(
            rng.uniform() - 0.5,
            rng.uniform() + 0.5,
            3.0 + rng.uniform(),
        );
        let fov = 20.0 + 60.0 * rng.uniform();
        Camera::new(from, DVec3::new(0.0, 0.5, 0.0), DVec3::Y, fov, 48, 36).unwrap()
    }

    #[test]
    fn sphere_outlines_are_marked() {
        let mut rng = SplitMix64::new(5);
        for _ in 0..12 {
            let cam = camera(&mut rng);
            let center = DVec3::new(
                2.0 * rng.uniform() - 1.0,
                rng.uniform(),
                2.0 * rng.uniform() - 1.0,
            );
            let radius = 0.02 + 0.5 * rng.uniform();
            let sphere = Sphere { center, radius };
            let l = lights(vec![LightKind::Sphere {
                sphere,
                spectrum: Spectrum::Constant(1.0),
            }]);
            let mask = EmitterEdges::build(&cam, &l, 8);
            check(&cam, mask.as_ref(), &|o, d| {
                let oc = center - o;
                let b = oc.dot(d);
                b > 0.0 && oc.length_squared() - b * b <= radius * radius
            });
        }
    }

    #[test]
    fn rectangle_outlines_are_marked() {
        let mut rng = SplitMix64::new(9);
        for _ in 0..12 {
            let cam = camera(&mut rng);
            let xf = Transform::new(
                [360.0 * rng.uniform(), 360.0 * rng.uniform(), 0.0],
                1.0,
                [rng.uniform() - 0.5, rng.uniform(), rng.uniform() - 0.5],
            );
            let size = [0.1 + rng.uniform(), 0.1 + rng.uniform()];
            let shape = Planar::rectangle(size, &xf);
            let l = lights(vec![LightKind::Rectangle {
                shape,
                spectrum: Spectrum::Constant(1.0),
                two_sided: true,
            }]);
            let mask = EmitterEdges::build(&cam, &l, 8);
            check(&cam, mask.as_ref(), &|o, d| {
                let dn = d.dot(shape.n);
                if dn.abs() < 1e-12 {
                    return false;
                }
                let t = (shape.center - o).dot(shape.n) / dn;
                let q = o + t * d - shape.center;
                t > 0.0
                    && q.dot(shape.u).abs() <= shape.half.0
                    && q.dot(shape.v).abs() <= shape.half.1
            });
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// Over the accepted domain of cameras (field of view 1–170°,
        /// non-square images) and sphere lights from a thousandth of the
        /// view to as large as it, near and far: every pixel whose footprint
        /// both sees and misses the light is marked, and up to a 60° field
        /// (either way) the marks stay a band along the outline. (Wider,
        /// the reach taken from the image centre's pixels marks a wider band
        /// toward the edges, whose pixels subtend less: more rays, the same
        /// expectation.)
        #[test]
        fn sphere_outlines_are_marked_for_any_camera(
            fov in 1.0f64..170.0,
            (w, h) in (8u32..40, 8u32..40),
            dir in proptest::array::uniform3(-1.0f64..1.0),
            dist in 0.05f64..1e4,
            size in 1e-3f64..1.0,
        ) {
            let axis = DVec3::from_array(dir).try_normalize().unwrap_or(DVec3::NEG_Z);
            let cam = Camera::new(DVec3::ZERO, axis, DVec3::Y, fov, w, h);
            proptest::prop_assume!(cam.is_ok());
            let cam = cam.unwrap();
            // The light on the view axis, offset by a fraction of the view.
            let half = (0.5 * fov).to_radians().tan() * dist;
            let center = axis * dist + DVec3::new(0.2, -0.1, 0.0) * half;
            let radius = size * half;
            proptest::prop_assume!((center - cam.origin()).length() > radius * 1.01);
            let l = lights(vec![LightKind::Sphere {
                sphere: Sphere { center, radius },
                spectrum: Spectrum::Constant(1.0),
            }]);
            let mask = EmitterEdges::build(&cam, &l, 8);
            let hits = |o: DVec3, d: DVec3| {
                let oc = center - o;
                let b = oc.dot(d);
                b > 0.0 && oc.length_squared() - b * b <= radius * radius
            };
            // The wider of the vertical and horizontal fields (degrees).
            let aspect = w as f64 / h as f64;
            let horizontal = 2.0 * ((0.5 * fov).to_radians().tan() * aspect).atan().to_degrees();
            let widest = fov.max(horizontal);
            check_band(&cam, mask.as_ref(), &hits, widest <= 60.0);
        }
    }

    #[test]
    fn no_mask_without_an_outline_in_view_or_with_one_sample() {
        let cam = Camera::new(
            DVec3::new(0.0, 0.0, 3.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            32,
            24,
        )
        .unwrap();
        let sphere = |center: DVec3, radius: f64| {
            lights(vec![LightKind::Sphere {
                sphere: Sphere { center, radius },
                spectrum: Spectrum::Constant(1.0),
            }])
        };
        let behind = sphere(DVec3::new(0.0, 0.0, 6.0), 0.3);
        assert!(EmitterEdges::build(&cam, &behind, 8).is_none());
        let inside = sphere(DVec3::new(0.0, 0.0, 3.0), 1.0);
        assert!(EmitterEdges::build(&cam, &inside, 8).is_none());
        let ahead = sphere(DVec3::ZERO, 0.3);
        assert!(EmitterEdges::build(&cam, &ahead, 1).is_none());
        let m = EmitterEdges::build(&cam, &ahead, 8).unwrap();
        assert!(
            !m.contains(16, 12),
            "the disk's centre is inside, not on the outline"
        );
        assert!(
            !m.contains(32, 0) && !m.contains(0, 24),
            "outside the image"
        );
    }
}
