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

/// The log10 rms error of the model `key` in a judge report, if it was ranked.
// Not every test file that shares this module looks models up.
#[allow(dead_code)]
pub fn model(j: &Value, key: &str) -> Option<f64> {
    j["models"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["key"] == key)
        .map(|m| m["log10_rms_error"].as_f64().unwrap())
}
