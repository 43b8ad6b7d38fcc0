//! Scene descriptions written as files parse back to themselves, over the
//! whole schema (every shape and light kind, every optional key, any finite
//! number, any name or path, any comment), and the scenes lustre makes
//! itself (`render::scene::presets`) are valid scenes.

use proptest::prelude::*;
use render::scene::desc::{
    CameraDesc, FilmDesc, IntegratorDesc, LightDesc, MaterialDesc, MisHeuristic, ModelKind,
    SamplerKind, SceneDesc, ShapeDesc, SpectralIntegration, TransformDesc, WavelengthMode,
    spanless,
};
use render::scene::presets::{PlateScene, PreviewLight, PreviewScene, plate_view};
use render::scene::write::{Comments, SceneFile};
use std::collections::BTreeMap;
use std::path::Path;

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
        -10.0..10.0f64,
        Just(0.0),
        Just(-0.0),
        Just(1.0),
    ]
}

fn vec3() -> impl Strategy<Value = [f64; 3]> {
    [finite(), finite(), finite()]
}

/// Any text, including quotes, backslashes, newlines and control characters.
fn text() -> impl Strategy<Value = String> {
    prop_oneof![
        "[a-z_]{1,12}",
        any::<String>(),
        Just(String::new()),
        Just("a \"quoted\" \\ path\n# not a comment".to_string()),
    ]
}

fn transform() -> impl Strategy<Value = TransformDesc> {
    (vec3(), vec3(), finite()).prop_map(|(translate, rotate_deg, scale)| TransformDesc {
        translate,
        rotate_deg,
        scale,
    })
}

fn material() -> impl Strategy<Value = MaterialDesc> {
    let names = ["ggx", "beckmann", "smooth", "ghs_ssa", "ghs", "two_scale"];
    (
        proptest::option::of(proptest::sample::select(names.to_vec())),
        proptest::option::of(text()),
        proptest::option::of([finite(), finite()]),
        proptest::option::of(finite()),
        proptest::option::of(finite()),
        proptest::option::of(text()),
        proptest::option::of(text()),
    )
        .prop_map(
            |(model, metal, nk, alpha, sigma, psd, include)| MaterialDesc {
                model: model.and_then(ModelKind::from_name),
                metal,
                nk,
                alpha,
                sigma_um: sigma,
                psd_csv: psd,
                include,
                ..MaterialDesc::default()
            },
        )
}

fn shape() -> impl Strategy<Value = ShapeDesc> {
    prop_oneof![
        ([finite(), finite()], text(), transform()).prop_map(|(size, material, transform)| {
            ShapeDesc::Rectangle {
                size,
                material,
                transform,
            }
        }),
        (finite(), text(), transform()).prop_map(|(radius, material, transform)| {
            ShapeDesc::Disk {
                radius,
                material,
                transform,
            }
        }),
        (vec3(), finite(), text()).prop_map(|(center, radius, material)| ShapeDesc::Sphere {
            center,
            radius,
            material,
        }),
        (text(), text(), transform()).prop_map(|(file, material, transform)| ShapeDesc::Mesh {
            file: file.into(),
            material,
            transform,
        }),
    ]
}

fn light() -> impl Strategy<Value = LightDesc> {
    let spectrum = || proptest::option::of(text());
    prop_oneof![
        (vec3(), finite(), spectrum()).prop_map(|(position, intensity, spectrum)| {
            LightDesc::Point {
                position,
                intensity,
                spectrum,
            }
        }),
        (vec3(), finite(), finite(), spectrum()).prop_map(
            |(center, radius, radiance, spectrum)| {
                LightDesc::Sphere {
                    center,
                    radius,
                    radiance,
                    spectrum,
                }
            }
        ),
        (
            [finite(), finite()],
            finite(),
            transform(),
            any::<bool>(),
            spectrum()
        )
            .prop_map(|(size, radiance, transform, two_sided, spectrum)| {
                LightDesc::Rectangle {
                    size,
                    radiance,
                    transform,
                    two_sided,
                    spectrum,
                }
            }),
        (finite(), spectrum(), proptest::option::of(text()), finite()).prop_map(
            |(radiance, spectrum, file, rotate_deg)| LightDesc::Environment {
                radiance,
                spectrum,
                file: file.map(Into::into),
                rotate_deg,
            }
        ),
        (
            finite(),
            finite(),
            finite(),
            finite(),
            any::<bool>(),
            finite()
        )
            .prop_map(|(e, a, t, scale, sun, g)| LightDesc::Sky {
                sun_elevation_deg: e,
                sun_azimuth_deg: a,
                turbidity: t,
                scale,
                sun,
                ground_albedo: g,
            }),
    ]
}

fn integrator() -> impl Strategy<Value = IntegratorDesc> {
    (
        any::<u32>(),
        any::<bool>(),
        proptest::option::of(any::<u32>()),
        any::<u32>(),
        any::<bool>(),
        any::<bool>(),
        proptest::option::of(finite()),
        any::<bool>(),
        proptest::option::of(any::<u32>()),
        (
            proptest::option::of(finite()),
            proptest::option::of(finite()),
        ),
        proptest::option::of(any::<u32>()),
        proptest::option::of(any::<u32>()),
    )
        .prop_map(
            |(depth, single, hero, rr, indep, balance, w, sampled, dps, (guide, res), eps, br)| {
                IntegratorDesc {
                    max_depth: spanless(depth),
                    wavelengths: if single {
                        WavelengthMode::Single
                    } else {
                        WavelengthMode::Hero
                    },
                    hero_wavelengths: hero.map(spanless),
                    rr_depth: rr,
                    sampler: if indep {
                        SamplerKind::Independent
                    } else {
                        SamplerKind::Sobol
                    },
                    mis: if balance {
                        MisHeuristic::Balance
                    } else {
                        MisHeuristic::Power
                    },
                    mis_light_weight: w.map(spanless),
                    spectral_integration: if sampled {
                        SpectralIntegration::Sampled
                    } else {
                        SpectralIntegration::Auto
                    },
                    delta_pixel_samples: dps.map(spanless),
                    glossy_residual: res.map(spanless),
                    emitter_pixel_samples: eps.map(spanless),
                    caustic_guiding: guide.map(spanless),
                    branches: br.map(spanless),
                }
            },
        )
}

fn scene() -> impl Strategy<Value = SceneDesc> {
    let camera = (vec3(), vec3(), vec3(), finite(), any::<[u32; 2]>()).prop_map(
        |(from, at, up, fov, res)| CameraDesc {
            look_from: spanless(from),
            look_at: spanless(at),
            up: spanless(up),
            fov_deg: spanless(fov),
            resolution: spanless(res),
        },
    );
    let film = (
        any::<u64>(),
        0..=i64::MAX as u64,
        proptest::option::of(text()),
        proptest::option::of(text()),
        finite(),
        proptest::option::of(0..=300u32),
    )
        .prop_map(|(spp, seed, exr, png, exposure, bands)| FilmDesc {
            spp: spanless(spp % (i64::MAX as u64)),
            seed,
            exr: exr.map(Into::into),
            png: png.map(Into::into),
            exposure: spanless(exposure),
            spectral_bands: bands.map(spanless),
        });
    (
        camera,
        film,
        integrator(),
        proptest::collection::btree_map(text(), material(), 0..4),
        proptest::collection::vec(shape(), 0..5),
        proptest::collection::vec(light(), 0..5),
    )
        .prop_map(
            |(camera, film, integrator, materials, shapes, lights)| SceneDesc {
                camera,
                film,
                integrator,
                materials: materials
                    .into_iter()
                    .map(|(k, m)| (k, spanless(m)))
                    .collect(),
                shapes: shapes.into_iter().map(spanless).collect(),
                lights: lights.into_iter().map(spanless).collect(),
            },
        )
}

fn comments() -> impl Strategy<Value = Comments> {
    (
        text(),
        proptest::collection::btree_map(text(), text(), 0..3),
        proptest::collection::vec(text(), 0..6),
        proptest::collection::vec(text(), 0..6),
    )
        .prop_map(|(header, materials, shapes, lights)| Comments {
            header,
            materials,
            shapes,
            lights,
        })
}

fn parse(text: &str) -> SceneDesc {
    render::scene::parse(Path::new("written.toml"), text)
        .unwrap_or_else(|e| panic!("{e}\n--- the written scene:\n{text}"))
}

proptest! {
    #[test]
    fn a_written_scene_parses_back_to_its_description(desc in scene(), comments in comments()) {
        let file = SceneFile { desc: desc.clone(), comments };
        let text = file.to_toml().unwrap();
        prop_assert_eq!(parse(&text), desc.clone());
        // Plain serde serialisation holds the same description.
        let plain = toml::to_string(&desc).unwrap();
        prop_assert_eq!(parse(&plain), desc);
    }
}

#[test]
fn a_value_toml_cannot_hold_is_an_error() {
    let mut file = PlateScene {
        view_deg: 45.0,
        width: 8,
        height: 6,
        spp: 1,
        material: MaterialDesc::default(),
        outputs: None,
    }
    .file();
    file.desc.film.seed = u64::MAX;
    assert!(file.to_toml().is_err());
}

#[test]
fn keys_at_their_default_are_left_out_and_comments_go_above_their_tables() {
    let mut file = PlateScene {
        view_deg: 45.0,
        width: 160,
        height: 120,
        spp: 16,
        material: MaterialDesc {
            model: Some(ModelKind::Ggx),
            metal: Some("cu".into()),
            alpha: Some(0.2),
            ..MaterialDesc::default()
        },
        outputs: None,
    }
    .file();
    file.comments.header = "line one\nline\rtwo".into();
    file.comments.materials = BTreeMap::from([("plate".into(), "copper".into())]);
    let text = file.to_toml().unwrap();
    assert!(
        text.starts_with("# line one\n# line two\n\n[camera]\n"),
        "{text}"
    );
    assert!(
        text.contains("\n# copper\n[materials.plate]\nmodel = \"ggx\"\n"),
        "{text}"
    );
    assert!(
        text.contains("transform = { rotate_deg = [-90.0, 0.0, 0.0] }\n"),
        "{text}"
    );
    // `up`, `exposure`, `wavelengths`, `scale`, `two_sided` are at their defaults.
    for absent in [
        "up =",
        "exposure",
        "wavelengths",
        "scale",
        "two_sided",
        "rr_depth",
    ] {
        assert!(!text.contains(absent), "{absent}: {text}");
    }
    assert!(text.ends_with("spectrum = \"d65\"\n"), "{text}");
}

/// The plate's positions are rounded to 10⁻⁶ (a file states them exactly).
#[test]
// 0.707107 is the file's six-decimal value, deliberately not 1/√2.
#[allow(clippy::approx_constant)]
fn the_plate_view_is_rounded_to_micrometres() {
    let v = plate_view(45.0);
    assert_eq!(v.camera, [0.0, 0.707107, 0.707107]);
    assert_eq!(v.light, [0.0, 0.848528, -0.848528]);
    assert_eq!(v.up, [0.0, 1.0, 0.0]);
    let v = plate_view(0.0);
    assert_eq!(v.camera, [0.0, 1.0, 0.0]);
    assert_eq!(v.up, [0.0, 0.0, -1.0]);
    for deg in 0..90 {
        for p in [plate_view(deg as f64).camera, plate_view(deg as f64).light] {
            for x in p {
                let text = format!("{x}");
                let decimals = text.split_once('.').map_or(0, |(_, d)| d.len());
                assert!(decimals <= 6, "{deg}°: {text}");
            }
        }
    }
}

#[test]
fn preset_scenes_are_valid_scenes() {
    let material = MaterialDesc {
        model: Some(ModelKind::Ggx),
        metal: Some("au".into()),
        alpha: Some(0.1),
        ..MaterialDesc::default()
    };
    let plate = PlateScene {
        view_deg: 80.0,
        width: 16,
        height: 12,
        spp: 1,
        material: material.clone(),
        outputs: Some(("a.exr".into(), "a.png".into())),
    };
    let text = plate.file().to_toml().unwrap();
    let scene = render::load_str(Path::new("plate.toml"), &text).unwrap();
    assert_eq!((scene.camera.width, scene.settings.spp), (16, 1));
    assert_eq!(scene.lights.len(), 2);
    // The preview reads its meshes from `assets`: the bundled ones.
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/assets");
    for light in [PreviewLight::Sky, PreviewLight::Studio, PreviewLight::Both] {
        let preview = PreviewScene {
            width: 8,
            height: 6,
            spp: 1,
            material: material.clone(),
            light,
            sun_elevation_deg: 35.0,
            sun_azimuth_deg: 220.0,
            turbidity: 2.5,
            exposure: 0.5,
            assets: assets.display().to_string(),
            outputs: None,
        };
        let file = preview.file();
        let text = file.to_toml().unwrap();
        assert_eq!(parse(&text), file.desc);
        let scene = render::load_str(Path::new("preview.toml"), &text)
            .unwrap_or_else(|e| panic!("{light:?}: {e}\n{text}"));
        let lights = match light {
            PreviewLight::Sky => 1,
            PreviewLight::Studio => 4,
            PreviewLight::Both => 4,
        };
        assert_eq!(scene.lights.len(), lights, "{light:?}");
        assert_eq!(scene.materials.len(), 3);
    }
}
