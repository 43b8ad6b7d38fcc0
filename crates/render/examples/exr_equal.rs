//! Compares the pixel data of EXR files pairwise, bit for bit:
//! `cargo run --release -p render --example exr_equal -- A.exr B.exr [A2.exr B2.exr …]`.
//! Prints one line per pair (identical, or the differing pixel count and the
//! largest difference) and exits with status 1 when any pair differs. EXR
//! files of the same pixels may differ as bytes (chunk order of the parallel
//! compression), so `cmp` cannot tell.

use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() || !args.len().is_multiple_of(2) {
        eprintln!("usage: exr_equal A.exr B.exr [A2.exr B2.exr …]");
        std::process::exit(2);
    }
    let mut all_equal = true;
    for pair in args.chunks(2) {
        let read = |p: &str| {
            render::output::read_exr(Path::new(p)).unwrap_or_else(|e| {
                eprintln!("{e}");
                std::process::exit(2)
            })
        };
        let (a, b) = (read(&pair[0]), read(&pair[1]));
        if (a.0, a.1) != (b.0, b.1) {
            println!("{} {}: sizes differ", pair[0], pair[1]);
            all_equal = false;
            continue;
        }
        let (mut differing, mut largest) = (0usize, 0.0f32);
        for (p, q) in a.2.iter().zip(&b.2) {
            if p.iter().zip(q).any(|(x, y)| x.to_bits() != y.to_bits()) {
                differing += 1;
                for (x, y) in p.iter().zip(q) {
                    largest = largest.max((x - y).abs());
                }
            }
        }
        if differing == 0 {
            println!("identical  {} ({}×{})", pair[0], a.0, a.1);
        } else {
            all_equal = false;
            println!(
                "DIFFERENT  {}: {differing} of {} pixels, largest difference {largest:e}",
                pair[0],
                a.2.len()
            );
        }
    }
    if !all_equal {
        std::process::exit(1);
    }
}
