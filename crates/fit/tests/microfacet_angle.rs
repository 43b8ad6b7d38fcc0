//! `lustre fit` writes the anisotropic GGX of a scan flagged anisotropic with its axes in
//! the scan's frame: `[material].angle_deg` is the direction across the lay (degrees from
//! the scan's x towards y, the stretched models' φ₀), `alpha_x` along it and `alpha_y`
//! across it. On stretched synthetic maps at several orientations the written angle
//! recovers the map's own (±2°, modulo 180°), and the written GGX, built as an `include`
//! of the file builds it, is the GGX of the map's slopes in the map's own frame (its axes
//! known from the synthesis, not from the fit) evaluated at directions turned into that
//! frame.

use brdf::spec::{MaterialDesc, ModelKind, ModelSpec, NoFiles};
use brdf::{Bxdf, DVec3, Distribution, Fresnel, MicrofacetConductor};
use fit::kc2d;
use fit::material_file as material;
use fit::pipeline::{Options, analyse};

#[allow(dead_code)] // the file_of round trip is the other material tests'
mod common;
use common::{UM, prov, stretched};

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// R(−φ) v: a scan-frame direction in the frame whose x axis is at φ.
fn into_frame(v: DVec3, phi_deg: f64) -> DVec3 {
    let (s, c) = phi_deg.to_radians().sin_cos();
    DVec3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)
}

/// The difference of two axis directions, modulo 180°, in [0, 90].
fn axis_gap_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

/// Rms slopes of the map along the axis at `phi_deg` and across it (forward differences,
/// the map's own grid).
fn slopes_in_frame(t: &fit::Topography, phi_deg: f64) -> (f64, f64) {
    let (s, c) = phi_deg.to_radians().sin_cos();
    let (mut uu, mut vv, mut n) = (0.0, 0.0, 0.0);
    for y in 0..t.ny - 1 {
        for x in 0..t.nx - 1 {
            let i = y * t.nx + x;
            let sx = (t.heights[i + 1] - t.heights[i]) / t.dx;
            let sy = (t.heights[i + t.nx] - t.heights[i]) / t.dy;
            let (su, sv) = (c * sx + s * sy, -s * sx + c * sy);
            uu += su * su;
            vv += sv * sv;
            n += 1.0;
        }
    }
    ((uu / n).sqrt(), (vv / n).sqrt())
}

#[test]
fn the_written_angle_and_ggx_render_the_scan_as_it_lay() {
    let ratio = 3.0;
    let mut worst_angle: f64 = 0.0;
    let mut worst_brdf: f64 = 0.0;
    for (k, phi) in [0.0, 30.0, 75.0, -50.0, 120.0].into_iter().enumerate() {
        let params = stretched(ratio, phi, 0.01);
        let t = kc2d::synth_surface(256, 256, 20.0 * UM / 256.0, params, 40 + k as u64);
        let (su, sv) = slopes_in_frame(&t, phi);
        let a = analyse(t, None, &Options::default()).unwrap();
        let doc = material::build(&a, &prov("synthetic"));
        assert!(doc.anisotropy.as_ref().unwrap().anisotropic, "φ {phi}");
        let m = &doc.material;
        let angle = m.angle_deg.unwrap();
        let gap = axis_gap_deg(angle, phi);
        worst_angle = worst_angle.max(gap);
        assert!(gap <= 2.0, "φ {phi}: written angle_deg {angle}");
        let (ax, ay) = (m.alpha_x.unwrap(), m.alpha_y.unwrap());
        // Across the lay first, in the proportion of the map's own slopes (not Ly/Lx: at
        // γ = 3 the slope variance is set by the pixel, which cuts the steep axis more).
        assert!(
            ax > 1.5 * ay && (ax / ay / (su / sv) - 1.0).abs() < 0.05,
            "φ {phi}: alpha_x {ax} alpha_y {ay}, own-frame slopes {su} {sv}"
        );
        // Every model the file offers builds, and the file reads back with its axes.
        material::check(&doc).unwrap();
        let text = material::to_toml(&doc).unwrap();
        let back: brdf::spec::MaterialFile = toml::from_str(&text).unwrap();
        assert_eq!(back.material, doc.material);
        // The file's GGX as a scene's include of it builds it.
        let written = doc
            .resolve(
                &MaterialDesc {
                    model: Some(ModelKind::Ggx),
                    ..MaterialDesc::default()
                },
                &mut NoFiles,
            )
            .unwrap();
        assert!(
            matches!(written.model, ModelSpec::Ggx { angle_deg, .. } if angle_deg == angle),
            "{:?}",
            written.model
        );
        let written = written.build().unwrap();
        // The GGX of the map's slopes in its own frame: the isotropic NDF fit split as the
        // slopes along the synthesis axes are.
        let alpha = m.alpha.unwrap();
        let mean = ((su * su + sv * sv) / 2.0).sqrt();
        let own = MicrofacetConductor::new(
            Distribution::ggx(alpha * su / mean, alpha * sv / mean).unwrap(),
            Fresnel::conductor(brdf::Ior::metal(brdf::Metal::Cu)),
        )
        .unwrap();
        for (ti, pi) in [(0.0, 0.0), (30.0, 10.0), (45.0, 200.0)] {
            let wi = dir(ti, pi);
            let mirror = DVec3::new(-wi.x, -wi.y, wi.z);
            // Points in the lobe: the mirror direction and offsets of about one α along and
            // across the lay.
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.7, -0.7), (-1.0, 0.3)] {
                let (s, c) = phi.to_radians().sin_cos();
                let off =
                    DVec3::new(ax * dx * c - ay * dy * s, ax * dx * s + ay * dy * c, 0.0) * 0.5;
                let wo = (mirror + off).normalize();
                if wo.z <= 0.05 {
                    continue;
                }
                let f = written.eval(wi, wo, 550.0);
                let g = own.eval(into_frame(wi, phi), into_frame(wo, phi), 550.0);
                let rel = (f / g - 1.0).abs();
                worst_brdf = worst_brdf.max(rel);
                assert!(
                    rel < 0.05,
                    "φ {phi}: θi {ti} offset ({dx}, {dy}): {f} vs {g}"
                );
            }
        }
        println!(
            "φ {phi:6.1}°: angle_deg {angle:7.2} (gap {gap:.2}°), alpha_x {ax:.4}, alpha_y \
             {ay:.4}, own-frame α ({:.4}, {:.4})",
            alpha * su / mean,
            alpha * sv / mean
        );
    }
    println!("worst angle gap {worst_angle:.2}°, worst BRDF ratio − 1: {worst_brdf:.3}");
}

/// A map not flagged anisotropic gets the isotropic `alpha` only, and its GGX is not turned.
#[test]
fn an_isotropic_map_writes_no_axes() {
    let params = stretched(1.0, 0.0, 0.01);
    let t = kc2d::synth_surface(256, 256, 20.0 * UM / 256.0, params, 7);
    let doc = material::build(
        &analyse(t, None, &Options::default()).unwrap(),
        &prov("synthetic"),
    );
    assert!(!doc.anisotropy.as_ref().unwrap().anisotropic);
    assert_eq!((doc.material.alpha_x, doc.material.alpha_y), (None, None));
    let ggx = doc
        .resolve(
            &MaterialDesc {
                model: Some(ModelKind::Ggx),
                ..MaterialDesc::default()
            },
            &mut NoFiles,
        )
        .unwrap();
    let ModelSpec::Ggx {
        alpha_x, alpha_y, ..
    } = ggx.model
    else {
        panic!("{:?}", ggx.model)
    };
    assert_eq!(alpha_x, alpha_y);
}
