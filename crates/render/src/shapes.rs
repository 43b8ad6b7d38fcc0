//! Everything a ray can hit, the two ray queries the integrator asks of it
//! (`intersect`, `occluded`), and what they answer ([`Hit`], [`Surface`]).

use crate::analytic_bvh::{AnalyticBvh, Prim};
use crate::geometry::{Planar, Ray, Sphere, SurfacePoint};
use crate::mesh::MeshAccel;
use glam::DVec3;

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// A reflecting surface with this material index.
    Material(u32),
    /// An emitting shape: index into [`Lights::lights`](crate::light::Lights::lights).
    Emitter(u32),
}

/// A ray hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Geometry at the hit.
    pub geo: SurfacePoint,
    /// What was hit.
    pub surface: Surface,
    /// Whether it is a mesh triangle (traversed in f32: needs a larger ray offset).
    pub mesh: bool,
    /// Interpolated vertex normal of a smooth-shaded mesh triangle (same
    /// orientation convention as `geo.n`); `None`: shade with `geo.n`.
    pub shading_n: Option<DVec3>,
}

impl Hit {
    /// A hit on an analytic shape (intersected in f64, shaded with its geometric normal).
    #[inline]
    pub fn analytic(geo: SurfacePoint, surface: Surface) -> Hit {
        Hit {
            geo,
            surface,
            mesh: false,
            shading_n: None,
        }
    }
}

/// A checkerboard over a shape's texture coordinates: a shape given material
/// `m` (the ρ1 squares) shows material `color0` on the squares (i, j) =
/// (⌊u·tiles₀⌋, ⌊v·tiles₁⌋) with i + j even
/// ([`brdf::spec::MaterialDesc::checker_split`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// Squares across the (u, v) unit square, along u and v.
    pub tiles: [f64; 2],
    /// Material index of the ρ0 squares.
    pub color0: u32,
}

impl Checker {
    /// Whether (u, v) lies on a ρ0 square.
    #[inline]
    pub fn color0_at(&self, uv: [f64; 2]) -> bool {
        self.color0_in([
            (uv[0] * self.tiles[0]).floor(),
            (uv[1] * self.tiles[1]).floor(),
        ])
    }

    /// Whether square (i, j) is a ρ0 square.
    #[inline]
    pub fn color0_in(&self, [i, j]: [f64; 2]) -> bool {
        (i + j).rem_euclid(2.0) == 0.0
    }
}

/// Everything a ray can hit: analytic shapes tested one by one (a scene
/// has a handful) and, only when the scene has meshes, one BVH over all
/// their triangles.
pub struct Shapes {
    /// Rectangles and disks (reflectors and emitters).
    pub planars: Vec<(Planar, Surface)>,
    /// Spheres (reflectors and emitters).
    pub spheres: Vec<(Sphere, Surface)>,
    /// Mesh triangles (only when the scene has any).
    pub mesh: Option<MeshAccel>,
    /// A hierarchy over `planars` and `spheres` when they are many
    /// ([`AnalyticBvh::build`]); `None`: rays test them one by one.
    pub analytic_bvh: Option<AnalyticBvh>,
    /// Per material index, its checkerboard if it has one; empty when no
    /// material has one (then no hit computes texture coordinates).
    pub checkers: Vec<Option<Checker>>,
}

/// The nearest analytic shape along a ray.
#[derive(Clone, Copy)]
enum Analytic {
    /// Planar shape `.0`, at in-plane coordinates (`.1`, `.2`).
    Planar(usize, f64, f64),
    Sphere(usize),
}

/// Which shape a hit is on, for its texture coordinates.
#[derive(Clone, Copy)]
enum Struck {
    Analytic(Analytic),
    Triangle(usize),
}

impl Shapes {
    /// Number of analytic shapes.
    pub fn analytic_count(&self) -> usize {
        self.planars.len() + self.spheres.len()
    }

    /// Nearest hit along `ray` in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        // The nearest analytic shape by distance alone; its point, normal
        // and tangent (for a sphere a normalisation and a division each) only
        // for the one that wins, instead of a 120-byte hit per candidate.
        let (nearest, t_max) = self.nearest_analytic(ray, t_max);
        let (mut hit, struck) = if let Some(m) = &self.mesh
            && let Some((g, mat, shading_n, id)) = m.intersect(ray, 0.0, t_max)
        {
            let hit = Hit {
                geo: g,
                surface: Surface::Material(mat),
                mesh: true,
                shading_n,
            };
            (hit, Struck::Triangle(id))
        } else {
            let nearest = nearest?;
            let hit = match nearest {
                Analytic::Planar(k, ..) => {
                    let (p, s) = &self.planars[k];
                    Hit::analytic(p.point_at(ray, t_max), *s)
                }
                Analytic::Sphere(i) => {
                    let (sp, s) = &self.spheres[i];
                    Hit::analytic(sp.point_at(ray, t_max), *s)
                }
            };
            (hit, Struck::Analytic(nearest))
        };
        if !self.checkers.is_empty()
            && let Surface::Material(m) = hit.surface
            && let Some(Some(c)) = self.checkers.get(m as usize)
            && self.color0(c, struck, hit.geo.p)
        {
            hit.surface = Surface::Material(c.color0);
        }
        Some(hit)
    }

    /// The nearest analytic shape along `ray` within (0, `t_max`), and its
    /// distance (`t_max` if none).
    #[inline]
    fn nearest_analytic(&self, ray: &Ray, t_max: f64) -> (Option<Analytic>, f64) {
        let mut t_max = t_max;
        let mut nearest = None;
        if let Some(bvh) = &self.analytic_bvh {
            bvh.visit(ray, t_max, |prim, t| match prim {
                Prim::Planar(k) => {
                    let h = self.planars[k as usize].0.hit(ray, 0.0, t)?;
                    nearest = Some(Analytic::Planar(k as usize, h.a, h.b));
                    t_max = h.t;
                    Some(h.t)
                }
                Prim::Sphere(i) => {
                    let d = self.spheres[i as usize].0.hit_distance(ray, 0.0, t)?;
                    nearest = Some(Analytic::Sphere(i as usize));
                    t_max = d;
                    Some(d)
                }
            });
            return (nearest, t_max);
        }
        for (k, (p, _)) in self.planars.iter().enumerate() {
            if let Some(h) = p.hit(ray, 0.0, t_max) {
                t_max = h.t;
                nearest = Some(Analytic::Planar(k, h.a, h.b));
            }
        }
        for (i, (sp, _)) in self.spheres.iter().enumerate() {
            if let Some(t) = sp.hit_distance(ray, 0.0, t_max) {
                t_max = t;
                nearest = Some(Analytic::Sphere(i));
            }
        }
        (nearest, t_max)
    }

    /// Whether point `p` of the struck shape lies on checkerboard `c`'s ρ0
    /// squares. The square from the shape's coordinates where they decide
    /// it, which saves a disk's `hypot` and `atan2` and a sphere's `atan2`
    /// and `acos`; the texture coordinates' rule near the squares' edges.
    #[inline]
    fn color0(&self, c: &Checker, struck: Struck, p: DVec3) -> bool {
        let square = match struck {
            Struck::Analytic(Analytic::Planar(k, a, b)) => {
                self.planars[k].0.checker_square(a, b, c.tiles)
            }
            Struck::Analytic(Analytic::Sphere(k)) => self.spheres[k].0.checker_square(p, c.tiles),
            Struck::Triangle(_) => None,
        };
        match square {
            Some(square) => c.color0_in(square),
            None => c.color0_at(self.uv(struck, p)),
        }
    }

    /// Texture coordinates of point `p` on the struck shape.
    fn uv(&self, struck: Struck, p: DVec3) -> [f64; 2] {
        match struck {
            Struck::Analytic(Analytic::Planar(k, a, b)) => self.planars[k].0.uv_in_plane(a, b),
            Struck::Analytic(Analytic::Sphere(k)) => self.spheres[k].0.uv(p),
            Struck::Triangle(id) => self.mesh.as_ref().map_or([0.0; 2], |m| m.uv(id, p)),
        }
    }

    /// Whether anything lies on `ray` within `(0, t_max)`, not testing the
    /// analytic shapes whose surface is `own`: a shadow ray toward a point
    /// of an emitter that is the ray's nearest hit on it (a light sample's
    /// point) cannot be blocked by that emitter, and a sphere light's test
    /// is two square roots and a division per light sample.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64, own: Option<Surface>) -> bool {
        let other = |s: &Surface| own != Some(*s);
        let analytic = match &self.analytic_bvh {
            Some(bvh) => {
                let mut blocked = false;
                bvh.visit(ray, t_max, |prim, t| {
                    blocked = match prim {
                        Prim::Planar(k) => {
                            let (p, s) = &self.planars[k as usize];
                            other(s) && p.hit(ray, 0.0, t).is_some()
                        }
                        Prim::Sphere(i) => {
                            let (sp, s) = &self.spheres[i as usize];
                            other(s) && sp.hit_distance(ray, 0.0, t).is_some()
                        }
                    };
                    blocked.then_some(-1.0)
                });
                blocked
            }
            None => {
                self.planars
                    .iter()
                    .any(|(p, s)| other(s) && p.hit(ray, 0.0, t_max).is_some())
                    || self
                        .spheres
                        .iter()
                        .any(|(sp, s)| other(s) && sp.hit_distance(ray, 0.0, t_max).is_some())
            }
        };
        analytic
            || self
                .mesh
                .as_ref()
                .is_some_and(|m| m.occluded(ray, 0.0, t_max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{SurfacePoint, Transform};
    use crate::light::{LightKind, Lights};
    use crate::rng::Rng;
    use crate::spectrum::Spectrum;
    use glam::DVec3;

    /// A sphere light and a rectangle light, registered as emitters 0 and 1
    /// the way the scene builder does, and a blocking rectangle.
    fn scene() -> (Shapes, Lights) {
        let sphere = Sphere {
            center: DVec3::new(0.0, 0.0, 3.0),
            radius: 0.8,
        };
        let rect = Planar::rectangle(
            [1.5, 0.7],
            &Transform::new([30.0, 0.0, 10.0], 1.0, [2.0, 0.5, 2.0]),
        );
        let blocker =
            Planar::rectangle([0.4, 0.4], &Transform::new([0.0; 3], 1.0, [0.0, 0.0, 1.0]));
        let shapes = Shapes {
            planars: vec![(rect, Surface::Emitter(1)), (blocker, Surface::Material(0))],
            spheres: vec![(sphere, Surface::Emitter(0))],
            mesh: None,
            analytic_bvh: None,
            checkers: Vec::new(),
        };
        let lights = Lights {
            lights: vec![
                LightKind::Sphere {
                    sphere,
                    spectrum: Spectrum::Constant(1.0),
                },
                LightKind::Rectangle {
                    shape: rect,
                    spectrum: Spectrum::Constant(1.0),
                    two_sided: true,
                },
            ],
            environment: None,
            bsdf_only_environment: false,
        };
        (shapes, lights)
    }

    #[test]
    fn an_emitter_never_shadows_its_own_light_sample() {
        // From points all around (some within 1e-6 of the sphere, some in
        // the light's plane), the emitter's own test never reports a hit
        // before the sampled point: skipping it changes no answer.
        let (shapes, lights) = scene();
        let mut rng = Rng::for_sample(7, 1, 2);
        let (mut tested, mut blocked) = (0, 0);
        for k in 0..200_000 {
            let p = match k % 4 {
                0 => {
                    DVec3::new(0.0, 0.0, 3.0)
                        + crate::light::uniform_sphere([rng.uniform(), rng.uniform()])
                            * (0.8 + 1e-6 * rng.uniform())
                }
                _ => (DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5) * 8.0,
            };
            let Some(ls) = lights.sample(p, rng.uniform3()) else {
                continue;
            };
            if !ls.dist.is_finite() || ls.pdf <= 0.0 {
                continue;
            }
            let ray = Ray { o: p, d: ls.wi };
            let t_max = ls.dist * (1.0 - 1e-7);
            let own = ls.shape.expect("area lights name their shape");
            let self_hit = match own {
                Surface::Emitter(0) => shapes.spheres[0].0.hit_distance(&ray, 0.0, t_max).is_some(),
                _ => shapes.planars[0].0.intersect(&ray, 0.0, t_max).is_some(),
            };
            assert!(
                !self_hit,
                "{own:?} shadows its own sample from {p} toward {}",
                ls.wi
            );
            let all = shapes.occluded(&ray, t_max, None);
            assert_eq!(all, shapes.occluded(&ray, t_max, Some(own)));
            tested += 1;
            blocked += usize::from(all);
        }
        // The blocker is in the way of a fair share of them: the test sees
        // both answers.
        assert!(
            tested > 150_000 && blocked > 1_000 && blocked < tested / 2,
            "{tested} {blocked}"
        );
    }

    #[test]
    fn other_shapes_still_shadow() {
        let (shapes, _) = scene();
        // Straight up through the blocker to the sphere light.
        let ray = Ray {
            o: DVec3::ZERO,
            d: DVec3::Z,
        };
        assert!(shapes.occluded(&ray, 2.19, Some(Surface::Emitter(0))));
        // Without the blocker in range, nothing.
        assert!(!shapes.occluded(&ray, 0.99, Some(Surface::Emitter(0))));
        // Past the sphere's near side, skipping it is the caller's claim.
        assert!(shapes.occluded(
            &Ray {
                o: DVec3::new(0.0, 0.0, 1.5),
                d: DVec3::Z
            },
            2.0,
            None
        ));
        assert!(!shapes.occluded(
            &Ray {
                o: DVec3::new(0.0, 0.0, 1.5),
                d: DVec3::Z
            },
            2.0,
            Some(Surface::Emitter(0))
        ));
    }

    #[test]
    fn the_nearest_hit_is_the_nearest_of_every_shapes_own_hit() {
        // Overlapping rectangles, disks and spheres, hit from all around:
        // the search by distance then one surface point must give what
        // each shape's own `intersect` gives for the nearest of them; one
        // by one (6 + 6 shapes) and through the hierarchy (6 + 6 with it
        // forced, and 60 + 60).
        nearest_hits_agree(6, false, 3);
        nearest_hits_agree(6, true, 4);
        nearest_hits_agree(60, true, 5);
    }

    fn nearest_hits_agree(n: u32, hierarchy: bool, seed: u64) {
        let mut rng = Rng::for_sample(3, 4, seed);
        let mut u = || rng.uniform();
        let mut planars = Vec::new();
        let mut spheres = Vec::new();
        for k in 0..n {
            let xf = Transform::new(
                [360.0 * u(), 360.0 * u(), 360.0 * u()],
                0.5 + u(),
                [u() - 0.5, u() - 0.5, u() - 0.5],
            );
            let p = if k % 2 == 0 {
                Planar::rectangle([1.0 + u(), 0.5 + u()], &xf)
            } else {
                Planar::disk(0.3 + u(), &xf)
            };
            planars.push((p, Surface::Material(k)));
            let c = DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * (1.0 + (n / 10) as f64);
            spheres.push((
                Sphere {
                    center: c,
                    radius: 0.1 + 0.4 * u(),
                },
                Surface::Material(1000 + k),
            ));
        }
        let analytic_bvh = hierarchy.then(|| {
            let mut b = AnalyticBvh::build(&planars, &spheres);
            // Below MIN_SHAPES `build` declines; force it to test the tree.
            if b.is_none() {
                b = AnalyticBvh::build_always(&planars, &spheres);
            }
            b.expect("finite shapes")
        });
        let shapes = Shapes {
            planars: planars.clone(),
            spheres: spheres.clone(),
            mesh: None,
            analytic_bvh,
            checkers: Vec::new(),
        };
        let (mut hits, mut misses) = (0, 0);
        for i in 0..20_000 {
            let o = (DVec3::new(u(), u(), u()) - 0.5) * 6.0;
            let mut d = (DVec3::new(u(), u(), u()) - 0.5) * 1.2 - o;
            // Axis-parallel rays: zero direction components in the slabs.
            if i % 7 == 0 {
                d.x = 0.0;
            }
            if i % 11 == 0 {
                d.y = 0.0;
            }
            let d = d.normalize();
            let ray = Ray { o, d };
            let t_max = if u() < 0.2 { 3.0 * u() } else { f64::INFINITY };
            let mut want: Option<(SurfacePoint, Surface)> = None;
            let mut near = t_max;
            for (p, s) in &planars {
                if let Some(g) = p.intersect(&ray, 0.0, near) {
                    near = g.t;
                    want = Some((g, *s));
                }
            }
            for (sp, s) in &spheres {
                if let Some(g) = sp.intersect(&ray, 0.0, near) {
                    near = g.t;
                    want = Some((g, *s));
                }
            }
            let own = want.map(|(_, s)| s).filter(|_| u() < 0.5);
            let blocked = planars
                .iter()
                .any(|(p, s)| Some(*s) != own && p.hit(&ray, 0.0, t_max).is_some())
                || spheres
                    .iter()
                    .any(|(sp, s)| Some(*s) != own && sp.hit_distance(&ray, 0.0, t_max).is_some());
            assert_eq!(shapes.occluded(&ray, t_max, own), blocked, "ray {ray:?}");
            let got = shapes.intersect(&ray, t_max);
            match (got, want) {
                (None, None) => misses += 1,
                (Some(h), Some((g, s))) => {
                    hits += 1;
                    assert_eq!(h.surface, s);
                    assert!(h.geo.t == g.t && h.geo.p == g.p, "{:?} {:?}", h.geo, g);
                    assert!(h.geo.n == g.n && h.geo.tangent == g.tangent);
                }
                (h, w) => panic!("ray {ray:?}: {h:?} against {w:?}"),
            }
        }
        assert!(
            hits > 5_000 && misses > 1_000,
            "{n} shapes: {hits} hits, {misses} misses"
        );
    }
}
