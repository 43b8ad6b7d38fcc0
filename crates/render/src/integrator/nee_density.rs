//! The BSDF side's sums of a light sample, shared by the path loop's and
//! the glossy control variate's light samples (`nee_bsdf` in both).

/// Σ Q_k and the density Σ Q_k p_k of the path's wavelengths' sampling
/// toward a light sample whose (f, pdf) per wavelength are `fp`; toward a
/// delta light no density (BSDF sampling cannot reach it), set to 0 in `fp`.
#[inline]
pub(super) fn sums(fp: &mut [(f64, f64)], is_delta: bool, q: &[f64]) -> (f64, f64) {
    if is_delta {
        for v in fp.iter_mut() {
            v.1 = 0.0;
        }
    }
    let q_sum: f64 = q.iter().sum();
    let p_bsdf: f64 = q.iter().zip(fp.iter()).map(|(q, v)| q * v.1).sum();
    (q_sum, p_bsdf)
}
