//! Real instrument files against the reference table of data/surfaces/README.md
//! (SurfaceTopography 1.27.1 + scipy): Sq and RMS slope within 1 %, K-correlation
//! parameters within 5 % where the reference fit is not degenerate.

use fit::io::{ReadOptions, read_path};
use fit::{Topography, fill, kc, level, psd, stats};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name)
}

struct Reference {
    file: &'static str,
    sq: f64,
    rq_lines: Option<f64>,
    sdq: f64,
    rdq_x: Option<f64>,
    /// σ, L (README 1D form, cycles), γ
    kc: Option<(f64, f64, f64)>,
    f_range: (f64, f64),
}

const REFS: &[Reference] = &[
    Reference {
        file: "matrix-3.txt",
        sq: 3.5223e-08,
        rq_lines: Some(3.3981e-08),
        sdq: 0.1924,
        rdq_x: Some(0.1327),
        kc: Some((5.63e-08, 9.88e-06, 2.563)),
        f_range: (3.0e5, 6.4e6),
    },
    Reference {
        file: "di-3.di",
        sq: 3.5223e-08,
        rq_lines: Some(3.3981e-08),
        sdq: 0.1924,
        rdq_x: Some(0.1327),
        kc: Some((5.63e-08, 9.88e-06, 2.563)),
        f_range: (3.0e5, 6.4e6),
    },
    Reference {
        file: "di-6.di",
        sq: 1.4319e-08,
        rq_lines: Some(1.4108e-08),
        sdq: 0.2227,
        rdq_x: Some(0.1360),
        kc: Some((1.42e-08, 4.38e-07, 5.166)),
        f_range: (3.0e5, 1.28e7),
    },
    Reference {
        file: "dektak-1.csv",
        sq: 9.4243e-08,
        rq_lines: None,
        sdq: 0.00946,
        rdq_x: None,
        kc: Some((7.27e-09, 4.08e-06, 5.94)),
        f_range: (2.0e3, 1.6e6),
    },
    Reference {
        file: "KautschukInfiniteFocus.x3p",
        sq: 3.4006e-06,
        rq_lines: Some(3.2865e-06),
        sdq: 0.1360,
        rdq_x: Some(0.0971),
        kc: Some((2.58e-06, 1.49e-04, 4.042)),
        f_range: (1.53e3, 1.10e5),
    },
    Reference {
        file: "bcrf-1.bcrf",
        sq: 2.4367e-08,
        rq_lines: Some(2.3910e-08),
        sdq: 0.0199,
        rdq_x: Some(0.0117),
        kc: None,
        f_range: (1.69e3, 1.35e5),
    },
];

fn prepared(file: &str) -> Topography {
    let mut t = read_path(&data(file), &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    fill::harmonic(&mut t).unwrap();
    level::plane(&mut t).unwrap();
    t
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn statistics_match_reference_within_one_percent() {
    for r in REFS {
        let t = prepared(r.file);
        let s = stats::compute(&t);
        println!(
            "{}: Sq {:.5e} ({:+.3}%), Sdq {:.5} ({:+.3}%), Rq_lines {:.5e}, Rdq_x {:.5}",
            r.file,
            s.sq,
            100.0 * (s.sq / r.sq - 1.0),
            s.sdq,
            100.0 * (s.sdq / r.sdq - 1.0),
            s.rq_lines,
            s.rdq_x
        );
        assert!(
            rel(s.sq, r.sq) < 0.01,
            "{}: Sq {} vs {}",
            r.file,
            s.sq,
            r.sq
        );
        assert!(
            rel(s.sdq, r.sdq) < 0.01,
            "{}: Sdq {} vs {}",
            r.file,
            s.sdq,
            r.sdq
        );
        if let Some(rq) = r.rq_lines {
            assert!(
                rel(s.rq_lines, rq) < 0.01,
                "{}: Rq lines {} vs {rq}",
                r.file,
                s.rq_lines
            );
        }
        if let Some(rdq) = r.rdq_x {
            assert!(
                rel(s.rdq_x, rdq) < 0.01,
                "{}: Rdq_x {} vs {rdq}",
                r.file,
                s.rdq_x
            );
        }
    }
}

#[test]
fn kc_fits_match_reference_within_five_percent() {
    for r in REFS {
        let t = prepared(r.file);
        let p = psd::welch(&t, &psd::WelchOptions::default()).unwrap();
        let fit = kc::fit_bins(&p, 3, t.nx / 4).unwrap();
        let (lo, hi) = fit.range;
        assert!(
            rel(lo, r.f_range.0) < 0.01 && rel(hi, r.f_range.1) < 0.01,
            "{}: range {lo:e}..{hi:e}",
            r.file
        );
        let k = fit.params;
        println!(
            "{}: σ {:.4e} L {:.4e} γ {:.4} (±{:.2e}, ±{:.2e}, ±{:.3}) rms log res {:.3} degenerate {}",
            r.file,
            k.sigma,
            k.l_cycles(),
            k.gamma,
            fit.stderr.sigma,
            fit.stderr.lc * 2.0 * std::f64::consts::PI,
            fit.stderr.gamma,
            fit.rms_log_residual,
            fit.degenerate
        );
        match r.kc {
            Some((s, l, g)) => {
                println!(
                    "   deviations: σ {:+.2}%, L {:+.2}%, γ {:+.2}%",
                    100.0 * (k.sigma / s - 1.0),
                    100.0 * (k.l_cycles() / l - 1.0),
                    100.0 * (k.gamma / g - 1.0)
                );
                assert!(!fit.degenerate, "{}", r.file);
                assert!(rel(k.sigma, s) < 0.05, "{}: σ {} vs {s}", r.file, k.sigma);
                assert!(
                    rel(k.l_cycles(), l) < 0.05,
                    "{}: L {} vs {l}",
                    r.file,
                    k.l_cycles()
                );
                assert!(rel(k.gamma, g) < 0.05, "{}: γ {} vs {g}", r.file, k.gamma);
            }
            // The reference fit is degenerate (γ at its bound); ours must say so too.
            None => assert!(
                fit.degenerate,
                "{}: expected a degenerate fit, got {k:?}",
                r.file
            ),
        }
    }
}

#[test]
fn di3_and_matrix3_agree() {
    let a = prepared("di-3.di");
    let b = prepared("matrix-3.txt");
    assert_eq!((a.nx, a.ny), (b.nx, b.ny));
    assert!(rel(a.dx, b.dx) < 1e-12);
    let (sa, sb) = (stats::compute(&a), stats::compute(&b));
    println!("di-3 Sq {:e}, matrix-3 Sq {:e}", sa.sq, sb.sq);
    assert!(rel(sa.sq, sb.sq) < 1e-6, "Sq {} vs {}", sa.sq, sb.sq);
    assert!(rel(sa.sdq, sb.sdq) < 1e-3);
    // Same measurement point by point after levelling (the text export differs from the raw
    // channel by a plane), up to the 5 significant digits of the text export. The NanoScope
    // frame is stored bottom line first; the reader flips it.
    let (ra, rb) = (&a, &b);
    let offset = 0.0;
    let diff: Vec<f64> = ra
        .heights
        .iter()
        .zip(&rb.heights)
        .map(|(x, y)| x - offset - y)
        .collect();
    let rms = (diff.iter().map(|d| d * d).sum::<f64>() / diff.len() as f64).sqrt();
    let max = diff.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let ymax = rb.heights.iter().fold(0.0f64, |m, y| m.max(y.abs()));
    println!("point differences: rms {rms:e} m, max {max:e} m (largest |z| {ymax:e} m)");
    assert!(rms < 1e-4 * sa.sq, "{rms}");
    assert!(max < 5e-5 * ymax, "{max}");
}
