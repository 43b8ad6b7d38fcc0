//! Levelling: subtract a least-squares plane, a 2D polynomial, or a per-line polynomial.
//! NaN points are ignored by the fits and stay NaN.

use crate::{FitError, Topography};
use nalgebra::{DMatrix, DVector};

/// Subtract the least-squares plane `a + b·x + c·y` (a line for profiles).
pub fn plane(topo: &mut Topography) -> Result<(), FitError> {
    polynomial(topo, 1)
}

/// Subtract the least-squares 2D polynomial with all terms `xⁱ yʲ`, `i + j ≤ degree`
/// (only `xⁱ` for profiles). Coordinates are scaled to [−1, 1] for conditioning.
pub fn polynomial(topo: &mut Topography, degree: usize) -> Result<(), FitError> {
    let terms: Vec<(i32, i32)> = (0..=degree as i32)
        .flat_map(|i| (0..=degree as i32 - i).map(move |j| (i, j)))
        .filter(|&(_, j)| topo.ny > 1 || j == 0)
        .collect();
    let (nx, ny) = (topo.nx, topo.ny);
    let sx = |x: usize| {
        if nx > 1 {
            2.0 * x as f64 / (nx - 1) as f64 - 1.0
        } else {
            0.0
        }
    };
    let sy = |y: usize| {
        if ny > 1 {
            2.0 * y as f64 / (ny - 1) as f64 - 1.0
        } else {
            0.0
        }
    };
    let basis = |x: usize, y: usize, out: &mut [f64]| {
        let (u, v) = (sx(x), sy(y));
        for (k, &(i, j)) in terms.iter().enumerate() {
            out[k] = u.powi(i) * v.powi(j);
        }
    };
    let m = terms.len();
    let mut ata = DMatrix::<f64>::zeros(m, m);
    let mut atb = DVector::<f64>::zeros(m);
    let mut row = vec![0.0; m];
    let mut count = 0usize;
    for y in 0..ny {
        for x in 0..nx {
            let z = topo.heights[y * nx + x];
            if !z.is_finite() {
                continue;
            }
            basis(x, y, &mut row);
            for a in 0..m {
                atb[a] += row[a] * z;
                for b in 0..m {
                    ata[(a, b)] += row[a] * row[b];
                }
            }
            count += 1;
        }
    }
    if count < m {
        return Err(FitError::data(
            "levelling",
            format!("{count} valid points cannot fix {m} polynomial terms"),
        ));
    }
    let coef = ata.lu().solve(&atb).ok_or_else(|| {
        FitError::data(
            "levelling",
            "singular least-squares system (degree too high for the grid)",
        )
    })?;
    for y in 0..ny {
        for x in 0..nx {
            basis(x, y, &mut row);
            let p: f64 = row.iter().zip(coef.iter()).map(|(a, b)| a * b).sum();
            topo.heights[y * nx + x] -= p;
        }
    }
    Ok(())
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

/// Least-squares coefficients of all terms `uⁱvʲ`, `i + j ≤ degree` (u, v scaled to
/// [−1, 1]); NaN points are ignored.
fn fit_poly(topo: &Topography, degree: usize) -> Result<(Vec<(i32, i32)>, Vec<f64>), FitError> {
    let terms: Vec<(i32, i32)> = (0..=degree as i32)
        .flat_map(|i| (0..=degree as i32 - i).map(move |j| (i, j)))
        .filter(|&(_, j)| topo.ny > 1 || j == 0)
        .collect();
    let (nx, ny) = (topo.nx, topo.ny);
    let m = terms.len();
    let mut ata = DMatrix::<f64>::zeros(m, m);
    let mut atb = DVector::<f64>::zeros(m);
    let mut row = vec![0.0; m];
    let mut count = 0usize;
    let ux: Vec<f64> = (0..nx)
        .map(|x| {
            if nx > 1 {
                2.0 * x as f64 / (nx - 1) as f64 - 1.0
            } else {
                0.0
            }
        })
        .collect();
    let vy: Vec<f64> = (0..ny)
        .map(|y| {
            if ny > 1 {
                2.0 * y as f64 / (ny - 1) as f64 - 1.0
            } else {
                0.0
            }
        })
        .collect();
    for y in 0..ny {
        for x in 0..nx {
            let z = topo.heights[y * nx + x];
            if !z.is_finite() {
                continue;
            }
            for (k, &(i, j)) in terms.iter().enumerate() {
                row[k] = ux[x].powi(i) * vy[y].powi(j);
            }
            for a in 0..m {
                atb[a] += row[a] * z;
                for b in a..m {
                    ata[(a, b)] += row[a] * row[b];
                }
            }
            count += 1;
        }
    }
    for a in 0..m {
        for b in 0..a {
            ata[(a, b)] = ata[(b, a)];
        }
    }
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
    Ok((terms, coef.iter().copied().collect()))
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

/// Fraction of the variance of `t` a polynomial of `degree` removes.
fn explained(t: &Topography, degree: usize) -> Option<f64> {
    let total = variance(&t.heights);
    if total <= 0.0 {
        return None;
    }
    let mut c = t.clone();
    polynomial(&mut c, degree).ok()?;
    Some((1.0 - variance(&c.heights) / total).clamp(0.0, 1.0))
}

/// Level `topo` in place and describe what was removed.
pub fn apply(topo: &mut Topography, level: Level) -> Result<Form, FitError> {
    let before = topo.heights.clone();
    let mut terms = Vec::new();
    match level {
        Level::None => {}
        Level::Line if !topo.is_profile() => per_line(topo, 1)?,
        _ => {
            let (powers, coef) = fit_poly(topo, level.degree())?;
            let hx = 0.5 * (topo.nx.saturating_sub(1)) as f64 * topo.dx;
            let hy = 0.5 * (topo.ny.saturating_sub(1)) as f64 * topo.dy;
            let (nx, ny) = (topo.nx, topo.ny);
            for y in 0..ny {
                let v = if ny > 1 {
                    2.0 * y as f64 / (ny - 1) as f64 - 1.0
                } else {
                    0.0
                };
                for x in 0..nx {
                    let u = if nx > 1 {
                        2.0 * x as f64 / (nx - 1) as f64 - 1.0
                    } else {
                        0.0
                    };
                    let p: f64 = powers
                        .iter()
                        .zip(&coef)
                        .map(|(&(i, j), c)| c * u.powi(i) * v.powi(j))
                        .sum();
                    topo.heights[y * nx + x] -= p;
                }
            }
            for (&(i, j), &c) in powers.iter().zip(&coef) {
                let scale =
                    if i > 0 { hx.powi(i) } else { 1.0 } * if j > 0 { hy.powi(j) } else { 1.0 };
                terms.push(Term {
                    i: i as u32,
                    j: j as u32,
                    c: if scale > 0.0 { c / scale } else { c },
                });
            }
        }
    }
    let removed: Vec<f64> = before
        .iter()
        .zip(&topo.heights)
        .map(|(a, b)| a - b)
        .collect();
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
        removed_rms: variance(&removed).sqrt(),
        residual_form,
    })
}
