//! The harnesses tested on a toy model with exact, closed-form sampling:
//! they must accept it, and reject it when sampling and pdf disagree.

extern crate std;

use core::f64::consts::PI;

use glam::DVec3;

use super::*;
use crate::frame::{orthonormal_basis, reflect_z, spherical};
use crate::model::{Bxdf, BxdfSample, Specular};

/// A cosine-power lobe cos^n(∠(wo, mirror)) around the mirror direction,
/// clipped by the horizon, mixed with a specular delta of probability
/// `p_delta`. Each sabotage knob makes `sample` disagree with `pdf`.
#[derive(Clone, Copy)]
struct Toy {
    /// Exponent `pdf` believes in.
    n_pdf: f64,
    /// Exponent `sample` uses.
    n_sample: f64,
    /// Delta probability `specular` reports.
    p_delta: f64,
    /// Delta probability `sample` uses.
    p_delta_sample: f64,
    /// Delta weight (energy).
    w_delta: f64,
    /// Glossy weight scale k: eval · cos / pdf = k / (1 − p_delta).
    k: f64,
    /// Fraction of glossy samples silently dropped.
    extra_loss: f64,
}

impl Toy {
    fn exact(n: f64, p_delta: f64) -> Toy {
        Toy {
            n_pdf: n,
            n_sample: n,
            p_delta,
            p_delta_sample: p_delta,
            w_delta: 0.3,
            k: 0.6,
            extra_loss: 0.0,
        }
    }

    fn lobe(&self, wi: DVec3, wo: DVec3) -> f64 {
        let c = wo.dot(reflect_z(wi));
        if wo.z <= 0.0 || c <= 0.0 {
            0.0
        } else {
            (self.n_pdf + 1.0) / (2.0 * PI) * libm::pow(c, self.n_pdf)
        }
    }
}

impl Bxdf for Toy {
    fn eval(&self, wi: DVec3, wo: DVec3, _l: f64) -> f64 {
        if wo.z <= 0.0 {
            0.0
        } else {
            self.k * self.lobe(wi, wo) / wo.z
        }
    }
    fn pdf(&self, wi: DVec3, wo: DVec3, _l: f64) -> f64 {
        (1.0 - self.p_delta) * self.lobe(wi, wo)
    }
    fn sample(&self, wi: DVec3, l: f64, u: [f64; 3]) -> Option<BxdfSample> {
        let s = reflect_z(wi);
        if u[0] < self.p_delta_sample {
            return Some(BxdfSample {
                wo: s,
                weight: self.w_delta / self.p_delta,
                pdf: self.p_delta,
                is_delta: true,
            });
        }
        if (u[0] - self.p_delta_sample) / (1.0 - self.p_delta_sample) < self.extra_loss {
            return None;
        }
        let cos_a = libm::pow(u[1], 1.0 / (self.n_sample + 1.0));
        let local = spherical(libm::acos(cos_a), 2.0 * PI * u[2]);
        let (t, b) = orthonormal_basis(s);
        let wo = (t * local.x + b * local.y + s * local.z).normalize();
        let pdf = self.pdf(wi, wo, l);
        if wo.z <= 0.0 || pdf <= 0.0 {
            return None;
        }
        Some(BxdfSample {
            wo,
            weight: self.eval(wi, wo, l) * wo.z / pdf,
            pdf,
            is_delta: false,
        })
    }
    fn specular(&self, _wi: DVec3, _l: f64) -> Specular {
        Specular {
            weight: self.w_delta,
            probability: self.p_delta,
        }
    }
}

fn wi(theta_deg: f64) -> DVec3 {
    spherical(theta_deg.to_radians(), 0.4)
}

fn cfg() -> Chi2Config {
    Chi2Config {
        samples: 200_000,
        pilot_samples: 50_000,
        ..Chi2Config::default()
    }
}

#[test]
fn accepts_exact_sampling_including_delta_and_horizon_loss() {
    for (n, p_delta, th) in [
        (200.0, 0.0, 0.0),
        (200.0, 0.25, 60.0),
        (20.0, 0.1, 85.0),
        (2e6, 0.0, 30.0),
        (1.0, 0.5, 89.0),
    ] {
        let r = chi2_test(&Toy::exact(n, p_delta), wi(th), 550.0, &cfg());
        std::println!("n {n} p_delta {p_delta} θ {th}: {r}");
        r.check(0.01).unwrap();
        assert!(r.dof > 100, "{r}");
    }
}

#[test]
fn rejects_a_ten_percent_wrong_exponent() {
    let toy = Toy {
        n_sample: 180.0,
        ..Toy::exact(200.0, 0.0)
    };
    let r = chi2_test(&toy, wi(30.0), 550.0, &cfg());
    assert!(r.p_value < 1e-6, "{r}");
    // …and does so through the statistic, not through a consistency defect.
    assert_eq!(r.defect_count, 0, "{r}");
}

#[test]
fn rejects_a_wrong_delta_probability() {
    let toy = Toy {
        p_delta_sample: 0.27,
        ..Toy::exact(50.0, 0.25)
    };
    let r = chi2_test(&toy, wi(40.0), 550.0, &cfg());
    assert!(r.p_value < 1e-6 && r.defect_count == 0, "{r}");
}

#[test]
fn rejects_unaccounted_lost_samples() {
    let toy = Toy {
        extra_loss: 0.01,
        ..Toy::exact(50.0, 0.0)
    };
    let r = chi2_test(&toy, wi(20.0), 550.0, &cfg());
    assert!(r.p_value < 1e-6 && r.defect_count == 0, "{r}");
}

#[test]
fn flags_inconsistent_weights_as_defects() {
    /// Reports a pdf 1 % off in its samples.
    struct Liar(Toy);
    impl Bxdf for Liar {
        fn eval(&self, wi: DVec3, wo: DVec3, l: f64) -> f64 {
            self.0.eval(wi, wo, l)
        }
        fn pdf(&self, wi: DVec3, wo: DVec3, l: f64) -> f64 {
            self.0.pdf(wi, wo, l)
        }
        fn sample(&self, wi: DVec3, l: f64, u: [f64; 3]) -> Option<BxdfSample> {
            self.0.sample(wi, l, u).map(|s| BxdfSample {
                pdf: s.pdf * 1.01,
                ..s
            })
        }
    }
    let r = chi2_test(&Liar(Toy::exact(50.0, 0.0)), wi(20.0), 550.0, &cfg());
    assert!(r.defect_count > 0 && !r.passes(0.01), "{r}");
}

#[test]
fn furnace_matches_closed_form_and_both_estimators_agree() {
    // Normal incidence: the whole lobe is above the horizon, so the albedo is
    // exactly k + w_delta = 0.9.
    let toy = Toy::exact(500.0, 0.2);
    let q = albedo_quadrature(&toy, DVec3::Z, 550.0, 1e-9);
    assert!(q.converged && libm::fabs(q.value - 0.9) < 1e-8, "{q:?}");
    let s = albedo_sampled(&toy, DVec3::Z, 550.0, 100_000, 1);
    assert!(libm::fabs(s.mean - 0.9) < 4.0 * s.std_error, "{s:?}");
    // Oblique: part of the lobe is below the horizon; the two must agree.
    for th in [70.0, 88.0] {
        let toy = Toy::exact(30.0, 0.1);
        let q = albedo_quadrature(&toy, wi(th), 550.0, 1e-8);
        let s = albedo_sampled(&toy, wi(th), 550.0, 400_000, 2);
        assert!(q.converged && q.value < 0.89, "{q:?}");
        assert!(
            libm::fabs(q.value - s.mean) < 4.0 * s.std_error,
            "θ {th}: {q:?} vs {s:?}"
        );
    }
    // A broken sampler biases the sampled albedo, not the quadrature.
    let bad = Toy {
        extra_loss: 0.05,
        ..Toy::exact(500.0, 0.0)
    };
    let s = albedo_sampled(&bad, DVec3::Z, 550.0, 100_000, 3);
    assert!(libm::fabs(s.mean - 0.6) > 0.02, "{s:?}");
}
