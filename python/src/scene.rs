//! `render`: a scene file (or the same scene as TOML text) to a linear sRGB image.

use std::path::{Path, PathBuf};

use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray1, PyArray3};
use pyo3::prelude::*;

use crate::{os_error, value_error};

/// Renders the scene at `path`, or the scene `toml` (whose relative file names are read
/// relative to `base_dir`), with `spp` samples per pixel (default: the scene's) into an
/// `(height, width, 3)` float32 linear sRGB image, as `lustre render` renders it; with
/// `spectral = N` (as `--spectral N`) also the `(height, width, N)` mean spectral radiance
/// of N equal bands over 360–830 nm and the bands' bounds `(N + 1,)` in nm.
// One parameter per keyword argument of `lustre.render`.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(
    name = "render",
    signature = (path, toml, base_dir, spp=None, seed=None, threads=None, spectral=None)
)]
pub fn render_scene<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    toml: Option<String>,
    base_dir: PathBuf,
    spp: Option<u64>,
    seed: Option<u64>,
    threads: Option<usize>,
    spectral: Option<usize>,
) -> PyResult<Rendered<'py>> {
    let (w, h, rgb, bands) = py.detach(|| -> PyResult<_> {
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
        if let Some(n) = spectral {
            if n == 0 || n > render::film::MAX_BANDS {
                return Err(value_error(format!(
                    "spectral = {n}: expected 1..={} bands",
                    render::film::MAX_BANDS
                )));
            }
            scene
                .set_spectral_bands(n)
                .map_err(|m| value_error(format!("spectral = {n}: {m}")))?;
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
        let bands = film.band_layout().map(|layout| {
            let bounds: Vec<f64> = (0..layout.len())
                .map(|i| layout.bounds_nm(i).0)
                .chain(std::iter::once(layout.bounds_nm(layout.len() - 1).1))
                .collect();
            (film.band_means(), layout.len(), bounds)
        });
        Ok((film.width(), film.height(), film.rgb(), bands))
    })?;
    let flat: Vec<f32> = rgb.into_iter().flatten().collect();
    let img = Array3::from_shape_vec((h as usize, w as usize, 3), flat).map_err(value_error)?;
    let bands = match bands {
        Some((means, n, bounds)) => {
            let cube =
                Array3::from_shape_vec((h as usize, w as usize, n), means).map_err(value_error)?;
            Some((cube.into_pyarray(py), PyArray1::from_vec(py, bounds)))
        }
        None => None,
    };
    Ok((img.into_pyarray(py), bands))
}

/// The image, and with bands their radiance cube and bounds.
type Rendered<'py> = (
    Bound<'py, PyArray3<f32>>,
    Option<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray1<f64>>)>,
);
