//! Scaffolding shared by the material-file tests: a scan's provenance, a stretched KC
//! surface, and a scan's material file through its TOML round trip.

use brdf::spec::MaterialFile;
use fit::kc2d::AnisoKcParams;
use fit::material_file::{self as material, Provenance};
use fit::pipeline::{Options, analyse};

pub const UM: f64 = 1e-6;

pub fn prov(file: &str) -> Provenance<'_> {
    Provenance {
        file,
        bytes: b"",
        stylus: None,
        merge_cutoff_rad_per_um: 1.0,
        metal: "cu",
        model: "auto",
        notes: &[],
    }
}

/// A KC surface (γ 3) 0.25 µm across its lay and `ratio` times that along it.
pub fn stretched(ratio: f64, angle_deg: f64, sigma_um: f64) -> AnisoKcParams {
    AnisoKcParams {
        sigma: sigma_um * UM,
        lx: 0.25 * UM,
        ly: 0.25 * UM * ratio,
        angle_rad: angle_deg.to_radians(),
        gamma: 3.0,
    }
}

/// The material file `lustre fit` builds for `t`, and that file written as TOML and
/// read back, whose `[psd]` (with its `[psd.destretched]` and `[psd.map]`) must be the
/// built one's.
pub fn file_of(t: fit::Topography, name: &str) -> (MaterialFile, MaterialFile) {
    let a = analyse(t, None, &Options::default()).unwrap();
    let doc = material::build(&a, &prov(name));
    let text = material::to_toml(&doc).unwrap();
    let back: MaterialFile = toml::from_str(&text).unwrap();
    assert_eq!(back.psd, doc.psd, "{name}: [psd] does not round-trip");
    (doc, back)
}
