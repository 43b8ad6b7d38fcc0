//! The committed preview assets: the object's vertex normals against its
//! analytic surface, the mesh's topology and winding, and that
//! `lustre scenes` reproduces every committed asset and scene (tests/scenes_generated.rs).

use glam::DVec3;
use render::preview_mesh::PreviewObject;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

struct Obj {
    v: Vec<DVec3>,
    vn: Vec<DVec3>,
    /// Faces as vertex indices (0-based; this generator writes `f a//a`).
    f: Vec<[usize; 3]>,
}

fn parse_obj(text: &str) -> Obj {
    let mut o = Obj {
        v: Vec::new(),
        vn: Vec::new(),
        f: Vec::new(),
    };
    let vec3 = |it: &mut std::str::SplitWhitespace| {
        let mut c = [0.0; 3];
        for x in &mut c {
            *x = it.next().unwrap().parse().unwrap();
        }
        DVec3::from(c)
    };
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => o.v.push(vec3(&mut it)),
            Some("vn") => o.vn.push(vec3(&mut it)),
            Some("f") => {
                let mut idx = [0usize; 3];
                for x in &mut idx {
                    let tok = it.next().unwrap();
                    let (a, b) = tok.split_once("//").unwrap();
                    assert_eq!(a, b, "normals share the vertex index");
                    *x = a.parse::<usize>().unwrap() - 1;
                }
                o.f.push(idx);
            }
            _ => {}
        }
    }
    o
}

fn committed_object() -> Obj {
    parse_obj(&std::fs::read_to_string(root().join("scenes/assets/preview_object.obj")).unwrap())
}

/// Every vertex lies on the analytic surface and its normal is the analytic
/// normal there (up to the file's 6 decimals); the shading normal
/// interpolated at each triangle's centroid is within a degree of the
/// analytic normal at the closest surface point.
#[test]
fn object_normals_match_the_analytic_surface() {
    let obj = committed_object();
    let shape = PreviewObject::new();
    assert_eq!(obj.v.len(), obj.vn.len());
    let (mut max_dist, mut max_vn) = (0.0f64, 0.0f64);
    for (p, n) in obj.v.iter().zip(&obj.vn) {
        let (_, na, dist) = shape.closest(*p);
        max_dist = max_dist.max(dist);
        max_vn = max_vn.max(n.normalize().angle_between(na));
    }
    let (mut max_interp, mut sum_interp, mut max_face) = (0.0f64, 0.0, 0.0f64);
    for f in &obj.f {
        let [a, b, c] = f.map(|i| obj.v[i]);
        let centroid = (a + b + c) / 3.0;
        let ns = (obj.vn[f[0]] + obj.vn[f[1]] + obj.vn[f[2]]).normalize();
        let (_, na, _) = shape.closest(centroid);
        let e = ns.angle_between(na);
        max_interp = max_interp.max(e);
        sum_interp += e;
        // Winding: the geometric normal points to the outside (the vertex normals' side).
        let ng = (b - a).cross(c - a).normalize();
        assert!(ng.dot(ns) > 0.0, "face {f:?} is wound inward");
        max_face = max_face.max(ng.angle_between(ns));
    }
    eprintln!(
        "{} vertices, {} triangles: vertex distance to the surface ≤ {max_dist:.2e}, vertex normal error ≤ {:.2e}°, \
         interpolated normal at centroids ≤ {:.3}° (mean {:.4}°), facet vs shading normal ≤ {:.2}°",
        obj.v.len(),
        obj.f.len(),
        max_vn.to_degrees(),
        max_interp.to_degrees(),
        (sum_interp / obj.f.len() as f64).to_degrees(),
        max_face.to_degrees()
    );
    assert!(max_dist < 2e-6, "vertex off the surface by {max_dist}");
    // 6-decimal coordinates move a vertex by ≤ 8.7e-7, which turns the closest
    // point on the lip (radius 0.03) by up to 2.9e-5 rad; the normals themselves
    // are rounded to 1e-6.
    assert!(max_vn < 5e-5, "vertex normal off by {max_vn} rad");
    assert!(
        max_interp.to_degrees() < 1.0,
        "interpolated normal off by {max_interp} rad"
    );
    assert!(
        obj.f.len() < 8000,
        "{} triangles: keep the asset small",
        obj.f.len()
    );
}

/// The object is closed: every edge is shared by exactly two triangles with
/// opposite orientation, so rays cannot leak in (furnace tests rely on it).
#[test]
fn object_mesh_is_closed_and_consistently_wound() {
    let obj = committed_object();
    let mut edges = std::collections::HashMap::new();
    for f in &obj.f {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "directed edge {a}→{b} used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}→{b} has no twin");
    }
    // Euler characteristic of a sphere-like closed surface.
    let chi = obj.v.len() as i64 - (edges.len() / 2) as i64 + obj.f.len() as i64;
    assert_eq!(chi, 2);
}

/// The object's profile has the parts the preview promises: convex (both
/// curvatures > 0), saddle and fully concave regions.
#[test]
fn object_has_convex_saddle_and_concave_parts() {
    let shape = PreviewObject::new();
    let (mut convex, mut saddle, mut concave) = (0, 0, 0);
    for p in &shape.pieces {
        if let render::preview_mesh::Piece::Arc { c: _, r, a0, a1 } = *p {
            for k in 1..10 {
                let t = k as f64 / 10.0;
                let pt = p.point(t);
                let n = p.normal(t);
                // Meridian curvature: +1/r for a counter-clockwise (convex) arc.
                let k1 = (a1 - a0).signum() / r;
                // Parallel curvature n_ρ / ρ (positive when the normal points away from the axis).
                let k2 = n.x / pt.x;
                match (k1 > 0.0, k2 > 1e-9, k2 < -1e-9) {
                    (true, true, _) => convex += 1,
                    (false, false, true) => concave += 1,
                    _ => saddle += 1,
                }
            }
        }
    }
    eprintln!("profile samples: {convex} convex, {saddle} saddle, {concave} concave");
    assert!(convex > 0 && saddle > 0 && concave > 0);
}

// The committed assets and preview scenes are `lustre scenes` output:
// tests/scenes_generated.rs checks every file byte for byte.
