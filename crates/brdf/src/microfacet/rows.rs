//! The GGX conductor evaluated on many unrelated rows at once.
//!
//! A row's cost is the latency of two square roots and two divisions in the
//! geometry and two more of each in Fresnel; evaluated one at a time they
//! wait on each other. Here [`LANES`] rows go through the same operations in
//! the same order as [`MicrofacetConductor::eval_pdf`] (so every lane is
//! bit-identical to it), written as fixed-length element-wise loops that the
//! compiler turns into packed instructions. Rows below the horizon are
//! computed like the rest and zeroed at the end.

use glam::DVec3;

use super::{COS_HORIZON, Distribution, MicrofacetConductor};
use crate::fresnel::{Fresnel, conductor_reflectance_ratio_lanes};

/// Rows per packed evaluation: four f64 fill one 256-bit register.
pub(super) const LANES: usize = 4;

type Lanes = [f64; LANES];

/// `f(j)` for every lane.
#[inline(always)]
fn each(f: impl FnMut(usize) -> f64) -> Lanes {
    core::array::from_fn(f)
}

/// `x` where it is finite and positive, else 0 (`finite_nonneg` per lane).
#[inline(always)]
fn finite_nonneg(x: Lanes) -> Lanes {
    each(|j| {
        if x[j].is_finite() && x[j] > 0.0 {
            x[j]
        } else {
            0.0
        }
    })
}

/// GGX Λ as the fraction (a, d) of `Distribution::ggx_lambda_frac`, per lane.
#[inline(always)]
fn lambda_frac(dist: &Distribution, x: &Lanes, y: &Lanes, z: &Lanes) -> (Lanes, Lanes) {
    let ax = each(|j| dist.alpha_x * x[j]);
    let ay = each(|j| dist.alpha_y * y[j]);
    let a = each(|j| ax[j] * ax[j] + ay[j] * ay[j]);
    let r = crate::numerics::math::sqrt_lanes(each(|j| a[j] + z[j] * z[j]));
    (a, each(|j| 2.0 * z[j] * (z[j] + r[j])))
}

/// `(f, pdf)` of a GGX conductor for [`LANES`] rows (`MicrofacetConductor::
/// eval_pdf`, lane by lane).
#[inline(always)]
fn ggx_lanes(
    dist: &Distribution,
    fresnel: &Fresnel,
    wi: &[DVec3],
    wo: &[DVec3],
    lambda_nm: &[f64],
) -> (Lanes, Lanes) {
    let (ix, iy, iz) = (each(|j| wi[j].x), each(|j| wi[j].y), each(|j| wi[j].z));
    let (ox, oy, oz) = (each(|j| wo[j].x), each(|j| wo[j].y), each(|j| wo[j].z));
    let (vx, vy, vz) = (
        each(|j| ix[j] + ox[j]),
        each(|j| iy[j] + oy[j]),
        each(|j| iz[j] + oz[j]),
    );
    let len2 = each(|j| vx[j] * vx[j] + vy[j] * vy[j] + vz[j] * vz[j]);
    // D as the fraction of `Distribution::ggx_d_fraction`.
    let dx = each(|j| vx[j] * dist.inv_alpha_x);
    let dy = each(|j| vy[j] * dist.inv_alpha_y);
    let s = each(|j| dx[j] * dx[j] + dy[j] * dy[j] + vz[j] * vz[j]);
    let d_num = each(|j| dist.d_scale * (len2[j] * len2[j]));
    let d_den = each(|j| s[j] * s[j]);
    let (ai, di) = lambda_frac(dist, &ix, &iy, &iz);
    let (ao, do_) = lambda_frac(dist, &ox, &oy, &oz);
    let g2_den = each(|j| di[j] * do_[j] + ai[j] * do_[j] + ao[j] * di[j]);
    let f_over_fresnel = finite_nonneg(each(|j| {
        d_num[j] * (di[j] * do_[j]) / (d_den[j] * g2_den[j] * (4.0 * iz[j] * oz[j]))
    }));
    let pdf = finite_nonneg(each(|j| {
        d_num[j] * di[j] / (d_den[j] * (di[j] + ai[j]) * (4.0 * iz[j]))
    }));
    let r = match fresnel {
        Fresnel::One => [1.0; LANES],
        Fresnel::Conductor(ior) => {
            let (mut n, mut k) = ([0.0; LANES], [0.0; LANES]);
            ior.at_many(&lambda_nm[..LANES], &mut n, &mut k);
            conductor_reflectance_ratio_lanes(len2, 4.0, n, k)
        }
    };
    let f = finite_nonneg(each(|j| r[j] * f_over_fresnel[j]));
    let valid = |j: usize| {
        iz[j] >= COS_HORIZON && oz[j] >= COS_HORIZON && len2[j] > 0.0 && len2[j].is_finite()
    };
    (
        each(|j| if valid(j) { f[j] } else { 0.0 }),
        each(|j| if valid(j) { pdf[j] } else { 0.0 }),
    )
}

/// `Bxdf::eval_pdf_rows` of a GGX conductor: whole blocks of [`LANES`] rows
/// packed, the rest one by one through its `eval_pdf`.
pub(super) fn ggx_eval_pdf_rows(
    model: &MicrofacetConductor,
    (wi, wo, lambda_nm): (&[DVec3], &[DVec3], &[f64]),
    (f, pdf): (&mut [f64], &mut [f64]),
) {
    let (dist, fresnel) = (model.distribution(), model.fresnel());
    let n = wi
        .len()
        .min(wo.len())
        .min(lambda_nm.len())
        .min(f.len())
        .min(pdf.len());
    let whole = n - n % LANES;
    for i in (0..whole).step_by(LANES) {
        let r = i..i + LANES;
        let (fl, pl) = ggx_lanes(
            dist,
            fresnel,
            &wi[r.clone()],
            &wo[r.clone()],
            &lambda_nm[r.clone()],
        );
        f[r.clone()].copy_from_slice(&fl);
        pdf[r].copy_from_slice(&pl);
    }
    let tail = whole..n;
    crate::model::eval_pdf_each_row(
        model,
        &wi[tail.clone()],
        &wo[tail.clone()],
        &lambda_nm[tail.clone()],
        &mut f[tail.clone()],
        &mut pdf[tail],
    );
}
