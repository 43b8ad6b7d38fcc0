//! Lambertian reflection (Mitsuba's `diffuse`): f = ρ(λ)/π, sampled
//! cosine-weighted (docs/physics.md §16).
//!
//! The reflectance is a constant or a spectrum (rows `λ nm, ρ`), interpolated
//! linearly in λ; outside the table the end value is held.

// `!(x > 0.0)` is how these guards also refuse NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use core::f64::consts::{FRAC_1_PI, PI};

use glam::DVec3;

use crate::error::{BrdfError, check_range};
use crate::{Bxdf, BxdfSample};

/// A reflectance ρ(λ) ∈ [0, 1]: a constant or a tabulated spectrum.
#[derive(Clone, Debug, PartialEq)]
pub enum Reflectance {
    /// The same ρ at every wavelength.
    Constant(f64),
    /// Rows `[λ nm, ρ]`, λ strictly increasing; linear between rows, the end
    /// values held outside them.
    #[cfg(feature = "alloc")]
    Table(alloc::sync::Arc<ReflectanceTable>),
}

/// The rows of a tabulated reflectance (see [`Reflectance::table`]) and
/// what finds a wavelength's row without a search.
#[cfg(feature = "alloc")]
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectanceTable {
    rows: alloc::vec::Vec<[f64; 2]>,
    /// Each pair of neighbouring rows `[λa, ρa, λb, ρb]`: a lookup reads its
    /// interval from one record.
    segments: alloc::vec::Vec<[f64; 4]>,
    /// (rows − 1) / (last λ − first λ): a wavelength's interval if the
    /// rows were evenly spaced, the first guess of [`ReflectanceTable::at`].
    rows_per_nm: f64,
}

#[cfg(feature = "alloc")]
impl ReflectanceTable {
    fn new(rows: alloc::vec::Vec<[f64; 2]>) -> ReflectanceTable {
        let span = rows[rows.len() - 1][0] - rows[0][0];
        let rows_per_nm = if span > 0.0 {
            (rows.len() - 1) as f64 / span
        } else {
            0.0
        };
        let segments = rows
            .windows(2)
            .map(|w| [w[0][0], w[0][1], w[1][0], w[1][1]])
            .collect();
        ReflectanceTable {
            rows,
            segments,
            rows_per_nm,
        }
    }

    /// The rows `[λ nm, ρ]`.
    pub fn rows(&self) -> &[[f64; 2]] {
        &self.rows
    }

    /// ρ at `lambda_nm`: linear between the two rows around it, the end
    /// values held outside.
    #[inline]
    pub fn at(&self, lambda_nm: f64) -> f64 {
        let (Some(first), Some(last)) = (self.segments.first(), self.segments.last()) else {
            return self.rows[0][1];
        };
        if !(lambda_nm > first[0]) {
            return first[1];
        }
        if lambda_nm >= last[2] {
            return last[3];
        }
        // λ is strictly inside the table. Its interval is guessed as for
        // evenly spaced rows and searched for only if the guess misses:
        // measured tables are mostly evenly spaced, and the binary search
        // alone cost 80 instructions a lookup, half a rough plastic's
        // evaluation.
        let k = ((lambda_nm - first[0]) * self.rows_per_nm) as u32 as usize;
        let s = match self.segments.get(k) {
            Some(s) if s[0] <= lambda_nm && lambda_nm < s[2] => s,
            _ => self.search(lambda_nm, k),
        };
        let t = (lambda_nm - s[0]) / (s[2] - s[0]);
        (s[1] + t * (s[3] - s[1])).clamp(0.0, 1.0)
    }

    /// The interval holding `lambda_nm` (strictly inside the table) when
    /// the guess `k` missed: a neighbour of it (unevenly spaced rows), else
    /// by bisection.
    fn search(&self, lambda_nm: f64, k: usize) -> &[f64; 4] {
        for j in [k.wrapping_sub(1), k + 1] {
            if let Some(s) = self.segments.get(j)
                && s[0] <= lambda_nm
                && lambda_nm < s[2]
            {
                return s;
            }
        }
        let k = self.segments.partition_point(|s| s[2] <= lambda_nm);
        &self.segments[k.min(self.segments.len() - 1)]
    }
}

impl Reflectance {
    /// A constant reflectance, 0 ≤ ρ ≤ 1.
    pub fn constant(rho: f64) -> Result<Reflectance, BrdfError> {
        check_range("reflectance", rho, 0.0, 1.0, "0 ≤ reflectance ≤ 1").map(Reflectance::Constant)
    }

    /// A tabulated spectrum: at least one row, finite wavelengths (nm, > 0)
    /// strictly increasing, every ρ in [0, 1].
    #[cfg(feature = "alloc")]
    pub fn table(rows: alloc::vec::Vec<[f64; 2]>) -> Result<Reflectance, BrdfError> {
        if rows.is_empty() {
            return Err(BrdfError::InvalidTable {
                reason: "a reflectance table needs at least one row `wavelength_nm,reflectance`",
                row: None,
            });
        }
        for (i, r) in rows.iter().enumerate() {
            if !(r[0].is_finite() && r[0] > 0.0) {
                return Err(BrdfError::InvalidTable {
                    reason: "the wavelength must be a finite number of nm above 0",
                    row: Some(i),
                });
            }
            if i > 0 && r[0] <= rows[i - 1][0] {
                return Err(BrdfError::InvalidTable {
                    reason: "wavelengths must increase strictly from row to row",
                    row: Some(i),
                });
            }
            if !(r[1].is_finite() && (0.0..=1.0).contains(&r[1])) {
                return Err(BrdfError::InvalidTable {
                    reason: "a reflectance must lie in [0, 1] (a surface reflects no more than \
                             it receives)",
                    row: Some(i),
                });
            }
        }
        Ok(Reflectance::Table(alloc::sync::Arc::new(
            ReflectanceTable::new(rows),
        )))
    }

    /// ρ at `lambda_nm`.
    #[inline]
    pub fn at(&self, lambda_nm: f64) -> f64 {
        // Read only by tables (`alloc`).
        let _ = lambda_nm;
        match self {
            Reflectance::Constant(r) => *r,
            #[cfg(feature = "alloc")]
            Reflectance::Table(t) => t.at(lambda_nm),
        }
    }

    /// The mean of ρ over the table's wavelength range (trapezoidal; the
    /// constant itself, or a one-row table's value): what the rough plastic's
    /// lobe choice weighs the diffuse base by, as Mitsuba's `mean()`.
    pub fn mean(&self) -> f64 {
        match self {
            Reflectance::Constant(r) => *r,
            #[cfg(feature = "alloc")]
            Reflectance::Table(t) => {
                let rows = t.rows();
                let (first, last) = (rows[0][0], rows[rows.len() - 1][0]);
                if rows.len() < 2 || last <= first {
                    return rows[0][1];
                }
                let area: f64 = (rows.windows(2))
                    .map(|w| 0.5 * (w[0][1] + w[1][1]) * (w[1][0] - w[0][0]))
                    .sum();
                (area / (last - first)).clamp(0.0, 1.0)
            }
        }
    }
}

/// A direction on the upper hemisphere with density cosθ/π, from two uniform
/// numbers (Shirley–Chiu concentric disk, lifted): continuous in `u`, so
/// stratified numbers stay stratified.
#[inline]
pub fn sample_cosine_hemisphere(u: [f64; 2]) -> DVec3 {
    let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    let (r, phi) = if a == 0.0 && b == 0.0 {
        (0.0, 0.0)
    } else if a.abs() > b.abs() {
        (a, 0.25 * PI * (b / a))
    } else {
        (b, 0.5 * PI - 0.25 * PI * (a / b))
    };
    // One argument reduction for both: sincos uses sin's and cos's own
    // kernels and quadrant rule, so the values are theirs bit for bit.
    let (sin, cos) = libm::sincos(phi);
    let (x, y) = (r * cos, r * sin);
    let z = libm::sqrt((1.0 - x * x - y * y).max(0.0));
    DVec3::new(x, y, z)
}

/// A Lambertian reflector: f(wi, wo, λ) = ρ(λ)/π above the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Diffuse {
    reflectance: Reflectance,
}

impl Diffuse {
    /// A Lambertian reflector of reflectance `reflectance`.
    pub fn new(reflectance: Reflectance) -> Diffuse {
        Diffuse { reflectance }
    }

    /// Its reflectance.
    pub fn reflectance(&self) -> &Reflectance {
        &self.reflectance
    }
}

impl Bxdf for Diffuse {
    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.reflectance.at(lambda_nm) * FRAC_1_PI
        } else {
            0.0
        }
    }

    #[inline]
    fn pdf(&self, wi: DVec3, wo: DVec3, _lambda_nm: f64) -> f64 {
        if wi.z > 0.0 && wo.z > 0.0 {
            wo.z * FRAC_1_PI
        } else {
            0.0
        }
    }

    /// The pdf and, for a constant reflectance, f once for all wavelengths.
    #[inline]
    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        let out = out.iter_mut().take(lambdas.len());
        if !(wi.z > 0.0 && wo.z > 0.0) {
            out.for_each(|o| *o = (0.0, 0.0));
            return;
        }
        let pdf = wo.z * FRAC_1_PI;
        match &self.reflectance {
            Reflectance::Constant(r) => out.for_each(|o| *o = (r * FRAC_1_PI, pdf)),
            #[cfg(feature = "alloc")]
            Reflectance::Table(t) => {
                for (o, &l) in out.zip(lambdas) {
                    *o = (t.at(l) * FRAC_1_PI, pdf);
                }
            }
        }
    }

    /// Cosine-weighted from `u[1]`, `u[2]`; the weight is ρ(λ).
    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        if !(wi.z > 0.0) {
            return None;
        }
        let wo = sample_cosine_hemisphere([u[1], u[2]]);
        let rho = self.reflectance.at(lambda_nm);
        (wo.z > 0.0 && rho > 0.0).then_some(BxdfSample {
            wo,
            weight: rho,
            pdf: wo.z * FRAC_1_PI,
            is_delta: false,
        })
    }

    fn uses_lobe_choice(&self) -> bool {
        false
    }

    fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
        (wi.z > 0.0).then_some(FRAC_1_PI)
    }
}

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use super::*;

    /// The concentric map's (cos φ, sin φ) from `sincos` are `cos`'s and
    /// `sin`'s, bit for bit, over the map's whole range of φ (±π/4 and
    /// π/4…3π/4), its branch edges and the origin.
    #[test]
    fn cosine_hemisphere_sincos_is_sin_and_cos() {
        let old = |u: [f64; 2]| {
            let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
            let (r, phi) = if a == 0.0 && b == 0.0 {
                (0.0, 0.0)
            } else if a.abs() > b.abs() {
                (a, 0.25 * PI * (b / a))
            } else {
                (b, 0.5 * PI - 0.25 * PI * (a / b))
            };
            let (x, y) = (r * libm::cos(phi), r * libm::sin(phi));
            DVec3::new(x, y, libm::sqrt((1.0 - x * x - y * y).max(0.0)))
        };
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let edges = [
            0.0,
            0.5,
            0.5f64.next_up(),
            0.5f64.next_down(),
            1.0f64.next_down(),
            0.25,
            0.75,
        ];
        let mut us: alloc::vec::Vec<[f64; 2]> = (0..400_000).map(|_| [next(), next()]).collect();
        for &a in &edges {
            for &b in &edges {
                us.push([a, b]);
            }
            let t = next();
            us.extend([[a, t], [t, a], [t, t], [t, 1.0 - t]]);
        }
        for u in us {
            let (n, o) = (sample_cosine_hemisphere(u), old(u));
            assert_eq!(
                n.to_array().map(f64::to_bits),
                o.to_array().map(f64::to_bits),
                "{u:?}"
            );
        }
    }

    #[test]
    fn table_interpolates_and_holds_the_ends() {
        let r = Reflectance::table(alloc::vec![[400.0, 0.2], [500.0, 0.6], [700.0, 0.4]]).unwrap();
        assert_eq!(r.at(300.0), 0.2);
        assert!((r.at(450.0) - 0.4).abs() < 1e-15);
        assert!((r.at(600.0) - 0.5).abs() < 1e-15);
        assert_eq!(r.at(500.0), 0.6);
        assert_eq!(r.at(900.0), 0.4);
        assert_eq!(r.at(f64::NAN), 0.2);
        // (0.4·100 + 0.5·200) / 300
        assert!((r.mean() - 140.0 / 300.0).abs() < 1e-15);
    }

    /// The interpolation by a binary search over the rows: the lookup's
    /// guessed row must give its bits.
    fn searched(rows: &[[f64; 2]], lambda_nm: f64) -> f64 {
        let last = rows.len() - 1;
        if !(lambda_nm > rows[0][0]) {
            return rows[0][1];
        }
        if lambda_nm >= rows[last][0] {
            return rows[last][1];
        }
        let j = rows.partition_point(|r| r[0] <= lambda_nm).clamp(1, last);
        let (a, b) = (rows[j - 1], rows[j]);
        let t = (lambda_nm - a[0]) / (b[0] - a[0]);
        (a[1] + t * (b[1] - a[1])).clamp(0.0, 1.0)
    }

    #[test]
    fn guessed_rows_give_a_full_searchs_bits() {
        let even: alloc::vec::Vec<[f64; 2]> = (0..48)
            .map(|i| [360.0 + 10.0 * i as f64, (0.05 + 0.017 * i as f64).min(1.0)])
            .collect();
        let uneven = alloc::vec![
            [380.0, 0.28],
            [450.0, 0.31],
            [550.0, 0.33],
            [650.0, 0.35],
            [780.0, 0.36]
        ];
        // Rows crowded at one end: most guesses miss by many rows.
        let crowded: alloc::vec::Vec<[f64; 2]> = (0..40)
            .map(|i| {
                [
                    400.0 + 0.5 * (i * i) as f64,
                    0.5 + 0.4 * libm::sin(i as f64),
                ]
            })
            .collect();
        let two = alloc::vec![[500.0, 0.1], [600.0, 0.9]];
        let one = alloc::vec![[500.0, 0.4]];
        for rows in [even, uneven, crowded, two, one] {
            let Reflectance::Table(t) = Reflectance::table(rows.clone()).unwrap() else {
                unreachable!()
            };
            let mut ls: alloc::vec::Vec<f64> = (0..20_000)
                .map(|k| 300.0 + 600.0 * k as f64 / 20_000.0)
                .collect();
            for r in &rows {
                ls.extend([r[0], r[0].next_up(), r[0].next_down()]);
            }
            ls.extend([f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0]);
            for l in ls {
                assert_eq!(t.at(l).to_bits(), searched(&rows, l).to_bits(), "λ {l}");
            }
        }
    }

    #[test]
    fn bad_tables_name_the_row() {
        for (rows, row) in [
            (alloc::vec![[400.0, 0.2], [400.0, 0.3]], Some(1)),
            (alloc::vec![[400.0, 0.2], [500.0, 1.2]], Some(1)),
            (alloc::vec![[f64::NAN, 0.2]], Some(0)),
            (alloc::vec![[400.0, -0.1]], Some(0)),
            (alloc::vec![], None),
        ] {
            match Reflectance::table(rows) {
                Err(BrdfError::InvalidTable { row: r, .. }) => assert_eq!(r, row),
                other => panic!("{other:?}"),
            }
        }
        assert!(Reflectance::constant(1.0 + 1e-12).is_err());
        assert!(Reflectance::constant(f64::NAN).is_err());
    }

    #[test]
    fn cosine_samples_are_unit_and_above_the_surface() {
        for i in 0..=16 {
            for j in 0..=16 {
                let w = sample_cosine_hemisphere([i as f64 / 16.0, j as f64 / 16.0]);
                assert!((w.length() - 1.0).abs() < 1e-12, "{w}");
                assert!(w.z >= 0.0);
            }
        }
    }
}
