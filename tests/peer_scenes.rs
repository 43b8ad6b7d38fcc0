//! The Mitsuba peer's plate files (`benches/peer/*.toml`) hold lustre scene
//! tables that the peer scripts and `benches/error_vs_time.rs` render as they
//! are. A validation rule added to the scene reader can make one of them
//! unrenderable without any other test noticing (it happened: `metal` beside
//! `fresnel = "one"`), and the peer benchmarks then stop half-way. So every
//! plate must load and give a finite, non-negative pixel.

use render::integrator::sample_pixel;
use std::path::Path;

fn plates(file: &str) -> Vec<(String, String)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
    let table: toml::Table = toml::from_str(&text).unwrap_or_else(|e| panic!("{file}: {e}"));
    let scenes = table
        .get("scene")
        .and_then(|s| s.as_array())
        .unwrap_or_else(|| panic!("{file}: no [[scene]] entries"));
    scenes
        .iter()
        .map(|sc| {
            let mut t = sc
                .as_table()
                .cloned()
                .unwrap_or_else(|| panic!("{file}: a [[scene]] is not a table"));
            let name = t
                .remove("name")
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_else(|| panic!("{file}: a [[scene]] has no name"));
            t.remove("description");
            // The peer scripts add the film (sample count, outputs) per run.
            let mut film = toml::Table::new();
            film.insert("spp".into(), toml::Value::Integer(16));
            t.insert("film".into(), toml::Value::Table(film));
            (name, t.to_string())
        })
        .collect()
}

#[test]
fn every_peer_plate_is_a_valid_lustre_scene() {
    let mut n = 0;
    for file in [
        "benches/peer/plate_scenes.toml",
        "benches/peer/other_plates.toml",
    ] {
        for (name, text) in plates(file) {
            let path = Path::new(file).join(&name);
            let scene = render::load_str(&path, &text)
                .unwrap_or_else(|e| panic!("{file}: scene {name}: {e:#}"));
            let (w, h) = (scene.camera.width, scene.camera.height);
            let mut sum = [0.0; 3];
            for s in 0..16 {
                let p = sample_pixel(&scene, w / 2, h / 2, s);
                for c in 0..3 {
                    sum[c] += p[c];
                }
            }
            assert!(
                sum.iter().all(|v| v.is_finite() && *v >= 0.0),
                "{name}: centre pixel {sum:?}"
            );
            n += 1;
        }
    }
    assert_eq!(
        n, 12,
        "nine plates in plate_scenes.toml, three in other_plates.toml"
    );
}
