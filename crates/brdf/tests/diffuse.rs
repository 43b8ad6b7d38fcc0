//! The Lambertian reflector (`model = "diffuse"`): chi-square of its cosine
//! sampling against its pdf, the white furnace (ρ = 1 reflects everything, by
//! quadrature and by sampling), the closed form ρ(λ)/π, reciprocity, and the
//! albedo ρ ≤ 1 over the whole accepted domain through `brdf::spec`.

use std::f64::consts::{FRAC_1_PI, PI};

use brdf::frame::spherical;
use brdf::spec::{FileLoader, MaterialDesc, MaterialSpec, NoFiles};
use brdf::testing::{Chi2Config, Pcg32, albedo_quadrature, albedo_sampled, chi2_test, sidak};
use brdf::{Bxdf, DVec3, Diffuse, Reflectance};
use proptest::prelude::*;

const THETAS_DEG: [f64; 5] = [0.0, 30.0, 60.0, 80.0, 89.5];

fn grey_green() -> Reflectance {
    Reflectance::table(vec![
        [380.0, 0.05],
        [500.0, 0.2],
        [550.0, 0.7],
        [780.0, 0.4],
    ])
    .unwrap()
}

fn wi_at(theta_deg: f64) -> DVec3 {
    spherical(theta_deg.to_radians(), 0.7)
}

#[test]
fn chi_square_of_cosine_sampling() {
    let m = Diffuse::new(grey_green());
    let cfg = Chi2Config {
        samples: 200_000,
        pilot_samples: 50_000,
        z_cells: 16,
        phi_cells: 16,
        ..Chi2Config::default()
    };
    for th in THETAS_DEG {
        let r = chi2_test(&m, wi_at(th), 520.0, &cfg);
        println!("θi {th}°: {r}");
        r.check(sidak(0.01, THETAS_DEG.len())).unwrap();
        assert!(r.dof > 50, "θi {th}°: {r}");
        assert_eq!(r.lost.0, 0, "θi {th}°: {r}");
    }
}

/// A sampler that puts its directions at density cos²θ·3/(2π) while claiming
/// cosθ/π must fail: the test can fail.
#[test]
fn chi_square_rejects_a_wrong_cosine_power() {
    struct Wrong(Diffuse);
    impl Bxdf for Wrong {
        fn eval(&self, wi: DVec3, wo: DVec3, l: f64) -> f64 {
            self.0.eval(wi, wo, l)
        }
        fn pdf(&self, wi: DVec3, wo: DVec3, l: f64) -> f64 {
            self.0.pdf(wi, wo, l)
        }
        fn sample(&self, wi: DVec3, l: f64, u: [f64; 3]) -> Option<brdf::BxdfSample> {
            // cosθ = u^(1/3): density ∝ cos²θ.
            let z = u[1].cbrt();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let wo = DVec3::new(r * (2.0 * PI * u[2]).cos(), r * (2.0 * PI * u[2]).sin(), z);
            let pdf = self.0.pdf(wi, wo, l);
            (pdf > 0.0).then(|| brdf::BxdfSample {
                wo,
                weight: self.0.eval(wi, wo, l) * wo.z / pdf,
                pdf,
                is_delta: false,
            })
        }
    }
    let m = Wrong(Diffuse::new(Reflectance::constant(0.5).unwrap()));
    let cfg = Chi2Config {
        samples: 100_000,
        pilot_samples: 30_000,
        ..Chi2Config::default()
    };
    let r = chi2_test(&m, wi_at(30.0), 550.0, &cfg);
    assert!(!r.passes(0.01), "{r}");
}

#[test]
fn white_furnace_reflects_everything() {
    let m = Diffuse::new(Reflectance::constant(1.0).unwrap());
    for th in THETAS_DEG {
        let wi = wi_at(th);
        let q = albedo_quadrature(&m, wi, 550.0, 1e-10);
        assert!(q.converged, "θi {th}°: {q:?}");
        assert!((q.value - 1.0).abs() < 1e-8, "θi {th}°: {q:?}");
        // Every sample's weight is ρ itself: the sampled albedo is exact.
        let s = albedo_sampled(&m, wi, 550.0, 20_000, 3);
        assert_eq!((s.mean, s.std_error, s.lost_fraction), (1.0, 0.0, 0.0));
    }
}

#[test]
fn closed_form_reciprocity_and_horizon() {
    let m = Diffuse::new(grey_green());
    let mut rng = Pcg32::new(11, 0);
    for _ in 0..2000 {
        let wi = spherical(rng.next_f64() * 0.5 * PI, rng.next_f64() * 2.0 * PI);
        let wo = spherical(rng.next_f64() * 0.5 * PI, rng.next_f64() * 2.0 * PI);
        let l = 360.0 + 470.0 * rng.next_f64();
        // ρ(λ) by hand: linear between the rows, held outside.
        let rho = match l {
            l if l <= 380.0 => 0.05,
            l if l <= 500.0 => 0.05 + 0.15 * (l - 380.0) / 120.0,
            l if l <= 550.0 => 0.2 + 0.5 * (l - 500.0) / 50.0,
            l if l <= 780.0 => 0.7 - 0.3 * (l - 550.0) / 230.0,
            _ => 0.4,
        };
        let f = m.eval(wi, wo, l);
        assert!(
            (f - rho * FRAC_1_PI).abs() < 1e-14,
            "{l} nm: {f} vs {rho}/π"
        );
        assert_eq!(f, m.eval(wo, wi, l));
        assert!((m.pdf(wi, wo, l) - wo.z * FRAC_1_PI).abs() < 1e-15);
        let below = DVec3::new(wo.x, wo.y, -wo.z);
        assert_eq!((m.eval(wi, below, l), m.pdf(wi, below, l)), (0.0, 0.0));
        assert_eq!((m.eval(below, wo, l), m.pdf(below, wo, l)), (0.0, 0.0));
    }
    let horizon = DVec3::new(1.0, 0.0, 0.0);
    assert_eq!(m.eval(horizon, wi_at(10.0), 550.0), 0.0);
    assert!(m.sample(horizon, 550.0, [0.5; 3]).is_none());
}

/// Reads `grey.csv` as a scene's loader would, from memory.
struct Csv(Vec<[f64; 2]>);

impl FileLoader for Csv {
    fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
        Err(format!("{path}: not here"))
    }
    fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
        Err(format!("{path}: not here"))
    }
    fn reflectance_table(&mut self, _: &str) -> Result<Vec<[f64; 2]>, String> {
        Ok(self.0.clone())
    }
}

fn spec(json: &str, files: &mut dyn FileLoader) -> MaterialSpec {
    let d: MaterialDesc = serde_json::from_str(json).unwrap();
    d.into_spec(files).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Over the accepted domain (ρ ∈ [0, 1], constant or tabulated, any
    /// incidence and λ), the built model's albedo by the spec's own
    /// quadrature is ρ(λ) ≤ 1, sampling weights are ρ(λ), and eval and pdf
    /// are finite and non-negative.
    #[test]
    fn albedo_is_the_reflectance_and_at_most_one(
        rho in 0.0..=1.0f64,
        rows in prop::collection::vec(0.0..=1.0f64, 1..6),
        table in any::<bool>(),
        theta in 0.0..89.9f64,
        l in 360.0..830.0f64,
        u in prop::array::uniform3(0.0..1.0f64),
    ) {
        let s = if table {
            let rows: Vec<[f64; 2]> = (rows.iter().enumerate())
                .map(|(i, r)| [400.0 + 60.0 * i as f64, *r])
                .collect();
            spec(r#"{"model": "diffuse", "reflectance_csv": "t.csv"}"#, &mut Csv(rows))
        } else {
            spec(&format!(r#"{{"model": "diffuse", "reflectance": {rho}}}"#), &mut NoFiles)
        };
        let m = s.build().unwrap();
        let expected = match &s.model {
            brdf::spec::ModelSpec::Diffuse { reflectance } => reflectance.build().unwrap().at(l),
            other => panic!("{other:?}"),
        };
        let wi = spherical(theta.to_radians(), 1.0);
        let a = s.albedo(&m, wi, l);
        prop_assert!(a.total() <= 1.0 + 1e-9, "{a:?}");
        prop_assert!((a.total() - expected).abs() < 1e-6, "{a:?} vs ρ {expected}");
        if let Some(x) = m.sample(wi, l, u) {
            prop_assert!((x.weight - expected).abs() < 1e-15);
            let (f, pdf) = m.eval_pdf(wi, x.wo, l);
            prop_assert!(f.is_finite() && f >= 0.0 && pdf > 0.0);
            prop_assert!((x.pdf - pdf).abs() <= 1e-12 * pdf);
        } else {
            prop_assert_eq!(expected, 0.0);
        }
    }
}
