//! # render — a multi-threaded CPU spectral path tracer for the `brdf` models
//!
//! Scenes are TOML files (see `crates/render/README.md` for the schema).
//! Wavelengths are sampled per path (several hero wavelengths with spectral
//! MIS by default), the film turns each camera sample's spectral radiance
//! into CIE 1931 XYZ and sums it in fixed point so partial renders merge
//! exactly, and outputs are linear-sRGB EXR and 8-bit sRGB PNG, written
//! atomically.
//!
//! ```no_run
//! let scene = render::scene::load(std::path::Path::new("scenes/default.toml"))?;
//! let mut film = scene.film().map_err(render::RenderError::Options)?;
//! render::render_range(&scene, &mut film, 0..scene.settings.spp, &Default::default())?;
//! render::output::write_exr("out.exr".as_ref(), film.width(), film.height(), &film.rgb())?;
//! # Ok::<(), render::RenderError>(())
//! ```

pub mod analytic_bvh;
pub mod camera;
pub mod color;
pub mod distribution;
pub mod driver;
pub mod emitter_edges;
mod env_lift;
mod env_map;
pub mod error;
pub mod film;
pub mod geometry;
pub mod glossy_lambda_table;
pub mod guide;
pub mod inputs;
pub mod integrator;
pub mod interrupt;
pub mod light;
mod light_resample;
pub mod material;
pub mod memory;
pub mod mesh;
mod mesh_leaves;
mod mesh_traverse;
pub mod output;
pub mod preview_mesh;
pub mod rng;
pub mod sampler;
pub mod scene;
pub mod shapes;
pub mod sky;
pub mod spectral_table;
pub mod spectrum;
pub mod wavelength;

pub use driver::{
    Progress, ProgressEvent, RenderOptions, RenderOutcome, ThreadPool, max_threads, render_range,
    render_range_in, thread_pool,
};
pub use error::{RenderError, SceneError};
pub use film::Film;
pub use scene::{Scene, load as load_scene, load_str};
