//! `lustre._lustre`: the compiled half of the `lustre` Python package.
//!
//! Every function here calls the library function the `lustre` CLI calls for the same
//! job, so the numbers are the CLI's to the last bit: `brdf::spec` builds the materials
//! (`lustre brdf eval`), `fit::stats_report` makes the statistics (`lustre fit stats`),
//! `fit::material_file` the material file (`lustre fit`), `judge::judge` the judgement
//! (`lustre judge`) and `render::render_range` the image (`lustre render`). The public,
//! documented API is the pure-Python `lustre` package around it, which turns keyword
//! arguments and dicts into the JSON text these functions take, and numpy inputs into
//! contiguous float64 arrays.

mod material;
mod scan;
mod scene;

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// A `ValueError` carrying the library's message.
pub(crate) fn value_error(msg: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(msg.to_string())
}

/// An `OSError` carrying the library's message.
pub(crate) fn os_error(msg: impl std::fmt::Display) -> PyErr {
    PyOSError::new_err(msg.to_string())
}

/// A JSON value as the Python object `json.loads` makes of it (dicts, lists, floats
/// parsed from the shortest round-trip text, so every float is the library's bit for bit).
pub(crate) fn to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(value_error)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Every material key: `(key, type, documentation, models that read it)`, from the one
/// table in `brdf::spec` (`MaterialDesc::KEY_DOCS`).
#[pyfunction]
fn material_keys() -> Vec<(&'static str, &'static str, String, Vec<&'static str>)> {
    brdf::spec::MaterialDesc::KEY_DOCS
        .iter()
        .map(|k| {
            let doc = k.doc.lines().map(str::trim).collect::<Vec<_>>().join(" ");
            (
                k.key,
                k.ty,
                doc,
                k.models.iter().map(|m| m.name()).collect(),
            )
        })
        .collect()
}

/// The model names `model = …` accepts.
#[pyfunction]
fn model_names() -> Vec<&'static str> {
    brdf::spec::ModelKind::ALL
        .iter()
        .map(|m| m.name())
        .collect()
}

/// The built-in metal names `metal = …` accepts.
#[pyfunction]
fn metal_names() -> Vec<&'static str> {
    brdf::Metal::ALL.iter().map(|m| m.name()).collect()
}

/// The supported wavelength range [nm].
#[pyfunction]
fn wavelength_range_nm() -> (f64, f64) {
    (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM)
}

#[pymodule]
fn _lustre(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<material::Material>()?;
    m.add_class::<scan::Scan>()?;
    m.add_function(wrap_pyfunction!(material_keys, m)?)?;
    m.add_function(wrap_pyfunction!(model_names, m)?)?;
    m.add_function(wrap_pyfunction!(metal_names, m)?)?;
    m.add_function(wrap_pyfunction!(wavelength_range_nm, m)?)?;
    m.add_function(wrap_pyfunction!(scan::read_scan, m)?)?;
    m.add_function(wrap_pyfunction!(scan::fit_scan, m)?)?;
    m.add_function(wrap_pyfunction!(scan::judge_scan, m)?)?;
    m.add_function(wrap_pyfunction!(scene::render_scene, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
