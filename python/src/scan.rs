//! `Scan`, `read_scan`, `fit` and `judge`: a measured surface and what the CLI does with it.

use std::path::Path;
use std::sync::Arc;

use fit::Topography;
use fit::io::{ChannelSel, Format, ReadOptions, Units};
use fit::level::Level;
use fit::pipeline::{self, Checks};
use fit::quality::InvalidPolicy;
use numpy::PyUntypedArrayMethods;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::{os_error, to_py, value_error};

/// A height map or profile in metres, with where it came from.
#[pyclass(frozen, module = "lustre._lustre")]
pub struct Scan {
    topo: Topography,
    /// The file as named, or the caller's name for an array.
    name: String,
    format: String,
    channel: usize,
    channel_name: Option<String>,
    notes: Vec<String>,
    /// The bytes the material file's checksum is of: the file's, or the heights'
    /// little-endian float64 bytes for an array.
    bytes: Arc<Vec<u8>>,
    /// The `units` the scan was read with (named in the fix of an implausible Sq).
    units: Option<Units>,
}

#[pymethods]
impl Scan {
    /// A scan from an `(ny, nx)` array of heights [m] (a profile: one row) and the
    /// pixel spacings [m]; NaN marks invalid points.
    #[new]
    #[pyo3(signature = (heights, dx, dy, name))]
    fn new(heights: PyReadonlyArray2<'_, f64>, dx: f64, dy: f64, name: String) -> PyResult<Scan> {
        let [ny, nx] = [heights.shape()[0], heights.shape()[1]];
        if nx == 0 || ny == 0 {
            return Err(value_error(format!(
                "heights: the array is empty ({ny} × {nx})"
            )));
        }
        for (k, v) in [("dx", dx), ("dy", dy)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(value_error(format!(
                    "{k}: the pixel spacing must be a positive number of metres, got {v}"
                )));
            }
        }
        let heights: Vec<f64> = match heights.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => heights.as_array().iter().copied().collect(),
        };
        let bytes = heights.iter().flat_map(|h| h.to_le_bytes()).collect();
        Ok(Scan {
            topo: Topography {
                nx,
                ny,
                dx,
                dy: if ny == 1 { dx } else { dy },
                heights,
                channel: "heights".into(),
                format: "array",
            },
            name,
            format: "array".into(),
            channel: 0,
            channel_name: None,
            notes: Vec::new(),
            bytes: Arc::new(bytes),
            units: None,
        })
    }

    /// Heights [m], `(ny, nx)`, NaN where invalid (a copy).
    #[getter]
    fn heights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = &self.topo;
        let a = Array2::from_shape_vec((t.ny, t.nx), t.heights.clone()).map_err(value_error)?;
        Ok(a.into_pyarray(py))
    }

    /// Pixel spacing along x [m].
    #[getter]
    fn dx(&self) -> f64 {
        self.topo.dx
    }

    /// Pixel spacing along y [m] (equal to `dx` for a profile).
    #[getter]
    fn dy(&self) -> f64 {
        self.topo.dy
    }

    /// The file as named (or the name given to an array).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The reader used (`array` for an array).
    #[getter]
    fn format(&self) -> &str {
        &self.format
    }

    /// `(index, name)` of the channel read.
    #[getter]
    fn channel(&self) -> (usize, Option<String>) {
        (self.channel, self.channel_name.clone())
    }

    /// What the reader noted (assumed units, resampling, flags used).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    /// The dict `lustre fit stats --json` prints, as JSON text.
    #[pyo3(signature = (level, invalid, outliers))]
    fn stats_json(
        &self,
        py: Python<'_>,
        level: Option<&str>,
        invalid: &str,
        outliers: &str,
    ) -> PyResult<String> {
        let checks = checks(invalid, outliers, self.units)?;
        let level = level_of(level)?;
        let topo = self.topo.clone();
        let json = py.detach(|| {
            let s = pipeline::summarise_checked(topo, level, &checks)
                .map_err(|e| value_error(format!("{}: {e}", self.name)))?;
            let source = fit::stats_report::Source {
                file: &self.name,
                format: &self.format,
                channel: self.channel,
                channel_name: self.channel_name.as_deref(),
                notes: &self.notes,
            };
            let report = fit::stats_report::report(&source, &s);
            serde_json::to_string(&report.json).map_err(value_error)
        })?;
        Ok(json)
    }

    fn __repr__(&self) -> String {
        let t = &self.topo;
        format!(
            "Scan({:?}, {} × {} points, dx = {:e} m, dy = {:e} m, format {})",
            self.name, t.nx, t.ny, t.dx, t.dy, self.format
        )
    }
}

/// `--invalid` and `--outliers` as `lustre fit` takes them.
fn checks(invalid: &str, outliers: &str, units: Option<Units>) -> PyResult<Checks> {
    let invalid = match invalid {
        "refuse" => InvalidPolicy::Refuse,
        "crop" => InvalidPolicy::Crop,
        "fill" => InvalidPolicy::Fill,
        other => {
            return Err(value_error(format!(
                "invalid = {other:?}: use \"refuse\", \"crop\" or \"fill\""
            )));
        }
    };
    let mask_outliers = match outliers {
        "flag" => false,
        "mask" => true,
        other => {
            return Err(value_error(format!(
                "outliers = {other:?}: use \"flag\" or \"mask\""
            )));
        }
    };
    Ok(Checks {
        invalid,
        mask_outliers,
        units,
    })
}

/// `--level` as `lustre fit` takes it (`None`: a plane for maps, a line for profiles).
fn level_of(level: Option<&str>) -> PyResult<Option<Level>> {
    match level {
        None => Ok(None),
        Some(l) => Level::from_name(l).map(Some).ok_or_else(|| {
            value_error(format!(
                "level = {l:?}: use \"none\", \"line\", \"plane\", \"poly2\" or \"poly3\""
            ))
        }),
    }
}

/// A pixel spacing or scan size `(x, y)` in metres, checked.
fn pair(name: &str, v: Option<(f64, f64)>) -> PyResult<Option<(f64, f64)>> {
    match v {
        Some((a, b)) if !(a.is_finite() && a > 0.0 && b.is_finite() && b > 0.0) => {
            Err(value_error(format!(
                "{name}: must be positive lengths in metres, got ({a}, {b})"
            )))
        }
        v => Ok(v),
    }
}

/// Reads a scan file as `lustre fit` does (`units`, `format`, `channel`, `pixel_size`,
/// `size` as its flags; lengths in metres).
#[pyfunction]
#[pyo3(signature = (path, units=None, format=None, channel=None, pixel_size=None, size=None))]
pub fn read_scan(
    py: Python<'_>,
    path: std::path::PathBuf,
    units: Option<&str>,
    format: Option<&str>,
    channel: Option<&str>,
    pixel_size: Option<(f64, f64)>,
    size: Option<(f64, f64)>,
) -> PyResult<Scan> {
    let units = match units {
        Some(u) => Some(Units::parse(u).ok_or_else(|| {
            value_error(format!(
                "units = {u:?}: not a length unit (use m, mm, um, nm, or \"um,nm\" for lengths,heights)"
            ))
        })?),
        None => None,
    };
    let format = match format {
        Some(f) => Some(Format::from_name(f).ok_or_else(|| {
            let all: Vec<&str> = Format::all().map(|f| f.name()).collect();
            value_error(format!(
                "format = {f:?}: unknown; supported: {}",
                all.join(", ")
            ))
        })?),
        None => None,
    };
    let opts = ReadOptions {
        channel: channel.map(ChannelSel::parse),
        units,
        pixel_size: pair("pixel_size", pixel_size)?,
        size: pair("size", size)?,
        format,
    };
    py.detach(|| {
        let bytes = fit::io::read_scan_file(&path).map_err(os_error)?;
        let name = path.display().to_string();
        let scan = fit::io::open_bytes(&name, &bytes, &opts).map_err(value_error)?;
        Ok(Scan {
            channel_name: scan.channels.get(scan.channel).map(|c| c.name.clone()),
            format: scan.format.name().to_string(),
            channel: scan.channel,
            notes: scan.notes,
            topo: scan.topo,
            name,
            bytes: Arc::new(bytes),
            units,
        })
    })
}

/// The material file `lustre fit` writes for `scan`, as JSON text (see `lustre fit --help`
/// for the options; `lambda_nm` in nm, `merge_cutoff` in rad/µm).
#[pyfunction]
#[pyo3(name = "fit", signature = (scan, metal, model, cutoff, lambda_nm, merge_cutoff, level, invalid, outliers, stylus=None, stylus_segments=4))]
#[allow(clippy::too_many_arguments)]
pub fn fit_scan(
    py: Python<'_>,
    scan: &Scan,
    metal: &str,
    model: &str,
    cutoff: Vec<f64>,
    lambda_nm: f64,
    merge_cutoff: f64,
    level: Option<&str>,
    invalid: &str,
    outliers: &str,
    stylus: Option<&Scan>,
    stylus_segments: usize,
) -> PyResult<String> {
    let drawable = brdf::spec::ModelKind::from_name(model).is_some_and(|m| !m.stretched());
    if model != "auto" && !drawable {
        return Err(value_error(format!(
            "model = {model:?}: use \"auto\" or a model a fit can draw (not the anisotropic ones): {}",
            brdf::spec::ModelKind::names()
        )));
    }
    for (k, v) in [("lambda_nm", lambda_nm), ("merge_cutoff", merge_cutoff)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(value_error(format!("{k} must be positive, got {v}")));
        }
    }
    if cutoff.iter().any(|c| !(c.is_finite() && *c > 0.0)) {
        return Err(value_error("cutoff values must be positive"));
    }
    let opts = pipeline::Options {
        cutoff_multiples: cutoff,
        wavelength: lambda_nm * 1e-9,
        merge_cutoff: merge_cutoff * 1e6,
        stylus_segments,
        level: level_of(level)?,
        checks: checks(invalid, outliers, scan.units)?,
        ..pipeline::Options::default()
    };
    let (topo, stylus_topo) = (scan.topo.clone(), stylus.map(|s| s.topo.clone()));
    py.detach(|| {
        let analysis = pipeline::analyse(topo, stylus_topo, &opts).map_err(|e| {
            let file = match (&e, stylus) {
                (fit::FitError::Stylus(_), Some(s)) => &s.name,
                _ => &scan.name,
            };
            value_error(format!("{file}: {e}"))
        })?;
        let prov = fit::material_file::Provenance {
            file: &scan.name,
            bytes: &scan.bytes,
            stylus: stylus.map(|s| (s.name.as_str(), s.bytes.as_slice())),
            merge_cutoff_rad_per_um: merge_cutoff,
            metal,
            model,
            notes: &scan.notes,
        };
        let doc = fit::material_file::build(&analysis, &prov);
        fit::material_file::check(&doc)
            .map_err(|e| value_error(format!("{}: the material fitted to it: {e}", scan.name)))?;
        serde_json::to_string(&doc).map_err(value_error)
    })
}

/// The judgement `lustre judge --json` prints, as a Python dict.
#[pyfunction]
#[pyo3(name = "judge", signature = (scan, metal, lambda_nm, theta_i_deg, cutoff, angles, tile, crop, upsample, surrogate, level, reference))]
#[allow(clippy::too_many_arguments)]
pub fn judge_scan<'py>(
    py: Python<'py>,
    scan: &Scan,
    metal: Option<&str>,
    lambda_nm: Vec<f64>,
    theta_i_deg: Vec<f64>,
    cutoff: Vec<f64>,
    angles: usize,
    tile: Option<usize>,
    crop: Option<usize>,
    upsample: usize,
    surrogate: bool,
    level: Option<&str>,
    reference: Option<std::path::PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let metal = match metal {
        None => None,
        Some(m) if m.eq_ignore_ascii_case("none") => None,
        Some(m) => Some(brdf::Metal::from_name(m).ok_or_else(|| {
            value_error(format!(
                "metal = {m:?}: unknown; use cu, au, ag, al, fe, cr, brass or stainless_steel"
            ))
        })?),
    };
    let opts = judge::Options {
        metal,
        lambda_nm,
        theta_i_deg,
        cutoff_multiples: cutoff,
        angles,
        tile,
        crop,
        upsample,
        surrogate,
        level: level_of(level)?,
        reference,
    };
    opts.check().map_err(value_error)?;
    if let Some(r) = &opts.reference
        && !Path::new(r).is_file()
    {
        return Err(os_error(format!(
            "reference: {} is not a file",
            r.display()
        )));
    }
    let t = &scan.topo;
    judge::check_explicit_size(&opts, t.nx, t.ny, t.is_profile())
        .map_err(|e| value_error(format!("{}: {e}", scan.name)))?;
    let topo = t.clone();
    let json = py.detach(|| {
        judge::judge(&scan.name, topo, &opts, &mut |_| {})
            .map(|j| j.json())
            .map_err(value_error)
    })?;
    to_py(py, &json)
}
