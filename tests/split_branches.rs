//! `[integrator] branches` (`render::integrator`'s first-vertex
//! splitting): a camera sample that goes on from its first vertex along k
//! BSDF samples of weight 1/k renders the same image, in the mean, as one
//! that goes on along one: λ-exact paths and paths that hand over to
//! sampled wavelengths, sampled wavelengths from the camera, Russian
//! roulette from the first bounce, a delta lobe mixed with others, the
//! Sobol sampler's branch points and the independent sampler's. And the
//! branches lower the error of light that bounced more than once.

#[path = "support/paired.rs"]
mod paired;
#[path = "support/scene_fixtures.rs"]
mod scene_fixtures;

use paired::{batch_variance, paired};
use render::Scene;
use scene_fixtures::{BALL_CAMERA as CAMERA, ball_and_mirror};
use std::path::Path;

/// [`ball_and_mirror`] (a copper ball, where λ-exact paths hand over to
/// sampled wavelengths at a second conductor vertex, and a mirror beside
/// it) under a dim environment besides its small light.
fn ball() -> String {
    format!(
        "{}\n[[lights]]\ntype = \"environment\"\nradiance = 0.2\nspectrum = \"a\"\n",
        ball_and_mirror()
    )
}

fn scene(settings: &str, k: u32) -> Scene {
    let text = format!(
        "{CAMERA}\n[integrator]\nbranches = {k}\n{settings}\n{}",
        ball()
    );
    render::load_str(Path::new("split_branches.toml"), &text).unwrap()
}

/// The split and unsplit renders agree within 4.5 standard errors of their
/// paired difference on every channel, and the comparison can see a 3 %
/// error. (A weight of 1/(k − 1) instead of 1/k at k = 4 moves the
/// multi-bounce part by a third.)
fn agree(name: &str, settings: &str, k: u32, spp: u64) {
    let (one, split) = (scene(settings, 1), scene(settings, k));
    for (c, (ma, mb, d, e)) in paired(&split, &one, spp).into_iter().enumerate() {
        let z = d / e;
        eprintln!(
            "{name} channel {c}: {k} branches {ma:.6}, one {mb:.6}, difference {d:+.2e} ± {e:.2e} (z = {z:+.2})"
        );
        assert!(e < 6e-3 * mb.abs(), "{name}: too noisy to compare");
        assert!(z.abs() < 4.5, "{name} channel {c}: z = {z}");
    }
}

#[test]
fn lambda_exact_paths_with_the_sobol_sampler() {
    agree("exact, sobol", "max_depth = 4", 4, 2000);
}

#[test]
fn independent_sampler_and_roulette_from_the_first_bounce() {
    agree(
        "exact, independent, rr 1",
        "max_depth = 6\nrr_depth = 1\nsampler = \"independent\"",
        3,
        2000,
    );
}

#[test]
fn sampled_wavelengths_from_the_camera() {
    agree(
        "sampled",
        "max_depth = 4\nspectral_integration = \"sampled\"",
        4,
        2000,
    );
}

#[test]
fn sampled_wavelengths_with_roulette_and_balance() {
    agree(
        "sampled, rr 1, balance",
        "max_depth = 5\nrr_depth = 1\nmis = \"balance\"\nspectral_integration = \"sampled\"\nsampler = \"independent\"",
        2,
        2000,
    );
}

/// Variance of 8-sample pixel estimates over the floor beside the ball,
/// whose light is mostly the ball's glint (paths that bounce twice): four
/// branches must lower it to well under what one gives.
#[test]
fn branches_lower_the_error_of_light_that_bounced_twice() {
    let load = |k: u32| {
        let text = format!(
            "[camera]\nlook_from = [0.7, 1.5, 0.1]\nlook_at = [0.7, 0.0, 0.1]\nup = [0.0, 0.0, -1.0]\n\
             fov_deg = 30.0\nresolution = [6, 5]\n[film]\nspp = 1\n\
             [integrator]\nmax_depth = 3\nbranches = {k}\n{}",
            ball()
        );
        render::load_str(Path::new("split_branches.toml"), &text).unwrap()
    };
    let variance = |s: &Scene| batch_variance(s, 200, 8);
    let (v1, v4) = (variance(&load(1)), variance(&load(4)));
    eprintln!("variance of an 8-spp pixel (Y): one branch {v1:.4e}, four {v4:.4e}");
    assert!(v4 < 0.5 * v1, "{v4} vs {v1}");
}

#[test]
fn out_of_range_branch_counts_are_refused() {
    for bad in ["0", "65"] {
        let text = format!("{CAMERA}\n[integrator]\nbranches = {bad}\n{}", ball());
        let e = render::load_str(Path::new("bad.toml"), &text)
            .err()
            .unwrap_or_else(|| panic!("{bad} accepted"))
            .to_string();
        assert!(e.contains("branches") && e.contains("64"), "{e}");
    }
}
