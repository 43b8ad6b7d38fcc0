//! `with_fresnel` shares a model's tables with another Fresnel term: the
//! result must be the model built from scratch with that term, bit for bit
//! (`brdf eval` serves metals from one build per surface this way).

use brdf::statistics::KcPsd;
use brdf::wave::two_scale::{CoherentPart, TableResolution, TwoScale, TwoScaleParams};
use brdf::wave::{Energy, GhsOptions, GhsSsa};
use brdf::{Bxdf, Fresnel, Ior, Metal, frame};

fn same(a: &dyn Bxdf, b: &dyn Bxdf, what: &str) {
    for ti in [0.0f64, 0.4, 1.0, 1.45] {
        let wi = frame::spherical(ti, 0.0);
        for lam in [380.0, 550.0, 800.0] {
            assert_eq!(
                a.specular(wi, lam).weight.to_bits(),
                b.specular(wi, lam).weight.to_bits(),
                "{what}"
            );
            for (to, po) in [(0.0, 0.0), (0.3, 3.0), (1.2, 2.0), (0.7, 0.5)] {
                let wo = frame::spherical(to, po);
                assert_eq!(
                    a.eval(wi, wo, lam).to_bits(),
                    b.eval(wi, wo, lam).to_bits(),
                    "{what} θi {ti} θo {to} λ {lam}"
                );
                assert_eq!(a.pdf(wi, wo, lam).to_bits(), b.pdf(wi, wo, lam).to_bits());
            }
        }
    }
}

#[test]
fn ssa_with_fresnel_is_a_fresh_build() {
    let psd = KcPsd::new(0.14, 2.0, 2.0).unwrap();
    for energy in [Energy::Raw, Energy::Krywonos, Energy::SigmaRel] {
        let opts = GhsOptions {
            energy,
            ..GhsOptions::default()
        };
        let one = GhsSsa::with_options(psd, Fresnel::One, opts).unwrap();
        for metal in [Metal::Cu, Metal::Au, Metal::BrassCu70Zn30] {
            let f = Fresnel::conductor(Ior::metal(metal));
            let fresh = GhsSsa::with_options(psd, f.clone(), opts).unwrap();
            let shared = one.with_fresnel(f).unwrap();
            same(&fresh, &shared, &format!("ssa {energy:?} {metal:?}"));
        }
    }
}

#[test]
fn two_scale_with_fresnel_is_a_fresh_build() {
    let params = |fresnel| TwoScaleParams {
        beta: 0.05,
        sigma_um: 0.1,
        lc_um: 2.0,
        gamma: 2.5,
        fresnel,
        coherent: CoherentPart::MacroNdf,
        resolution: TableResolution {
            w_nodes: 8,
            theta_nodes: 16,
        },
    };
    let one = TwoScale::new(params(Fresnel::One)).unwrap();
    for metal in [Metal::Cu, Metal::Al] {
        let f = Fresnel::conductor(Ior::metal(metal));
        let fresh = TwoScale::new(params(f.clone())).unwrap();
        same(
            &fresh,
            &one.with_fresnel(f).unwrap(),
            &format!("two-scale {metal:?}"),
        );
    }
}
