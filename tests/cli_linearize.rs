//! `mbfmu linearize`: the eigenvalue table and the A, B, C, D files (json, npz, mat).

use std::process::Command;

fn mbfmu(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mbfmu")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

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
