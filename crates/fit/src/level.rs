//! Levelling: subtract a least-squares plane, a 2D polynomial, or a per-line polynomial.
//! NaN points are ignored by the fits and stay NaN.

use crate::ordered_sum::{map_blocks, sum_in_order};
use crate::{FitError, Topography};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Subtract the least-squares plane `a + b·x + c·y` (a line for profiles).
pub fn plane(topo: &mut Topography) -> Result<(), FitError> {
    polynomial(topo, 1)
}

/// Subtract the least-squares 2D polynomial with all terms `xⁱ yʲ`, `i + j ≤ degree`
/// (only `xⁱ` for profiles). Coordinates are scaled to [−1, 1] for conditioning.
pub fn polynomial(topo: &mut Topography, degree: usize) -> Result<(), FitError> {
    let f = fit_poly(topo, degree)?;
    subtract(topo, &f.terms, &f.coef);
    Ok(())
}

/// Scaled coordinates of `n` samples: −1 … 1 (0 for a single sample).
fn scaled(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| {
            if n > 1 {
                2.0 * k as f64 / (n - 1) as f64 - 1.0
            } else {
                0.0
            }
        })
        .collect()
}

/// Subtract `Σ c·uⁱvʲ`, one row at a time (rows in parallel): the row's polynomial in u
/// by Horner.
fn subtract(topo: &mut Topography, terms: &[(i32, i32)], coef: &[f64]) {
    let (nx, ny) = (topo.nx, topo.ny);
    let (ux, vy) = (scaled(nx), scaled(ny));
    let deg = terms.iter().map(|t| t.0).max().unwrap_or(0) as usize;
    topo.heights
        .par_chunks_mut(nx.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            let mut a = vec![0.0; deg + 1];
            for (&(i, j), c) in terms.iter().zip(coef) {
                a[i as usize] += c * vy[y.min(ny - 1)].powi(j);
            }
            for (h, &u) in row.iter_mut().zip(&ux) {
                *h -= a.iter().rev().fold(0.0, |acc, c| acc * u + c);
            }
        });
}

/// Subtract from every x-line its own least-squares polynomial of `degree` (0 = mean).
pub fn per_line(topo: &mut Topography, degree: usize) -> Result<(), FitError> {
    let nx = topo.nx;
    for y in 0..topo.ny {
        let mut line = Topography {
            nx,
            ny: 1,
            dx: topo.dx,
            dy: topo.dx,
            heights: topo.heights[y * nx..(y + 1) * nx].to_vec(),
            channel: String::new(),
            format: "",
        };
        polynomial(&mut line, degree)?;
        topo.heights[y * nx..(y + 1) * nx].copy_from_slice(&line.heights);
    }
    Ok(())
}

/// A levelling choice (`--level`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Nothing removed.
    None,
    /// Each x-line's own least-squares line (the usual AFM line levelling); the line of a
    /// profile.
    Line,
    /// The least-squares plane.
    Plane,
    /// The least-squares quadratic surface (curved parts: a bullet land, a bowed sheet).
    Poly2,
    /// The least-squares cubic surface.
    Poly3,
}

impl Level {
    /// Parse a `--level` value.
    pub fn from_name(s: &str) -> Option<Level> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "none" => Level::None,
            "line" => Level::Line,
            "plane" => Level::Plane,
            "poly2" | "quadratic" => Level::Poly2,
            "poly3" | "cubic" => Level::Poly3,
            _ => return None,
        })
    }

    /// The `--level` name.
    pub fn name(self) -> &'static str {
        match self {
            Level::None => "none",
            Level::Line => "line",
            Level::Plane => "plane",
            Level::Poly2 => "poly2",
            Level::Poly3 => "poly3",
        }
    }

    /// The default: a plane for maps, a line for profiles.
    pub fn default_for(t: &Topography) -> Level {
        if t.is_profile() {
            Level::Line
        } else {
            Level::Plane
        }
    }

    fn degree(self) -> usize {
        match self {
            Level::None => 0,
            Level::Line | Level::Plane => 1,
            Level::Poly2 => 2,
            Level::Poly3 => 3,
        }
    }
}

/// One term `c · Xⁱ Yʲ` of a fitted form, with X, Y [m] measured from the map centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Term {
    /// Power of X.
    pub i: u32,
    /// Power of Y.
    pub j: u32,
    /// Coefficient [m^(1−i−j)].
    pub c: f64,
}

/// What levelling removed, and whether the residual still shows form.
#[derive(Debug, Clone, PartialEq)]
pub struct Form {
    /// Levelling applied.
    pub level: Level,
    /// Fitted polynomial (empty for `none` and per-line levelling).
    pub terms: Vec<Term>,
    /// Rms of what was removed (about its mean) [m].
    pub removed_rms: f64,
    /// Fraction of the residual's height variance that the next polynomial degree would
    /// still remove (after a plane: a quadratic; after poly2: a cubic; after poly3: a
    /// quartic); `None` where not checked (`none`, tiny maps).
    pub residual_form: Option<(Level, f64)>,
}

/// A residual is said to still show form when the next polynomial degree would remove
/// more than this fraction of its variance. Random roughness whose correlation length is
/// small against the scan puts well under a few per cent of its variance in the lowest
/// polynomial modes; a curved part left after a plane puts most of it there.
pub const FORM_THRESHOLD: f64 = 0.2;

impl Form {
    /// The warning to print when the residual still shows form.
    pub fn warning(&self) -> Option<String> {
        let (next, frac) = self.residual_form?;
        (frac > FORM_THRESHOLD).then(|| {
            let fix = match self.level {
                Level::Poly3 => "the part's form is more complex than a cubic; remove it before \
                                 fitting (or analyse a smaller area)"
                    .to_string(),
                _ => format!("try --level {}", next.name()),
            };
            format!(
                "the residual still shows form: a {} fit would remove {:.0} % of its height \
                 variance; {fix}",
                if next == Level::Poly3 && self.level == Level::Poly3 {
                    "quartic".to_string()
                } else {
                    next.name().to_string()
                },
                100.0 * frac
            )
        })
    }
}

/// A least-squares polynomial fit and what it explains.
struct PolyFit {
    terms: Vec<(i32, i32)>,
    coef: Vec<f64>,
    /// Valid points.
    count: usize,
    /// Σ z and Σ z² over them.
    sum: f64,
    sum2: f64,
    /// `coefᵀ·Aᵀz`: with an intercept term, the residual sum of squares is
    /// `Σ z² − coefᵀ·Aᵀz`.
    explained: f64,
}

impl PolyFit {
    /// Variance of the data before, and of the residual after, subtracting the fit.
    fn variances(&self) -> (f64, f64) {
        let n = self.count as f64;
        let before = (self.sum2 / n - (self.sum / n).powi(2)).max(0.0);
        let after = ((self.sum2 - self.explained) / n).max(0.0);
        (before, after.min(before))
    }
}

/// Least-squares coefficients of all terms `uⁱvʲ`, `i + j ≤ degree` (u, v scaled to
/// [−1, 1]); NaN points are ignored. The normal equations are accumulated row by row
/// (rows in parallel) from the moments `Σₓ uᵏ` and `Σₓ uⁱ z` of the valid points, so the
/// cost is O(points · degree) rather than O(points · terms²).
fn fit_poly(topo: &Topography, degree: usize) -> Result<PolyFit, FitError> {
    let terms: Vec<(i32, i32)> = (0..=degree as i32)
        .flat_map(|i| (0..=degree as i32 - i).map(move |j| (i, j)))
        .filter(|&(_, j)| topo.ny > 1 || j == 0)
        .collect();
    let (nx, ny) = (topo.nx, topo.ny);
    let m = terms.len();
    let (ux, vy) = (scaled(nx), scaled(ny));
    // Accumulator: ata (m·m, upper triangle), atb (m), count, Σz, Σz².
    let size = m * m + m + 3;
    // Fixed blocks summed in order: the fit is the same on any thread count.
    let row_len = nx.max(1);
    let parts = map_blocks(topo.heights.len() / row_len, |rows| {
        let mut acc = vec![0.0; size];
        let mut mom = vec![0.0; 2 * degree + 1];
        let mut rz = vec![0.0; degree + 1];
        for y in rows {
            let row = &topo.heights[y * row_len..(y + 1) * row_len];
            mom.iter_mut().for_each(|v| *v = 0.0);
            rz.iter_mut().for_each(|v| *v = 0.0);
            let (mut n_row, mut s1, mut s2) = (0usize, 0.0, 0.0);
            for (&z, &u) in row.iter().zip(&ux) {
                if !z.is_finite() {
                    continue;
                }
                n_row += 1;
                s1 += z;
                s2 += z * z;
                let mut p = 1.0;
                for k in 0..=2 * degree {
                    mom[k] += p;
                    if k <= degree {
                        rz[k] += p * z;
                    }
                    p *= u;
                }
            }
            if n_row == 0 {
                continue;
            }
            let v = vy[y.min(ny - 1)];
            for (a, &(ia, ja)) in terms.iter().enumerate() {
                acc[m * m + a] += v.powi(ja) * rz[ia as usize];
                for (b, &(ib, jb)) in terms.iter().enumerate().skip(a) {
                    acc[a * m + b] += v.powi(ja + jb) * mom[(ia + ib) as usize];
                }
            }
            acc[m * m + m] += n_row as f64;
            acc[m * m + m + 1] += s1;
            acc[m * m + m + 2] += s2;
        }
        acc
    });
    let acc = sum_in_order(parts, size);
    let mut ata = DMatrix::<f64>::zeros(m, m);
    for a in 0..m {
        for b in a..m {
            ata[(a, b)] = acc[a * m + b];
            ata[(b, a)] = acc[a * m + b];
        }
    }
    let atb = DVector::<f64>::from_iterator(m, acc[m * m..m * m + m].iter().copied());
    let count = acc[m * m + m] as usize;
    if count < m {
        return Err(FitError::data(
            "levelling",
            format!("{count} valid points cannot fix {m} polynomial terms; use a lower --level"),
        ));
    }
    let coef = ata.lu().solve(&atb).ok_or_else(|| {
        FitError::data(
            "levelling",
            "singular least-squares system (degree too high for the grid); use a lower --level",
        )
    })?;
    Ok(PolyFit {
        explained: coef.dot(&atb),
        terms,
        coef: coef.iter().copied().collect(),
        count,
        sum: acc[m * m + m + 1],
        sum2: acc[m * m + m + 2],
    })
}

fn variance(h: &[f64]) -> f64 {
    let (s, n) = h
        .iter()
        .filter(|v| v.is_finite())
        .fold((0.0, 0.0), |(s, n), v| (s + v, n + 1.0));
    if n == 0.0 {
        return 0.0;
    }
    let m = s / n;
    h.iter()
        .filter(|v| v.is_finite())
        .map(|v| (v - m).powi(2))
        .sum::<f64>()
        / n
}

/// Fraction of the variance of `t` a polynomial of `degree` removes (from the normal
/// equations; `t` is not changed).
fn explained(t: &Topography, degree: usize) -> Option<f64> {
    let f = fit_poly(t, degree).ok()?;
    let (before, after) = f.variances();
    (before > 0.0).then(|| (1.0 - after / before).clamp(0.0, 1.0))
}

/// Level `topo` in place and describe what was removed.
pub fn apply(topo: &mut Topography, level: Level) -> Result<Form, FitError> {
    let mut terms = Vec::new();
    let removed_rms = match level {
        Level::None => 0.0,
        Level::Line if !topo.is_profile() => {
            let before = topo.heights.clone();
            per_line(topo, 1)?;
            let removed: Vec<f64> = before
                .iter()
                .zip(&topo.heights)
                .map(|(a, b)| a - b)
                .collect();
            variance(&removed).sqrt()
        }
        _ => {
            let f = fit_poly(topo, level.degree())?;
            let hx = 0.5 * (topo.nx.saturating_sub(1)) as f64 * topo.dx;
            let hy = 0.5 * (topo.ny.saturating_sub(1)) as f64 * topo.dy;
            subtract(topo, &f.terms, &f.coef);
            for (&(i, j), &c) in f.terms.iter().zip(&f.coef) {
                let scale =
                    if i > 0 { hx.powi(i) } else { 1.0 } * if j > 0 { hy.powi(j) } else { 1.0 };
                terms.push(Term {
                    i: i as u32,
                    j: j as u32,
                    c: if scale > 0.0 { c / scale } else { c },
                });
            }
            // The fit and the residual are orthogonal: var(removed) = var(before) − var(after).
            let (before, after) = f.variances();
            (before - after).max(0.0).sqrt()
        }
    };
    // Check the residual with the next degree (a quartic after poly3), when the grid has
    // enough points for it.
    let next = match level {
        Level::None => None,
        Level::Line | Level::Plane => Some((Level::Poly2, 2)),
        Level::Poly2 => Some((Level::Poly3, 3)),
        Level::Poly3 => Some((Level::Poly3, 4)),
    };
    let residual_form = next.and_then(|(l, d)| {
        let terms = if topo.is_profile() {
            d + 1
        } else {
            (d + 1) * (d + 2) / 2
        };
        (topo.nx * topo.ny >= 4 * terms)
            .then(|| explained(topo, d).map(|f| (l, f)))
            .flatten()
    });
    Ok(Form {
        level,
        terms,
        removed_rms,
        residual_form,
    })
}
