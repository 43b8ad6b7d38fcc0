//! The render loop reports its progress through a callback: the samples it
//! announces at the start are exactly those it reports done, every pass is
//! reported with the film's spp, and the loop says when it ends.

use render::{Progress, ProgressEvent, RenderOptions, load_str};
use std::path::Path;
use std::sync::{Arc, Mutex};

const SCENE: &str = r#"
[camera]
look_from = [0.0, 0.6, 1.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [21, 13]

[film]
spp = 8

[materials.plate]
model = "ggx"
alpha = 0.3
metal = "cu"

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "plate"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "environment"
radiance = 1.0
"#;

#[test]
fn progress_events_add_up() {
    let scene = load_str(Path::new("progress.toml"), SCENE).unwrap();
    let events: Arc<Mutex<Vec<ProgressEvent>>> = Arc::default();
    let sink = events.clone();
    let opts = RenderOptions {
        threads: Some(2),
        progress: Some(Progress::new(move |e| sink.lock().unwrap().push(e))),
        ..RenderOptions::default()
    };
    let mut film = scene.film().unwrap();
    render::render_range(&scene, &mut film, 0..37, &opts).unwrap();
    let events = events.lock().unwrap();
    assert_eq!(
        events.first(),
        Some(&ProgressEvent::Start {
            total: 21 * 13 * 37
        })
    );
    assert_eq!(events.last(), Some(&ProgressEvent::Finish));
    let done: u64 = events
        .iter()
        .map(|e| match e {
            ProgressEvent::Advance { samples } => *samples,
            _ => 0,
        })
        .sum();
    assert_eq!(done, 21 * 13 * 37);
    let passes: Vec<u64> = events
        .iter()
        .filter_map(|e| match e {
            ProgressEvent::Pass { spp } => Some(*spp),
            _ => None,
        })
        .collect();
    assert_eq!(passes.last(), Some(&37));
    assert!(passes.windows(2).all(|w| w[0] < w[1]), "{passes:?}");
}
