//! `mbfmu linearize`: the eigenvalue table and the A, B, C, D files (json, npz, mat).

use std::process::Command;

use crate::common::mbfmu;

#[test]
fn linearize_prints_the_seed_blade_table_and_writes_json_npz_mat() {
    let o = mbfmu(&["linearize", "models/blade_alpha.xml"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Eq. 21: 4.3994 rad/s (7 digits printed: 4.399413).
    assert!(text.contains("linearization states (1): alpha") && text.contains("4.399413e0"), "{text}");

    let o = mbfmu(&["linearize", "models/blade_y.xml", "--format", "json"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    // A = [[0, 1], [-(mel/(I+ml²) + 1) w², 0]] (seed Eq. 22): A[1][0] = −119.3548...
    let a10 = -(3.0 * 2.0 * 10.0 / (10.0 + 300.0) + 1.0) * 100.0;
    let start = text.find("\"A\": [[").unwrap() + 7;
    let rows: Vec<f64> = text[start..]
        .split(']')
        .take(3)
        .flat_map(|r| {
            r.trim_start_matches([',', ' ', '['])
                .split(',')
                .filter_map(|x| x.trim().parse::<f64>().ok())
                .collect::<Vec<_>>()
        })
        .collect();
    assert!((rows[2] - a10).abs() < 1e-9 * a10.abs(), "{rows:?} vs {a10}");

    let dir = std::env::temp_dir().join(format!("mbfmu-lin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for fmt in ["npz", "mat"] {
        let path = dir.join(format!("blade.{fmt}"));
        let o = mbfmu(&[
            "linearize",
            "models/blade_alpha.xml",
            "--at",
            "0,0.5",
            "--format",
            fmt,
            "--out",
            path.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(&path).unwrap();
        if fmt == "npz" {
            // A zip of .npy arrays, one set per time: A_0.npy ... time_1.npy.
            assert_eq!(&bytes[..4], b"PK\x03\x04");
            let names = String::from_utf8_lossy(&bytes);
            assert!(names.contains("A_0.npy") && names.contains("D_1.npy") && names.contains("NUMPY"));
        } else {
            // MATLAB v4: first matrix "A_0", 2×2 doubles: header (5 int32) + name + 32 bytes.
            let rows = i32::from_le_bytes(bytes[4..8].try_into().unwrap());
            let cols = i32::from_le_bytes(bytes[8..12].try_into().unwrap());
            assert_eq!((rows, cols), (2, 2));
            assert_eq!(&bytes[20..24], b"A_0\0");
        }
    }
    // Bad option values are usage errors (exit 2).
    assert_eq!(mbfmu(&["linearize", "models/blade_alpha.xml", "--format", "xls"]).status.code(), Some(2));
    assert_eq!(mbfmu(&["linearize", "models/blade_alpha.xml", "--format", "npz"]).status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn json_to_stdout_is_only_json_and_the_report_goes_to_stderr() {
    let o = mbfmu(&["linearize", "models/blade_alpha.xml", "--format", "json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    let body = out.trim();
    assert!(body.starts_with("[{\"time\"") && body.ends_with("}]"), "{out}");
    assert!(!out.contains("Undmp") && !out.contains("linearization states"), "{out}");
    assert!(err.contains("linearization states (1): alpha") && err.contains("Undmp. Freq."), "{err}");
}

#[test]
fn table_gives_the_frequency_in_rad_per_s_and_hz() {
    // Seed Eq. 21: 4.399413 rad/s = 0.7001919 Hz.
    let o = mbfmu(&["linearize", "models/blade_alpha.xml"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("(Hz)"), "{text}");
    let row: Vec<f64> = text
        .lines()
        .find(|l| l.contains("4.399413e0"))
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert!((row[1] - row[0] / (2.0 * std::f64::consts::PI)).abs() < 1e-6 * row[1], "{row:?}");
}

#[test]
fn static_prints_the_equilibrium_it_found() {
    // The double pendulum hangs straight down at equilibrium: both angles 0 (1e-12).
    let o = mbfmu(&["linearize", "models/double_pendulum.xml", "--static"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("static equilibrium at t = 0: ")).expect("equilibrium line");
    let values: Vec<f64> =
        line.split(", ").map(|kv| kv.rsplit(" = ").next().unwrap().parse::<f64>().unwrap()).collect();
    assert_eq!(values.len(), 2, "{line}");
    assert!(values.iter().all(|v| v.abs() < 1e-12), "{line}");
    assert!(line.contains("alpha1 = ") && line.contains("alpha2 = "), "{line}");
}

#[test]
fn simulate_static_starts_from_equilibrium() {
    // Released from th1 = 1, th2 = 0.5 without --static; with it, it stays hanging (1e-9).
    let o = mbfmu(&["simulate", "models/double_pendulum.xml", "--static", "--end", "0.5", "--step", "0.1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        assert!(v[1].abs() < 1e-9 && v[2].abs() < 1e-9, "{line}");
    }
}

#[test]
fn npz_and_mat_carry_the_names() {
    let dir = std::env::temp_dir().join(format!("mbfmu-names-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let npz = dir.join("c.npz");
    let o = mbfmu(&["linearize", "models/cart_pendulum_pid.xml", "--format", "npz", "-o", npz.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(&npz).unwrap();
    let has = |needle: &[u8]| bytes.windows(needle.len()).any(|w| w == needle);
    assert!(has(b"states.npy") && has(b"inputs.npy") && has(b"outputs.npy"));
    // "xi" as NumPy <U: UTF-32LE code units.
    assert!(has(&[b'x', 0, 0, 0, b'i', 0, 0, 0]) && has(b"'descr': '<U"));
    let mat = dir.join("c.mat");
    let o = mbfmu(&["linearize", "models/cart_pendulum_pid.xml", "--format", "mat", "-o", mat.to_str().unwrap()]);
    assert!(o.status.success());
    let bytes = std::fs::read(&mat).unwrap();
    let at = bytes.windows(7).position(|w| w == b"states\0").expect("states matrix");
    // Header before the name: type 1 (text), 5 rows (x, th, der(x), der(th), xi), 7 columns.
    let int = |k: usize| i32::from_le_bytes(bytes[at - 20 + 4 * k..at - 16 + 4 * k].try_into().unwrap());
    assert_eq!((int(0), int(1), int(2)), (1, 5, 7));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_closed_pipe_ends_quietly() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(["simulate", "models/pendulum.xml", "--end", "20", "--step", "0.0005"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
    assert!(first.starts_with("time,"));
    // The reader is gone (like `| head -1`): the next write fails with EPIPE.
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "exit {:?}: {}", o.status, String::from_utf8_lossy(&o.stderr));
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn automatic_states_are_named_after_joints_in_the_cli_output() {
    // spring_mass_damper.xml has no <linearization>: its one state is the guide's
    // displacement x, so A = [[0, 1], [−k/m, −c/m]] = [[0, 1], [−100, −2]] exactly (its
    // file comment: m x'' + c x' + k x = 0); 1e-9 leaves room for the sparse solve only.
    let o = mbfmu(&["linearize", "models/spring_mass_damper.xml", "--format", "json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = String::from_utf8_lossy(&o.stdout);
    assert!(json.contains(r#""guide.displacement""#) && json.contains(r#""der(guide.displacement)""#), "{json}");
    let start = json.find("\"A\": [[").unwrap() + 7;
    let a: Vec<f64> = json[start..]
        .split(']')
        .take(2)
        .flat_map(|r| {
            r.trim_start_matches([',', ' ', '[']).split(',').filter_map(|x| x.trim().parse().ok()).collect::<Vec<f64>>()
        })
        .collect();
    let want = [0.0, 1.0, -100.0, -2.0];
    assert!(a.len() == 4 && a.iter().zip(want).all(|(x, y)| (x - y).abs() < 1e-9), "{a:?}");
    let report = String::from_utf8_lossy(&o.stderr);
    assert!(report.contains("linearization states (1): guide.displacement"), "{report}");
}
