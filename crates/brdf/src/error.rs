/// Why a model, table or parameter was rejected when it was built.
///
/// Evaluation never fails: once a model exists every call returns a finite,
/// non-negative value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BrdfError {
    /// A parameter is NaN, infinite or outside its valid range.
    #[error("parameter `{name}` = {value} is invalid: expected {valid}")]
    OutOfRange {
        /// Parameter name as the user writes it (e.g. `alpha_x`).
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// The valid range, in words (e.g. `"1e-4 ≤ alpha ≤ 1"`).
        valid: &'static str,
    },
    /// A wavelength lies outside the range a spectral table covers.
    #[error(
        "wavelength {lambda_nm} nm is outside the table's range {min_nm}–{max_nm} nm; \
         supply data covering it or narrow the wavelength range"
    )]
    WavelengthOutOfRange {
        /// The requested wavelength in nm.
        lambda_nm: f64,
        /// Smallest wavelength the table covers, nm.
        min_nm: f64,
        /// Largest wavelength the table covers, nm.
        max_nm: f64,
    },
    /// A user-supplied table is malformed.
    #[error("invalid table{}: {reason}", AtRow(*row))]
    InvalidTable {
        /// What is wrong and how to fix it.
        reason: &'static str,
        /// Zero-based row of the offending entry, if one row is to blame.
        row: Option<usize>,
    },
}

/// " (data row N, zero-based)" when one row is to blame, else nothing.
struct AtRow(Option<usize>);

impl core::fmt::Display for AtRow {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some(r) => write!(f, " (data row {r}, zero-based)"),
            None => Ok(()),
        }
    }
}

/// Checks that `value` is finite and within `[lo, hi]`.
pub(crate) fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    valid: &'static str,
) -> Result<f64, BrdfError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(BrdfError::OutOfRange { name, value, valid })
    }
}
