//! Small numerical helpers shared by the models.

/// `sqrt(max(x, 0))`: square root that treats round-off negatives as zero.
#[inline]
pub fn safe_sqrt(x: f64) -> f64 {
    libm::sqrt(x.max(0.0))
}

/// Clamps a float to a finite, non-negative value (NaN → 0); the last line of
/// defence that keeps every public evaluation finite and ≥ 0.
#[inline]
pub fn finite_nonneg(x: f64) -> f64 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

/// (sin x, cos x): the platform's fast version with `std`, libm's without.
#[inline]
pub fn sincos(x: f64) -> (f64, f64) {
    #[cfg(feature = "std")]
    {
        x.sin_cos()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sincos(x)
    }
}

/// eˣ: the platform's version with `std`, libm's without.
#[inline]
pub fn exp(x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.exp()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::exp(x)
    }
}
