//! The conditional 2-D warp of the RGL format: a density on [0, 1]² given at
//! the nodes of a regular grid and interpolated bilinearly, optionally
//! depending on extra parameters (incident angles, wavelength) between whose
//! nodes the data are interpolated linearly.
//!
//! This is the "continuous marginal" scheme the format's readers use
//! (Mitsuba 3 `Marginal2D<Float, D, true>`, pbrt-v4 `PiecewiseLinear2D<D>`):
//! the row coordinate y is drawn from the exact marginal of the bilinear
//! density, then x from the exact conditional, so [`Marginal2D::sample`]
//! and [`Marginal2D::invert`] are inverse bijections of [0, 1]² and the
//! density of the mapping is the bilinear interpolant itself. The exporter
//! uses `sample` to place the table's nodes where the readers will look for
//! them, and its reader uses `invert` and `eval`, as Mitsuba and pbrt do.

/// f32's machine epsilon 2⁻²⁴, the readers' clamp of a uniform sample.
const EPSILON_F32: f64 = 5.960_464_477_539_063e-8;

/// A (conditional) piecewise-bilinear 2-D density.
#[derive(Clone, Debug)]
pub struct Marginal2D {
    /// Nodes along x (fastest in memory) and y.
    w: usize,
    h: usize,
    /// Node values of each parameter, outermost first.
    params: Vec<Vec<f64>>,
    /// Slice stride of each parameter (0 for a parameter with one node).
    strides: Vec<usize>,
    /// Node values, one `w·h` slice per parameter combination.
    data: Vec<f64>,
    /// Per slice and row, the integral of the row's linear interpolant from
    /// x = 0 to the end of each of its `w − 1` intervals.
    cond: Vec<f64>,
    /// Per slice, the integral of the density from y = 0 to the end of each
    /// of its `h − 1` row intervals.
    marg: Vec<f64>,
    sampling: bool,
}

/// The slices and weights that interpolate the parameters.
type Corners = Vec<(usize, f64)>;

impl Marginal2D {
    /// A density over a `w × h` grid (`data` holds one slice per parameter
    /// combination, the last parameter fastest). `normalize` scales each
    /// slice to integrate to 1; `sampling` builds the CDFs (and implies
    /// `normalize`, as in the readers). `None` when the sizes disagree or a
    /// slice to be normalised integrates to zero or a non-finite value.
    pub fn new(
        data: &[f32],
        w: usize,
        h: usize,
        params: Vec<Vec<f64>>,
        normalize: bool,
        sampling: bool,
    ) -> Option<Marginal2D> {
        if w < 2 || h < 2 || params.iter().any(|p| p.is_empty()) {
            return None;
        }
        let mut strides = vec![0; params.len()];
        let mut slices = 1usize;
        for i in (0..params.len()).rev() {
            strides[i] = if params[i].len() > 1 { slices } else { 0 };
            slices = slices.checked_mul(params[i].len())?;
        }
        let n = w.checked_mul(h)?;
        if data.len() != slices.checked_mul(n)? {
            return None;
        }
        let mut out = Marginal2D {
            w,
            h,
            params,
            strides,
            data: Vec::with_capacity(data.len()),
            cond: Vec::new(),
            marg: Vec::new(),
            sampling,
        };
        for slice in data.chunks_exact(n) {
            out.add_slice(slice, normalize || sampling)?;
        }
        Some(out)
    }

    fn add_slice(&mut self, d: &[f32], normalize: bool) -> Option<()> {
        let (w, h) = (self.w, self.h);
        let (sx, sy) = (0.5 / (w - 1) as f64, 0.5 / (h - 1) as f64);
        let mut cond = Vec::with_capacity(if self.sampling { h * (w - 1) } else { 0 });
        let mut rows = Vec::with_capacity(h);
        for y in 0..h {
            let mut acc = 0.0;
            for x in 0..w - 1 {
                let i = y * w + x;
                acc += sx * (d[i] as f64 + d[i + 1] as f64);
                if self.sampling {
                    cond.push(acc);
                }
            }
            rows.push(acc);
        }
        let mut marg = Vec::with_capacity(h - 1);
        let mut total = 0.0;
        for y in 0..h - 1 {
            total += sy * (rows[y] + rows[y + 1]);
            marg.push(total);
        }
        let norm = if normalize {
            if !(total.is_finite() && total > 0.0) {
                return None;
            }
            1.0 / total
        } else {
            1.0
        };
        self.data.extend(d.iter().map(|&v| v as f64 * norm));
        if self.sampling {
            self.cond.extend(cond.iter().map(|v| v * norm));
            self.marg.extend(marg.iter().map(|v| v * norm));
        }
        Some(())
    }

    /// The slices and weights of the parameter values `param` (one per
    /// parameter): linear between the two enclosing nodes, clamped to the
    /// end slices outside them.
    fn corners(&self, param: &[f64]) -> Corners {
        let mut out: Corners = vec![(0, 1.0)];
        for (d, values) in self.params.iter().enumerate() {
            if values.len() == 1 {
                continue;
            }
            let p = param.get(d).copied().unwrap_or(0.0);
            // The last node below p, at most the second to last.
            let i = values[1..values.len() - 1]
                .iter()
                .take_while(|&&v| v < p)
                .count();
            let (p0, p1) = (values[i], values[i + 1]);
            let t = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
            let t = if t.is_nan() { 0.0 } else { t };
            let s = self.strides[d];
            out = out
                .into_iter()
                .flat_map(|(off, wt)| [(off + i * s, wt * (1.0 - t)), (off + (i + 1) * s, wt * t)])
                .collect();
        }
        out
    }

    fn lookup(arr: &[f64], slice_len: usize, c: &Corners, i: usize) -> f64 {
        c.iter().map(|&(s, wt)| wt * arr[s * slice_len + i]).sum()
    }

    /// The interpolated density at `pos` ∈ [0, 1]².
    pub fn eval(&self, pos: [f64; 2], param: &[f64]) -> f64 {
        let c = self.corners(param);
        let (i, fx, fy) = self.patch(pos);
        let n = self.w * self.h;
        let v = |o: usize| Self::lookup(&self.data, n, &c, i + o);
        let (v00, v10, v01, v11) = (v(0), v(1), v(self.w), v(self.w + 1));
        lerp(lerp(v00, v10, fx), lerp(v01, v11, fx), fy)
    }

    /// Index of the lower-left node of the patch holding `pos`, and the
    /// position inside it.
    fn patch(&self, pos: [f64; 2]) -> (usize, f64, f64) {
        let x = pos[0].clamp(0.0, 1.0) * (self.w - 1) as f64;
        let y = pos[1].clamp(0.0, 1.0) * (self.h - 1) as f64;
        let ix = (x as usize).min(self.w - 2);
        let iy = (y as usize).min(self.h - 2);
        (iy * self.w + ix, x - ix as f64, y - iy as f64)
    }

    /// Maps a uniform `u` ∈ [0, 1)² to a point distributed as the density,
    /// with the density there. Needs `sampling`.
    pub fn sample(&self, u: [f64; 2], param: &[f64]) -> ([f64; 2], f64) {
        debug_assert!(self.sampling);
        let (w, h) = (self.w, self.h);
        let c = self.corners(param);
        let (n_marg, n_cond, n_data) = (h - 1, h * (w - 1), w * h);
        let ux = u[0].clamp(EPSILON_F32, 1.0 - EPSILON_F32);
        let uy = u[1].clamp(EPSILON_F32, 1.0 - EPSILON_F32);
        let marg = |i: usize| Self::lookup(&self.marg, n_marg, &c, i);
        let row = (0..n_marg - 1).take_while(|&i| marg(i) < uy).count();
        let y = uy - if row > 0 { marg(row - 1) } else { 0.0 };
        let cond = |r: usize, i: usize| Self::lookup(&self.cond, n_cond, &c, r * (w - 1) + i);
        let (r0, r1) = (cond(row, w - 2), cond(row + 1, w - 2));
        let t = sample_segment(y, (h - 1) as f64, r0, r1);
        let x = ux * lerp(r0, r1, t);
        let condf = |i: usize| lerp(cond(row, i), cond(row + 1, i), t);
        let col = (0..w - 2).take_while(|&i| condf(i) < x).count();
        let x = x - if col > 0 { condf(col - 1) } else { 0.0 };
        let v = |o: usize| Self::lookup(&self.data, n_data, &c, row * w + col + o);
        let (c0, c1) = (lerp(v(0), v(w), t), lerp(v(1), v(w + 1), t));
        let s = sample_segment(x, (w - 1) as f64, c0, c1);
        (
            [
                (col as f64 + s) / (w - 1) as f64,
                (row as f64 + t) / (h - 1) as f64,
            ],
            lerp(c0, c1, s),
        )
    }

    /// The inverse of [`Marginal2D::sample`]: the uniform point that maps to
    /// `p`, with the density at `p`. Needs `sampling`.
    pub fn invert(&self, p: [f64; 2], param: &[f64]) -> ([f64; 2], f64) {
        debug_assert!(self.sampling);
        let (w, h) = (self.w, self.h);
        let c = self.corners(param);
        let (n_marg, n_cond, n_data) = (h - 1, h * (w - 1), w * h);
        let (i, fx, fy) = self.patch(p);
        let (col, row) = (i % w, i / w);
        let v = |o: usize| Self::lookup(&self.data, n_data, &c, i + o);
        let (c0, c1) = (lerp(v(0), v(w), fy), lerp(v(1), v(w + 1), fy));
        let pdf = lerp(c0, c1, fx);
        let cond = |r: usize, k: usize| Self::lookup(&self.cond, n_cond, &c, r * (w - 1) + k);
        let mut x = fx * lerp(c0, c1, 0.5 * fx) / (w - 1) as f64;
        if col > 0 {
            x += lerp(cond(row, col - 1), cond(row + 1, col - 1), fy);
        }
        let (r0, r1) = (cond(row, w - 2), cond(row + 1, w - 2));
        let row_total = lerp(r0, r1, fy);
        let x = if row_total > 0.0 { x / row_total } else { 0.0 };
        let mut y = fy * lerp(r0, r1, 0.5 * fy) / (h - 1) as f64;
        if row > 0 {
            y += Self::lookup(&self.marg, n_marg, &c, row - 1);
        }
        ([x, y], pdf)
    }
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// The t ∈ [0, 1] at which the integral of the linear density v0 → v1 over
/// an interval of width 1/`inv_width` reaches `sample`.
fn sample_segment(sample: f64, inv_width: f64, v0: f64, v1: f64) -> f64 {
    let non_const = (v0 - v1).abs() > 1e-4 * (v0 + v1);
    let divisor = if non_const { v0 - v1 } else { v0 + v1 };
    let mut s = sample * 2.0 * inv_width;
    if non_const {
        s = v0 - (v0 * v0 + s * (v1 - v0)).max(0.0).sqrt();
    }
    if divisor != 0.0 { s / divisor } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(w: usize, h: usize, f: impl Fn(f64, f64) -> f64) -> Vec<f32> {
        let mut v = Vec::new();
        for y in 0..h {
            for x in 0..w {
                v.push(f(x as f64 / (w - 1) as f64, y as f64 / (h - 1) as f64) as f32);
            }
        }
        v
    }

    #[test]
    fn sample_and_invert_are_inverse_and_the_density_is_the_interpolant() {
        let d = grid(7, 5, |x, y| 0.1 + x * x + 3.0 * (y - 0.3).abs());
        let m = Marginal2D::new(&d, 7, 5, vec![], true, true).unwrap();
        let raw = Marginal2D::new(&d, 7, 5, vec![], true, false).unwrap();
        for i in 0..40 {
            for j in 0..40 {
                let u = [(i as f64 + 0.5) / 40.0, (j as f64 + 0.5) / 40.0];
                let (p, pdf) = m.sample(u, &[]);
                let (back, pdf2) = m.invert(p, &[]);
                assert!((back[0] - u[0]).abs() < 1e-9 && (back[1] - u[1]).abs() < 1e-9);
                assert!((pdf - pdf2).abs() < 1e-9 * pdf);
                assert!((pdf - raw.eval(p, &[])).abs() < 1e-9 * pdf);
            }
        }
    }

    #[test]
    fn the_density_integrates_to_one_and_matches_the_jacobian() {
        let d = grid(9, 4, |x, y| 1.0 + 5.0 * x * y + (6.0 * x).sin().abs());
        let m = Marginal2D::new(&d, 9, 4, vec![], true, true).unwrap();
        // Jacobian determinant of invert() by central differences = pdf.
        let h = 1e-6;
        for &(x, y) in &[(0.31, 0.42), (0.77, 0.1), (0.05, 0.93)] {
            let (a, pdf) = m.invert([x, y], &[]);
            let (bx, _) = m.invert([x + h, y], &[]);
            let (by, _) = m.invert([x, y + h], &[]);
            let det = ((bx[0] - a[0]) * (by[1] - a[1]) - (bx[1] - a[1]) * (by[0] - a[0])) / (h * h);
            assert!((det - pdf).abs() < 1e-4 * pdf, "{det} vs {pdf}");
        }
        // Midpoint rule over a fine grid.
        let n = 400;
        let mut s = 0.0;
        for i in 0..n {
            for j in 0..n {
                s += m.eval(
                    [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64],
                    &[],
                );
            }
        }
        assert!(
            (s / (n * n) as f64 - 1.0).abs() < 1e-4,
            "{}",
            s / (n * n) as f64
        );
    }

    #[test]
    fn parameters_interpolate_linearly_and_clamp() {
        let a = grid(3, 3, |_, _| 1.0);
        let b = grid(3, 3, |x, _| 2.0 * x);
        let data: Vec<f32> = a.iter().chain(&b).copied().collect();
        let m = Marginal2D::new(&data, 3, 3, vec![vec![10.0, 20.0]], false, false).unwrap();
        assert!((m.eval([0.5, 0.5], &[15.0]) - 1.0).abs() < 1e-12);
        assert!((m.eval([1.0, 0.5], &[15.0]) - 1.5).abs() < 1e-12);
        assert!((m.eval([1.0, 0.5], &[-5.0]) - 1.0).abs() < 1e-12);
        assert!((m.eval([1.0, 0.5], &[99.0]) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_zero_slice_cannot_be_normalised() {
        let z = vec![0.0f32; 4];
        assert!(Marginal2D::new(&z, 2, 2, vec![], true, true).is_none());
        assert!(Marginal2D::new(&z, 2, 2, vec![], false, false).is_some());
        assert!(Marginal2D::new(&z, 2, 3, vec![], false, false).is_none());
    }
}
