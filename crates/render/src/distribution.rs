//! Piecewise-constant 1-D and 2-D distributions for importance sampling:
//! one 1-D type serves the wavelength pdf, environment-map rows and
//! marginals, and the sky's table.

/// A piecewise-constant density on [0, 1) with `n` equal bins.
///
/// Sampling inverts the CDF with a guide table (one cell per bin: the cell
/// of `u` gives a start index, a short walk gives the exact answer), so the
/// result is what a binary search would give, at O(1) expected cost.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// `cdf[i]` = probability of bins `< i`; `cdf[n]` = 1.
    cdf: Vec<f64>,
    /// Probability of each bin (weight / total).
    pmf: Vec<f64>,
    /// Sum of weights / n: the integral of the unnormalised density.
    integral: f64,
    /// `guide[k]` = number of CDF entries ≤ k/guide.len().
    guide: Vec<u32>,
    /// `guide.len()` as a float: the cell of `u` is ⌊u · cells⌋.
    cells: f64,
}

impl Distribution1D {
    /// From bin weights; negative and non-finite weights count as 0, and
    /// all-zero weights give a uniform density.
    pub fn new(weights: &[f64]) -> Distribution1D {
        Distribution1D::with_guide(weights, 1)
    }

    /// [`new`](Self::new) with `cells_per_bin` guide cells per bin: more
    /// cells shorten the walk where one bin holds several times the mean
    /// probability (the wavelength pdf's peak bin holds 2.7× the mean; four
    /// cells per bin keep its walk to one or two steps).
    pub fn with_guide(weights: &[f64], cells_per_bin: usize) -> Distribution1D {
        let n = weights.len().max(1);
        let mut w: Vec<f64> = weights
            .iter()
            .map(|w| if w.is_finite() { w.max(0.0) } else { 0.0 })
            .collect();
        w.resize(n, 0.0);
        let total: f64 = w.iter().sum();
        let (total, integral) = if total > 0.0 && total.is_finite() {
            (total, total / n as f64)
        } else {
            w.iter_mut().for_each(|v| *v = 1.0);
            (n as f64, 1.0)
        };
        let pmf: Vec<f64> = w.iter().map(|v| v / total).collect();
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for w in &w {
            acc += w / total;
            cdf.push(acc);
        }
        cdf[n] = 1.0;
        let cells = n * cells_per_bin.max(1);
        let guide = (0..cells)
            .map(|k| {
                let u = k as f64 / cells as f64;
                cdf.partition_point(|&c| c <= u) as u32
            })
            .collect();
        Distribution1D {
            cdf,
            pmf,
            integral,
            guide,
            cells: cells as f64,
        }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Whether there are no bins (never: at least one exists).
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Sum of weights / n: the integral of the unnormalised density.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The CDF entries (`len() + 1` of them, from 0 to 1).
    pub fn cdf(&self) -> &[f64] {
        &self.cdf
    }

    /// The bin of a uniform `u` ∈ [0, 1) and the position within it,
    /// `t` ∈ [0, 1] (½ for a bin of probability 0).
    ///
    /// The bin is the number of CDF entries ≤ `u` less one
    /// (`partition_point(|c| c <= u) − 1`), walked to from the guide's cell,
    /// so it does not depend on how `u · cells` rounds.
    #[inline(always)]
    pub fn sample_bin(&self, u: f64) -> (usize, f64) {
        let cdf = &self.cdf[..];
        // `as u32` saturates: NaN and negative `u` give cell 0. (A cast to
        // usize costs a dozen instructions more: it runs twice per map sample.)
        let cell = ((u * self.cells) as u32 as usize).min(self.guide.len() - 1);
        let count = walk_count_le(cdf, self.guide[cell] as usize, u);
        let i = count.saturating_sub(1).min(cdf.len() - 2);
        let (lo, hi) = (cdf[i], cdf[i + 1]);
        let span = hi - lo;
        let t = if span > 0.0 {
            ((u - lo) / span).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (i, t)
    }

    /// Draws x ∈ [0, 1); returns (x, density at x, bin).
    #[inline]
    pub fn sample(&self, u: f64) -> (f64, f64, usize) {
        let (i, t) = self.sample_bin(u);
        let n = self.pmf.len();
        let x = (i as f64 + t.min(1.0 - f64::EPSILON)) / n as f64;
        (x, self.pdf_bin(i), i)
    }

    /// Probability of bin `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f64 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Density on [0, 1) in bin `i`.
    #[inline]
    pub fn pdf_bin(&self, i: usize) -> f64 {
        self.pmf(i) * self.pmf.len() as f64
    }
}

/// The number of `keys` (non-decreasing) that are ≤ `x`, walked to from a
/// guide table's start `p`: exact whatever the guess, a step or two from a
/// good one.
#[inline]
pub(crate) fn walk_count_le(keys: &[f64], mut p: usize, x: f64) -> usize {
    p = p.min(keys.len());
    while p < keys.len() && keys[p] <= x {
        p += 1;
    }
    while p > 0 && keys[p - 1] > x {
        p -= 1;
    }
    p
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

    /// The bins a uniform `u` draws, `[row, column]`, and the positions
    /// within them, `[t_u, t_v]` ∈ [0, 1]² (the inverse-CDF map of
    /// [`sample`](Self::sample), so strata of `u` stay strata).
    #[inline]
    pub fn sample_bins(&self, u: [f64; 2]) -> ([usize; 2], [f64; 2]) {
        let (row, tv) = self.marginal.sample_bin(u[1]);
        let (col, tu) = self.rows[row].sample_bin(u[0]);
        ([row, col], [tu, tv])
    }

    /// Probability of the bin in `row` and `col` (0 outside the grid).
    pub fn pmf(&self, row: usize, col: usize) -> f64 {
        self.rows
            .get(row)
            .map_or(0.0, |r| self.marginal.pmf(row) * r.pmf(col))
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
    fn guided_inversion_matches_binary_search_and_zero_bins_are_never_drawn() {
        let mut w: Vec<f64> = (0..300).map(|i| ((i * 37) % 11) as f64).collect();
        w[5] = f64::NAN;
        w[6] = -3.0;
        w[299] = 1e-300;
        let d = Distribution1D::new(&w);
        let mut us: Vec<f64> = d
            .cdf()
            .iter()
            .flat_map(|&c| [c, c.next_up(), c.next_down()])
            .filter(|u| (0.0..1.0).contains(u))
            .collect();
        us.extend((0..20_000).map(|k| (k as f64 + 0.5) / 20_000.0));
        us.extend([0.0, 1.0f64.next_down()]);
        for u in us {
            let want = (d.cdf().partition_point(|&c| c <= u) - 1).min(d.len() - 1);
            let (i, t) = d.sample_bin(u);
            assert_eq!(i, want, "u = {u}");
            assert!((0.0..=1.0).contains(&t));
            let (x, p, j) = d.sample(u);
            assert!((0.0..1.0).contains(&x) && j == i);
            assert!(p > 0.0, "u = {u} drew bin {i} of weight {}", w[i]);
        }
        let sum: f64 = (0..d.len()).map(|i| d.pmf(i)).sum();
        assert!((sum - 1.0).abs() < 1e-12);
        // Out-of-range and NaN `u` (the guide cell's cast saturates): a bin
        // in range, without panicking.
        for u in [-0.5, -0.0, f64::NAN, 1.0, 7.0, f64::INFINITY] {
            let (i, t) = d.sample_bin(u);
            assert!(
                i < d.len() && (t.is_nan() || (0.0..=1.0).contains(&t)),
                "u = {u}: {i}, {t}"
            );
        }
        // All-zero weights: uniform.
        let z = Distribution1D::new(&[0.0, 0.0, f64::INFINITY]);
        assert_eq!(z.pdf_bin(2), 1.0);
        assert_eq!(z.sample(0.5).2, 1);
    }

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
