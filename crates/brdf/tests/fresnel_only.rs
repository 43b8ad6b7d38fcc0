//! `ModelKind::fresnel_only` is a promise renderers rely on to integrate a
//! single-scattering contribution over λ exactly: the model with a Fresnel
//! term is the model built with `FresnelSpec::One`, at any other wavelength,
//! times F(λ, |wi + wo|/2),
//! in value, pdf, sampled direction and sample weight. Checked here over the
//! directions and wavelengths; and the models it excludes must really break
//! the factorisation somewhere, or the predicate would hide a cheaper path.

use brdf::spec::{
    AnisoSpec, FresnelSpec, KcSpec, MaterialSpec, MeasuredAnisoSpec, ModelKind, ModelSpec,
    RrSurface,
};
use brdf::statistics::KcPsd;
use brdf::wave::two_scale::CoherentPart;
use brdf::wave::{GhsOptions, Polarization};
use brdf::{Bxdf, Metal, frame};
use core::f64::consts::{FRAC_PI_2, TAU};

/// xorshift64*: the test's own deterministic numbers.
struct Rng(u64);

impl Rng {
    fn f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn kc() -> KcSpec {
    KcSpec {
        sigma_um: 0.05,
        lc_um: 3.0,
        gamma: 2.5,
    }
}

fn models() -> Vec<ModelSpec> {
    vec![
        ModelSpec::Ggx {
            alpha_x: 0.2,
            alpha_y: 0.2,
            angle_deg: 0.0,
        },
        ModelSpec::Ggx {
            alpha_x: 0.03,
            alpha_y: 0.7,
            angle_deg: 0.0,
        },
        ModelSpec::Beckmann {
            alpha_x: 0.05,
            alpha_y: 0.05,
            angle_deg: 0.0,
        },
        ModelSpec::Beckmann {
            alpha_x: 1.0,
            alpha_y: 0.3,
            angle_deg: 0.0,
        },
        // Turned by `angle_deg`: the frame changes, not the Fresnel factor.
        ModelSpec::Ggx {
            alpha_x: 0.03,
            alpha_y: 0.7,
            angle_deg: 37.0,
        },
        ModelSpec::Beckmann {
            alpha_x: 1.0,
            alpha_y: 0.3,
            angle_deg: -120.0,
        },
        ModelSpec::Smooth,
        ModelSpec::GhsSsa {
            surface: kc(),
            options: GhsOptions::default(),
        },
        ModelSpec::Ghs {
            surface: kc(),
            options: GhsOptions::default(),
        },
        ModelSpec::TwoScale {
            beta: 0.1,
            surface: kc(),
            coherent: CoherentPart::MacroNdf,
        },
        ModelSpec::RayleighRice {
            surface: RrSurface::Kc(kc()),
            polarization: Polarization::Unpolarized,
        },
        ModelSpec::GhsSsaAniso {
            surface: aniso(),
            options: GhsOptions::default(),
        },
        ModelSpec::GhsAniso {
            surface: aniso(),
            options: GhsOptions::default(),
        },
        ModelSpec::MeasuredPsdSsaAniso {
            surface: measured_aniso(),
            options: GhsOptions::default(),
        },
        ModelSpec::MeasuredPsd2dSsa {
            surface: measured_map(),
            options: GhsOptions::default(),
        },
    ]
}

/// A 2-D table of the KC of `kc()` stretched by 3 along 20° (a grid over ±8 rad/µm).
fn measured_map() -> brdf::spec::Psd2dSpec {
    let k = kc();
    let a = brdf::statistics::AnisotropicKc::new(
        k.sigma_um,
        k.lc_um / 3f64.sqrt(),
        k.lc_um * 3f64.sqrt(),
        20f64.to_radians(),
        k.gamma,
    )
    .unwrap();
    let (mx, my, d) = (20usize, 20usize, 0.4);
    let mut psd_um4 = Vec::new();
    for j in 0..=my {
        for i in 0..=2 * mx {
            psd_um4.push(a.psd((i as f64 - mx as f64) * d, j as f64 * d));
        }
    }
    brdf::spec::Psd2dSpec {
        half_nx: mx,
        half_ny: my,
        dzx_rad_per_um: d,
        dzy_rad_per_um: d,
        psd_um4,
        tail_exponent: k.gamma + 1.0,
        angle_deg: 0.0,
    }
}

/// A stretched tabulated PSD (the KC of `kc()` sampled over a scan's band).
fn measured_aniso() -> MeasuredAnisoSpec {
    let k = kc();
    let zeta: Vec<f64> = (0..60).map(|i| 0.05 * 1.12f64.powi(i)).collect();
    let psd_um4 = zeta
        .iter()
        .map(|z| {
            KcPsd::new(k.sigma_um, k.lc_um, k.gamma)
                .unwrap()
                .p1(k.lc_um * z)
                * (k.sigma_um * k.lc_um).powi(2)
        })
        .collect();
    MeasuredAnisoSpec {
        zeta_rad_per_um: zeta,
        psd_um4,
        lx_um: 1.0,
        ly_um: 4.0,
        angle_deg: -35.0,
    }
}

fn aniso() -> AnisoSpec {
    let k = kc();
    AnisoSpec {
        sigma_um: k.sigma_um,
        lx_um: k.lc_um,
        ly_um: 3.0 * k.lc_um,
        angle_deg: 20.0,
        gamma: k.gamma,
    }
}

fn fresnels() -> Vec<FresnelSpec> {
    let mut f: Vec<FresnelSpec> = Metal::ALL.into_iter().map(FresnelSpec::Metal).collect();
    f.push(FresnelSpec::Constant { n: 0.2, k: 3.0 });
    f.push(FresnelSpec::Table(vec![
        [300.0, 1.4, 0.1],
        [500.0, 0.3, 2.0],
        [900.0, 2.5, 6.0],
    ]));
    f
}

/// Largest relative departure from the factorisation over random
/// directions and wavelengths.
fn worst_departure(model: &ModelSpec, fresnel: &FresnelSpec, rng: &mut Rng) -> f64 {
    let with = MaterialSpec {
        model: model.clone(),
        fresnel: fresnel.clone(),
    }
    .build()
    .unwrap();
    let one = MaterialSpec {
        model: model.clone(),
        fresnel: FresnelSpec::One,
    }
    .build()
    .unwrap();
    let f = fresnel.build().unwrap();
    let rel = |a: f64, b: f64| {
        if a == b {
            0.0
        } else {
            (a - b).abs() / a.abs().max(b.abs())
        }
    };
    let mut worst = 0.0f64;
    for _ in 0..400 {
        // Incidence from the normal to 1e-3 rad above the horizon.
        // √u leans toward grazing.
        let ti = (FRAC_PI_2 - 1e-3) * rng.f64().sqrt();
        let wi = frame::spherical(ti, TAU * rng.f64());
        let wo = frame::spherical(1.5 * rng.f64(), TAU * rng.f64());
        let lambda = 360.0 + 470.0 * rng.f64();
        // The unit model at another wavelength: f₁ must not depend on λ.
        let other = 360.0 + 470.0 * rng.f64();
        let cos_d = 0.5 * (wi + wo).length();
        let fd = f.reflectance(cos_d, lambda);
        let (e1, p1) = one.eval_pdf(wi, wo, other);
        let (e, p) = with.eval_pdf(wi, wo, lambda);
        worst = worst.max(rel(e, fd * e1)).max(rel(p, p1));
        let u = [rng.f64(), rng.f64(), rng.f64()];
        match (with.sample(wi, lambda, u), one.sample(wi, other, u)) {
            (Some(s), Some(s1)) => {
                let d = (s.wo - s1.wo).length();
                let fs = if s.is_delta {
                    f.reflectance(wi.z, lambda)
                } else {
                    f.reflectance(0.5 * (wi + s.wo).length(), lambda)
                };
                worst = worst
                    .max(d)
                    .max(rel(s.pdf, s1.pdf))
                    .max(rel(s.weight, fs * s1.weight))
                    .max(if s.is_delta == s1.is_delta { 0.0 } else { 1.0 });
            }
            // Only a zero Fresnel factor may drop a sample the unit model keeps.
            (None, Some(s1)) => {
                let fs = f.reflectance(0.5 * (wi + s1.wo).length(), lambda);
                worst = worst.max(if fs == 0.0 { 0.0 } else { 1.0 });
            }
            (Some(_), None) => worst = 1.0,
            (None, None) => {}
        }
        let sp = with.specular(wi, lambda);
        let sp1 = one.specular(wi, other);
        worst = worst
            .max(rel(sp.weight, f.reflectance(wi.z, lambda) * sp1.weight))
            .max(rel(sp.probability, sp1.probability));
    }
    worst
}

#[test]
fn fresnel_only_models_factor_and_the_others_do_not() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for model in models() {
        let kind = model.kind();
        let worst = fresnels()
            .iter()
            .map(|f| worst_departure(&model, f, &mut rng))
            .fold(0.0f64, f64::max);
        if kind.fresnel_only() {
            assert!(worst < 1e-12, "{kind:?}: departs by {worst:e}");
        } else {
            assert!(
                worst > 1e-3,
                "{kind:?} factors ({worst:e}): mark it fresnel_only"
            );
        }
    }
    // Every kind is classified by a case above, or has no Fresnel factor to
    // split off at all (diffuse, roughplastic: their spec refuses one).
    for kind in ModelKind::ALL {
        let covered = models().iter().any(|m| m.kind() == kind);
        assert!(
            // The full measured models: slow tables, the same λ dependence as the SSA's.
            covered
                || matches!(
                    kind,
                    ModelKind::MeasuredPsd | ModelKind::MeasuredPsdAniso | ModelKind::MeasuredPsd2d
                )
                || !kind.conductor(),
            "{kind:?} untested"
        );
        if !kind.conductor() {
            assert!(!kind.fresnel_only(), "{kind:?}");
        }
    }
    assert!(!ModelKind::MeasuredPsd.fresnel_only());
}

/// A model that says its `sample` ignores `u[0]` must give the same sample
/// whatever `u[0]` is; the microfacet and smooth conductors say so (the
/// renderer then skips computing that number), the wave-optical models,
/// which choose between a delta and a glossy lobe with it, do not.
#[test]
fn single_lobe_models_ignore_the_lobe_choice() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    for model in models() {
        let kind = model.kind();
        let m = MaterialSpec {
            model: model.clone(),
            fresnel: FresnelSpec::Metal(Metal::Au),
        }
        .build()
        .unwrap();
        assert_eq!(m.uses_lobe_choice(), !kind.fresnel_only(), "{kind:?}");
        let mut reads = false;
        for _ in 0..2000 {
            let wi = frame::spherical(1.5 * rng.f64(), TAU * rng.f64());
            let lambda = 360.0 + 470.0 * rng.f64();
            let (u1, u2) = (rng.f64(), rng.f64());
            let a = m.sample(wi, lambda, [0.003, u1, u2]);
            let b = m.sample(wi, lambda, [0.997, u1, u2]);
            if m.uses_lobe_choice() {
                reads |= a != b;
            } else {
                assert_eq!(a, b, "{kind:?}");
            }
        }
        assert!(!m.uses_lobe_choice() || reads, "{kind:?} never reads u[0]");
    }
}

/// Largest difference of value, pdf, sampled direction and weight between
/// 400 nm and 700 nm over random directions: zero for a λ-free model.
fn lambda_departure(m: &MaterialSpec, rng: &mut Rng) -> f64 {
    let b = m.build().unwrap();
    let mut worst = 0.0f64;
    let dir = |rng: &mut Rng| {
        let (ct, phi) = (rng.f64().max(1e-3), TAU * rng.f64());
        let st = (1.0 - ct * ct).sqrt();
        glam::DVec3::new(st * phi.cos(), st * phi.sin(), ct)
    };
    for _ in 0..200 {
        let (wi, wo) = (dir(rng), dir(rng));
        let (a, c) = (b.eval_pdf(wi, wo, 400.0), b.eval_pdf(wi, wo, 700.0));
        worst = worst.max((a.0 - c.0).abs()).max((a.1 - c.1).abs());
        let u = [rng.f64(), rng.f64(), rng.f64()];
        match (b.sample(wi, 400.0, u), b.sample(wi, 700.0, u)) {
            (Some(s), Some(t)) => {
                worst = worst
                    .max((s.wo - t.wo).length())
                    .max((s.weight - t.weight).abs())
                    .max((s.pdf - t.pdf).abs());
            }
            (None, None) => {}
            _ => worst = f64::INFINITY,
        }
    }
    worst
}

/// `MaterialSpec::lambda_free` lets a renderer carry a vertex's factor as
/// one number for every wavelength: the models it names must not change
/// with λ, and the ones it excludes must.
#[test]
fn lambda_free_models_do_not_change_with_wavelength() {
    use brdf::spec::ReflectanceSpec;
    let mut rng = Rng(0x5151_2323_abab_7777);
    let plastic = |reflectance| ModelSpec::RoughPlastic {
        alpha: 0.2,
        int_ior: 1.5,
        ext_ior: 1.0,
        reflectance,
        nonlinear: false,
    };
    let table = || ReflectanceSpec::Table(vec![[400.0, 0.1], [700.0, 0.9]]);
    let one = |model| MaterialSpec {
        model,
        fresnel: FresnelSpec::One,
    };
    let mut cases = vec![
        one(ModelSpec::Diffuse {
            reflectance: ReflectanceSpec::Constant(0.4),
        }),
        one(ModelSpec::Diffuse {
            reflectance: table(),
        }),
        one(plastic(ReflectanceSpec::Constant(0.4))),
        one(plastic(table())),
    ];
    for model in models() {
        cases.push(one(model.clone()));
        cases.push(MaterialSpec {
            model,
            fresnel: FresnelSpec::Metal(Metal::Au),
        });
    }
    for m in cases {
        let worst = lambda_departure(&m, &mut rng);
        if m.lambda_free() {
            assert_eq!(worst, 0.0, "{m:?}");
        } else {
            assert!(worst > 1e-6, "{:?} is λ-free ({worst:e})", m.model.kind());
        }
    }
}
