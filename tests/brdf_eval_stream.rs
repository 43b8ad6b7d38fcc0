//! `lustre brdf eval` as a stream others script against: a bad line gets an
//! error object and the stream goes on (invalid UTF-8, overlong lines,
//! malformed JSON, unknown or repeated keys), misspelt keys are refused
//! with the list of valid ones, and θ = 90° lies exactly on the horizon.

use std::io::Write;
use std::process::{Command, Stdio};

use serde_json::Value;

fn run(input: &[u8]) -> Vec<Value> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(["brdf", "eval"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run lustre");
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    // Write from a thread: the answers fill the stdout pipe meanwhile.
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).expect("each output line is JSON"))
        .collect()
}

const GOOD: &str = r#"{"model": "ggx", "alpha": 0.2, "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "none"}"#;

#[test]
fn bad_lines_get_error_objects_and_the_stream_goes_on() {
    let mut input = Vec::new();
    let mut line = |b: &[u8]| {
        input.extend_from_slice(b);
        input.push(b'\n');
    };
    line(GOOD.as_bytes());
    line(b"{\"model\": \"ggx\", \"alpha\": 0.2, \"fresnel\": \"caf\xe9\"}"); // Latin-1 é
    line(&[0xff, 0xfe, 0xfd]);
    line(GOOD.as_bytes());
    line(&vec![b' '; 2 << 20]); // 2 MiB of spaces: longer than a line may be
    line(&GOOD.replace("\"alpha\"", "\"alpah\"").into_bytes());
    line(
        &GOOD
            .replace(
                "\"fresnel\": \"none\"",
                "\"fresnel\": \"none\", \"enrgy\": \"krywonos\"",
            )
            .into_bytes(),
    );
    line(
        &GOOD
            .replace("\"alpha\": 0.2", "\"alpha\": 0.2, \"alpha\": 0.3")
            .into_bytes(),
    );
    line(b"{\"model\": \"ggx\", \"alpha\":");
    line(b"[1, 2, 3]");
    line(b"");
    line(format!("{GOOD}\r").as_bytes()); // CRLF line ending
    line(GOOD.as_bytes());
    let out = run(&input);
    assert_eq!(out.len(), 12, "{out:?}");
    let f0 = out[0]["f"].as_f64().unwrap();
    let field = |i: usize| out[i]["field"].as_str().unwrap_or("<none>").to_string();
    let error = |i: usize| out[i]["error"].as_str().unwrap_or("").to_string();
    assert_eq!(field(1), "line");
    assert!(
        error(1).starts_with("line 2: not valid UTF-8"),
        "{}",
        error(1)
    );
    assert_eq!(field(2), "line");
    assert!(error(2).contains("UTF-8"), "{}", error(2));
    assert_eq!(
        out[3]["f"].as_f64(),
        Some(f0),
        "the stream goes on after bad bytes"
    );
    assert_eq!(field(4), "line");
    assert!(error(4).contains("longer than 1 MiB"), "{}", error(4));
    assert_eq!(field(5), "alpah");
    assert!(
        error(5).contains("unknown key `alpah`") && error(5).contains("`alpha`"),
        "{}",
        error(5)
    );
    assert_eq!(field(6), "enrgy");
    assert!(
        error(6).contains("`energy`"),
        "the valid keys are listed: {}",
        error(6)
    );
    assert_eq!(field(7), "alpha");
    assert!(error(7).contains("duplicate key `alpha`"), "{}", error(7));
    assert_eq!(field(8), "line");
    assert!(error(8).contains("not valid JSON"), "{}", error(8));
    assert_eq!(field(9), "line");
    assert!(error(9).contains("JSON object"), "{}", error(9));
    // The empty line is skipped; line numbers still count it.
    assert_eq!(out[10]["f"].as_f64(), Some(f0), "CRLF: {:?}", out[10]);
    assert_eq!(out[11]["f"].as_f64(), Some(f0));
}

#[test]
fn ninety_degrees_is_the_horizon_for_every_model() {
    let models = [
        r#""model": "ggx", "alpha": 0.1"#,
        r#""model": "beckmann", "alpha": 0.1"#,
        r#""model": "ghs_ssa", "sigma_um": 0.1, "lc_um": 5, "gamma": 2.5"#,
        r#""model": "ghs", "sigma_um": 0.1, "lc_um": 5, "gamma": 2.5"#,
        r#""model": "two_scale", "sigma_um": 0.1, "lc_um": 5, "gamma": 2.5, "beta": 0.1"#,
    ];
    let mut input = String::new();
    let mut cases = Vec::new();
    for m in models {
        for fresnel in ["none", "cu"] {
            for (ti, to) in [
                ("90", "90"),
                ("90", "30"),
                ("30", "90"),
                ("89.999999999999", "89.999999999999"),
                ("89.999999999999", "30"),
                ("30", "89.999999999999"),
            ] {
                for phi in ["0", "180", "90"] {
                    input.push_str(&format!(
                        "{{{m}, \"fresnel\": \"{fresnel}\", \"lambda_nm\": 550, \"theta_i_deg\": {ti}, \"theta_o_deg\": {to}, \"phi_o_deg\": {phi}}}\n"
                    ));
                    cases.push((m, fresnel, ti, to, phi));
                }
            }
        }
    }
    let out = run(input.as_bytes());
    assert_eq!(out.len(), cases.len());
    for (o, (m, fr, ti, to, phi)) in out.iter().zip(&cases) {
        let ctx = format!("{m} F={fr} θi={ti} θo={to} φ={phi}: {o}");
        let f = o["f"].as_f64().unwrap_or_else(|| panic!("{ctx}"));
        let pdf = o["pdf"].as_f64().unwrap();
        let spec = o["specular_weight"].as_f64().unwrap();
        assert!(
            f.is_finite() && f >= 0.0 && pdf.is_finite() && pdf >= 0.0,
            "{ctx}"
        );
        if *ti == "90" || *to == "90" {
            // On the horizon: nothing, rather than a value set by cos(π/2) = 6e−17.
            assert_eq!(f, 0.0, "{ctx}");
            assert_eq!(pdf, 0.0, "{ctx}");
        }
        if *ti == "90" {
            assert_eq!(spec, 0.0, "{ctx}");
        }
        // 1e−12° above the horizon the reflected fraction f cosθi cosθo is
        // tiny for these lobes (all well away from the mirror pair at 90°).
        let ci = ti.parse::<f64>().unwrap().to_radians().cos();
        let co = to.parse::<f64>().unwrap().to_radians().cos();
        assert!(f * ci * co < 1.0, "{ctx}");
    }
}
