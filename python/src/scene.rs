//! `render`: a scene file (or the same scene as TOML text) to a linear sRGB image.

use std::path::{Path, PathBuf};

use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;

use crate::{os_error, value_error};

/// Renders the scene at `path`, or the scene `toml` (whose relative file names are read
/// relative to `base_dir`), with `spp` samples per pixel (default: the scene's) into an
/// `(height, width, 3)` float32 linear sRGB image, as `lustre render` renders it.
#[pyfunction]
#[pyo3(name = "render", signature = (path, toml, base_dir, spp=None, seed=None, threads=None))]
pub fn render_scene<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    toml: Option<String>,
    base_dir: PathBuf,
    spp: Option<u64>,
    seed: Option<u64>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (w, h, rgb) = py.detach(|| -> PyResult<_> {
        let mut scene = match (&path, &toml) {
            (Some(p), None) => {
                if !p.is_file() {
                    return Err(os_error(format!("{}: no such scene file", p.display())));
                }
                render::load_scene(p).map_err(value_error)?
            }
            (None, Some(text)) => {
                render::load_str(&base_dir.join("<dict>.toml"), text).map_err(value_error)?
            }
            _ => return Err(value_error("give a scene path or a scene dict")),
        };
        let name = path.as_deref().unwrap_or(Path::new("<dict>")).display();
        if let Some(s) = seed {
            scene.settings.seed = s;
        }
        let spp = spp.unwrap_or(scene.settings.spp);
        if spp == 0 || spp > render::scene::MAX_SPP {
            return Err(value_error(format!(
                "spp = {spp}: expected 1..={}",
                render::scene::MAX_SPP
            )));
        }
        if threads == Some(0) {
            return Err(value_error("threads must be ≥ 1"));
        }
        render::memory::check_fits(scene.camera.width, scene.camera.height)
            .map_err(|m| value_error(format!("{name}: {m}")))?;
        let mut film = scene.film().map_err(value_error)?;
        let opts = render::RenderOptions {
            threads,
            ..render::RenderOptions::default()
        };
        render::render_range(&scene, &mut film, 0..spp, &opts).map_err(value_error)?;
        Ok((film.width(), film.height(), film.rgb()))
    })?;
    let flat: Vec<f32> = rgb.into_iter().flatten().collect();
    let img = Array3::from_shape_vec((h as usize, w as usize, 3), flat).map_err(value_error)?;
    Ok(img.into_pyarray(py))
}
