//! `Material`: a material built from its flat keys, evaluated on whole arrays.

use std::path::Path;

use brdf::spec::{DynBxdf, MaterialDesc, MaterialFile, MaterialSpec};
use brdf::{Bxdf, DVec3};
use numpy::PyUntypedArrayMethods;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use rayon::prelude::*;

use crate::value_error;

/// Below this many rows the work stays on the calling thread: spreading it costs more
/// than it saves.
const PARALLEL_MIN_ROWS: usize = 4096;
/// Rows per parallel task.
const CHUNK_ROWS: usize = 1024;

/// `out[i] = f(i)` for every row, over rayon's threads when there are many rows.
fn fill<T: Send>(out: &mut [T], f: impl Fn(usize) -> T + Sync) {
    if out.len() < PARALLEL_MIN_ROWS {
        out.iter_mut().enumerate().for_each(|(i, o)| *o = f(i));
    } else {
        out.par_chunks_mut(CHUNK_ROWS)
            .enumerate()
            .for_each(|(c, chunk)| {
                for (j, o) in chunk.iter_mut().enumerate() {
                    *o = f(c * CHUNK_ROWS + j);
                }
            });
    }
}

/// `f(start, a_block, b_block)` over consecutive blocks of the two output arrays (rows
/// `start..start + len`), written in place, over rayon's threads when there are many rows.
fn fill_pair_blocks(
    a: &mut [f64],
    b: &mut [f64],
    f: impl Fn(usize, &mut [f64], &mut [f64]) + Sync,
) {
    if a.len() < PARALLEL_MIN_ROWS {
        f(0, a, b);
    } else {
        a.par_chunks_mut(CHUNK_ROWS)
            .zip(b.par_chunks_mut(CHUNK_ROWS))
            .enumerate()
            .for_each(|(c, (ca, cb))| f(c * CHUNK_ROWS, ca, cb));
    }
}

/// Rows gathered per call of `Bxdf::eval_pdf_rows` (on the stack: 14 KiB).
const GATHER_ROWS: usize = 256;

/// `(f, pdf)` of rows `start..start + f.len()` through `Bxdf::eval_pdf_rows`, the rows
/// gathered from the input arrays (a broadcast row repeated) in blocks.
fn eval_block(
    model: &DynBxdf,
    (wi, wo, lambda): (&Rows, &Rows, &Lambdas),
    start: usize,
    f: &mut [f64],
    pdf: &mut [f64],
) {
    let mut a = [DVec3::ZERO; GATHER_ROWS];
    let mut b = [DVec3::ZERO; GATHER_ROWS];
    let mut l = [0.0; GATHER_ROWS];
    for (k, (fc, pc)) in f
        .chunks_mut(GATHER_ROWS)
        .zip(pdf.chunks_mut(GATHER_ROWS))
        .enumerate()
    {
        let first = start + k * GATHER_ROWS;
        let m = fc.len();
        for j in 0..m {
            (a[j], b[j], l[j]) = (wi.dir(first + j), wo.dir(first + j), lambda.at(first + j));
        }
        model.eval_pdf_rows(&a[..m], &b[..m], &l[..m], fc, pc);
    }
}

/// An `(n, 3)` array of rows (one row is broadcast to every output row).
struct Rows<'a> {
    data: &'a [f64],
    n: usize,
}

impl<'a> Rows<'a> {
    fn new(a: &'a PyReadonlyArray2<'_, f64>, name: &str) -> PyResult<Rows<'a>> {
        let shape = a.shape();
        if shape[1] != 3 {
            return Err(value_error(format!(
                "{name}: expected an array of shape (N, 3), got ({}, {})",
                shape[0], shape[1]
            )));
        }
        let data = a
            .as_slice()
            .map_err(|_| value_error(format!("{name}: the array must be C-contiguous")))?;
        Ok(Rows { data, n: shape[0] })
    }

    #[inline]
    fn at(&self, i: usize) -> [f64; 3] {
        let k = if self.n == 1 { 0 } else { 3 * i };
        [self.data[k], self.data[k + 1], self.data[k + 2]]
    }

    #[inline]
    fn dir(&self, i: usize) -> DVec3 {
        DVec3::from_array(self.at(i))
    }
}

/// Wavelengths: one for every row, or one per row.
struct Lambdas<'a>(&'a [f64]);

impl<'a> Lambdas<'a> {
    /// Checks every wavelength is finite and inside the range the models support, with
    /// the message `lustre brdf eval` gives.
    fn new(a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<Lambdas<'a>> {
        let s = a
            .as_slice()
            .map_err(|_| value_error("lambda_nm: the array must be contiguous"))?;
        let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
        if let Some(bad) = s.iter().find(|l| !(lo..=hi).contains(*l)) {
            return Err(value_error(format!(
                "lambda_nm: {bad} nm is outside the supported range {lo}–{hi} nm"
            )));
        }
        if s.is_empty() {
            return Err(value_error("lambda_nm: no wavelength given"));
        }
        Ok(Lambdas(s))
    }

    fn n(&self) -> usize {
        self.0.len()
    }

    #[inline]
    fn at(&self, i: usize) -> f64 {
        if self.0.len() == 1 {
            self.0[0]
        } else {
            self.0[i]
        }
    }
}

/// The number of output rows of inputs with `counts` rows each (1 broadcasts).
fn row_count(counts: &[(&str, usize)]) -> PyResult<usize> {
    let n = counts.iter().map(|c| c.1).max().unwrap_or(1);
    match counts.iter().find(|(_, c)| *c != 1 && *c != n) {
        Some((name, c)) => Err(value_error(format!(
            "{name} has {c} rows but another input has {n}: give N rows or one (broadcast)"
        ))),
        None => Ok(n),
    }
}

/// Two arrays of one number per row.
type Pair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

fn array1<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    v.into_pyarray(py)
}

/// A material: the flat keys of a scene's `[materials.NAME]` table, resolved and built
/// as a scene build does it (`include`, `nk_csv` and `psd_csv` read relative to the
/// working directory).
#[pyclass(frozen, module = "lustre._lustre")]
pub struct Material {
    model: DynBxdf,
    spec: MaterialSpec,
    keys: String,
}

/// A material file from the JSON of a fit result. JSON has no NaN, so a fit's
/// undefined diagnostics arrive as `null` (serde_json writes NaN so, and Python's
/// `from_fit` turns a parsed TOML file's nan into None): they go back to NaN through
/// the TOML data model, where the file's schema was written.
fn material_file_from_json(text: &str) -> Result<MaterialFile, String> {
    fn to_toml(v: serde_json::Value) -> Result<toml::Value, String> {
        use serde_json::Value as J;
        Ok(match v {
            J::Null => toml::Value::Float(f64::NAN),
            J::Bool(b) => toml::Value::Boolean(b),
            J::Number(n) => match n.as_i64() {
                Some(i) => toml::Value::Integer(i),
                None => toml::Value::Float(n.as_f64().ok_or("a number out of range")?),
            },
            J::String(s) => toml::Value::String(s),
            J::Array(a) => {
                toml::Value::Array(a.into_iter().map(to_toml).collect::<Result<_, _>>()?)
            }
            J::Object(o) => toml::Value::Table(
                o.into_iter()
                    .map(|(k, v)| Ok((k, to_toml(v)?)))
                    .collect::<Result<_, String>>()?,
            ),
        })
    }
    let json: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    to_toml(json)?
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_string())
}

impl Material {
    /// Resolves and builds `keys_json` (over `file` when given) as a scene build does.
    fn build(py: Python<'_>, keys_json: &str, file: Option<&MaterialFile>) -> PyResult<Material> {
        let desc: MaterialDesc =
            serde_json::from_str(keys_json).map_err(|e| key_error(e, keys_json))?;
        let (spec, model) = py
            .detach(|| -> Result<_, String> {
                let dir = Path::new(".");
                let mut inputs = render::inputs::Inputs::new(dir);
                let spec = match file {
                    Some(f) => {
                        render::material::resolve_spec_over_file(&desc, f, dir, &mut inputs)?
                    }
                    None => render::material::resolve_spec(&desc, dir, &mut inputs)?,
                };
                let model = spec
                    .build()
                    .map_err(|e| format!("`{}`: {}", e.field, e.message))?;
                Ok((spec, model))
            })
            .map_err(value_error)?;
        Ok(Material {
            model,
            spec,
            keys: keys_json.to_string(),
        })
    }
}

#[pymethods]
impl Material {
    /// Builds the material of `keys_json`, a JSON object of material keys.
    #[new]
    fn new(py: Python<'_>, keys_json: &str) -> PyResult<Material> {
        Material::build(py, keys_json, None)
    }

    /// Builds the material of `keys_json` over the material file `file_json` (a fit
    /// result as JSON), as a scene's `include` of that file would.
    #[staticmethod]
    fn over_file(py: Python<'_>, file_json: &str, keys_json: &str) -> PyResult<Material> {
        let file = material_file_from_json(file_json)
            .map_err(|e| value_error(format!("material file: {e}")))?;
        let mut m = Material::build(py, keys_json, Some(&file))?;
        // What the include resolved to, as flat keys (a measured PSD table is data,
        // not a key: it stays in the file).
        m.keys = serde_json::to_string(&m.spec.to_desc())
            .map_err(|e| value_error(format!("material keys: {e}")))?;
        Ok(m)
    }

    /// The keys the material was built from, as JSON.
    #[getter]
    fn keys_json(&self) -> &str {
        &self.keys
    }

    /// The resolved material (every default filled in), in Rust's debug notation.
    #[getter]
    fn resolved(&self) -> String {
        format!("{:?}", self.spec)
    }

    /// `(f, pdf)` at `(wi, wo)` rows and `lambda_nm` (one or one per row).
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wi: PyReadonlyArray2<'py, f64>,
        wo: PyReadonlyArray2<'py, f64>,
        lambda_nm: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Pair<'py>> {
        let (wi, wo) = (Rows::new(&wi, "wi")?, Rows::new(&wo, "wo")?);
        let lambda = Lambdas::new(&lambda_nm)?;
        let n = row_count(&[("wi", wi.n), ("wo", wo.n), ("lambda_nm", lambda.n())])?;
        let model = &self.model;
        let (f, pdf) = py.detach(|| {
            let (mut f, mut pdf) = (vec![0.0; n], vec![0.0; n]);
            // `eval_pdf_rows` is bit-identical to `eval_pdf`, which `lustre brdf eval`
            // calls: the values are the CLI's.
            fill_pair_blocks(&mut f, &mut pdf, |start, f, pdf| {
                eval_block(model, (&wi, &wo, &lambda), start, f, pdf)
            });
            (f, pdf)
        });
        Ok((array1(py, f), array1(py, pdf)))
    }

    /// `(wo, pdf, weight, is_delta)` sampled at `wi` rows with `u` rows in [0, 1)³.
    #[allow(clippy::type_complexity)]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wi: PyReadonlyArray2<'py, f64>,
        lambda_nm: PyReadonlyArray1<'py, f64>,
        u: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<bool>>,
    )> {
        let (wi, u) = (Rows::new(&wi, "wi")?, Rows::new(&u, "u")?);
        let lambda = Lambdas::new(&lambda_nm)?;
        let n = row_count(&[("wi", wi.n), ("u", u.n), ("lambda_nm", lambda.n())])?;
        let model = &self.model;
        let out = py.detach(|| {
            let mut out = vec![None; n];
            fill(&mut out, |i| model.sample(wi.dir(i), lambda.at(i), u.at(i)));
            out
        });
        let mut wo = Vec::with_capacity(3 * n);
        let (mut pdf, mut weight, mut delta) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for s in out {
            let s = s.unwrap_or(brdf::BxdfSample {
                wo: DVec3::ZERO,
                weight: 0.0,
                pdf: 0.0,
                is_delta: false,
            });
            wo.extend_from_slice(&s.wo.to_array());
            pdf.push(s.pdf);
            weight.push(s.weight);
            delta.push(s.is_delta);
        }
        let wo = Array2::from_shape_vec((n, 3), wo).map_err(value_error)?;
        Ok((
            wo.into_pyarray(py),
            array1(py, pdf),
            array1(py, weight),
            delta.into_pyarray(py),
        ))
    }

    /// The weight of the specular delta lobe at `wi` rows.
    fn specular<'py>(
        &self,
        py: Python<'py>,
        wi: PyReadonlyArray2<'py, f64>,
        lambda_nm: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let wi = Rows::new(&wi, "wi")?;
        let lambda = Lambdas::new(&lambda_nm)?;
        let n = row_count(&[("wi", wi.n), ("lambda_nm", lambda.n())])?;
        let model = &self.model;
        let out = py.detach(|| {
            let mut out = vec![0.0; n];
            fill(&mut out, |i| model.specular(wi.dir(i), lambda.at(i)).weight);
            out
        });
        Ok(array1(py, out))
    }

    /// `(scattered, specular)` directional albedo at incidence angles `theta_i_deg`
    /// (azimuth 0), by the quadrature `lustre brdf plot` uses.
    fn albedo<'py>(
        &self,
        py: Python<'py>,
        theta_i_deg: PyReadonlyArray1<'py, f64>,
        lambda_nm: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Pair<'py>> {
        let theta = theta_i_deg
            .as_slice()
            .map_err(|_| value_error("theta_i_deg: the array must be contiguous"))?;
        if let Some(bad) = theta.iter().find(|t| !(0.0..90.0).contains(*t)) {
            return Err(value_error(format!(
                "theta_i_deg: {bad}° is outside [0, 90)"
            )));
        }
        let lambda = Lambdas::new(&lambda_nm)?;
        let n = row_count(&[("theta_i_deg", theta.len()), ("lambda_nm", lambda.n())])?;
        let (model, spec) = (&self.model, &self.spec);
        let out = py.detach(|| {
            let mut out = vec![
                brdf::spec::Albedo {
                    scattered: 0.0,
                    specular: 0.0
                };
                n
            ];
            // One quadrature is thousands of evaluations: spread even a few angles.
            out.par_iter_mut().enumerate().for_each(|(i, o)| {
                let t = if theta.len() == 1 { theta[0] } else { theta[i] };
                let wi = brdf::frame::spherical(t.to_radians(), 0.0);
                *o = spec.albedo(model.as_ref() as &dyn Bxdf, wi, lambda.at(i));
            });
            out
        });
        let (s, d): (Vec<f64>, Vec<f64>) = out.iter().map(|a| (a.scattered, a.specular)).unzip();
        Ok((array1(py, s), array1(py, d)))
    }
}

/// A key the schema refuses, named as `lustre brdf eval` names it: an unknown key, or
/// the first key whose value fails on its own.
fn key_error(e: serde_json::Error, keys_json: &str) -> PyErr {
    let msg = e.to_string();
    if let Some(k) = msg
        .strip_prefix("unknown field `")
        .and_then(|rest| rest.split('`').next())
    {
        return value_error(format!("`{k}`: {}", msg.replace("field", "key")));
    }
    let keys: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(keys_json).unwrap_or_default();
    let bad = keys.iter().find(|(k, v)| {
        let one = serde_json::json!({ (*k).clone(): (*v).clone() });
        serde_json::from_value::<MaterialDesc>(one).is_err()
    });
    match bad {
        Some((k, v)) => value_error(format!("`{k}` = {v}: {msg}")),
        None => value_error(msg),
    }
}
