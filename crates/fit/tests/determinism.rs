//! The analysis of a scan is the same, to the bit, on any number of threads:
//! a fit, a `judge` ranking or a material file must not change with the
//! machine or with scheduling (parallel sums are added in a fixed order).

use fit::io::{ReadOptions, read_path};
use fit::pipeline::summarise;
use fit::psd;
use std::path::Path;

fn scan(name: &str) -> fit::Topography {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name);
    read_path(&p, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// Everything `fit stats` reports and the radial PSD, as text with every
/// float's exact digits (Debug prints the shortest round-trip form).
fn analysis(t: &fit::Topography) -> String {
    let s = summarise(t.clone(), None).unwrap();
    let radial = psd::radial(&s.prepared.scan).unwrap();
    format!(
        "{:?}\n{:?}\n{:?}\n{:?}\n{:?}",
        s.stats, s.line_psd, s.kc, s.anisotropy, radial
    )
}

#[test]
fn the_analysis_does_not_depend_on_the_thread_count() {
    for name in ["di-3.di", "di-6.di"] {
        let t = scan(name);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| analysis(&t))
        };
        let one = on(1);
        assert!(one.contains("KcFit"), "{name}: nothing analysed");
        for threads in [2, 3, 7] {
            // Repeats: work stealing splits differently from run to run.
            for _ in 0..3 {
                assert!(
                    on(threads) == one,
                    "{name}: {threads} threads differ from one"
                );
            }
        }
    }
}
