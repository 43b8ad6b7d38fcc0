//! The full GHS kernel of a tabulated 2-D PSD (physics.md §15.4), over
//! (ζ, ln g):
//!
//! ```text
//! S̃(ζ; g) = e^{−g} Σ_{n≥1} gⁿ/n! P₂^{*n}(ζ)/σ^{2n}
//!         = e^{−g} g P₂(ζ)/σ²  +  m₂(g) W(ζ; g),
//! m₂(g) = 1 − e^{−g}(1 + g),   m₂ W = e^{−g} FT₂⁻¹[e^{gC/σ²} − 1 − gC/σ²],
//! ```
//!
//! C(τ) = ∫P₂(ζ) e^{iζ·τ} d²ζ the autocovariance. The first order is the
//! table's P₂ itself, evaluated exactly at any ζ (so the model is the SSA's
//! lobe plus the orders n ≥ 2, and tends to it as g → 0). The orders n ≥ 2 are
//! transformed once per slice g_j = g₀ e^{jΔ} on a periodic (ζx, ζy) grid:
//!
//! * the grid is the table's frame, step h = max(Δζ/2, 2Z/256) per axis and
//!   N = 2^k ≥ 2Z/h nodes, Z = 1.25 · 2k(360 nm): the lobes are read at
//!   |ζ| ≤ 2k, and what the period folds back onto that disk comes from
//!   |ζ| ≥ 2Z − 2k = 1.5 · 2k(360 nm) (slopes past the grazing ones);
//! * P₂ enters as the mean of each node's cell (midpoint rule on ⌈h/Δζ⌉²
//!   points), so C is the trapezoid rule of the table; P₂ beyond the period
//!   (above Z) is left out of the orders n ≥ 2: it scatters beyond 2k;
//! * e^{−g}(e^{x} − 1 − x), x = g C/σ², is summed as its series Σ_{n≥2} xⁿ/n!
//!   where |x| < 0.5 (no cancellation of 1 + x, 20 terms reach round-off) and
//!   as e^{x−g} − e^{−g}(1 + x) elsewhere (x ≤ g, so nothing overflows at any
//!   g); pointwise in τ this is the Poisson series of self-convolutions;
//! * W_j = that transform / m₂(g_j), a density (∫W ≈ 1), is kept on the
//!   disk's square |ζx|, |ζy| ≤ 2k(360 nm) as a [`TabulatedPsd2d`] (bilinear
//!   in ζ, with its exact cell sampler); between slices ln W is linear in
//!   ln g (W falls as a power of g where the lobe widens), below g₀ W is
//!   W(g₀) (the orders n ≥ 2 are then a share g/2 of the lobe).

use alloc::vec;
use alloc::vec::Vec;

use super::wavenumber;
use crate::BrdfError;
use crate::model::WAVELENGTH_MIN_NM;
use crate::numerics::fft2::Fft2;
use crate::statistics::TabulatedPsd2d;
use crate::statistics::psd2d::TAIL_EXPONENT_MAX;

/// The smallest slice, g₀.
pub const G_MIN: f64 = 0.01;

/// The largest slice: 1e6 (σ ≈ 29 µm at 360 nm).
pub const G_TOP: f64 = 1e6;

/// Largest FFT side.
const N_MAX: usize = 256;

/// The resolution of a [`Psd2dGhsTable`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Psd2dResolution {
    /// Slices per unit of ln g.
    pub slices_per_ln_g: f64,
    /// Largest FFT side (a power of two, 16–1024).
    pub n_max: usize,
}

impl Default for Psd2dResolution {
    fn default() -> Self {
        Psd2dResolution {
            slices_per_ln_g: 8.0,
            n_max: N_MAX,
        }
    }
}

/// The orders n ≥ 2 of the full GHS of a [`TabulatedPsd2d`], sliced over ln g
/// (module documentation).
#[derive(Clone, Debug)]
pub struct Psd2dGhsTable {
    psd: TabulatedPsd2d,
    ln_g0: f64,
    dln: f64,
    n_max: usize,
    /// `None`: nothing of the orders n ≥ 2 within the kept square (all of
    /// that g's lobe is beyond 2k(360 nm): a PSD whose mass lies above it).
    slices: Vec<Option<TabulatedPsd2d>>,
    /// The node-wise largest W of all slices: a share of every proposal, so the
    /// pdf is positive wherever a slice is (slices of different g differ in
    /// support).
    envelope: Option<TabulatedPsd2d>,
}

/// The envelope's share of the glossy proposal.
const ENVELOPE_SHARE: f64 = 0.05;

/// The periodic grid of one build.
struct Grid {
    nx: usize,
    ny: usize,
    hx: f64,
    hy: f64,
    /// Half nodes kept per axis.
    qx: usize,
    qy: usize,
    /// C(τ)/σ² on the τ grid (row-major, wrapped order).
    c: Vec<f64>,
    plan: Fft2,
}

/// m₂(g) = 1 − e^{−g}(1 + g), the share of the orders n ≥ 2.
pub fn second_order_share(g: f64) -> f64 {
    if !(g > 0.0) {
        return 0.0;
    }
    if g < 0.5 {
        let (mut term, mut sum) = (g * g / 2.0, 0.0);
        for n in 3..24 {
            sum += term;
            term *= g / n as f64;
        }
        return libm::exp(-g) * sum;
    }
    -libm::expm1(-g) - g * libm::exp(-g)
}

/// e^{−g}(e^{x} − 1 − x) without cancellation or overflow (x ≤ g).
fn higher_orders(x: f64, g: f64) -> f64 {
    if libm::fabs(x) < 0.5 {
        let (mut term, mut sum) = (x * x / 2.0, 0.0);
        for n in 3..23 {
            sum += term;
            term *= x / n as f64;
        }
        return libm::exp(-g) * sum;
    }
    libm::exp(x - g) - libm::exp(-g) * (1.0 + x)
}

impl Psd2dGhsTable {
    /// Slices from g₀ up to `g_max` at the default resolution.
    pub fn new(psd: TabulatedPsd2d, g_max: f64) -> Result<Self, BrdfError> {
        Self::with_resolution(psd, g_max, Psd2dResolution::default())
    }

    /// Slices from g₀ up to `g_max` (at least two).
    pub fn with_resolution(
        psd: TabulatedPsd2d,
        g_max: f64,
        res: Psd2dResolution,
    ) -> Result<Self, BrdfError> {
        crate::error::check_range(
            "slices_per_ln_g",
            res.slices_per_ln_g,
            0.5,
            100.0,
            "0.5 to 100 slices per unit of ln g",
        )?;
        if !(res.n_max.is_power_of_two() && (16..=1024).contains(&res.n_max)) {
            return Err(BrdfError::OutOfRange {
                name: "n_max",
                value: res.n_max as f64,
                valid: "a power of two from 16 to 1024",
            });
        }
        crate::error::check_range("g_max", g_max, 0.0, f64::MAX, "a finite g_max ≥ 0")?;
        let dln = 1.0 / res.slices_per_ln_g;
        // Above G_TOP the lobe is the slopes' (its width k·slope does not grow with g):
        // the last slice stands for every larger g.
        let span = crate::numerics::math::ln(g_max.clamp(G_MIN, G_TOP) / G_MIN);
        let n = (libm::ceil(span / dln) as usize + 1).max(2);
        let grid = Grid::new(&psd, res.n_max);
        let ln_g0 = crate::numerics::math::ln(G_MIN);
        let g_of = |j: usize| libm::exp(ln_g0 + j as f64 * dln);
        let values: Vec<Vec<f64>> = crate::parallel::map_rows(n.div_ceil(2), |p| {
            grid.slice_pair(g_of(2 * p), (2 * p + 1 < n).then(|| g_of(2 * p + 1)))
        })
        .into_iter()
        .flat_map(|(a, b)| core::iter::once(a).chain(b))
        .collect();
        let mut top = alloc::vec![0.0f64; values[0].len()];
        for v in &values {
            for (t, x) in top.iter_mut().zip(v) {
                *t = t.max(*x);
            }
        }
        let angle = psd.angle_rad();
        let envelope = grid.table(&top, angle)?;
        let slices = values
            .iter()
            .map(|v| grid.table(v, angle))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Psd2dGhsTable {
            psd,
            ln_g0,
            dln,
            n_max: res.n_max,
            slices,
            envelope,
        })
    }

    /// The PSD.
    pub fn psd(&self) -> &TabulatedPsd2d {
        &self.psd
    }

    /// The number of ln g slices.
    pub fn slice_count(&self) -> usize {
        self.slices.len()
    }

    /// (j, t): g between slices j and j + 1, weight t of j + 1.
    fn bracket(&self, g: f64) -> (usize, f64) {
        if !(g > G_MIN) {
            return (0, 0.0);
        }
        let x = (crate::numerics::math::ln(g) - self.ln_g0) / self.dln;
        let last = self.slices.len() - 1;
        if !(x < last as f64) {
            return (last, 0.0);
        }
        let j = libm::floor(x) as usize;
        (j, x - j as f64)
    }

    /// W(ζ; g) of the orders n ≥ 2 (∫W d²ζ ≈ 1), ζ in the tangent frame.
    pub fn higher_density(&self, zx: f64, zy: f64, g: f64) -> f64 {
        let (j, t) = self.bracket(g);
        let at = |i: usize| self.slices[i].as_ref().map_or(0.0, |s| s.psd(zx, zy));
        let a = at(j);
        if !(t > 0.0) {
            return a;
        }
        let b = at(j + 1);
        if a > 0.0 && b > 0.0 {
            // Geometric: exact for a power law in g, which W follows where the
            // lobe widens (W(0) ∝ g^−1.8 on crossing lays: linear in ln g
            // missed it by 3 % at four slices per unit).
            a * libm::exp(t * crate::numerics::math::ln(b / a))
        } else {
            (1.0 - t) * a + t * b
        }
    }

    /// S̃(ζ; g), 1/(rad/µm)², ζ in the tangent frame: ∫S̃ d²ζ = 1 − e^{−g} less
    /// what lies beyond the kept square.
    pub fn s_tilde(&self, zx: f64, zy: f64, g: f64) -> f64 {
        self.s_tilde_with(self.psd.unit_psd(zx, zy), zx, zy, g)
    }

    /// [`s_tilde`](Self::s_tilde) at g and [`proposal_density`](Self::proposal_density)
    /// at g_s, with P₂/σ² at ζ looked up once (an evaluation needs both).
    pub fn s_tilde_and_proposal(&self, zx: f64, zy: f64, g: f64, gs: f64) -> (f64, f64) {
        let p = self.psd.unit_psd(zx, zy);
        (
            self.s_tilde_with(p, zx, zy, g),
            self.proposal_with(p, zx, zy, gs),
        )
    }

    /// S̃ given `p` = P₂(ζ)/σ².
    fn s_tilde_with(&self, p: f64, zx: f64, zy: f64, g: f64) -> f64 {
        if !(g > 0.0) {
            return 0.0;
        }
        libm::exp(-g) * g * p + second_order_share(g) * self.higher_density(zx, zy, g)
    }

    /// The proposal density for the glossy lobe at g_s (∫ = 1 over the plane):
    /// 5 % the envelope of the slices, the rest the first order's P₂/σ² and the
    /// slices bracketing g_s mixed by their shares of the lobe at g_s, each kept
    /// between 5 % and 95 % (an empty slice's share goes to P₂/σ²); so the
    /// density is positive wherever S̃ is at any g.
    pub fn proposal_density(&self, zx: f64, zy: f64, gs: f64) -> f64 {
        self.proposal_with(self.psd.unit_psd(zx, zy), zx, zy, gs)
    }

    /// The proposal density given `p` = P₂(ζ)/σ².
    fn proposal_with(&self, p: f64, zx: f64, zy: f64, gs: f64) -> f64 {
        let mixed = self.mixed_density(p, zx, zy, gs);
        match &self.envelope {
            Some(e) => ENVELOPE_SHARE * e.unit_psd(zx, zy) + (1.0 - ENVELOPE_SHARE) * mixed,
            None => mixed,
        }
    }

    fn mixed_density(&self, p: f64, zx: f64, zy: f64, gs: f64) -> f64 {
        let w1 = self.first_share(gs);
        let (j, t) = self.bracket(gs);
        let (mut first, mut w) = (w1, 0.0);
        for (i, share) in [(j, 1.0 - t), (j + 1, t)] {
            if !(share > 0.0) {
                continue;
            }
            match &self.slices[i] {
                Some(s) => w += (1.0 - w1) * share * s.unit_psd(zx, zy),
                None => first += (1.0 - w1) * share,
            }
        }
        first * p + w
    }

    /// A frequency ζ (tangent frame) drawn from [`proposal_density`](Self::proposal_density)
    /// with three uniform numbers.
    pub fn proposal_sample(&self, gs: f64, v: f64, u1: f64, u2: f64) -> (f64, f64) {
        let v = match &self.envelope {
            Some(e) if v < ENVELOPE_SHARE => return e.sample_zeta(u1, u2),
            Some(_) => ((v - ENVELOPE_SHARE) / (1.0 - ENVELOPE_SHARE)).clamp(0.0, 1.0),
            None => v,
        };
        let w1 = self.first_share(gs);
        if v < w1 {
            return self.psd.sample_zeta(u1, u2);
        }
        let v = ((v - w1) / (1.0 - w1)).clamp(0.0, 1.0);
        let (j, t) = self.bracket(gs);
        let s = if t > 0.0 && v < t { j + 1 } else { j };
        match &self.slices[s] {
            Some(s) => s.sample_zeta(u1, u2),
            None => self.psd.sample_zeta(u1, u2),
        }
    }

    fn first_share(&self, gs: f64) -> f64 {
        let lobe = -libm::expm1(-gs);
        let w1 = if lobe > 0.0 {
            libm::exp(-gs) * gs / lobe
        } else {
            1.0
        };
        w1.clamp(0.05, 0.95)
    }

    /// W at one g computed afresh (no interpolation in ln g), at the grid
    /// nodes of the kept square (`None`: zero there): for checking the slice
    /// spacing.
    pub fn direct_slice(&self, g: f64) -> Result<Option<TabulatedPsd2d>, BrdfError> {
        let grid = Grid::new(&self.psd, self.n_max);
        grid.table(&grid.slice_values(g), self.psd.angle_rad())
    }
}

impl Grid {
    fn new(psd: &TabulatedPsd2d, n_max: usize) -> Grid {
        let zq = 2.0 * wavenumber(WAVELENGTH_MIN_NM) * 1.001;
        let zp = 1.25 * zq;
        let (dx, dy) = psd.steps_rad_per_um();
        let side = |d: f64| {
            // At least two nodes per half axis of the kept square, whatever the step.
            let h = (0.5 * d).max(2.0 * zp / n_max as f64).min(0.5 * zq);
            let n = (libm::ceil(2.0 * zp / h) as usize)
                .next_power_of_two()
                .min(n_max);
            // A node per h up to zq, and the period covers ±zp.
            let h = h.max(2.0 * zp / n as f64);
            let q = (libm::ceil(zq / h) as usize).min(n / 2 - 1);
            (n, h, q)
        };
        let (nx, hx, qx) = side(dx);
        let (ny, hy, qy) = side(dy);
        let sub = |h: f64, d: f64| (libm::ceil(h / d) as usize).clamp(1, 16);
        let (sx, sy) = (sub(hx, dx), sub(hy, dy));
        let sigma2 = psd.sigma_um() * psd.sigma_um();
        let wrap = |i: usize, n: usize| {
            if i < n / 2 {
                i as f64
            } else {
                i as f64 - n as f64
            }
        };
        let mut re = vec![0.0; nx * ny];
        for row in 0..ny {
            let b0 = wrap(row, ny) * hy;
            for col in 0..nx {
                let a0 = wrap(col, nx) * hx;
                let mut acc = 0.0;
                for v in 0..sy {
                    let b = b0 + ((v as f64 + 0.5) / sy as f64 - 0.5) * hy;
                    for u in 0..sx {
                        let a = a0 + ((u as f64 + 0.5) / sx as f64 - 0.5) * hx;
                        acc += psd.psd_in_frame(a, b);
                    }
                }
                re[row * nx + col] = acc / (sx * sy) as f64 * hx * hy / sigma2;
            }
        }
        let mut im = vec![0.0; nx * ny];
        let plan = Fft2::new(nx, ny);
        plan.run(&mut re, &mut im);
        // |C(τ)| ≤ C(0) ≤ σ² holds for the true PSD; the midpoint rule can put C(0)
        // a little above σ² (a coarse grid over a peaked table), and then e^{g(c − 1)}
        // overflows at large g: scale the sampled C down to C(0) = σ².
        let c0 = re[0];
        if c0 > 1.0 {
            re.iter_mut().for_each(|c| *c /= c0);
        }
        Grid {
            nx,
            ny,
            hx,
            hy,
            qx,
            qy,
            c: re,
            plan,
        }
    }

    /// W at g at the nodes of the kept square's half plane (rows j = 0..=q_y,
    /// each i = −q_x..=q_x).
    fn slice_values(&self, g: f64) -> Vec<f64> {
        self.slice_pair(g, None).0
    }

    /// W at g_a and at g_b with one complex FFT: the transform of a real even
    /// sequence is real, so g_a's goes in as the real part, g_b's as the
    /// imaginary part, and they come out apart (halves the build's FFTs).
    fn slice_pair(&self, ga: f64, gb: Option<f64>) -> (Vec<f64>, Option<Vec<f64>>) {
        let (nx, ny) = (self.nx, self.ny);
        let mut re: Vec<f64> = self.c.iter().map(|&c| higher_orders(ga * c, ga)).collect();
        let mut im = match gb {
            Some(g) => self.c.iter().map(|&c| higher_orders(g * c, g)).collect(),
            None => vec![0.0; nx * ny],
        };
        self.plan.run(&mut re, &mut im);
        (self.kept(&re, ga), gb.map(|g| self.kept(&im, g)))
    }

    /// The kept square's half plane of a transform at g, as W.
    fn kept(&self, t: &[f64], g: f64) -> Vec<f64> {
        let nx = self.nx;
        // (1/(2π)²) Σ F δτx δτy with δτ = 2π/(N h).
        let scale = 1.0 / ((nx * self.ny) as f64 * self.hx * self.hy * second_order_share(g));
        let (qx, qy) = (self.qx, self.qy);
        let mut half = Vec::with_capacity((2 * qx + 1) * (qy + 1));
        for j in 0..=qy {
            for i in 0..=2 * qx {
                let col = (i + nx - qx) % nx;
                half.push((t[j * nx + col] * scale).max(0.0));
            }
        }
        half
    }

    /// The half-plane values of the kept square as a table in the PSD's frame
    /// (`None`: zero everywhere).
    fn table(&self, half: &[f64], angle_rad: f64) -> Result<Option<TabulatedPsd2d>, BrdfError> {
        if !half.iter().any(|v| *v > 0.0) {
            return Ok(None);
        }
        TabulatedPsd2d::new(
            self.qx,
            self.qy,
            self.hx,
            self.hy,
            half,
            TAIL_EXPONENT_MAX,
            angle_rad,
        )
        .map(Some)
    }
}
