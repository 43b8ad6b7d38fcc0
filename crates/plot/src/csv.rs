//! CSV export of the data behind a plot, so every figure ships with its numbers.

use crate::{PlotError, Series, io::write_atomic};
use std::fmt::Write as _;
use std::path::Path;

/// Writes `series` as long-format CSV (`series,<x label>,<y label>`, one row per point, in
/// the order given) to `path`, atomically. Values are written with Rust's shortest
/// round-trip formatting, so parsing them back gives the identical `f64`; NaN and ±∞ are
/// written as `NaN`, `inf`, `-inf` (the CSV keeps every point, including those a log plot
/// skips).
pub fn write_series_csv(
    path: impl AsRef<Path>,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), PlotError> {
    write_atomic(
        path.as_ref(),
        series_csv(x_label, y_label, series).as_bytes(),
    )
}

/// The CSV text [`write_series_csv`] writes.
pub fn series_csv(x_label: &str, y_label: &str, series: &[Series]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "series,{},{}", quote(x_label), quote(y_label));
    for s in series {
        let label = quote(&s.label);
        for (x, y) in s.xs.iter().zip(&s.ys) {
            let _ = writeln!(out, "{label},{x},{y}");
        }
    }
    out
}

/// RFC 4180 quoting: only when the field holds a comma, quote or line break.
pub(crate) fn quote(field: &str) -> String {
    if field.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_values_and_quotes_labels() {
        let xs = [0.1, 1.0 / 3.0, f64::NAN];
        let ys = [1e-300, 2.5, f64::INFINITY];
        let text = series_csv(
            "θ [deg]",
            "f, \"r\"",
            &[Series::line("GGX, α=0.1", &xs, &ys)],
        );
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), "series,θ [deg],\"f, \"\"r\"\"\"");
        let row: Vec<&str> = lines.next().unwrap().rsplitn(3, ',').collect();
        assert_eq!(row[2], "\"GGX, α=0.1\"");
        assert_eq!(row[1].parse::<f64>().unwrap(), 0.1);
        assert_eq!(row[0].parse::<f64>().unwrap(), 1e-300);
        let row2: Vec<&str> = lines.next().unwrap().rsplitn(3, ',').collect();
        assert_eq!(row2[1].parse::<f64>().unwrap(), 1.0 / 3.0);
        assert_eq!(lines.next().unwrap().rsplit(',').next().unwrap(), "inf");
        assert!(lines.next().is_none());
    }
}
