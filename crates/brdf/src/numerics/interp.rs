//! Polynomial interpolation weights shared by the tabulated statistics and
//! the model tables.

/// Weights of 4-point Lagrange interpolation at offsets −1, 0, 1, 2 for
/// t ∈ [0, 1] (extrapolates smoothly outside).
#[inline]
pub fn lagrange4(t: f64) -> [f64; 4] {
    const SIXTH: f64 = 1.0 / 6.0;
    let tm1 = t - 1.0;
    let tm2 = t - 2.0;
    let tp1 = t + 1.0;
    let a = t * tm1; // t(t−1)
    let b = tp1 * tm2; // (t+1)(t−2)
    [
        -a * tm2 * SIXTH,
        b * tm1 * 0.5,
        -b * t * 0.5,
        a * tp1 * SIXTH,
    ]
}
