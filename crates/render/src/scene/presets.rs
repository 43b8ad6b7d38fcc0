//! The scenes lustre makes itself, each built in one place as a typed
//! description: the plate of the paper's figures (the bundled sample
//! plates `scenes/samples/` and every cell of `lustre compare`) and the
//! material preview (`lustre preview` and the bundled `scenes/preview/`).

use super::desc::{
    CameraDesc, FilmDesc, IntegratorDesc, LightDesc, MaterialDesc, ModelKind, SceneDesc, ShapeDesc,
    TransformDesc, spanless,
};
use super::write::{Comments, SceneFile};
use crate::preview_mesh::{PreviewObject, checker_floor_obj};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Where a plate scene puts the camera, its light and the camera's up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateView {
    /// Camera position.
    pub camera: [f64; 3],
    /// Centre of the light.
    pub light: [f64; 3],
    /// The camera's up direction.
    pub up: [f64; 3],
}

/// The plate's camera and light for a view `view_deg` from the plate's
/// normal: the camera 1 m away, the light 1.2 m away at its mirror
/// direction so the specular peak is in view (at normal view 1° further
/// out, so camera and light do not coincide). Coordinates are rounded to
/// 10⁻⁶, so that a scene file states them exactly in a few digits.
pub fn plate_view(view_deg: f64) -> PlateView {
    let micro = |x: f64| -> f64 { format!("{x:.6}").parse().unwrap_or(x) };
    let t = view_deg.to_radians();
    let tl = view_deg.max(1.0).to_radians();
    PlateView {
        camera: [0.0, t.cos(), t.sin()].map(micro),
        light: [0.0, 1.2 * tl.cos(), -1.2 * tl.sin()].map(micro),
        // Looking straight down, the usual +y up is the view direction itself.
        up: if view_deg < 1.0 {
            [0.0, 0.0, -1.0]
        } else {
            [0.0, 1.0, 0.0]
        },
    }
}

/// A 20 cm plate in the xz plane seen from `view_deg` off its normal, a
/// small D65 light at the mirror direction and a dim D65 surround: the
/// scene of the paper's Fig. 1 and 4.
#[derive(Clone, Debug, PartialEq)]
pub struct PlateScene {
    /// Viewing angle from the plate's normal, degrees.
    pub view_deg: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u64,
    /// The plate's material, `[materials.plate]`.
    pub material: MaterialDesc,
    /// The `exr` and `png` outputs, if any.
    pub outputs: Option<(PathBuf, PathBuf)>,
}

impl PlateScene {
    /// The scene, with comments on the plate and the light.
    pub fn file(&self) -> SceneFile {
        let view = plate_view(self.view_deg);
        let desc = SceneDesc {
            camera: CameraDesc {
                look_from: spanless(view.camera),
                look_at: spanless([0.0; 3]),
                up: spanless(view.up),
                fov_deg: spanless(14.0),
                resolution: spanless([self.width, self.height]),
            },
            film: film(self.spp, &self.outputs, 0.0),
            integrator: IntegratorDesc {
                max_depth: spanless(3),
                ..IntegratorDesc::default()
            },
            materials: BTreeMap::from([("plate".to_string(), spanless(self.material.clone()))]),
            shapes: vec![spanless(ShapeDesc::Rectangle {
                size: [0.2, 0.2],
                material: "plate".into(),
                transform: TransformDesc {
                    rotate_deg: [-90.0, 0.0, 0.0],
                    ..TransformDesc::default()
                },
            })],
            lights: vec![
                spanless(LightDesc::Sphere {
                    center: view.light,
                    radius: 0.018,
                    radiance: 200.0,
                    spectrum: Some("d65".into()),
                }),
                spanless(LightDesc::Environment {
                    radiance: 0.02,
                    spectrum: Some("d65".into()),
                    file: None,
                    rotate_deg: 0.0,
                }),
            ],
        };
        SceneFile {
            desc,
            comments: Comments {
                shapes: vec!["A 20 cm x 20 cm plate in the xz plane, normal +y.".into()],
                lights: vec![
                    "A small light at the mirror direction of the camera (about 1.7 deg across)."
                        .into(),
                ],
                ..Comments::default()
            },
        }
    }
}

/// `[film]` with seed 1.
fn film(spp: u64, outputs: &Option<(PathBuf, PathBuf)>, exposure: f64) -> FilmDesc {
    FilmDesc {
        spp: spanless(spp),
        seed: 1,
        exr: outputs.as_ref().map(|o| o.0.clone()),
        png: outputs.as_ref().map(|o| o.1.clone()),
        exposure: spanless(exposure),
        spectral_bands: None,
    }
}

/// File name of the preview object.
pub const PREVIEW_OBJECT_OBJ: &str = "preview_object.obj";
/// File name of the floor's light squares.
pub const PREVIEW_FLOOR_A_OBJ: &str = "preview_floor_a.obj";
/// File name of the floor's dark squares.
pub const PREVIEW_FLOOR_B_OBJ: &str = "preview_floor_b.obj";
/// Floor squares per side and their size.
const FLOOR_N: usize = 28;
const FLOOR_SQUARE: f64 = 0.5;

/// The preview's OBJ files (object, light and dark floor squares) and
/// their text, generated; a preview scene reads them from its `assets`
/// folder.
pub fn preview_assets() -> [(&'static str, String); 3] {
    [
        (PREVIEW_OBJECT_OBJ, PreviewObject::new().obj()),
        (
            PREVIEW_FLOOR_A_OBJ,
            checker_floor_obj(FLOOR_N, FLOOR_SQUARE, 0),
        ),
        (
            PREVIEW_FLOOR_B_OBJ,
            checker_floor_obj(FLOOR_N, FLOOR_SQUARE, 1),
        ),
    ]
}

/// The lights of a preview.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PreviewLight {
    /// The Preetham daylight sky with its sun.
    Sky,
    /// Three rectangle lights (key, fill, rim) over a dim uniform surround.
    Studio,
    /// The sky and the studio lights together.
    Both,
}

/// A material on the preview object over a checkered floor, under a
/// daylight sky and/or studio lights.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewScene {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u64,
    /// The object's material, `[materials.object]`.
    pub material: MaterialDesc,
    /// Lighting.
    pub light: PreviewLight,
    /// Sun elevation, degrees.
    pub sun_elevation_deg: f64,
    /// Sun azimuth, degrees.
    pub sun_azimuth_deg: f64,
    /// Sky turbidity.
    pub turbidity: f64,
    /// Exposure, stops.
    pub exposure: f64,
    /// Folder of the preview's OBJ files ([`preview_assets`]), relative to
    /// the scene file.
    pub assets: String,
    /// The `exr` and `png` outputs, if any.
    pub outputs: Option<(PathBuf, PathBuf)>,
}

impl PreviewScene {
    /// The scene, with comments on the floor and the lights.
    pub fn file(&self) -> SceneFile {
        // A white Lambertian square and a dark glossy plastic one, as a studio's
        // checkerboard: what the object reflects and what it is lit by through
        // the floor is then a known, colourless surround.
        let light_square = spanless(MaterialDesc {
            model: Some(ModelKind::Diffuse),
            reflectance: Some(0.8),
            ..MaterialDesc::default()
        });
        let dark_square = spanless(MaterialDesc {
            model: Some(ModelKind::RoughPlastic),
            reflectance: Some(0.05),
            alpha: Some(0.25),
            ..MaterialDesc::default()
        });
        let mesh = |file: &str, material: &str| {
            spanless(ShapeDesc::Mesh {
                file: format!("{}/{file}", self.assets).into(),
                material: material.into(),
                transform: TransformDesc::default(),
            })
        };
        let mut comments = Comments {
            materials: BTreeMap::from([
                (
                    "floor_dark".to_string(),
                    "The floor's dark squares: a dark rough plastic (GGX coat, α 0.25, over\n\
                     a 5 % diffuse base)."
                        .to_string(),
                ),
                (
                    "floor_light".to_string(),
                    "The floor's light squares: white Lambertian (ρ = 0.8).".to_string(),
                ),
            ]),
            ..Comments::default()
        };
        let (lights, notes) = self.lights();
        comments.lights = notes;
        let desc = SceneDesc {
            camera: CameraDesc {
                look_from: spanless([0.0, 1.75, 3.2]),
                look_at: spanless([0.0, 0.45, 0.0]),
                up: spanless([0.0, 1.0, 0.0]),
                fov_deg: spanless(24.0),
                resolution: spanless([self.width, self.height]),
            },
            film: film(self.spp, &self.outputs, self.exposure),
            integrator: IntegratorDesc::default(),
            materials: BTreeMap::from([
                ("object".to_string(), spanless(self.material.clone())),
                ("floor_light".to_string(), light_square),
                ("floor_dark".to_string(), dark_square),
            ]),
            shapes: vec![
                mesh(PREVIEW_OBJECT_OBJ, "object"),
                mesh(PREVIEW_FLOOR_A_OBJ, "floor_light"),
                mesh(PREVIEW_FLOOR_B_OBJ, "floor_dark"),
            ],
            lights: lights.into_iter().map(spanless).collect(),
        };
        SceneFile { desc, comments }
    }

    /// The lights and their comments.
    fn lights(&self) -> (Vec<LightDesc>, Vec<String>) {
        let mut lights = Vec::new();
        let mut notes = Vec::new();
        if matches!(self.light, PreviewLight::Sky | PreviewLight::Both) {
            lights.push(LightDesc::Sky {
                sun_elevation_deg: self.sun_elevation_deg,
                sun_azimuth_deg: self.sun_azimuth_deg,
                turbidity: self.turbidity,
                scale: 5e-5,
                sun: true,
                ground_albedo: 0.2,
            });
            notes.push(
                "Daylight: Preetham sky, its sun and a 20 % ground; scale 5e-5 maps 20 kcd/m² to 1."
                    .to_string(),
            );
        }
        if matches!(self.light, PreviewLight::Studio | PreviewLight::Both) {
            let rectangle = |size, radiance, translate, rotate_deg| LightDesc::Rectangle {
                size,
                radiance,
                transform: TransformDesc {
                    translate,
                    rotate_deg,
                    scale: 1.0,
                },
                two_sided: false,
                spectrum: Some("d65".into()),
            };
            lights.push(rectangle(
                [1.2, 0.8],
                6.0,
                [-1.6, 1.9, 1.6],
                [-40.0, -45.0, 0.0],
            ));
            notes.push(
                "Studio: a large key light to the front left, a fill to the right and a rim light\n\
                 behind, all facing the object."
                    .to_string(),
            );
            lights.push(rectangle(
                [1.0, 1.0],
                1.5,
                [2.0, 1.0, 1.2],
                [-15.0, 60.0, 0.0],
            ));
            notes.push(String::new());
            lights.push(rectangle(
                [1.6, 0.4],
                8.0,
                [0.0, 2.0, -2.2],
                [-140.0, 0.0, 0.0],
            ));
            notes.push(String::new());
            if self.light == PreviewLight::Studio {
                lights.push(LightDesc::Environment {
                    radiance: 0.05,
                    spectrum: Some("d65".into()),
                    file: None,
                    rotate_deg: 0.0,
                });
                notes.push(String::new());
            }
        }
        (lights, notes)
    }
}
