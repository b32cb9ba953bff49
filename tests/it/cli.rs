//! The `mbfmu` command as a user meets it: exit codes, error format, CSV layout, and the
//! example models (each checks and simulates).

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::mbfmu;
use mbfmu::model::load_file;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Every model in `models/`, with the degrees of freedom its header comment states.
const MODELS: &[(&str, isize)] = &[
    ("double_pendulum", 2),
    ("fourbar", 1),
    ("pendulum", 1),
    ("slider_crank", 0),
    ("spinning_top", 3),
    ("spring_mass_damper", 1),
    ("torque_free_body", 6),
];

fn model_path(name: &str) -> String {
    format!("models/{name}.xml")
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-tests");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A `file:line:col: element 'name': what` line.
fn is_located_model_error(line: &str, file: &str) -> bool {
    let Some(rest) = line.strip_prefix(file).and_then(|r| r.strip_prefix(':')) else {
        return false;
    };
    let mut parts = rest.splitn(3, ':');
    let line_no = parts.next().is_some_and(|s| s.parse::<usize>().is_ok_and(|n| n > 0));
    let col_no = parts.next().is_some_and(|s| s.parse::<usize>().is_ok_and(|n| n > 0));
    let what = parts.next().unwrap_or("");
    line_no && col_no && what.starts_with(' ') && what.contains(" '") && what.contains("': ")
}

#[test]
fn every_example_model_checks_with_the_documented_degrees_of_freedom() {
    for &(name, dof) in MODELS {
        let path = model_path(name);
        let o = mbfmu(&["check", &path]);
        assert!(o.status.success(), "{path}: {}", stderr(&o));
        let unit = if dof == 1 { "degree of freedom" } else { "degrees of freedom" };
        assert!(stdout(&o).contains(&format!("; {dof} {unit}")), "{path}: {}", stdout(&o));
        let model =
            load_file(Path::new(env!("CARGO_MANIFEST_DIR")).join(&path).as_path()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(model.summary().dof, dof, "{path}");
        assert!(!model.outputs.is_empty(), "{path} has outputs for the tests");
        assert!(model.experiment.stop.is_some(), "{path} has an <experiment>");
    }
}

#[test]
fn malformed_model_answers_file_line_col_and_exit_code_2() {
    let bad = scratch("unclosed.xml");
    std::fs::write(&bad, "<multibody name=\"m\" version=\"1\">\n  <body name=\"b\" mass=\"1\"").unwrap();
    let file = bad.display().to_string();
    for cmd in ["check", "simulate"] {
        let o = mbfmu(&[cmd, &file]);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(is_located_model_error(err.trim_end(), &file), "{cmd}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn semantic_model_error_names_the_element() {
    let bad = scratch("unknown_marker.xml");
    std::fs::write(
        &bad,
        "<multibody name=\"m\" version=\"1\">\n  <body name=\"b\" mass=\"1\" inertia=\"1 1 1\" position=\"0 0 0\"/>\n  <output name=\"o\" function=\"dx(b.nothere)\"/>\n</multibody>\n",
    )
    .unwrap();
    let file = bad.display().to_string();
    let o = mbfmu(&["check", &file]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(is_located_model_error(err.trim_end(), &file), "{err}");
    assert!(err.starts_with(&format!("{file}:3:")), "{err}");
    assert!(err.contains("output 'o'"), "{err}");
}

#[test]
fn missing_model_file_is_exit_code_2() {
    let o = mbfmu(&["check", "models/does_not_exist.xml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).starts_with("models/does_not_exist.xml:"), "{}", stderr(&o));
}

#[test]
fn bad_command_line_values_are_exit_code_2() {
    let path = model_path("pendulum");
    for args in [
        vec!["simulate", path.as_str(), "--step", "0"],
        vec!["simulate", path.as_str(), "--step", "-0.1"],
        vec!["simulate", path.as_str(), "--tol", "0"],
        vec!["simulate", path.as_str(), "--end", "-1"],
        vec!["simulate", path.as_str(), "--step", "abc"],
        vec!["simulate", path.as_str(), "--step", "nan"],
        vec!["simulate"],
        vec!["frobnicate"],
    ] {
        let o = mbfmu(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
}

/// Exit 0 with a CSV whose header is time + outputs and whose time column is exactly
/// start + k·step (the last one exactly the end).
fn check_simulation(o: &Output, names: &[String], (start, end, step): (f64, f64, f64), n: usize) {
    let err = stderr(o);
    assert!(!err.contains("panicked"), "{err}");
    match o.status.code() {
        Some(0) => {
            let text = stdout(o);
            let mut lines = text.lines();
            let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
            assert_eq!(header[0], "time");
            assert_eq!(&header[1..=names.len()], names);
            let rows: Vec<Vec<f64>> =
                lines.map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect()).collect();
            assert_eq!(rows.len(), n + 1);
            for (k, row) in rows.iter().enumerate() {
                assert_eq!(row.len(), header.len());
                assert!(row.iter().all(|x| x.is_finite()));
                let t = if k == n { end } else { start + k as f64 * step };
                assert_eq!(row[0], t, "time of row {k}");
            }
        }
        other => panic!("exit {other:?}: {err}"),
    }
}

#[test]
fn every_example_model_simulates_to_csv_with_time_and_every_output() {
    for &(name, _) in MODELS {
        let path = model_path(name);
        let model = load_file(Path::new(env!("CARGO_MANIFEST_DIR")).join(&path).as_path()).unwrap();
        let names: Vec<String> = model.outputs.iter().map(|o| o.name.clone()).collect();
        let o = mbfmu(&["simulate", &path, "--end", "0.2", "--step", "0.05"]);
        check_simulation(&o, &names, (0.0, 0.2, 0.05), 4);
    }
}

#[test]
fn simulate_with_out_writes_the_same_csv_to_a_file() {
    let path = model_path("spring_mass_damper");
    let out = scratch("smd.csv");
    let _ = std::fs::remove_file(&out);
    let out_s = out.display().to_string();
    let args = ["simulate", &path, "--end", "0.1", "--step", "0.05", "--states", "--out", &out_s];
    let o = mbfmu(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).is_empty());
    let csv = std::fs::read_to_string(&out).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.starts_with("time,x,x_exact,x_err,spring_force,"), "{header}");
    // --states adds the 6 coordinates and 6 velocities of the one body.
    assert_eq!(header.split(',').count(), 5 + 12, "{header}");
    assert_eq!(csv.lines().count(), 4);
}

/// The CSV carries the closed form x(t) of the damped oscillator (model header): the
/// simulated x agrees with it to 1e-5 m over 1 s at tolerance 1e-8 (amplitude 0.1 m; the
/// bound leaves room for the global error of a local tolerance).
#[test]
fn simulated_spring_mass_damper_csv_matches_the_closed_form() {
    let path = model_path("spring_mass_damper");
    let o = mbfmu(&["simulate", &path, "--end", "1", "--step", "0.01", "--tol", "1e-8"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (x, exact) = (col("x"), col("x_exact"));
    let mut rows = 0;
    for line in lines {
        let row: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        assert!((row[x] - row[exact]).abs() < 1e-5, "t = {}: {} vs {}", row[0], row[x], row[exact]);
        rows += 1;
    }
    assert_eq!(rows, 101);
}

#[test]
fn run_prints_the_eigenvalue_table_and_a_table_of_the_default_model() {
    let o = mbfmu(&["run"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("theta1") && text.contains("theta2"), "{text}");
    // Eigenvalue table: the hanging double pendulum's ω² = (g/L)(3 ∓ 6/√7), printed with
    // 7 digits: 2.679656 and 7.187443 rad/s.
    let eig: Vec<&str> = text.lines().skip(2).take(2).collect();
    assert!(eig[0].contains("2.679656e0") && eig[1].contains("7.187443e0"), "{text}");
    // Eigen title, header, 2 rows, blank line; title, header, 21 rows (t = 0, 0.1, ..., 2).
    assert_eq!(text.lines().count(), 5 + 23, "{text}");
    let last: Vec<&str> = text.lines().last().unwrap().split_whitespace().collect();
    assert_eq!(last[0], "2.000");
}

#[test]
fn check_counts_redundant_equations_honestly() {
    // The planar four-bar with four revolutes in 3-D: 20 equations on 18 coordinates, rank
    // 17 (3 equations implied by the others), so 1 degree of freedom, not 18 − 20 = −2.
    let text = std::fs::read_to_string(model_path("fourbar"))
        .unwrap()
        .replace(r#"<joint name="crank_pin" type="spherical""#, r#"<joint name="crank_pin" type="revolute""#)
        .replace(r#"<joint name="rocker_pin" type="universal""#, r#"<joint name="rocker_pin" type="revolute""#)
        .replace(
            r#"<marker name="B" position="b/2, 0, 0" z_axis="0 1 0"/>"#,
            r#"<marker name="B" position="b/2, 0, 0"/>"#,
        );
    let file = scratch("fourbar_revolutes.xml");
    std::fs::write(&file, text).unwrap();
    let o = mbfmu(&["check", &file.display().to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let line = out.lines().find(|l| l.starts_with("positions: ")).unwrap_or_else(|| panic!("{out}"));
    assert!(line.starts_with("positions: 20 constraint equations, 17 independent, 3 redundant (joint '"), "{line}");
    assert!(line.ends_with("; 1 degree of freedom"), "{line}");
    // Non-holonomic: the bicycle's 4 no-slip rows are independent: 7 − 4 = 3 velocity dof.
    let o = mbfmu(&["check", &model_path("benchmark_bicycle")]);
    let out = stdout(&o);
    assert!(
        out.contains("positions: 17 constraint equations, 17 independent, 0 redundant; 7 degrees of freedom"),
        "{out}"
    );
    assert!(
        out.contains("velocities: 4 non-holonomic equations, 4 independent; 3 velocity degrees of freedom"),
        "{out}"
    );
}

/// A free rotor (J = 0.5) driven by the input torque T about its bearing: J ω' = T(t).
const ROTOR: &str = r#"<multibody name="rotor" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="r" mass="2" inertia="1 1 0.5" position="0 0 0"><marker name="axis" position="0 0 0"/></body>
  <joint name="bearing" type="revolute" i="r.axis" j="ground.O"/>
  <input name="T"/>
  <gforce name="drive" i="r.cm" torque="0 0 T"/>
  <output name="w" function="wz(r.cm)"/>
</multibody>
"#;

fn rotor_run(csv: &str, tag: &str) -> Vec<(f64, f64)> {
    let model = scratch(&format!("rotor_{tag}.xml"));
    std::fs::write(&model, ROTOR).unwrap();
    let input = scratch(&format!("rotor_{tag}.csv"));
    std::fs::write(&input, csv).unwrap();
    let o = mbfmu(&[
        "simulate",
        &model.display().to_string(),
        "--input",
        &input.display().to_string(),
        "--end",
        "2",
        "--step",
        "0.25",
        "--tol",
        "1e-10",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    stdout(&o)
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0], v[1])
        })
        .collect()
}

#[test]
fn simulate_follows_a_piecewise_linear_input_file() {
    // T = 2t up to t = 1, then 2: ω = t²/J = 2t² up to 1, then 2 + 4(t − 1) (exact for
    // Radau on a polynomial; 1e-9).
    for (t, w) in rotor_run("time,T\n0,0\n1,2\n2,2\n", "ramp") {
        let want = if t <= 1.0 { 2.0 * t * t } else { 2.0 + 4.0 * (t - 1.0) };
        assert!((w - want).abs() < 1e-9, "t {t}: {w} vs {want}");
    }
    // A repeated time is a jump: T = 0 before 0.5, 1 after: ω = 2 (t − 0.5)⁺.
    for (t, w) in rotor_run("time,T\n0,0\n0.5,0\n0.5,1\n2,1\n", "step") {
        let want = 2.0 * (t - 0.5).max(0.0);
        assert!((w - want).abs() < 1e-9, "t {t}: {w} vs {want}");
    }
}

#[test]
fn bad_input_files_are_located() {
    let model = scratch("rotor_bad.xml");
    std::fs::write(&model, ROTOR).unwrap();
    for (csv, want) in [
        ("time,torque\n0,1\n", ":1: column 2 'torque' is not an input of model 'rotor' (inputs: T)"),
        ("time,T\n0,1\n0.5,x\n", ":3: column 2 'T': 'x' is not a finite number"),
        ("time,T\n1,1\n0.5,1\n", ":3: time 0.5 is before the previous row's 1"),
        ("t,T\n0,1\n", ":1: the first column must be 'time'"),
    ] {
        let input = scratch("bad_input.csv");
        std::fs::write(&input, csv).unwrap();
        for cmd in ["simulate", "linearize"] {
            let o = mbfmu(&[cmd, &model.display().to_string(), "--input", &input.display().to_string()]);
            assert_eq!(o.status.code(), Some(2), "{cmd} {csv}: {}", stderr(&o));
            assert!(stderr(&o).contains(&format!("bad_input.csv{want}")), "{cmd}: {}", stderr(&o));
        }
    }
}

#[test]
fn assembly_that_moves_a_body_far_is_reported_and_a_failed_one_names_every_unmet_element() {
    // A 0.2 m typo in rod2's x position: assembly puts rod2 back on its hinge, moving its
    // CM by about 0.1–0.2 m, far more than 1 % of the 2 m model (warning on stderr).
    let text = std::fs::read_to_string(model_path("double_pendulum"))
        .unwrap()
        .replace(r#"position="-L*sin(th1) - L/2*sin(th2), 0,"#, r#"position="0.2 - L*sin(th1) - L/2*sin(th2), 0,"#);
    let file = scratch("double_pendulum_typo.xml");
    std::fs::write(&file, text).unwrap();
    let o = mbfmu(&["check", &file.display().to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let line = err
        .lines()
        .find(|l| l.starts_with("warning: assembly moved body 'rod2' by "))
        .unwrap_or_else(|| panic!("{err}"));
    let d: f64 = line["warning: assembly moved body 'rod2' by ".len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(d > 0.05 && d < 0.25, "{line}");
    // (The min-norm assembly also shifts rod1, by 1.9 cm: it is named too.)
    // The model as written gives no warning.
    assert!(stderr(&mbfmu(&["check", &model_path("double_pendulum")])).is_empty());

    // A crank 25 times the ground link: no assembly; every joint that cannot close is named
    // with how far apart its markers are as written.
    let text = std::fs::read_to_string(model_path("fourbar"))
        .unwrap()
        .replace(r#"<parameter name="a" value="0.2""#, r#"<parameter name="a" value="5""#);
    let file = scratch("fourbar_long_crank.xml");
    std::fs::write(&file, text).unwrap();
    let o = mbfmu(&["check", &file.display().to_string()]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("cannot be assembled") && err.contains("equations not met: joint 'rocker_pin' (residual "),
        "{err}"
    );
    assert!(err.contains("joint 'crank_pin' (residual ") && err.contains("m apart as written"), "{err}");
}
