//! Spectral complex refractive index n + iκ of conductors.
//!
//! Built-in metals carry measured tables (sources cited in `ior_data.rs`);
//! values between samples are interpolated linearly in wavelength, and never
//! extrapolated: outside the table the end value is held, and building a model
//! checks that the wavelengths it will be asked about lie inside the table.

use crate::error::BrdfError;
use crate::ior_data;

/// The metals with built-in measured n, κ tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Metal {
    /// Copper (Johnson & Christy 1972).
    Cu,
    /// Gold (Johnson & Christy 1972).
    Au,
    /// Silver (Johnson & Christy 1972).
    Ag,
    /// Aluminium (Rakić 1995).
    Al,
    /// Iron (Johnson & Christy 1974).
    Fe,
    /// Chromium (Johnson & Christy 1974).
    Cr,
    /// Brass, 70 % Cu / 30 % Zn (Querry 1985).
    BrassCu70Zn30,
    /// Austenitic stainless steel (Karlsson & Ribbing 1982).
    StainlessSteel,
}

impl Metal {
    /// Every built-in metal.
    pub const ALL: [Metal; 8] = [
        Metal::Cu,
        Metal::Au,
        Metal::Ag,
        Metal::Al,
        Metal::Fe,
        Metal::Cr,
        Metal::BrassCu70Zn30,
        Metal::StainlessSteel,
    ];

    /// The name used in scene and query files (`"cu"`, `"brass"`, …).
    pub fn name(self) -> &'static str {
        match self {
            Metal::Cu => "cu",
            Metal::Au => "au",
            Metal::Ag => "ag",
            Metal::Al => "al",
            Metal::Fe => "fe",
            Metal::Cr => "cr",
            Metal::BrassCu70Zn30 => "brass",
            Metal::StainlessSteel => "stainless_steel",
        }
    }

    /// Looks a metal up by name, case-insensitively. Accepts the [`Metal::name`]
    /// spellings plus common aliases (`copper`, `gold`, `steel`, `cu70zn30`, …).
    pub fn from_name(name: &str) -> Option<Metal> {
        let aliases: [(&str, Metal); 22] = [
            ("cu", Metal::Cu),
            ("copper", Metal::Cu),
            ("au", Metal::Au),
            ("gold", Metal::Au),
            ("ag", Metal::Ag),
            ("silver", Metal::Ag),
            ("al", Metal::Al),
            ("aluminium", Metal::Al),
            ("aluminum", Metal::Al),
            ("fe", Metal::Fe),
            ("iron", Metal::Fe),
            ("cr", Metal::Cr),
            ("chromium", Metal::Cr),
            ("brass", Metal::BrassCu70Zn30),
            ("cu70zn30", Metal::BrassCu70Zn30),
            ("brass_cu70zn30", Metal::BrassCu70Zn30),
            ("stainless_steel", Metal::StainlessSteel),
            ("stainless", Metal::StainlessSteel),
            ("steel", Metal::StainlessSteel),
            ("stainless_steel_austenitic", Metal::StainlessSteel),
            ("ss", Metal::StainlessSteel),
            ("inox", Metal::StainlessSteel),
        ];
        aliases
            .iter()
            .find(|(a, _)| a.eq_ignore_ascii_case(name))
            .map(|&(_, m)| m)
    }

    /// The table, its guide and its slopes, resolved with one dispatch.
    #[inline]
    fn lookup(
        self,
    ) -> (
        &'static [[f64; 3]],
        &'static [u8; GUIDE_LEN],
        &'static [[f64; 2]],
    ) {
        match self {
            Metal::Cu => (&ior_data::CU, &GUIDE_CU, &SLOPES_CU),
            Metal::Au => (&ior_data::AU, &GUIDE_AU, &SLOPES_AU),
            Metal::Ag => (&ior_data::AG, &GUIDE_AG, &SLOPES_AG),
            Metal::Al => (&ior_data::AL, &GUIDE_AL, &SLOPES_AL),
            Metal::Fe => (&ior_data::FE, &GUIDE_FE, &SLOPES_FE),
            Metal::Cr => (&ior_data::CR, &GUIDE_CR, &SLOPES_CR),
            Metal::BrassCu70Zn30 => (&ior_data::BRASS, &GUIDE_BRASS, &SLOPES_BRASS),
            Metal::StainlessSteel => (
                &ior_data::STAINLESSSTEEL,
                &GUIDE_STAINLESSSTEEL,
                &SLOPES_STAINLESSSTEEL,
            ),
        }
    }

    /// The measured table: rows of `[λ nm, n, κ]`, λ strictly increasing.
    pub fn table(self) -> &'static [[f64; 3]] {
        match self {
            Metal::Cu => &ior_data::CU,
            Metal::Au => &ior_data::AU,
            Metal::Ag => &ior_data::AG,
            Metal::Al => &ior_data::AL,
            Metal::Fe => &ior_data::FE,
            Metal::Cr => &ior_data::CR,
            Metal::BrassCu70Zn30 => &ior_data::BRASS,
            Metal::StainlessSteel => &ior_data::STAINLESSSTEEL,
        }
    }
}

const GUIDE_BASE_NM: usize = 200;
const GUIDE_LEN: usize = 800;

/// For each integer wavelength GUIDE_BASE_NM + j, the index of the last row
/// at or below it (clamped to a valid interval start), computed at compile time.
const fn build_guide<const N: usize>(rows: &[[f64; 3]; N]) -> [u8; GUIDE_LEN] {
    let mut out = [0u8; GUIDE_LEN];
    let mut j = 0;
    while j < GUIDE_LEN {
        let lambda = (GUIDE_BASE_NM + j) as f64;
        let mut i = 0;
        while i + 2 < N && rows[i + 1][0] <= lambda {
            i += 1;
        }
        out[j] = i as u8;
        j += 1;
    }
    out
}

/// Per-interval slopes (dn/dλ, dκ/dλ) of a table, so that interpolation
/// needs no division (the lookup sits at the head of the Fresnel chain).
const fn build_slopes<const N: usize>(rows: &[[f64; 3]; N]) -> [[f64; 2]; N] {
    let mut out = [[0.0; 2]; N];
    let mut i = 0;
    while i + 1 < N {
        let dl = rows[i + 1][0] - rows[i][0];
        out[i] = [
            (rows[i + 1][1] - rows[i][1]) / dl,
            (rows[i + 1][2] - rows[i][2]) / dl,
        ];
        i += 1;
    }
    out
}

static SLOPES_CU: [[f64; 2]; ior_data::CU.len()] = build_slopes(&ior_data::CU);
static SLOPES_AU: [[f64; 2]; ior_data::AU.len()] = build_slopes(&ior_data::AU);
static SLOPES_AG: [[f64; 2]; ior_data::AG.len()] = build_slopes(&ior_data::AG);
static SLOPES_AL: [[f64; 2]; ior_data::AL.len()] = build_slopes(&ior_data::AL);
static SLOPES_FE: [[f64; 2]; ior_data::FE.len()] = build_slopes(&ior_data::FE);
static SLOPES_CR: [[f64; 2]; ior_data::CR.len()] = build_slopes(&ior_data::CR);
static SLOPES_BRASS: [[f64; 2]; ior_data::BRASS.len()] = build_slopes(&ior_data::BRASS);
static SLOPES_STAINLESSSTEEL: [[f64; 2]; ior_data::STAINLESSSTEEL.len()] =
    build_slopes(&ior_data::STAINLESSSTEEL);

static GUIDE_CU: [u8; GUIDE_LEN] = build_guide(&ior_data::CU);
static GUIDE_AU: [u8; GUIDE_LEN] = build_guide(&ior_data::AU);
static GUIDE_AG: [u8; GUIDE_LEN] = build_guide(&ior_data::AG);
static GUIDE_AL: [u8; GUIDE_LEN] = build_guide(&ior_data::AL);
static GUIDE_FE: [u8; GUIDE_LEN] = build_guide(&ior_data::FE);
static GUIDE_CR: [u8; GUIDE_LEN] = build_guide(&ior_data::CR);
static GUIDE_BRASS: [u8; GUIDE_LEN] = build_guide(&ior_data::BRASS);
static GUIDE_STAINLESSSTEEL: [u8; GUIDE_LEN] = build_guide(&ior_data::STAINLESSSTEEL);

/// A complex refractive index as a function of wavelength.
#[derive(Clone, Debug, PartialEq)]
pub enum Ior {
    /// Wavelength-independent n + iκ.
    Constant {
        /// Real part.
        n: f64,
        /// Extinction coefficient.
        k: f64,
    },
    /// A built-in measured metal.
    Metal(Metal),
    /// A user-supplied table of `[λ nm, n, κ]` rows.
    #[cfg(feature = "alloc")]
    Table(alloc::sync::Arc<[[f64; 3]]>),
}

/// Smallest n of a user-given index (constant or table).
pub const N_MIN: f64 = 1e-6;
/// Largest n and κ of a user-given index: past it the Fresnel arithmetic
/// loses the reflectance (n = κ = 1e77 gives 0 for a mirror).
pub const NK_MAX: f64 = 1e6;

/// Whether (n, κ) lies within the bounds every user-given index obeys.
pub fn nk_in_bounds(n: f64, k: f64) -> bool {
    (N_MIN..=NK_MAX).contains(&n) && (0.0..=NK_MAX).contains(&k)
}

impl Ior {
    /// A built-in metal.
    pub fn metal(metal: Metal) -> Ior {
        Ior::Metal(metal)
    }

    /// A constant index; [`N_MIN`] ≤ n ≤ [`NK_MAX`], 0 ≤ k ≤ [`NK_MAX`].
    pub fn constant(n: f64, k: f64) -> Result<Ior, BrdfError> {
        crate::error::check_range("n", n, N_MIN, NK_MAX, "0 < n ≤ 1e6")?;
        crate::error::check_range("k", k, 0.0, NK_MAX, "0 ≤ k ≤ 1e6")?;
        Ok(Ior::Constant { n, k })
    }

    /// A user-supplied table of `[λ nm, n, κ]` rows: at least two rows,
    /// λ strictly increasing and positive, 1e−6 ≤ n ≤ 1e6, 0 ≤ κ ≤ 1e6 (the
    /// bounds of [`Ior::constant`]: past them the Fresnel arithmetic loses
    /// its precision, and at n = κ = 1e77 it returned 0 for a mirror).
    #[cfg(feature = "alloc")]
    pub fn table(rows: alloc::vec::Vec<[f64; 3]>) -> Result<Ior, BrdfError> {
        if rows.len() < 2 {
            return Err(BrdfError::InvalidTable {
                reason: "an n,k table needs at least two rows (wavelength_nm, n, k)",
                row: None,
            });
        }
        for (i, r) in rows.iter().enumerate() {
            let (n_ok, k_ok) = (nk_in_bounds(r[1], 0.0), nk_in_bounds(1.0, r[2]));
            if !(r[0].is_finite() && r[0] > 0.0 && n_ok && k_ok) {
                return Err(BrdfError::InvalidTable {
                    reason: "each row needs finite wavelength_nm > 0, 1e-6 ≤ n ≤ 1e6 and 0 ≤ k ≤ 1e6",
                    row: Some(i),
                });
            }
            if i > 0 && r[0] <= rows[i - 1][0] {
                return Err(BrdfError::InvalidTable {
                    reason: "wavelengths must be strictly increasing",
                    row: Some(i),
                });
            }
        }
        Ok(Ior::Table(rows.into()))
    }

    /// The measured rows `[λ nm, n, κ]` that [`at`](Self::at) interpolates
    /// linearly (its knots), or `None` for a constant index.
    pub fn rows(&self) -> Option<&[[f64; 3]]> {
        match self {
            Ior::Constant { .. } => None,
            Ior::Metal(m) => Some(m.table()),
            #[cfg(feature = "alloc")]
            Ior::Table(t) => Some(t),
        }
    }

    /// Wavelength range `[min, max]` in nm covered by measured data
    /// (infinite for a constant index).
    pub fn range_nm(&self) -> (f64, f64) {
        match self.rows() {
            None => (0.0, f64::INFINITY),
            Some(r) => (r[0][0], r[r.len() - 1][0]),
        }
    }

    /// Checks that `[lo, hi]` nm lies within the data range.
    pub fn check_covers(&self, lo_nm: f64, hi_nm: f64) -> Result<(), BrdfError> {
        let (min_nm, max_nm) = self.range_nm();
        for lambda_nm in [lo_nm, hi_nm] {
            if !(lambda_nm >= min_nm && lambda_nm <= max_nm) {
                return Err(BrdfError::WavelengthOutOfRange {
                    lambda_nm,
                    min_nm,
                    max_nm,
                });
            }
        }
        Ok(())
    }

    /// (n, κ) at `lambda_nm`, linearly interpolated; held constant beyond the
    /// ends of the table (never extrapolated). NaN input gives the first row.
    #[inline]
    pub fn at(&self, lambda_nm: f64) -> (f64, f64) {
        match self {
            Ior::Constant { n, k } => (*n, *k),
            Ior::Metal(m) => {
                let (rows, guide, slopes) = m.lookup();
                metal_at(rows, guide, slopes, lambda_nm)
            }
            #[cfg(feature = "alloc")]
            Ior::Table(rows) => table_at(rows, lambda_nm),
        }
    }

    /// [`at`](Self::at) for each of `lambdas` into `n` and `k` (as many as
    /// the shortest of the three): one dispatch on the kind of data for the
    /// whole set, so the per-wavelength lookups form a loop with no calls,
    /// which the processor overlaps. Bit-identical to `at`.
    #[inline]
    pub fn at_many(&self, lambdas: &[f64], n: &mut [f64], k: &mut [f64]) {
        let out = n.iter_mut().zip(k.iter_mut()).zip(lambdas);
        match self {
            Ior::Constant { n: nc, k: kc } => {
                for ((n, k), _) in out {
                    (*n, *k) = (*nc, *kc);
                }
            }
            Ior::Metal(m) => {
                let (rows, guide, slopes) = m.lookup();
                for ((n, k), &l) in out {
                    (*n, *k) = metal_at(rows, guide, slopes, l);
                }
            }
            #[cfg(feature = "alloc")]
            Ior::Table(rows) => {
                for ((n, k), &l) in out {
                    (*n, *k) = table_at(rows, l);
                }
            }
        }
    }
}

/// Linear interpolation in a built-in table through its guide.
#[inline(always)]
fn metal_at(
    rows: &[[f64; 3]],
    guide: &[u8; GUIDE_LEN],
    slopes: &[[f64; 2]],
    lambda_nm: f64,
) -> (f64, f64) {
    let last = rows.len() - 1;
    if lambda_nm.is_nan() || lambda_nm <= rows[0][0] {
        return (rows[0][1], rows[0][2]);
    }
    if lambda_nm >= rows[last][0] {
        return (rows[last][1], rows[last][2]);
    }
    // The guide gives the interval of ⌊λ⌋ exactly, and at most one
    // row lies in (⌊λ⌋, λ], so one branch-free step finishes the
    // search (a data-dependent branch here mispredicts for random
    // λ and cost more than the rest of the lookup).
    // Through u32 (λ is finite and positive here): shorter than the
    // saturating f64 → usize.
    let j = ((lambda_nm as u32 as usize).saturating_sub(GUIDE_BASE_NM)).min(GUIDE_LEN - 1);
    let lo = guide[j] as usize;
    let lo = lo + usize::from(rows[lo + 1][0] <= lambda_nm);
    let (a, s) = (rows[lo], slopes[lo]);
    let dl = lambda_nm - a[0];
    (a[1] + dl * s[0], a[2] + dl * s[1])
}

/// Linear interpolation in a user table (at least two rows, λ increasing):
/// the tables are close to uniform in λ, so guess from the proportional
/// position and walk.
#[cfg(feature = "alloc")]
fn table_at(rows: &[[f64; 3]], lambda_nm: f64) -> (f64, f64) {
    let last = rows.len() - 1;
    if lambda_nm.is_nan() || lambda_nm <= rows[0][0] {
        return (rows[0][1], rows[0][2]);
    }
    if lambda_nm >= rows[last][0] {
        return (rows[last][1], rows[last][2]);
    }
    let span = rows[last][0] - rows[0][0];
    let mut lo = (((lambda_nm - rows[0][0]) / span * last as f64) as usize).min(last - 1);
    while lo > 0 && rows[lo][0] > lambda_nm {
        lo -= 1;
    }
    while lo + 1 < last && rows[lo + 1][0] <= lambda_nm {
        lo += 1;
    }
    let (a, b) = (rows[lo], rows[lo + 1]);
    let t = (lambda_nm - a[0]) / (b[0] - a[0]);
    (a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_many_is_at_for_as_many_as_the_shortest_slice() {
        let lambdas = [350.0, 400.5, 555.0, 829.9, f64::NAN];
        let iors = [
            Ior::metal(Metal::Au),
            Ior::constant(1.5, 0.25).unwrap(),
            Ior::table(alloc::vec![[400.0, 0.3, 3.0], [700.0, 1.5, 0.0]]).unwrap(),
        ];
        for ior in iors {
            for len in 0..=lambdas.len() {
                // Longer outputs than wavelengths: the extra slots stay as they were.
                let (mut n, mut k) = ([-1.0; 6], [-1.0; 6]);
                ior.at_many(&lambdas[..len], &mut n, &mut k);
                for j in 0..len {
                    let (a, b) = ior.at(lambdas[j]);
                    assert_eq!((n[j].to_bits(), k[j].to_bits()), (a.to_bits(), b.to_bits()));
                }
                assert!(
                    n[len..].iter().chain(&k[len..]).all(|&v| v == -1.0),
                    "{ior:?} {len}"
                );
            }
        }
    }

    #[test]
    fn tables_cover_visible_range_and_increase() {
        for m in Metal::ALL {
            let ior = Ior::metal(m);
            ior.check_covers(300.0, 900.0).unwrap();
            for w in m.table().windows(2) {
                assert!(w[1][0] > w[0][0], "{m:?} not increasing");
            }
            assert_eq!(Metal::from_name(m.name()), Some(m));
        }
    }

    #[test]
    fn interpolation_hits_rows_and_midpoints() {
        let t = Metal::Cu.table();
        let ior = Ior::metal(Metal::Cu);
        for i in 0..t.len() - 1 {
            let (n, k) = ior.at(t[i][0]);
            assert!((n - t[i][1]).abs() < 1e-12 && (k - t[i][2]).abs() < 1e-12);
            let mid = 0.5 * (t[i][0] + t[i + 1][0]);
            let (n, k) = ior.at(mid);
            assert!((n - 0.5 * (t[i][1] + t[i + 1][1])).abs() < 1e-12);
            assert!((k - 0.5 * (t[i][2] + t[i + 1][2])).abs() < 1e-12);
        }
        assert_eq!(ior.at(1.0), (t[0][1], t[0][2]));
        assert_eq!(ior.at(1e9), (t[t.len() - 1][1], t[t.len() - 1][2]));
        assert_eq!(ior.at(f64::NAN), (t[0][1], t[0][2]));
    }

    #[test]
    fn guided_lookup_equals_binary_search() {
        for m in Metal::ALL {
            let rows = m.table();
            let ior = Ior::metal(m);
            for i in 0..60_000 {
                let l = rows[0][0] + (rows[rows.len() - 1][0] - rows[0][0]) * i as f64 / 60_000.0;
                let hi = rows.partition_point(|r| r[0] <= l).clamp(1, rows.len() - 1);
                let (a, b) = (rows[hi - 1], rows[hi]);
                // The same operations as the precomputed slopes: bit-equal
                // exactly when the guide picked the right interval.
                let dl = b[0] - a[0];
                let s = ((b[1] - a[1]) / dl, (b[2] - a[2]) / dl);
                let want = (a[1] + (l - a[0]) * s.0, a[2] + (l - a[0]) * s.1);
                assert_eq!(ior.at(l), want, "{m:?} at {l} nm");
            }
        }
    }

    #[test]
    fn bad_tables_are_rejected_with_row() {
        use alloc::vec;
        assert!(Ior::table(vec![[400.0, 1.0, 1.0]]).is_err());
        let e = Ior::table(vec![[400.0, 1.0, 1.0], [390.0, 1.0, 1.0]]).unwrap_err();
        assert_eq!(
            e,
            BrdfError::InvalidTable {
                reason: "wavelengths must be strictly increasing",
                row: Some(1)
            }
        );
        assert!(Ior::table(vec![[400.0, 1.0, 1.0], [500.0, f64::NAN, 1.0]]).is_err());
        // The bounds of a constant index, row by row (n = κ = 1e77 rendered black).
        for bad in [[500.0, 1e77, 1e77], [500.0, 1.0, 2e6], [500.0, 1e-7, 1.0]] {
            let e = Ior::table(vec![[400.0, 1.0, 1.0], bad]).unwrap_err();
            assert!(
                matches!(e, BrdfError::InvalidTable { row: Some(1), .. }),
                "{bad:?}"
            );
        }
        Ior::table(vec![[400.0, 1e6, 1e6], [500.0, 1e-6, 0.0]]).unwrap();
        assert!(Ior::constant(0.0, 1.0).is_err());
        assert!(Ior::metal(Metal::Al).check_covers(200.0, 830.0).is_err());
    }
}
