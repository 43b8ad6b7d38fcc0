//! Exact unpolarised Fresnel reflectance of a conductor, R = ½(|r_s|² + |r_p|²).

use crate::ior::Ior;

/// How a model weights reflection by the surface's optical constants.
#[derive(Clone, Debug, PartialEq)]
pub enum Fresnel {
    /// R ≡ 1: a perfect mirror material (white furnace tests, reference values).
    One,
    /// Conductor with complex index n + iκ relative to the outer medium (air).
    Conductor(Ior),
}

impl Fresnel {
    /// Conductor Fresnel for the given index.
    pub fn conductor(ior: Ior) -> Fresnel {
        Fresnel::Conductor(ior)
    }

    /// Reflectance for the cosine between the incident direction and the
    /// reflecting normal, at `lambda_nm`. `cos_theta` is clamped to [0, 1].
    #[inline]
    pub fn reflectance(&self, cos_theta: f64, lambda_nm: f64) -> f64 {
        let c = clamp_cos(cos_theta);
        self.reflectance_ratio(c * c, 1.0, lambda_nm)
    }

    /// Reflectance for cos²θ = `num` / `den` (see [`conductor_reflectance_ratio`]).
    #[inline]
    pub fn reflectance_ratio(&self, num: f64, den: f64, lambda_nm: f64) -> f64 {
        match self {
            Fresnel::One => 1.0,
            Fresnel::Conductor(ior) => {
                let (n, k) = ior.at(lambda_nm);
                conductor_reflectance_ratio(num, den, n, k)
            }
        }
    }

    /// [`reflectance_ratio`](Self::reflectance_ratio) at each of `lambdas`
    /// into `out` (as many as the shorter of the two), bit-identical to it.
    ///
    /// Only n and κ vary across the set, so the optical constants are looked
    /// up in one loop and the reflectances computed in pairs, two lanes per
    /// square root and division (their latency is most of a conductor
    /// BRDF's cost at each further wavelength).
    #[inline]
    pub fn reflectance_ratio_many(&self, num: f64, den: f64, lambdas: &[f64], out: &mut [f64]) {
        let ior = match self {
            Fresnel::One => {
                for o in out.iter_mut().take(lambdas.len()) {
                    *o = 1.0;
                }
                return;
            }
            Fresnel::Conductor(ior) => ior,
        };
        const CHUNK: usize = 16;
        let len = lambdas.len().min(out.len());
        let (mut n, mut k) = ([0.0; CHUNK], [0.0; CHUNK]);
        for (ls, os) in lambdas[..len]
            .chunks(CHUNK)
            .zip(out[..len].chunks_mut(CHUNK))
        {
            let m = ls.len();
            ior.at_many(ls, &mut n[..m], &mut k[..m]);
            let mut j = 0;
            while j + 1 < m {
                let r =
                    conductor_reflectance_ratio_pair(num, den, [n[j], n[j + 1]], [k[j], k[j + 1]]);
                (os[j], os[j + 1]) = (r[0], r[1]);
                j += 2;
            }
            if j < m {
                os[j] = conductor_reflectance_ratio(num, den, n[j], k[j]);
            }
        }
    }

    /// Checks that the data cover `[lo, hi]` nm (always true for [`Fresnel::One`]).
    pub fn check_covers(&self, lo_nm: f64, hi_nm: f64) -> Result<(), crate::BrdfError> {
        match self {
            Fresnel::One => Ok(()),
            Fresnel::Conductor(ior) => ior.check_covers(lo_nm, hi_nm),
        }
    }
}

/// Unpolarised reflectance of an interface from air into a medium of index
/// n + iκ, for incidence cosine `cos_theta`.
///
/// Uses the real-arithmetic form of the complex Fresnel equations: with
/// a² + b² = |η² − sin²θ| it needs two square roots and no complex division,
/// and both ratios tend to 1 (not 0/0) as cosθ → 0, which keeps grazing
/// incidence exact. Equal to the complex form to round-off (tested).
#[inline]
pub fn conductor_reflectance(cos_theta: f64, n: f64, k: f64) -> f64 {
    let c = clamp_cos(cos_theta);
    conductor_reflectance_ratio(c * c, 1.0, n, k)
}

/// cosθ clamped to [0, 1], NaN to 0.
#[inline]
fn clamp_cos(c: f64) -> f64 {
    if c > 0.0 { c.min(1.0) } else { 0.0 }
}

/// [`conductor_reflectance`] for cos²θ = `num` / `den` (0 ≤ num ≤ den, den > 0),
/// without forming the quotient.
///
/// The cosine enters only squared and in the product c·a (taken as √(c²a²)),
/// and written in C = cos²θ·Q, S = sin²θ·Q and Q the reflectance is a ratio of
/// homogeneous polynomials in which Q cancels. A microfacet sampler that
/// knows wi·h and |h|² of an unnormalised h thus pays no division and no
/// square root before the Fresnel chain (its critical path).
#[inline]
pub fn conductor_reflectance_ratio(num: f64, den: f64, n: f64, k: f64) -> f64 {
    let c = num.max(0.0);
    let s = (den - c).max(0.0);
    let n2 = n * n;
    // λ-only terms, off the critical path.
    let e = n2 - k * k - 1.0;
    let nk4 = 4.0 * n2 * (k * k);
    // The textbook quantities times powers of Q: t0 = (n² − κ² − sin²θ)·Q,
    // a2b2 = (a² + b²)·Q, t2 = 2ca·Q with a² = ½(a² + b² + t0); the
    // expressions are arranged for the shortest dependent chain.
    let t0 = e * den + c;
    let a2b2 = libm::sqrt(t0 * t0 + nk4 * (den * den));
    let t2_sq = 2.0 * c * (a2b2 + t0);
    let t2 = libm::sqrt(t2_sq);
    let t1 = a2b2 + c;
    let t3 = c * a2b2 + s * s;
    // R_s = (t1 − t2)/(t1 + t2) and R_p = R_s (t3 − t2 s)/(t3 + t2 s), so
    // ½(R_s + R_p) = (t1 − t2) t3 / ((t1 + t2)(t3 + t2 s)): one division,
    // its denominator expanded so that only one product waits for t2.
    let r = (t1 * t3 - t2 * t3) / (t1 * t3 + s * t2_sq + t2 * (t1 * s + t3));
    // n = 1, κ = 0 at normal incidence is 0/0; a matched interface reflects nothing.
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// [`conductor_reflectance_ratio`] for four (cos²θ, index) lanes with one
/// shared `den`: the same operations in the same order on each lane, so each
/// is bit-identical to the scalar call; written as element-wise loops over
/// fixed-length arrays, which compile to packed instructions.
#[inline(always)]
pub(crate) fn conductor_reflectance_ratio_lanes(
    num: [f64; 4],
    den: f64,
    n: [f64; 4],
    k: [f64; 4],
) -> [f64; 4] {
    use crate::numerics::math::sqrt_lanes;
    fn each(f: impl FnMut(usize) -> f64) -> [f64; 4] {
        core::array::from_fn(f)
    }
    let c = each(|j| num[j].max(0.0));
    let s = each(|j| (den - c[j]).max(0.0));
    let n2 = each(|j| n[j] * n[j]);
    let e = each(|j| n2[j] - k[j] * k[j] - 1.0);
    let nk4 = each(|j| 4.0 * n2[j] * (k[j] * k[j]));
    let t0 = each(|j| e[j] * den + c[j]);
    let a2b2 = sqrt_lanes(each(|j| t0[j] * t0[j] + nk4[j] * (den * den)));
    let t2_sq = each(|j| 2.0 * c[j] * (a2b2[j] + t0[j]));
    let t2 = sqrt_lanes(t2_sq);
    let t1 = each(|j| a2b2[j] + c[j]);
    let t3 = each(|j| c[j] * a2b2[j] + s[j] * s[j]);
    let r = each(|j| {
        (t1[j] * t3[j] - t2[j] * t3[j])
            / (t1[j] * t3[j] + s[j] * t2_sq[j] + t2[j] * (t1[j] * s[j] + t3[j]))
    });
    each(|j| {
        if r[j].is_finite() {
            r[j].clamp(0.0, 1.0)
        } else {
            0.0
        }
    })
}

/// [`conductor_reflectance_ratio`] for two indices at one angle, with the
/// same operations in the same order on each lane (so bit-identical to two
/// scalar calls): SSE2 is part of every x86-64, and its packed square root
/// and division take two lanes for the latency of one.
#[cfg(target_arch = "x86_64")]
#[inline]
fn conductor_reflectance_ratio_pair(num: f64, den: f64, n: [f64; 2], k: [f64; 2]) -> [f64; 2] {
    use core::arch::x86_64::{
        __m128d, _mm_add_pd, _mm_div_pd, _mm_mul_pd, _mm_set_pd, _mm_set1_pd, _mm_sqrt_pd,
        _mm_storeu_pd, _mm_sub_pd,
    };
    // SAFETY: every intrinsic used is SSE2, which the x86_64 target always
    // has; the store writes two f64 into a two-element array.
    unsafe {
        let c = num.max(0.0);
        let s = (den - c).max(0.0);
        let splat = |x: f64| _mm_set1_pd(x);
        let (vc, vs, vden) = (splat(c), splat(s), splat(den));
        let vn: __m128d = _mm_set_pd(n[1], n[0]);
        let vk: __m128d = _mm_set_pd(k[1], k[0]);
        let n2 = _mm_mul_pd(vn, vn);
        let k2 = _mm_mul_pd(vk, vk);
        let e = _mm_sub_pd(_mm_sub_pd(n2, k2), splat(1.0));
        let nk4 = _mm_mul_pd(_mm_mul_pd(splat(4.0), n2), k2);
        let t0 = _mm_add_pd(_mm_mul_pd(e, vden), vc);
        let a2b2 = _mm_sqrt_pd(_mm_add_pd(
            _mm_mul_pd(t0, t0),
            _mm_mul_pd(nk4, splat(den * den)),
        ));
        let t2_sq = _mm_mul_pd(splat(2.0 * c), _mm_add_pd(a2b2, t0));
        let t2 = _mm_sqrt_pd(t2_sq);
        let t1 = _mm_add_pd(a2b2, vc);
        let t3 = _mm_add_pd(_mm_mul_pd(vc, a2b2), splat(s * s));
        let t1t3 = _mm_mul_pd(t1, t3);
        let numer = _mm_sub_pd(t1t3, _mm_mul_pd(t2, t3));
        let denom = _mm_add_pd(
            _mm_add_pd(t1t3, _mm_mul_pd(vs, t2_sq)),
            _mm_mul_pd(t2, _mm_add_pd(_mm_mul_pd(t1, vs), t3)),
        );
        let mut r = [0.0; 2];
        _mm_storeu_pd(r.as_mut_ptr(), _mm_div_pd(numer, denom));
        r.map(|r| {
            if r.is_finite() {
                r.clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
    }
}

#[cfg(not(target_arch = "x86_64"))]
#[inline]
fn conductor_reflectance_ratio_pair(num: f64, den: f64, n: [f64; 2], k: [f64; 2]) -> [f64; 2] {
    [
        conductor_reflectance_ratio(num, den, n[0], k[0]),
        conductor_reflectance_ratio(num, den, n[1], k[1]),
    ]
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface,
/// R = ½(r_s² + r_p²), for incidence cosine `cos_i` (clamped to [0, 1]) and
/// relative index `eta` = n_transmitted / n_incident (> 0), with the cosine of
/// the refracted direction: `(R, cosθt)`. Beyond the critical angle (η < 1)
/// the reflection is total: `(1, 0)`.
#[inline]
pub fn dielectric_reflectance(cos_i: f64, eta: f64) -> (f64, f64) {
    let ci = clamp_cos(cos_i);
    let sin2_t = (1.0 - ci * ci) / (eta * eta);
    // Total reflection, or a NaN η.
    if sin2_t >= 1.0 || sin2_t.is_nan() {
        return (1.0, 0.0);
    }
    let ct = libm::sqrt(1.0 - sin2_t);
    let rs = (ci - eta * ct) / (ci + eta * ct);
    let rp = (eta * ci - ct) / (eta * ci + ct);
    let r = 0.5 * (rs * rs + rp * rp);
    (
        if r.is_finite() {
            r.clamp(0.0, 1.0)
        } else {
            1.0
        },
        ct,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ior::Metal;

    /// Minimal complex arithmetic for the textbook form of the Fresnel equations.
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    impl C {
        fn mul(self, o: C) -> C {
            C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
        }
        fn div(self, o: C) -> C {
            let d = o.0 * o.0 + o.1 * o.1;
            C(
                (self.0 * o.0 + self.1 * o.1) / d,
                (self.1 * o.0 - self.0 * o.1) / d,
            )
        }
        fn add(self, o: C) -> C {
            C(self.0 + o.0, self.1 + o.1)
        }
        fn sub(self, o: C) -> C {
            C(self.0 - o.0, self.1 - o.1)
        }
        fn norm2(self) -> f64 {
            self.0 * self.0 + self.1 * self.1
        }
        fn sqrt(self) -> C {
            let r = libm::hypot(self.0, self.1);
            let re = libm::sqrt(0.5 * (r + self.0));
            let im = libm::sqrt(0.5 * (r - self.0)).copysign(self.1);
            C(re, im)
        }
    }

    fn complex_form(c: f64, n: f64, k: f64) -> f64 {
        let eta = C(n, k);
        let eta2 = eta.mul(eta);
        let ct = C(1.0, 0.0).sub(C(1.0 - c * c, 0.0).div(eta2)).sqrt();
        let cc = C(c, 0.0);
        let rs = cc.sub(eta.mul(ct)).div(cc.add(eta.mul(ct)));
        let rp = eta.mul(cc).sub(ct).div(eta.mul(cc).add(ct));
        0.5 * (rs.norm2() + rp.norm2())
    }

    #[test]
    fn matches_complex_form() {
        for &(n, k) in &[
            (0.27, 2.77),
            (1.5, 0.0),
            (2.9, 3.1),
            (0.05, 4.0),
            (1.0, 0.5),
        ] {
            for i in 0..=100 {
                let c = i as f64 / 100.0;
                let a = conductor_reflectance(c, n, k);
                let b = if c == 0.0 { 1.0 } else { complex_form(c, n, k) };
                assert!((a - b).abs() < 1e-13, "n={n} k={k} c={c}: {a} vs {b}");
                // The unnormalised form at any scale of (cos², 1).
                for q in [1e-30, 1e-8, 0.25, 3.0, 1e12] {
                    let r = conductor_reflectance_ratio(c * c * q, q, n, k);
                    assert!((r - b).abs() < 1e-13, "n={n} k={k} c={c} q={q}: {r} vs {b}");
                }
            }
        }
    }

    #[test]
    fn batched_reflectance_is_bit_identical_to_scalar_over_the_domain() {
        // Odd lengths (the unpaired last lane), more than one chunk, every
        // kind of data, and the extremes of angle and index.
        let lambdas: [f64; 37] = core::array::from_fn(|j| 340.0 + 14.1 * j as f64);
        let iors = [
            Ior::metal(Metal::Cu),
            Ior::metal(Metal::Al),
            Ior::constant(1.0, 0.0).unwrap(),
            Ior::constant(1e-6, 1e6).unwrap(),
            Ior::constant(1e6, 0.0).unwrap(),
            Ior::table(alloc::vec![[400.0, 0.3, 3.0], [700.0, 1.5, 0.0]]).unwrap(),
        ];
        let cos2 = [0.0, 1e-300, 1e-12, 0.25, 0.5, 1.0 - 1e-16, 1.0, 1.5, -0.1];
        for ior in iors {
            let f = Fresnel::conductor(ior);
            for &c2 in &cos2 {
                for q in [1e-30, 1.0, 4.0, 1e12] {
                    for len in [0, 1, 2, 5, 16, 17, 37] {
                        let mut out = [-1.0; 38];
                        f.reflectance_ratio_many(c2 * q, q, &lambdas[..len], &mut out);
                        for j in 0..len {
                            let r = f.reflectance_ratio(c2 * q, q, lambdas[j]);
                            assert_eq!(out[j].to_bits(), r.to_bits(), "{f:?} c²={c2} q={q} j={j}");
                        }
                        assert!(out[len..].iter().all(|&v| v == -1.0));
                    }
                }
            }
        }
        let mut out = [0.0; 4];
        Fresnel::One.reflectance_ratio_many(0.3, 1.0, &lambdas[..3], &mut out);
        assert_eq!(out, [1.0, 1.0, 1.0, 0.0]);
    }

    #[test]
    fn normal_incidence_closed_form_and_grazing_limit() {
        let (n, k) = (0.27, 2.77);
        let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((conductor_reflectance(1.0, n, k) - want).abs() < 1e-15);
        assert_eq!(conductor_reflectance(0.0, n, k), 1.0);
        assert!(conductor_reflectance(1e-9, n, k) > 0.999_999);
        assert_eq!(conductor_reflectance(-0.5, n, k), 1.0);
        assert_eq!(conductor_reflectance(1.0, 1.0, 0.0), 0.0);
    }

    #[test]
    fn measured_metals_match_data_readme() {
        // data/spectra/README.md "Normal-incidence reflectance" table.
        let cases = [
            (Metal::Cu, 550.0, 0.624),
            (Metal::Al, 550.0, 0.915),
            (Metal::Au, 650.0, 0.957),
            (Metal::Ag, 400.0, 0.964),
            (Metal::Fe, 450.0, 0.496),
            (Metal::Cr, 700.0, 0.562),
            (Metal::BrassCu70Zn30, 550.0, 0.789),
            (Metal::StainlessSteel, 400.0, 0.570),
        ];
        for (m, l, want) in cases {
            let r = Fresnel::conductor(Ior::metal(m)).reflectance(1.0, l);
            assert!((r - want).abs() < 6e-4, "{m:?} at {l} nm: {r} vs {want}");
        }
    }
}
