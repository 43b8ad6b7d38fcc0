use glam::DVec3;

/// Shortest wavelength, in nm, that every built-in spectral table covers.
pub const WAVELENGTH_MIN_NM: f64 = 360.0;
/// Longest wavelength, in nm, that every built-in spectral table covers.
pub const WAVELENGTH_MAX_NM: f64 = 830.0;

/// One sampled outgoing direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BxdfSample {
    /// Outgoing direction, unit length, local frame.
    pub wo: DVec3,
    /// Monte Carlo weight. Glossy: `eval(wi, wo) · cosθo / pdf`. Delta:
    /// `specular.weight / specular.probability`.
    pub weight: f64,
    /// Glossy: solid-angle pdf of `wo`, including the probability of having
    /// chosen the glossy lobe (equals [`Bxdf::pdf`]). Delta: the discrete
    /// probability of having chosen the delta lobe.
    pub pdf: f64,
    /// Whether `wo` came from the specular delta lobe.
    pub is_delta: bool,
}

/// What a model's (f, pdf) at one pair of directions shares between
/// wavelengths, kept from [`Bxdf::sample_kept`] for
/// [`Bxdf::eval_pdf_many_kept`]: a renderer that samples a direction at one
/// wavelength and needs f and pdf there at others later need not redo the
/// λ-free part. Opaque; only the model that made it reads it, and a model
/// that keeps nothing hands out [`Kept::NOTHING`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kept(Option<[f64; 3]>);

impl Kept {
    /// Nothing kept: [`Bxdf::eval_pdf_many_kept`] evaluates in full.
    pub const NOTHING: Kept = Kept(None);

    /// Three numbers of the model's own.
    #[inline]
    pub(crate) fn new(parts: [f64; 3]) -> Kept {
        Kept(Some(parts))
    }

    /// The numbers, if a model kept any.
    #[inline]
    pub(crate) fn parts(&self) -> Option<[f64; 3]> {
        self.0
    }
}

/// The specular (delta) lobe of a model at one incident direction.
///
/// Its BRDF is `weight · δ_ω(o − s) / cosθo` with `s` the mirror direction of
/// `wi`; the reflected radiance along `s` is `weight` times the incident one.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Specular {
    /// Fraction of incident energy reflected coherently (e.g. `R · e^{−g}`).
    pub weight: f64,
    /// Probability that [`Bxdf::sample`] returns a delta sample for this `wi`
    /// and wavelength; 0 for purely glossy models.
    pub probability: f64,
}

/// The interface every reflection model implements.
///
/// Directions are unit vectors in the local shading frame (normal = +z),
/// both pointing away from the surface. `lambda_nm` is the wavelength in
/// nanometres; models whose parameters do not depend on it ignore it except
/// through Fresnel. No method panics or returns NaN, infinity or a negative
/// number, whatever the input: directions below the surface give 0.
pub trait Bxdf {
    /// Glossy (non-delta) BRDF value f(wi, wo) in sr⁻¹.
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64;

    /// Solid-angle density with which [`Bxdf::sample`] returns the glossy
    /// direction `wo`, including the probability of choosing the glossy lobe.
    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64;

    /// `(eval, pdf)` together. Light sampling with MIS needs both at the same
    /// pair of directions; models override this to share the work.
    #[inline]
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        (self.eval(wi, wo, lambda_nm), self.pdf(wi, wo, lambda_nm))
    }

    /// [`Bxdf::eval_pdf`] at several wavelengths for one pair of directions:
    /// `out[j] = eval_pdf(wi, wo, lambdas[j])` for `j < min(lambdas.len(),
    /// out.len())`. Spectral renderers carry several wavelengths per path
    /// (hero wavelengths); models whose geometry does not depend on λ (the
    /// microfacet conductors) override this to compute it once.
    #[inline]
    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        for (o, &l) in out.iter_mut().zip(lambdas) {
            *o = self.eval_pdf(wi, wo, l);
        }
    }

    /// [`Bxdf::eval_pdf`] over rows: `(f[i], pdf[i]) = eval_pdf(wi[i], wo[i],
    /// lambda_nm[i])` for `i` below the shortest of the five lengths,
    /// bit-identical to it. Array front ends (the Python package) evaluate
    /// millions of unrelated rows; models whose arithmetic has no branches
    /// worth keeping (GGX) override this to evaluate several rows per SIMD
    /// instruction.
    #[inline]
    fn eval_pdf_rows(
        &self,
        wi: &[DVec3],
        wo: &[DVec3],
        lambda_nm: &[f64],
        f: &mut [f64],
        pdf: &mut [f64],
    ) {
        eval_pdf_each_row(self, wi, wo, lambda_nm, f, pdf);
    }

    /// Draws an outgoing direction from three uniform numbers in [0, 1).
    /// Returns `None` when the sample carries no energy (below the horizon,
    /// evanescent, or zero weight).
    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample>;

    /// [`Bxdf::sample`], and what its evaluation at the sampled direction
    /// shares between wavelengths ([`Kept`]). The default keeps nothing.
    #[inline]
    fn sample_kept(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<(BxdfSample, Kept)> {
        self.sample(wi, lambda_nm, u).map(|s| (s, Kept::NOTHING))
    }

    /// [`Bxdf::eval_pdf_many`] at a direction `wo` that [`Bxdf::sample_kept`]
    /// of this model returned for this `wi` together with `kept`; the same
    /// values, bit for bit. The default ignores `kept`.
    #[inline]
    fn eval_pdf_many_kept(
        &self,
        wi: DVec3,
        wo: DVec3,
        kept: &Kept,
        lambdas: &[f64],
        out: &mut [(f64, f64)],
    ) {
        let _ = kept;
        self.eval_pdf_many(wi, wo, lambdas, out);
    }

    /// The specular delta lobe at `wi`; zero for models without one.
    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        let _ = (wi, lambda_nm);
        Specular::default()
    }

    /// Whether [`Bxdf::sample`] reads `u[0]` (the choice between a delta and
    /// a glossy lobe). A model with one lobe returns `false`, and a caller may
    /// then pass any value there instead of computing it. `true`, the
    /// default, is always safe.
    fn uses_lobe_choice(&self) -> bool {
        true
    }

    /// The size of the glossy lobe at `wi` as a density: an upper bound on
    /// the solid-angle density [`Bxdf::sample`] gives a glossy direction, as
    /// close as the model can cheaply make it, or `None` (the default) when
    /// the model does not say. A renderer can compare it with a light's
    /// density to tell a lobe much narrower than the light from one as wide
    /// or wider (MIS weights that favour light sampling only in the second
    /// case).
    fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
        let _ = wi;
        None
    }
}

/// [`Bxdf::eval_pdf_rows`] one row at a time through `eval_pdf`: the default,
/// and what an override falls back to for the models it does not pack.
#[inline]
pub(crate) fn eval_pdf_each_row<B: Bxdf + ?Sized>(
    model: &B,
    wi: &[DVec3],
    wo: &[DVec3],
    lambda_nm: &[f64],
    f: &mut [f64],
    pdf: &mut [f64],
) {
    let rows = wi
        .iter()
        .zip(wo)
        .zip(lambda_nm)
        .zip(f.iter_mut().zip(pdf.iter_mut()));
    for (((&a, &b), &l), (f, p)) in rows {
        (*f, *p) = model.eval_pdf(a, b, l);
    }
}

/// A pointer to a model is the model: every method forwards.
macro_rules! forward_bxdf {
    ($($ptr:tt)*) => {
        impl<T: Bxdf + ?Sized> Bxdf for $($ptr)* {
            fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
                (**self).eval(wi, wo, lambda_nm)
            }
            fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
                (**self).pdf(wi, wo, lambda_nm)
            }
            fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
                (**self).eval_pdf(wi, wo, lambda_nm)
            }
            fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
                (**self).eval_pdf_many(wi, wo, lambdas, out)
            }
            fn eval_pdf_rows(
                &self,
                wi: &[DVec3],
                wo: &[DVec3],
                lambda_nm: &[f64],
                f: &mut [f64],
                pdf: &mut [f64],
            ) {
                (**self).eval_pdf_rows(wi, wo, lambda_nm, f, pdf)
            }
            fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
                (**self).sample(wi, lambda_nm, u)
            }
            fn sample_kept(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<(BxdfSample, Kept)> {
                (**self).sample_kept(wi, lambda_nm, u)
            }
            fn eval_pdf_many_kept(
                &self,
                wi: DVec3,
                wo: DVec3,
                kept: &Kept,
                lambdas: &[f64],
                out: &mut [(f64, f64)],
            ) {
                (**self).eval_pdf_many_kept(wi, wo, kept, lambdas, out)
            }
            fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
                (**self).specular(wi, lambda_nm)
            }
            fn uses_lobe_choice(&self) -> bool {
                (**self).uses_lobe_choice()
            }
            fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
                (**self).lobe_peak_pdf(wi)
            }
        }
    };
}

forward_bxdf!(&T);
#[cfg(feature = "alloc")]
forward_bxdf!(alloc::boxed::Box<T>);
