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
