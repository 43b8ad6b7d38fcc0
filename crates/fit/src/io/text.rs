//! Helpers for whitespace/comma separated numeric text.

/// Parse one row of numbers separated by whitespace, commas, semicolons or tabs.
/// Empty fields (as in `1.0,2.0,,`) are skipped. Non-finite values become NaN.
/// Returns `None` if any field is not a number.
pub fn parse_row(line: &str) -> Option<Vec<f64>> {
    let mut out = Vec::new();
    for tok in line.split(|c: char| c.is_whitespace() || c == ',' || c == ';') {
        if tok.is_empty() {
            continue;
        }
        let v: f64 = tok.parse().ok()?;
        out.push(if v.is_finite() { v } else { f64::NAN });
    }
    (!out.is_empty()).then_some(out)
}
