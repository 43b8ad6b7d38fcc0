//! `[psd.map]` in the material file (physics.md §15.4): two crossing lays (a 2-D PSD that
//! is not elliptical) get a usable grid that survives a TOML round trip, is offered, and an
//! `include` with `model = "measured_psd2d_ssa"` builds the model of that grid; a stretched
//! (elliptical) map and an isotropic one get no grid and are not offered the model.

use brdf::spec::{MaterialDesc, MaterialFile, ModelKind, ModelSpec, NoFiles};
use fit::kc2d;

mod common;
use common::{UM, file_of, stretched};

fn offers_map(doc: &MaterialFile) -> bool {
    doc.offered()
        .iter()
        .any(|o| o.model == Some(ModelKind::MeasuredPsd2dSsa))
}

#[test]
fn crossing_lays_get_a_grid_that_builds() {
    let dx = 20.0 * UM / 256.0;
    let a = kc2d::synth_surface(256, 256, dx, stretched(8.0, 0.0, 0.01), 5);
    let b = kc2d::synth_surface(256, 256, dx, stretched(8.0, 70.0, 0.006), 6);
    let mut t = a.clone();
    for (h, g) in t.heights.iter_mut().zip(&b.heights) {
        *h += g;
    }
    let doc = file_of(t, "crossed").1;
    let m = doc.psd.as_ref().and_then(|p| p.map.as_ref()).unwrap();
    println!(
        "crossed: {}×{} nodes, step {:.3} rad/µm, α {}, tail {:.4}; {}",
        2 * m.half_nx + 1,
        m.half_ny + 1,
        m.dzx_rad_per_um,
        m.tail_exponent,
        m.tail_fraction,
        doc.reliability.psd_destretched
    );
    assert!(m.usable);
    assert!(m.half_nx <= fit::psd_map::HALF_NODES && m.half_ny <= fit::psd_map::HALF_NODES);
    assert!(
        m.tail_fraction > 0.0 && m.tail_fraction < 0.2,
        "{}",
        m.tail_fraction
    );
    assert!(offers_map(&doc));
    let desc = MaterialDesc {
        model: Some(ModelKind::MeasuredPsd2dSsa),
        ..MaterialDesc::default()
    };
    let spec = doc.resolve(&desc, &mut NoFiles).unwrap();
    let ModelSpec::MeasuredPsd2dSsa { surface, .. } = &spec.model else {
        panic!("{:?}", spec.model);
    };
    assert_eq!(surface.psd_um4, m.p_um4);
    assert_eq!(surface.angle_deg, 0.0);
    let table = surface.psd().unwrap();
    // σ of the grid with its tail against the two lays' (0.01² + 0.006² µm²).
    let want = (0.01f64.powi(2) + 0.006f64.powi(2)).sqrt();
    assert!(
        (table.sigma_um() / want - 1.0).abs() < 0.15,
        "σ {} vs {want}",
        table.sigma_um()
    );
    spec.build().unwrap();
}

#[test]
fn elliptical_and_isotropic_maps_get_no_grid() {
    let dx = 20.0 * UM / 256.0;
    for (name, p) in [
        ("stretched", stretched(5.0, 30.0, 0.01)),
        ("isotropic", stretched(1.0, 0.0, 0.01)),
    ] {
        let doc = file_of(kc2d::synth_surface(256, 256, dx, p, 3), name).1;
        assert!(
            doc.psd.as_ref().is_some_and(|p| p.map.is_none()),
            "{name}: a grid was written"
        );
        assert!(!offers_map(&doc), "{name}");
        let desc = MaterialDesc {
            model: Some(ModelKind::MeasuredPsd2dSsa),
            ..MaterialDesc::default()
        };
        let e = doc.resolve(&desc, &mut NoFiles).unwrap_err();
        assert_eq!(e.field, "psd_map", "{name}: {e}");
    }
}
