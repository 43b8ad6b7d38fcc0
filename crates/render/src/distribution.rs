//! Piecewise-constant 1-D and 2-D distributions for importance sampling.

/// A piecewise-constant density on [0, 1) with `n` equal bins.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    func: Vec<f64>,
    integral: f64,
}

impl Distribution1D {
    /// From non-negative bin weights. All-zero weights give a uniform density.
    pub fn new(weights: &[f64]) -> Distribution1D {
        let n = weights.len().max(1);
        let mut func: Vec<f64> = weights
            .iter()
            .map(|w| if w.is_finite() { w.max(0.0) } else { 0.0 })
            .collect();
        func.resize(n, 0.0);
        let mut cdf = vec![0.0; n + 1];
        for i in 0..n {
            cdf[i + 1] = cdf[i] + func[i] / n as f64;
        }
        let integral = cdf[n];
        if integral > 0.0 {
            cdf.iter_mut().for_each(|c| *c /= integral);
        } else {
            func.iter_mut().for_each(|f| *f = 1.0);
            cdf.iter_mut()
                .enumerate()
                .for_each(|(i, c)| *c = i as f64 / n as f64);
        }
        cdf[n] = 1.0;
        let integral = if integral > 0.0 { integral } else { 1.0 };
        Distribution1D {
            cdf,
            func,
            integral,
        }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no bins (never: at least one exists).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Sum of weights / n: the integral of the unnormalised density.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// Draws x ∈ [0, 1); returns (x, density at x, bin).
    pub fn sample(&self, u: f64) -> (f64, f64, usize) {
        let n = self.func.len();
        let i = (self.cdf.partition_point(|&c| c <= u).saturating_sub(1)).min(n - 1);
        let span = self.cdf[i + 1] - self.cdf[i];
        let t = if span > 0.0 {
            ((u - self.cdf[i]) / span).clamp(0.0, 1.0 - f64::EPSILON)
        } else {
            0.5
        };
        ((i as f64 + t) / n as f64, self.func[i] / self.integral, i)
    }

    /// Density at bin `i`.
    pub fn pdf_bin(&self, i: usize) -> f64 {
        self.func.get(i).map_or(0.0, |f| f / self.integral)
    }
}

/// A piecewise-constant density on [0, 1)² (rows = v, columns = u).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// From row-major weights of `width × height` bins.
    pub fn new(weights: &[f64], width: usize, height: usize) -> Distribution2D {
        let rows: Vec<Distribution1D> = (0..height)
            .map(|y| Distribution1D::new(&weights[y * width..(y + 1) * width]))
            .collect();
        let marginal = Distribution1D::new(&rows.iter().map(|r| r.integral()).collect::<Vec<_>>());
        Distribution2D { rows, marginal }
    }

    /// Draws (u, v) ∈ [0, 1)² with its density.
    pub fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        let (v, pv, row) = self.marginal.sample(u[1]);
        let (x, pu, _) = self.rows[row].sample(u[0]);
        ([x, v], pv * pu)
    }

    /// Density at (u, v).
    pub fn pdf(&self, uv: [f64; 2]) -> f64 {
        let h = self.rows.len();
        let row = ((uv[1] * h as f64) as usize).min(h - 1);
        let w = self.rows[row].len();
        let col = ((uv[0] * w as f64) as usize).min(w - 1);
        self.marginal.pdf_bin(row) * self.rows[row].pdf_bin(col)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_match_pdf() {
        let w = [0.0, 1.0, 3.0, 0.0, 4.0, 2.0];
        let d = Distribution2D::new(&w, 3, 2);
        let mut hist = [0usize; 6];
        let n = 60_000;
        for i in 0..n {
            let u = [
                ((i * 7919) % n) as f64 / n as f64,
                (i as f64 + 0.5) / n as f64,
            ];
            let (uv, p) = d.sample(u);
            assert!((p - d.pdf(uv)).abs() < 1e-12);
            let bin = (uv[1] * 2.0) as usize * 3 + (uv[0] * 3.0) as usize;
            hist[bin] += 1;
        }
        for (b, &c) in hist.iter().enumerate() {
            let want = w[b] / 10.0;
            assert!((c as f64 / n as f64 - want).abs() < 0.01, "bin {b}: {c}");
        }
    }
}
