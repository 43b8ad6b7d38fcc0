//! The `[psd]` tables `lustre fit` writes for the measured-PSD model, on five synthetic
//! K-correlation maps and on every bundled real scan that yields one: the inputs of
//! `crates/brdf/tests/measured_psd_maps.rs`, which checks the full-GHS table of each against
//! the direct Hankel transform. The tables are committed under
//! `crates/brdf/tests/data/measured_psd/` (brdf's tests cannot depend on `fit`); the test
//! here checks that `fit`'s table route still makes exactly those tables from the synthetic
//! maps, and `--ignored` rewrites all of them (the real scans from `LUSTRE_SCANS`, a folder
//! holding the bundled scans, e.g. `../shared/data/surfaces`).

use std::path::{Path, PathBuf};

use fit::kc::KcParams;
use fit::pipeline::{Options, analyse};
use fit::sampled_kc::PointSampledKc;

/// (name, n, pixel µm, σ µm, Lc µm, γ, seed): 256²–512² maps, σ 0.01–0.5 µm.
pub const MAPS: [(&str, usize, f64, f64, f64, f64, u64); 5] = [
    ("kc_s0.01_256", 256, 0.1, 0.01, 1.0, 3.0, 11),
    ("kc_s0.05_256", 256, 0.05, 0.05, 0.5, 4.0, 12),
    ("kc_s0.1_512", 512, 0.1, 0.1, 2.0, 2.5, 13),
    ("kc_s0.2_512", 512, 0.2, 0.2, 5.0, 3.5, 14),
    ("kc_s0.5_512", 512, 0.05, 0.5, 1.0, 3.0, 15),
];

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../brdf/tests/data/measured_psd")
}

/// The measured-PSD table of one synthetic map, as `lustre fit` makes it.
fn map_table(i: usize) -> (Vec<f64>, Vec<f64>) {
    let (_, n, dx, s, lc, g, seed) = MAPS[i];
    let params = KcParams {
        sigma: s * 1e-6,
        lc: lc * 1e-6,
        gamma: g,
    };
    let topo = PointSampledKc::new(n, n, dx * 1e-6, params).realise(seed);
    let a = analyse(topo, None, &Options::default()).expect("analysis of a synthetic map");
    let (z, p, _) = fit::candidates::measured_table(&a).expect("a measured-PSD table");
    (z, p)
}

fn csv(source: &str, z: &[f64], p: &[f64]) -> String {
    let mut s = format!("# {source}\nzeta_rad_per_um,psd_um4\n");
    for (a, b) in z.iter().zip(p) {
        s += &format!("{a:e},{b:e}\n");
    }
    s
}

fn map_source(i: usize) -> String {
    let (_, n, dx, s, lc, g, seed) = MAPS[i];
    format!(
        "fit::candidates::measured_table of PointSampledKc {n}x{n}, pixel {dx} um, sigma {s} um, \
         Lc {lc} um, gamma {g}, seed {seed} (crates/fit/tests/measured_psd_tables.rs)"
    )
}

#[test]
fn the_committed_synthetic_tables_are_what_fit_makes() {
    for (i, m) in MAPS.iter().enumerate() {
        let (z, p) = map_table(i);
        let path = data_dir().join(format!("{}.csv", m.0));
        let have = std::fs::read_to_string(&path).unwrap_or_default();
        assert_eq!(
            have,
            csv(&map_source(i), &z, &p),
            "{}: rerun `cargo test -p fit --test measured_psd_tables -- --ignored`",
            path.display()
        );
    }
}

#[test]
#[ignore = "rewrites crates/brdf/tests/data/measured_psd (LUSTRE_SCANS: the bundled scans)"]
fn write_tables() {
    let dir = data_dir();
    std::fs::create_dir_all(&dir).unwrap();
    for (i, m) in MAPS.iter().enumerate() {
        let (z, p) = map_table(i);
        std::fs::write(
            dir.join(format!("{}.csv", m.0)),
            csv(&map_source(i), &z, &p),
        )
        .unwrap();
    }
    let Ok(root) = std::env::var("LUSTRE_SCANS") else {
        return;
    };
    let mut files = Vec::new();
    for d in [PathBuf::from(&root), Path::new(&root).join("corpus")] {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if p.is_file() && !name.ends_with(".md") && !name.ends_with(".json") {
                files.push(p);
            }
        }
    }
    files.sort();
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let table = fit::io::read_path(&f, &fit::io::ReadOptions::default())
            .map_err(|e| e.to_string())
            .and_then(|t| analyse(t, None, &Options::default()).map_err(|e| e.to_string()))
            .and_then(|a| fit::candidates::measured_table(&a));
        match table {
            Ok((z, p, _)) => {
                let stem = name.replace('.', "_");
                let src = format!("fit::candidates::measured_table of {name} (bundled scan)");
                std::fs::write(dir.join(format!("scan_{stem}.csv")), csv(&src, &z, &p)).unwrap();
                println!("{name}: {} rows", z.len());
            }
            Err(e) => println!("{name}: no table: {e}"),
        }
    }
}
