//! Checks of a material's `nk_csv` and `psd_csv` that need the file's line
//! numbers, which the brdf crate never sees (it gets the parsed rows): values
//! it would accept but that cannot be meant, or that would stall the build.

use crate::spectrum::parse_csv_lines;
use brdf::ior::nk_in_bounds;
use brdf::statistics::measured_psd::{TAIL_SLOPE_MIN, tail_too_steep};

/// A wavelength column spanning no more than this range reads as
/// micrometres: no nm table of a metal covers only 0.2–20 nm.
const MICROMETRE_RANGE: (f64, f64) = (0.2, 20.0);

/// Checks the rows of an `nk_csv` (`name` for messages). Malformed files
/// pass: the table parser reports those.
pub fn check_nk_csv(name: &str, text: &str) -> Result<(), String> {
    let Ok(rows) = parse_csv_lines(text, 3) else {
        return Ok(());
    };
    for (line, r) in &rows {
        let (n, k) = (r[1], r[2]);
        // The bounds `brdf::Ior::table` applies too, here with the line.
        if !nk_in_bounds(n, k) {
            return Err(format!(
                "{name}: line {line}: n = {n:e}, k = {k:e} is outside 1e-6 ≤ n ≤ 1e6, \
                 0 ≤ k ≤ 1e6 (the bounds of `nk = [n, k]`); check the columns are \
                 wavelength_nm,n,k and the values' units"
            ));
        }
    }
    let (lo, hi) = (rows[0].1[0], rows[rows.len() - 1].1[0]);
    if lo >= MICROMETRE_RANGE.0 && hi <= MICROMETRE_RANGE.1 {
        return Err(format!(
            "{name}: the wavelengths span {lo}–{hi}, which looks like micrometres; the \
             first column must be in nm (multiply it by 1000)"
        ));
    }
    Ok(())
}

/// Checks the last segment of a `psd_csv`, which sets the tail beyond the
/// table (see [`TAIL_SLOPE_MIN`]).
pub fn check_psd_csv(name: &str, text: &str) -> Result<(), String> {
    let Ok(rows) = parse_csv_lines(text, 2) else {
        return Ok(());
    };
    let [(l0, a), (l1, b)] = [&rows[rows.len() - 2], &rows[rows.len() - 1]];
    let slope = (b[1].ln() - a[1].ln()) / (b[0].ln() - a[0].ln());
    if tail_too_steep(slope) {
        return Err(format!(
            "{name}: the last segment (lines {l0}–{l1}: zeta {} → {} rad/µm, P {:e} → {:e} µm⁴) \
             falls as zeta^{slope:.4e}; the steepest accepted is zeta^{TAIL_SLOPE_MIN} (the tail \
             of a K-correlation with gamma = 100). End the table before the roll-off (drop line \
             {l1}) or make the last segment shallower",
            a[0], b[0], a[1], b[1]
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nk_rows_get_the_bounds_of_nk() {
        let e = check_nk_csv("h.csv", "wavelength_nm,n,k\n300,0.2,3\n900,1e77,1e77\n").unwrap_err();
        assert!(
            e.contains("h.csv") && e.contains("line 3") && e.contains("1e6"),
            "{e}"
        );
        assert!(check_nk_csv("t.csv", "300,1e-7,0\n900,0.2,3\n").is_err());
        assert!(check_nk_csv("ok.csv", "300,1e6,1e6\n900,1e-6,0\n").is_ok());
        // Malformed: left to the parser's own message.
        assert!(check_nk_csv("bad.csv", "300,0.2\n").is_ok());
    }

    #[test]
    fn micrometre_wavelengths_get_a_hint() {
        let e = check_nk_csv("um.csv", "wavelength_um,n,k\n0.3,0.2,3\n0.9,0.2,3\n").unwrap_err();
        assert!(e.contains("micrometres") && e.contains("nm"), "{e}");
        assert!(check_nk_csv("nm.csv", "300,0.2,3\n900,0.2,3\n").is_ok());
    }

    #[test]
    fn a_psd_tail_steeper_than_kc_allows_is_named_with_its_lines() {
        let e = check_psd_csv("steep.csv", "# comment\n1,1e-3\n1.0001,1e-300\n").unwrap_err();
        assert!(
            e.contains("steep.csv") && e.contains("lines 2–3") && e.contains("-101"),
            "{e}"
        );
        let at_bound = format!("1,1e-3\n2,{:e}\n", 1e-3 * 2f64.powf(TAIL_SLOPE_MIN));
        assert!(check_psd_csv("ok.csv", &at_bound).is_ok());
        assert!(
            brdf::statistics::TabulatedPsd::new(
                &[1.0, 2.0],
                &[1e-3, 1e-3 * 2f64.powf(TAIL_SLOPE_MIN)]
            )
            .is_ok()
        );
    }
}
