//! The stretched measured-PSD model in the material file (physics.md §15.2): a stretched map
//! gets a usable `[psd.destretched]`, its reliability `ok`, and an `include` of the file with
//! `model = "measured_psd_aniso"` builds the model with the file's axes; the file survives a
//! TOML round trip. Two crossing lays (a 2-D PSD that is a cross, not an ellipse) are said to
//! be so in `[reliability].psd_destretched`. An isotropic map is not flagged and gets no table.

use brdf::spec::{MaterialDesc, ModelKind, ModelSpec, NoFiles};
use fit::kc2d;

mod common;
use common::{UM, file_of, stretched};

#[test]
fn a_stretched_map_gets_a_usable_destretched_table_that_builds() {
    let t = kc2d::synth_surface(256, 256, 20.0 * UM / 256.0, stretched(5.0, 30.0, 0.01), 3);
    let doc = file_of(t, "stretched").0;
    let d = doc
        .psd
        .as_ref()
        .and_then(|p| p.destretched.as_ref())
        .unwrap();
    println!(
        "stretched: residual {:.3}; {}",
        d.rms_log_residual, doc.reliability.psd_destretched
    );
    assert!(d.usable);
    assert!(d.rms_log_residual < 0.5, "{}", d.rms_log_residual);
    assert_eq!(doc.reliability.psd_destretched, "ok");
    let desc = MaterialDesc {
        model: Some(ModelKind::MeasuredPsdAniso),
        ..MaterialDesc::default()
    };
    let spec = doc.resolve(&desc, &mut NoFiles).unwrap();
    let ModelSpec::MeasuredPsdAniso { surface, .. } = &spec.model else {
        panic!("{:?}", spec.model);
    };
    assert_eq!(surface.zeta_rad_per_um, d.zeta_rad_per_um);
    let ratio = surface.ly_um / surface.lx_um;
    assert!((ratio / 5.0 - 1.0).abs() < 0.1, "Ly/Lx {ratio}");
    assert!(
        (surface.angle_deg - 30.0).abs() < 2.0,
        "{}",
        surface.angle_deg
    );
    spec.build().unwrap();
    assert!(
        doc.offered()
            .iter()
            .any(|o| o.model == Some(ModelKind::MeasuredPsdAniso))
    );
}

#[test]
fn crossing_lays_are_said_not_to_be_elliptical() {
    let dx = 20.0 * UM / 256.0;
    let a = kc2d::synth_surface(256, 256, dx, stretched(8.0, 0.0, 0.01), 5);
    let b = kc2d::synth_surface(256, 256, dx, stretched(8.0, 90.0, 0.004), 6);
    let mut t = a.clone();
    for (h, g) in t.heights.iter_mut().zip(&b.heights) {
        *h += g;
    }
    let doc = file_of(t, "crossed").0;
    let an = doc.anisotropy.as_ref().unwrap();
    println!(
        "crossed: anisotropic {}; {}; {:?}",
        an.anisotropic,
        doc.reliability.psd_destretched,
        doc.psd
            .as_ref()
            .and_then(|p| p.destretched.as_ref())
            .map(|d| d.rms_log_residual)
    );
    assert!(an.anisotropic, "{:?}", an.warning);
    assert!(
        doc.reliability
            .psd_destretched
            .contains("not constant on ellipses"),
        "{}",
        doc.reliability.psd_destretched
    );
    assert!(
        doc.reliability
            .unreliable
            .contains(&"psd_destretched".to_string())
    );
}

#[test]
fn an_isotropic_map_is_not_flagged_and_gets_no_table() {
    let t = kc2d::synth_surface(256, 256, 20.0 * UM / 256.0, stretched(1.0, 0.0, 0.01), 7);
    let doc = file_of(t, "isotropic").0;
    let an = doc.anisotropy.as_ref().unwrap();
    assert!(!an.anisotropic, "{:?}", an.warning);
    assert!(doc.psd.as_ref().unwrap().destretched.is_none());
    assert!(
        doc.reliability.psd_destretched.starts_with("not written"),
        "{}",
        doc.reliability.psd_destretched
    );
}
