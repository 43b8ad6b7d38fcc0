//! Spectra: the CIE 1931 observer, emission spectra of lights, and CSV tables.
//!
//! Every emission spectrum is normalised to unit luminance,
//! ∫S ȳ dλ / ∫ȳ dλ = 1 over 360–830 nm, so a light's scalar strength is
//! directly its luminance-weighted value whatever its spectral shape.

use std::path::Path;
use std::sync::OnceLock;

/// Shortest wavelength rendered, nm (the CIE table's first row; the range
/// every `brdf` model is defined on).
pub const LAMBDA_MIN: f64 = brdf::WAVELENGTH_MIN_NM;
/// Longest wavelength rendered, nm (the CIE table's last row).
pub const LAMBDA_MAX: f64 = brdf::WAVELENGTH_MAX_NM;

const CIE_1931_CSV: &str = include_str!("../../../data/spectra/cie1931_2deg_xyz.csv");
const D65_CSV: &str = include_str!("../../../data/spectra/illuminant_D65.csv");
const A_CSV: &str = include_str!("../../../data/spectra/illuminant_A.csv");

/// The CIE 1931 2° colour-matching functions at 1 nm, 360–830 nm.
pub struct Cie {
    /// Fixed length, so a clamped index needs no bounds check.
    xyz: Box<[[f64; 3]; 471]>,
    y_integral: f64,
}

impl Cie {
    /// The table, parsed once from the repository's `data/spectra` CSV.
    pub fn get() -> &'static Cie {
        static CIE: OnceLock<Cie> = OnceLock::new();
        CIE.get_or_init(|| {
            let rows = parse_csv_rows(CIE_1931_CSV, 4).expect("bundled CIE table is valid");
            let xyz: Vec<[f64; 3]> = rows.iter().map(|r| [r[1], r[2], r[3]]).collect();
            let xyz: Box<[[f64; 3]; 471]> = xyz
                .into_boxed_slice()
                .try_into()
                .expect("bundled CIE table has 471 rows, 360–830 nm");
            // Trapezoid rule on the 1 nm grid.
            let y_integral = xyz.windows(2).map(|w| 0.5 * (w[0][1] + w[1][1])).sum();
            Cie { xyz, y_integral }
        })
    }

    /// x̄, ȳ, z̄ at `lambda` nm, interpolated linearly; zero outside 360–830 nm.
    #[inline]
    pub fn xyz(&self, lambda: f64) -> [f64; 3] {
        if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
            return [0.0; 3];
        }
        let x = lambda - LAMBDA_MIN;
        // Through u32: x ∈ [0, 470] here, and f64 → u32 is a shorter
        // instruction sequence than the saturating f64 → usize.
        let i = (x as u32 as usize).min(self.xyz.len() - 2);
        let t = x - i as f64;
        let (a, b) = (self.xyz[i], self.xyz[i + 1]);
        [
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            a[2] + t * (b[2] - a[2]),
        ]
    }

    /// ∫ȳ dλ over 360–830 nm (≈ 106.86 nm).
    pub fn y_integral(&self) -> f64 {
        self.y_integral
    }
}

/// A spectral power distribution as a function of wavelength.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Constant(f64),
    /// Planck's law at `kelvin`, multiplied by `scale`.
    Blackbody {
        /// Temperature in K.
        kelvin: f64,
        /// Normalisation factor.
        scale: f64,
    },
    /// Linear interpolation of `(λ nm, value)` rows; zero outside the table.
    Table(Table),
}

impl Spectrum {
    /// A table spectrum from `(λ nm, value)` rows sorted by wavelength.
    pub fn table(rows: Vec<[f64; 2]>) -> Spectrum {
        Spectrum::Table(Table::new(rows))
    }

    /// Value at `lambda` nm.
    #[inline]
    pub fn eval(&self, lambda: f64) -> f64 {
        match self {
            Spectrum::Constant(v) => *v,
            Spectrum::Blackbody { kelvin, scale } => scale * planck(lambda, *kelvin),
            Spectrum::Table(t) => t.eval(lambda),
        }
    }

    /// [`eval`](Self::eval) at each of `lambdas` into `out` (as many as the
    /// shorter of the two), bit-identical to it, with one match for the set.
    #[inline]
    pub fn eval_many(&self, lambdas: &[f64], out: &mut [f64]) {
        let pairs = out.iter_mut().zip(lambdas);
        match self {
            Spectrum::Constant(v) => pairs.for_each(|(o, _)| *o = *v),
            Spectrum::Blackbody { kelvin, scale } => {
                pairs.for_each(|(o, &l)| *o = scale * planck(l, *kelvin))
            }
            Spectrum::Table(t) => pairs.for_each(|(o, &l)| *o = t.eval(l)),
        }
    }

    /// The wavelength interval outside which the spectrum is zero,
    /// intersected with 360–830 nm; `None` if it is zero everywhere there.
    pub fn support(&self) -> Option<(f64, f64)> {
        match self {
            Spectrum::Constant(v) => (*v != 0.0).then_some((LAMBDA_MIN, LAMBDA_MAX)),
            Spectrum::Blackbody { .. } => Some((LAMBDA_MIN, LAMBDA_MAX)),
            Spectrum::Table(t) => {
                let rows = t.rows();
                // A row with a nonzero value makes the segments on both sides nonzero.
                let first = rows.iter().position(|r| r[1] != 0.0)?;
                let last = rows.iter().rposition(|r| r[1] != 0.0)?;
                let lo = rows[first.saturating_sub(1)][0].max(LAMBDA_MIN);
                let hi = rows[(last + 1).min(rows.len() - 1)][0].min(LAMBDA_MAX);
                (lo < hi).then_some((lo, hi))
            }
        }
    }

    /// ∫S ȳ dλ / ∫ȳ dλ over 360–830 nm. ȳ is piecewise linear on the 1 nm
    /// grid (as the renderer evaluates it) and a table spectrum piecewise
    /// linear between its rows, so on the union of both sets of breakpoints
    /// the product is quadratic and Simpson's rule is exact; a narrow band
    /// between grid nodes is integrated correctly. Planck's law is smooth,
    /// for which Simpson per 1 nm is accurate to ~1e−10.
    pub fn luminance(&self) -> f64 {
        let cie = Cie::get();
        let mut nodes: Vec<f64> = (0..=470).map(|i| LAMBDA_MIN + i as f64).collect();
        if let Spectrum::Table(t) = self {
            nodes.extend(
                t.rows()
                    .iter()
                    .map(|r| r[0])
                    .filter(|l| (LAMBDA_MIN..=LAMBDA_MAX).contains(l)),
            );
            nodes.sort_by(f64::total_cmp);
            nodes.dedup();
        }
        // A table is discontinuous only at its ends (zero outside); evaluate just inside them.
        let f = |l: f64| self.eval(l) * cie.xyz(l)[1];
        let sum: f64 = nodes
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                let e = 1e-9 * (b - a);
                (b - a) / 6.0 * (f(a + e) + 4.0 * f(0.5 * (a + b)) + f(b - e))
            })
            .sum();
        sum / cie.y_integral()
    }

    /// This spectrum scaled so that its luminance is `target`.
    /// Errors when the spectrum has no luminance to scale.
    pub fn with_luminance(self, target: f64) -> Result<Spectrum, String> {
        let lum = self.luminance();
        if !(lum.is_finite() && lum > 0.0) {
            return Err("the spectrum has zero luminance over 360–830 nm".into());
        }
        let k = target / lum;
        Ok(match self {
            Spectrum::Constant(v) => Spectrum::Constant(v * k),
            Spectrum::Blackbody { kelvin, scale } => Spectrum::Blackbody {
                kelvin,
                scale: scale * k,
            },
            Spectrum::Table(t) => {
                Spectrum::table(t.rows.into_iter().map(|[l, v]| [l, v * k]).collect())
            }
        })
    }
}

/// Planck's spectral radiance at `lambda_nm`, in arbitrary units (W·sr⁻¹·m⁻³ / 1e13).
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    const C2: f64 = 1.438_776_877e7; // hc/k in nm·K
    let l = lambda_nm * 1e-3; // µm, keeps the numbers O(1)
    let x = C2 / (lambda_nm * kelvin);
    // exp_m1 keeps the Rayleigh–Jeans end accurate; huge x underflows to 0 cleanly.
    // l⁵ spelled out: `powi`'s expansion (and so its last bit) depends on
    // the context it is inlined into, and a spectrum must evaluate to the
    // same value per wavelength and in a batch.
    let l2 = l * l;
    1.0 / (l2 * l2 * l * x.exp_m1())
}

/// Most cells of a [`Table`]'s guide (cells are 1 nm wide up to this many).
/// Bundled and measured tables have rows ≥ 1 nm apart, so a cell holds at
/// most about one row boundary and a lookup walks one or two rows.
const GUIDE_CELLS_MAX: usize = 1 << 14;

/// `(λ nm, value)` rows sorted by wavelength, interpolated linearly, zero
/// outside. A guide table (per cell of ≈ 1 nm, the index of the first row
/// beyond the cell's start) replaces the binary search: evaluation walks at
/// most the rows inside one cell and then interpolates with exactly the same
/// arithmetic as before, so the result is bit-identical to the binary search.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    rows: Vec<[f64; 2]>,
    guide: Vec<u32>,
    cells_per_nm: f64,
}

impl Table {
    /// Builds the guide for `rows` (sorted by wavelength).
    pub fn new(rows: Vec<[f64; 2]>) -> Table {
        let (lo, span) = match (rows.first(), rows.last()) {
            (Some(a), Some(b)) if b[0] > a[0] => (a[0], b[0] - a[0]),
            _ => (0.0, 0.0),
        };
        let cells = if span > 0.0 {
            (span.ceil() as usize + 1).clamp(1, GUIDE_CELLS_MAX)
        } else {
            1
        };
        let cells_per_nm = if span > 0.0 { cells as f64 / span } else { 0.0 };
        let guide = (0..cells)
            .map(|c| {
                let start = lo + c as f64 / cells_per_nm.max(f64::MIN_POSITIVE);
                rows.partition_point(|r| r[0] <= start) as u32
            })
            .collect();
        Table {
            rows,
            guide,
            cells_per_nm,
        }
    }

    /// The rows.
    pub fn rows(&self) -> &[[f64; 2]] {
        &self.rows
    }

    /// Linear interpolation at `lambda` nm; zero outside the rows.
    #[inline]
    pub fn eval(&self, lambda: f64) -> f64 {
        let rows = &self.rows[..];
        let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
            return 0.0;
        };
        if lambda < first[0] || lambda > last[0] {
            return 0.0;
        }
        // `p` = number of rows with λᵢ ≤ lambda (what `partition_point` returns),
        // found from the guide's estimate; the walks make it exact whatever
        // the rounding of the cell index.
        let cell = (((lambda - first[0]) * self.cells_per_nm) as usize).min(self.guide.len() - 1);
        let mut p = self.guide[cell] as usize;
        while p < rows.len() && rows[p][0] <= lambda {
            p += 1;
        }
        while p > 0 && rows[p - 1][0] > lambda {
            p -= 1;
        }
        let i = p.clamp(1, rows.len() - 1);
        lerp_rows(rows[i - 1], rows[i], lambda)
    }
}

/// Linear interpolation at `lambda` between rows `a` and `b` (λ, value);
/// `a`'s value where the two share a wavelength.
#[inline]
fn lerp_rows(a: [f64; 2], b: [f64; 2], lambda: f64) -> f64 {
    let t = if b[0] > a[0] {
        (lambda - a[0]) / (b[0] - a[0])
    } else {
        0.0
    };
    a[1] + t * (b[1] - a[1])
}

/// Linear interpolation in rows sorted by wavelength by binary search; the
/// reference the guided [`Table::eval`] must reproduce bit for bit.
#[cfg(test)]
fn interpolate(rows: &[[f64; 2]], lambda: f64) -> f64 {
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        return 0.0;
    };
    if lambda < first[0] || lambda > last[0] {
        return 0.0;
    }
    let i = rows
        .partition_point(|r| r[0] <= lambda)
        .clamp(1, rows.len() - 1);
    lerp_rows(rows[i - 1], rows[i], lambda)
}

/// Parses numeric CSV rows with exactly `columns` fields, skipping one
/// header line (the first line that is not blank or a `#` comment, when it
/// does not parse as numbers) and blank / `#` lines. Errors name the 1-based
/// line; a second non-numeric line before the data is an error, not a
/// header (a garbled file must not lose its first rows silently).
pub fn parse_csv_rows(text: &str, columns: usize) -> Result<Vec<Vec<f64>>, String> {
    Ok(parse_csv_lines(text, columns)?
        .into_iter()
        .map(|(_, row)| row)
        .collect())
}

/// [`parse_csv_rows`] with each row's 1-based line number, for messages
/// about the values themselves.
pub fn parse_csv_lines(text: &str, columns: usize) -> Result<Vec<(usize, Vec<f64>)>, String> {
    // Editors on Windows prefix a UTF-8 BOM; left in, it made a headerless
    // file's first data row unparsable, and so taken for the header.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut rows = Vec::new();
    let mut header_allowed = true;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
        let first = std::mem::replace(&mut header_allowed, false);
        match parsed {
            Ok(v) if v.len() == columns && v.iter().all(|x| x.is_finite()) => rows.push((i + 1, v)),
            Ok(v) => {
                return Err(format!(
                    "line {}: expected {columns} finite numbers, found {} field(s)",
                    i + 1,
                    v.len()
                ));
            }
            Err(_) if first => continue, // header
            Err(_) => return Err(format!("line {}: `{line}` is not {columns} numbers", i + 1)),
        }
    }
    if rows.len() < 2 {
        return Err(format!("needs at least two data rows of {columns} numbers"));
    }
    if rows.windows(2).any(|w| w[1].1[0] <= w[0].1[0]) {
        return Err("the wavelength column (first) must be strictly increasing".into());
    }
    Ok(rows)
}

/// A spectrum from the text of a `wavelength_nm,value` CSV (`path` for messages).
pub fn spectrum_from_csv(path: &Path, text: &str) -> Result<Spectrum, String> {
    let rows = parse_csv_rows(text, 2).map_err(|e| format!("{}: {e}", path.display()))?;
    if rows.iter().any(|r| r[1] < 0.0) {
        return Err(format!("{}: spectral values must be ≥ 0", path.display()));
    }
    Ok(Spectrum::table(
        rows.into_iter().map(|r| [r[0], r[1]]).collect(),
    ))
}

/// The CIE standard illuminant D65 (relative SPD, not yet normalised).
pub fn d65() -> Spectrum {
    bundled(D65_CSV)
}

/// The CIE standard illuminant A (relative SPD, not yet normalised).
pub fn illuminant_a() -> Spectrum {
    bundled(A_CSV)
}

fn bundled(csv: &str) -> Spectrum {
    let rows = parse_csv_rows(csv, 2).expect("bundled illuminant table is valid");
    Spectrum::table(rows.into_iter().map(|r| [r[0], r[1]]).collect())
}

/// Parses a spectrum description: `d65`, `a`, `constant`, `blackbody(T)` (T in K)
/// or `csv(path)` (path relative to `base_dir`). The result is normalised to
/// unit luminance.
pub fn parse_spectrum(desc: &str, base_dir: &Path) -> Result<Spectrum, String> {
    parse_spectrum_with(desc, base_dir, &mut |p: &Path| {
        let bytes = safe_io::read_input(p, "spectrum CSV", crate::inputs::MAX_CSV_BYTES)
            .map_err(|e| e.to_string())?;
        String::from_utf8(bytes).map_err(|_| format!("{} is not UTF-8 text", p.display()))
    })
}

/// [`parse_spectrum`] reading a `csv(…)` file through `read` (the scene
/// build passes its [`crate::inputs::Inputs`], which hashes what it reads).
pub fn parse_spectrum_with(
    desc: &str,
    base_dir: &Path,
    read: &mut dyn FnMut(&Path) -> Result<String, String>,
) -> Result<Spectrum, String> {
    const CHOICES: &str =
        "valid: \"d65\", \"a\", \"constant\", \"blackbody(T)\" with T in kelvin, \"csv(path.csv)\"";
    let d = desc.trim();
    let lower = d.to_ascii_lowercase();
    let raw = if lower == "d65" {
        d65()
    } else if lower == "a" {
        illuminant_a()
    } else if lower == "constant" {
        Spectrum::Constant(1.0)
    } else if let Some(arg) = lower
        .strip_prefix("blackbody(")
        .and_then(|s| s.strip_suffix(')'))
    {
        let t: f64 = arg
            .trim()
            .trim_end_matches('k')
            .trim()
            .parse()
            .map_err(|_| {
                format!("spectrum `{d}`: temperature `{arg}` is not a number; {CHOICES}")
            })?;
        if !(t.is_finite() && (100.0..=1e6).contains(&t)) {
            return Err(format!(
                "spectrum `{d}`: temperature must be within 100–1e6 K"
            ));
        }
        Spectrum::Blackbody {
            kelvin: t,
            scale: 1.0,
        }
    } else if lower.starts_with("csv(") && d.ends_with(')') {
        let file = d[4..d.len() - 1].trim().trim_matches('"');
        let path = base_dir.join(file);
        spectrum_from_csv(&path, &read(&path)?)?
    } else {
        return Err(format!("unknown spectrum `{d}`; {CHOICES}"));
    };
    raw.with_luminance(1.0)
        .map_err(|e| format!("spectrum `{d}`: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cie_y_integral_matches_published_value() {
        // CIE 1931 ∫ȳ over 360–830 nm at 1 nm is 106.857 (sum of the table).
        let y = Cie::get().y_integral();
        assert!((y - 106.857).abs() < 0.01, "{y}");
        assert_eq!(Cie::get().xyz(555.0)[1], 1.0);
    }

    #[test]
    fn normalised_spectra_have_unit_luminance() {
        for s in [
            "d65",
            "a",
            "constant",
            "blackbody(3000)",
            "BlackBody(6500 K)",
        ] {
            let sp = parse_spectrum(s, Path::new(".")).unwrap();
            assert!((sp.luminance() - 1.0).abs() < 1e-12, "{s}");
        }
        assert!(
            parse_spectrum("blackbody(x)", Path::new("."))
                .unwrap_err()
                .contains("not a number")
        );
        assert!(
            parse_spectrum("sun", Path::new("."))
                .unwrap_err()
                .contains("valid:")
        );
    }

    #[test]
    fn planck_peak_follows_wien() {
        // Wien: λ_max = 2.897771955e6 nm·K / T. At 5000 K → 579.6 nm.
        let s = Spectrum::Blackbody {
            kelvin: 5000.0,
            scale: 1.0,
        };
        let peak = (4000..7000)
            .map(|i| i as f64 / 10.0)
            .max_by(|a, b| s.eval(*a).total_cmp(&s.eval(*b)));
        assert!((peak.unwrap() - 579.6).abs() < 0.15);
    }

    #[test]
    fn narrow_band_luminance_is_exact() {
        // A 1.25 nm-wide trapezoid around 700 nm, between grid nodes: its
        // luminance is ȳ(700)·1.25/∫ȳ up to ȳ's curvature across the band.
        let s = Spectrum::table(vec![
            [699.25, 0.0],
            [699.5, 1.0],
            [700.5, 1.0],
            [700.75, 0.0],
        ]);
        let cie = Cie::get();
        let want = cie.xyz(700.0)[1] * 1.25 / cie.y_integral();
        assert!(
            (s.luminance() / want - 1.0).abs() < 1e-3,
            "{} vs {want}",
            s.luminance()
        );
    }

    #[test]
    fn a_byte_order_mark_does_not_cost_the_first_row() {
        let rows = parse_csv_lines("\u{feff}300,0.2,3\n900,0.2,3\n", 3).unwrap();
        assert_eq!(
            rows,
            vec![(1, vec![300.0, 0.2, 3.0]), (2, vec![900.0, 0.2, 3.0])]
        );
        // A header after the mark is still a header.
        let rows = parse_csv_rows("\u{feff}wavelength_nm,n,k\n300,0.2,3\n900,0.2,3\n", 3).unwrap();
        assert_eq!(rows.len(), 2);
    }

    #[test]
    fn table_support_and_interpolation() {
        let s = Spectrum::table(vec![
            [500.0, 0.0],
            [520.0, 0.0],
            [530.0, 2.0],
            [540.0, 0.0],
            [600.0, 0.0],
        ]);
        assert_eq!(s.support(), Some((520.0, 540.0)));
        assert_eq!(s.eval(525.0), 1.0);
        assert_eq!(s.eval(700.0), 0.0);
    }

    #[test]
    fn guided_table_matches_binary_search_bit_for_bit() {
        use crate::rng::Rng;
        let mut tables: Vec<Vec<[f64; 2]>> = Vec::new();
        for sp in [d65(), illuminant_a()] {
            let Spectrum::Table(t) = sp else { panic!() };
            tables.push(t.rows().to_vec());
        }
        // Irregular spacing, sub-nm rows, a single segment, a wide sparse table.
        tables.push(vec![
            [400.0, 1.0],
            [400.3, 2.0],
            [400.31, 0.5],
            [401.9, 3.0],
            [650.0, 0.0],
        ]);
        tables.push(vec![[500.0, 1.0], [501.0, 2.0]]);
        tables.push(vec![[1.0, 1.0], [377.7, 2.5], [1e6, 3.0]]);
        tables.push(
            (0..50)
                .map(|i| [360.0 + 9.4 * i as f64, (i % 7) as f64])
                .collect(),
        );
        let mut rng = Rng::for_sample(7, 0, 0);
        for rows in tables {
            let t = Table::new(rows.clone());
            let (lo, hi) = (rows[0][0], rows[rows.len() - 1][0]);
            let mut probes: Vec<f64> = rows
                .iter()
                .flat_map(|r| {
                    let l = r[0];
                    [l, l.next_up(), l.next_down(), l + 0.5]
                })
                .collect();
            probes.extend((0..20_000).map(|_| lo - 1.0 + (hi - lo + 2.0) * rng.uniform()));
            probes.extend([f64::NAN, -1.0, 1e9, LAMBDA_MIN, LAMBDA_MAX]);
            for l in probes {
                let (got, want) = (t.eval(l), interpolate(&rows, l));
                assert!(got.to_bits() == want.to_bits(), "λ = {l}: {got} vs {want}");
            }
        }
    }
}
