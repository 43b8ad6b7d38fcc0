//! Zygo `.datx` (Mx software of Zygo's interferometers): an HDF5 file (read by
//! [`super::hdf5`]). Its `/MetaData` dataset is a table of (category, key, value) strings
//! in which `Root/Measurement` names a category whose `Surface` names one whose `Path` is
//! the height dataset's path (`/Measurement/Surface` when the table cannot be followed). The
//! dataset holds the heights (rows along y, x fastest) in the unit of its `Unit` attribute
//! (`MicroMeters`, `NanoMeters`, …); points equal to its `No Data` attribute, and
//! non-finite ones, were not measured. Its `X Converter` and `Y Converter` attributes are
//! compounds whose first member is the category (`LateralCat`), the second the base unit
//! (`Pixels`) and the last the parameters, of which the second is the pixel size in
//! metres; the `Z Converter`'s category is `HeightCat` and its base unit the heights'.
//!
//! Sources: SurfaceTopography `IO/DATX.py` (1.27.1: the metadata table, the attributes,
//! the converters' parameters, the axes) and Gwyddion `modules/file/datxfile.c` (rows
//! along y). No real sample could be obtained (SurfaceTopography's `datx-1.datx` and
//! `datx-2.datx` are absent from the stored snapshot of its repository), so the reader is
//! tested on `data/surfaces/formats/datx-synth.datx` and `datx-synth-latest.datx`, written
//! by h5py (the HDF5 library) from this description by `make_synthetic.py` there, the one
//! with HDF5's oldest structures and chunked, shuffled, deflated data, the other with its
//! newest; SurfaceTopography 1.27.1 reads both (`data/surfaces/reference/statistics.json`).

use super::hdf5::{self, Value};
use super::{Ctx, Decoded, Raw, Unit, Want, check_spacing, checked_grid, units};
use crate::ReadError;

const CORRUPT: &str = "the DATX file is corrupt or truncated; export it again from Mx";
const DEFAULT_PATH: &str = "/Measurement/Surface";
/// Rows of the metadata table read at most.
const MAX_METADATA_ROWS: u64 = 1 << 16;

/// Read a DATX file (its surface dataset).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// The surface dataset's path from the metadata table.
fn surface_path(f: &hdf5::File<'_>) -> Option<String> {
    let d = f.dataset("/MetaData").ok()?;
    let rows = f.read_values(&d, MAX_METADATA_ROWS).ok()?;
    let text = |v: &Value| match v {
        Value::Text(t) => Some(t.clone()),
        _ => None,
    };
    let table: Vec<[String; 3]> = rows
        .iter()
        .filter_map(|r| match r {
            Value::Compound(m) if m.len() >= 3 => {
                Some([text(&m[0].1)?, text(&m[1].1)?, text(&m[2].1)?])
            }
            _ => None,
        })
        .collect();
    let get = |cat: &str, key: &str| {
        table
            .iter()
            .find(|r| r[0] == cat && r[1] == key)
            .map(|r| r[2].clone())
    };
    get(&get(&get("Root", "Measurement")?, "Surface")?, "Path")
}

/// A converter's (category, base unit, parameters).
fn converter(v: Option<Value>) -> Option<(String, String, Vec<f64>)> {
    let Some(Value::Compound(m)) = v else {
        return None;
    };
    let text = |i: usize| match m.get(i).map(|x| &x.1) {
        Some(Value::Text(t)) => Some(t.clone()),
        _ => None,
    };
    let params = match m.last().map(|x| &x.1) {
        Some(Value::Numbers(n)) => n.clone(),
        _ => return None,
    };
    Some((text(0)?, text(1)?, params))
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let hdf = |e: String| ctx.err("HDF5", e, CORRUPT);
    let f = hdf5::File::open(bytes).map_err(hdf)?;
    let path = surface_path(&f).unwrap_or_else(|| DEFAULT_PATH.into());
    let d = f.dataset(&path).map_err(|e| {
        ctx.err(
            "MetaData",
            format!("the surface dataset `{path}`: {e}"),
            "not a Zygo DATX measurement (an HDF5 file of another kind, or damaged)",
        )
    })?;
    if d.dims.len() != 2 {
        return Err(ctx.err(
            &path,
            format!(
                "the surface has dimensions {:?}, not rows × columns",
                d.dims
            ),
            CORRUPT,
        ));
    }
    let (ny, nx) = (d.dims[0], d.dims[1]);
    checked_grid(ctx, &path, nx, ny, 1, u64::MAX)?;
    let attr = |name: &str| f.attribute(&d, name).map_err(hdf);
    let unit_name = match attr("Unit")? {
        Some(Value::Text(t)) => t,
        _ => return Err(ctx.err("Unit", "missing or not a string", CORRUPT)),
    };
    let z = units::length_factor(&unit_name).ok_or_else(|| {
        ctx.err(
            "Unit",
            format!("`{unit_name}` is not a length unit"),
            "choose a height (surface) measurement",
        )
    })?;
    let mut spacing = [0.0; 2];
    for (i, axis) in ["X Converter", "Y Converter"].into_iter().enumerate() {
        let (cat, base, p) = converter(attr(axis)?)
            .ok_or_else(|| ctx.err(axis, "missing or not a converter compound", CORRUPT))?;
        if cat != "LateralCat" || base != "Pixels" || p.len() < 2 {
            return Err(ctx.err(
                axis,
                format!("category `{cat}` with base unit `{base}` (only `LateralCat` in `Pixels` is read)"),
                "export the measurement with a lateral calibration",
            ));
        }
        spacing[i] = check_spacing(ctx, axis, p[1])?;
    }
    if let Some((cat, base, _)) = converter(attr("Z Converter")?) {
        let same = units::length_factor(&base).is_some_and(|b| rel_eq(b, z));
        if cat != "HeightCat" || !same {
            return Err(ctx.err(
                "Z Converter",
                format!("category `{cat}` in `{base}`, while the heights are in `{unit_name}`"),
                CORRUPT,
            ));
        }
    }
    let no_data = match attr("No Data")? {
        Some(Value::Numbers(n)) => n.first().copied(),
        _ => None,
    };
    let mut heights = f.read_numbers(&d).map_err(hdf)?;
    for h in &mut heights {
        if !h.is_finite() || Some(*h) == no_data {
            *h = f64::NAN;
        }
    }
    Ok(Raw::si(
        nx as usize,
        ny as usize,
        spacing[0],
        spacing[1],
        heights,
        "Surface",
    )
    .in_units(Unit::Known(z), Unit::Known(1.0))
    .spacing_from("X Converter", "Y Converter"))
}

fn rel_eq(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}
