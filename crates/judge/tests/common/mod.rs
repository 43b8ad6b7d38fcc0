//! Scaffolding shared by the synthetic-map judge tests.

use brdf::Metal;
use serde_json::Value;

/// `judge`'s report (JSON) of a synthetic map as the tests compare models on it: copper at
/// 550 nm, θi 0° and 45°, without the Gaussian surrogate.
pub fn judge_cu(t: fit::Topography) -> Value {
    let opts = judge::Options {
        metal: Some(Metal::Cu),
        lambda_nm: vec![550.0],
        theta_i_deg: vec![0.0, 45.0],
        surrogate: false,
        ..judge::Options::default()
    };
    judge::judge("synthetic", t, &opts, &mut |_| {})
        .unwrap()
        .json()
}
