//! `--set NAME=VALUE` (issue 25, item 4) on `check`, `simulate`, `linearize` and `pack`:
//! the value replaces the parameter's in the file, with every attribute using it
//! re-evaluated, so the results equal those of an edited copy of the model file (and the
//! analytic ones of the edited model); bad names and values are bad input (exit 2, one
//! line). A packed FMU starts from the values set, without any fmi2SetReal.

use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::host::{self, free, messages};
use crate::common::{mbfmu, model_text};
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::types::{CO_SIMULATION, Status};

const PENDULUM: &str = "models/pendulum.xml";
const G: f64 = 9.80665;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-set-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn arg(p: &Path) -> String {
    p.to_str().expect("UTF-8 path").to_string()
}

/// `text` with the `value` of `<parameter name="name" ...>` replaced by `value`: the
/// edit a user makes by hand.
fn edited(text: &str, edits: &[(&str, &str)]) -> String {
    let mut t = text.to_string();
    for (name, value) in edits {
        let tag = format!("<parameter name=\"{name}\" value=\"");
        let start = t.find(&tag).unwrap_or_else(|| panic!("no parameter {name}")) + tag.len();
        let end = start + t[start..].find('"').unwrap();
        t.replace_range(start..end, value);
    }
    t
}

/// The CSV of `mbfmu simulate` as numbers, header dropped.
fn csv_numbers(o: &Output) -> Vec<Vec<f64>> {
    assert!(o.status.success(), "{}", stderr(o));
    stdout(o).lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect()
}

/// Bad input: exit code 2 and one line on stderr containing `what`.
fn assert_bad_input(o: &Output, what: &str) {
    assert_eq!(o.status.code(), Some(2), "stderr: {}", stderr(o));
    let e = stderr(o);
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e}");
    assert!(e.contains(what), "expected '{what}' in: {e}");
}

#[test]
fn linearize_set_gives_the_pendulum_of_the_new_length() {
    // Compound pendulum about its hinge: ω² = m g L / (Jc + m L²); m = 1, Jc = 0.1.
    for l in [2.0, 0.25] {
        let set_l = format!("L={l}");
        let o = mbfmu(&["linearize", PENDULUM, "--set", "th0=0", "--set", &set_l, "--format", "json"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        let a = &v[0]["A"];
        assert_eq!(v[0]["states"], serde_json::json!(["hinge.angle", "der(hinge.angle)"]));
        let w2 = -a[1][0].as_f64().unwrap();
        let want = G * l / (0.1 + l * l);
        assert!((w2 - want).abs() <= 1e-9 * want, "L = {l}: ω² = {w2}, analytic {want}");
    }
    // The eigenvalue table says the same: ω = sqrt(2 g / 4.1).
    let o = mbfmu(&["linearize", PENDULUM, "--set", "th0=0", "--set", "L=2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let w = (2.0 * G / 4.1_f64).sqrt();
    assert!(stdout(&o).contains(&format!("{w:.6e}")), "ω = {w:.6e} in:\n{}", stdout(&o));
}

#[test]
fn simulate_set_equals_simulating_an_edited_copy() {
    let dir = scratch("simulate");
    let copy = dir.join("pendulum_edited.xml");
    std::fs::write(&copy, edited(&model_text("pendulum.xml"), &[("L", "0.7"), ("th0", "1")])).unwrap();
    let common = ["--end", "0.5", "--step", "0.1", "--tol", "1e-10"];
    let run = |model: &str, extra: &[&str]| {
        let mut args = vec!["simulate", model];
        args.extend(common);
        args.extend(extra);
        csv_numbers(&mbfmu(&args))
    };
    let set = run(PENDULUM, &["--set", "L=0.7", "--set", "th0=1"]);
    let copied = run(&arg(&copy), &[]);
    let plain = run(PENDULUM, &[]);
    assert_eq!(set.len(), 6);
    assert_eq!(set.len(), copied.len());
    let mut worst = 0.0f64;
    for (a, b) in set.iter().zip(&copied) {
        for (x, y) in a.iter().zip(b) {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(worst <= 1e-12, "--set and the edited copy differ by {worst}");
    // The values set matter: the start angle is 1 rad, not 170°.
    let angle = 1; // time, angle, omega, x, z, energy
    assert!((set[0][angle] - 1.0).abs() < 1e-9, "{:?}", set[0]);
    assert!((plain[0][angle] - 170f64.to_radians()).abs() < 1e-9, "{:?}", plain[0]);
    // Energy of the edited model: E = −m g L cos θ0 (at rest), conserved.
    let energy = 5;
    let e0 = -G * 0.7 * 1f64.cos();
    assert!((set[5][energy] - e0).abs() < 1e-6, "{} vs {e0}", set[5][energy]);
}

#[test]
fn set_errors_are_bad_input_on_one_line() {
    let o = mbfmu(&["linearize", PENDULUM, "--set", "Lx=2"]);
    assert_bad_input(&o, "has no parameter 'Lx'; did you mean 'L'?");
    let o = mbfmu(&["simulate", PENDULUM, "--set", "th00=2"]);
    assert_bad_input(&o, "did you mean 'th0'?");
    let o = mbfmu(&["check", PENDULUM, "--set", "nothing_like_it=2"]);
    assert_bad_input(&o, "no parameter 'nothing_like_it'");
    assert!(!stderr(&o).contains("did you mean"), "{}", stderr(&o));
    let o = mbfmu(&["simulate", PENDULUM, "--set", "L=two"]);
    assert_bad_input(&o, "'two' is not a number");
    let o = mbfmu(&["simulate", PENDULUM, "--set", "L=inf"]);
    assert_bad_input(&o, "must be finite");
    let o = mbfmu(&["linearize", PENDULUM, "--set", "L"]);
    assert_bad_input(&o, "'L' is not NAME=VALUE");
    let o = mbfmu(&["check", PENDULUM, "--set", "L=1", "--set", "L=2"]);
    assert_bad_input(&o, "'L' is set twice");
    let dir = scratch("errors");
    let fmu = dir.join("p.fmu");
    let o = mbfmu(&["pack", PENDULUM, "-o", &arg(&fmu), "--set", "Jcc=1"]);
    assert_bad_input(&o, "did you mean 'Jc'?");
    assert!(!fmu.exists(), "no FMU is written for bad input");
}

#[test]
fn check_set_validates_the_values() {
    let o = mbfmu(&["check", PENDULUM, "--set", "m=-1"]);
    assert_bad_input(&o, "body 'bob': mass must be positive");
    let o = mbfmu(&["check", PENDULUM, "--set", "m=3", "--set", "L=1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("1 degree of freedom"), "{}", stdout(&o));
}

/// The `start` of the ScalarVariable `name` in a modelDescription.xml.
fn start_of(xml: &str, name: &str) -> String {
    let at = xml.find(&format!("<ScalarVariable name=\"{name}\"")).unwrap_or_else(|| panic!("no variable {name}"));
    let s = at + xml[at..].find(" start=\"").unwrap() + 8;
    xml[s..s + xml[s..].find('"').unwrap()].to_string()
}

fn guid_of(xml: &str) -> String {
    let start = xml.find(" guid=\"").unwrap() + 7;
    xml[start..start + xml[start..].find('"').unwrap()].to_string()
}

fn pack_dir(dir: &Path, set: &[&str]) -> (PathBuf, String) {
    let out = dir.join("fmu");
    let mut args = vec!["pack".to_string(), PENDULUM.to_string(), "--out-dir".to_string(), arg(&out)];
    for s in set {
        args.extend(["--set".to_string(), s.to_string()]);
    }
    let o = mbfmu(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let xml = std::fs::read_to_string(out.join("modelDescription.xml")).unwrap();
    (out, xml)
}

/// Instantiate the FMU unzipped at `dir` with the GUID `guid` (NULL when refused), and
/// the messages logged meanwhile.
fn instantiate(dir: &Path, guid: &str) -> (mbfmu::fmi::types::Component, Vec<String>) {
    let path = dir.join("resources").display().to_string().replace('%', "%25").replace(' ', "%20");
    let (g, uri) = (CString::new(guid).unwrap(), CString::new(format!("file://{path}")).unwrap());
    // SAFETY: valid NUL-terminated strings; the host's callbacks.
    unsafe { host::instantiate_logged(c"set".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), 0, 1) }
}

#[test]
fn pack_set_makes_the_values_the_fmus_start_values() {
    let (plain_dir, plain_xml) = pack_dir(&scratch("pack-plain"), &[]);
    let (dir, xml) = pack_dir(&scratch("pack-set"), &["L=2", "th0=0.3"]);
    let (_, xml3) = pack_dir(&scratch("pack-set3"), &["L=3", "th0=0.3"]);
    assert_eq!(start_of(&xml, "L"), "2");
    assert_eq!(start_of(&xml, "th0"), "0.3");
    assert_eq!(start_of(&xml, "m"), "1");
    assert_eq!(start_of(&plain_xml, "L"), "0.5");
    // The model file is packed as it is; the values set go beside it.
    let original = std::fs::read(PENDULUM).unwrap();
    assert_eq!(std::fs::read(dir.join("resources/model.xml")).unwrap(), original);
    assert_eq!(std::fs::read_to_string(dir.join("resources/start_values.txt")).unwrap(), "L=2\nth0=0.3\n");
    assert!(!plain_dir.join("resources/start_values.txt").exists());
    // Other start values, another FMU; no start values, the plain GUID (golden files).
    let (g_plain, g2, g3) = (guid_of(&plain_xml), guid_of(&xml), guid_of(&xml3));
    assert!(g2 != g_plain && g3 != g2 && g3 != g_plain, "{g_plain} {g2} {g3}");
    assert_eq!(g_plain, crate::common::guid(&model_text("pendulum.xml")));

    // The reference: the engine on an edited copy of the model file.
    let edited_text = edited(&model_text("pendulum.xml"), &[("L", "2"), ("th0", "0.3")]);
    let m = mbfmu::model::parse::load_str(&edited_text, "edited.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    sim.advance(0.5).unwrap();
    let names = sim.output_names();
    let want = sim.outputs().unwrap();
    let vars = mbfmu::fmi::variables::variables(
        &m,
        &mbfmu::linearize::StateLayout::at_start(&m),
        mbfmu::fmi::variables::Standard::Fmi2,
    );
    let vr = |n: &str| vars.iter().find(|v| v.name == n).unwrap().value_reference;
    let out_vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();

    // The FMU, told nothing but the experiment.
    let (c, _) = instantiate(&dir, &g2);
    assert!(!c.is_null());
    // SAFETY: a live instance and arrays of the stated lengths throughout.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 1, 1e-10, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(host::get(c, &[vr("L"), vr("th0")]), [2.0, 0.3]);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok, "{:?}", messages(c));
        assert_eq!(fmi2DoStep(c, 0.0, 0.5, 1), Status::Ok, "{:?}", messages(c));
    }
    let got = host::get(c, &out_vrs);
    for ((n, g), w) in names.iter().zip(&got).zip(&want) {
        assert!((g - w).abs() <= 1e-12 * w.abs().max(1.0), "{n}: FMU {g}, edited file {w}");
    }
    // Energy of the edited model: E = −m g L cos θ0, conserved; 170° would give +9.66 J.
    let e = got[names.iter().position(|n| n == "energy").unwrap()];
    assert!((e + G * 2.0 * 0.3f64.cos()).abs() < 1e-6, "energy {e}");
    // fmi2Reset goes back to the packed start values, not the file's.
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi2Reset(c), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
    }
    assert_eq!(host::get(c, &[vr("L"), vr("th0")]), [2.0, 0.3]);
    free(c);

    // The GUID of the plain FMU does not open this one, and a broken start values file
    // is a refused fmi2Instantiate with a message, not a crash.
    let (c, log) = instantiate(&dir, &g_plain);
    assert!(c.is_null());
    assert!(log.join("\n").contains("does not match"), "{log:?}");
    for (bad, what) in [("L=two\n", "'two' is not a number"), ("Lx=1\n", "did you mean 'L'?"), ("m=-1\n", "mass")] {
        std::fs::write(dir.join("resources/start_values.txt"), bad).unwrap();
        let (c, log) = instantiate(&dir, &g2);
        assert!(c.is_null(), "{bad}");
        let msgs = log.join("\n");
        assert!(msgs.contains("start_values.txt") && msgs.contains(what), "{bad}: {msgs}");
    }
}

#[test]
fn set_on_states_starts_there_as_the_exact_joint_ics_of_an_edited_file_do() {
    // `--set hinge.angle=1 --set der(hinge.angle)=-0.5` against the same start written as
    // exact joint ICs in the file (ic_angle, ic_angular_speed: another path through
    // assembly), and against the analytic energy E = ½ (Jc + m L²) ω² − m g L cos θ.
    let dir = scratch("states");
    let copy = dir.join("pendulum_ics.xml");
    let text = model_text("pendulum.xml").replace(
        r#"<joint name="hinge" type="revolute" i="bob.P" j="ground.O"/>"#,
        r#"<joint name="hinge" type="revolute" i="bob.P" j="ground.O" ic_angle="1" ic_angular_speed="-0.5"/>"#,
    );
    std::fs::write(&copy, text).unwrap();
    let common = ["--end", "0.5", "--step", "0.1", "--tol", "1e-10"];
    let run = |model: &str, extra: &[&str]| {
        let mut args = vec!["simulate", model];
        args.extend(common);
        args.extend(extra);
        csv_numbers(&mbfmu(&args))
    };
    let set = run(PENDULUM, &["--set", "hinge.angle=1", "--set", "der(hinge.angle)=-0.5"]);
    let ics = run(&arg(&copy), &[]);
    let (angle, omega, energy) = (1, 2, 5); // time, angle, omega, x, z, energy
    assert_eq!((set[0][angle], set[0][omega]), (1.0, -0.5), "{:?}", set[0]);
    let mut worst = 0.0f64;
    for (a, b) in set.iter().zip(&ics) {
        for (x, y) in a.iter().zip(b) {
            worst = worst.max((x - y).abs());
        }
    }
    // The same initial state to round-off, integrated at tolerance 1e-10 over 0.5 s.
    assert!(worst <= 1e-9, "--set on states and the file's exact ICs differ by {worst}");
    let e0 = 0.5 * (0.1 + 0.25) * 0.25 - G * 0.5 * 1f64.cos();
    for row in &set {
        assert!((row[energy] - e0).abs() < 1e-6, "{} vs {e0}", row[energy]);
    }
    // An unknown state is bad input, with the closest name.
    let o = mbfmu(&["simulate", PENDULUM, "--set", "hinge.angel=1"]);
    assert_bad_input(&o, "did you mean 'hinge.angle'?");
}

#[test]
fn pack_set_on_a_state_is_the_fmus_start_and_a_host_value_replaces_it() {
    let (dir, xml) = pack_dir(&scratch("pack-state"), &["hinge.angle=0.3"]);
    assert_eq!(start_of(&xml, "hinge.angle"), "0.3");
    assert_eq!(std::fs::read_to_string(dir.join("resources/start_values.txt")).unwrap(), "hinge.angle=0.3\n");
    let vars = mbfmu::fmi::variables::variables(
        &mbfmu::model::parse::load_str(&model_text("pendulum.xml"), "p.xml").unwrap(),
        &mbfmu::fmi::resources::read_layout(&dir.join("resources"), &guid_of(&xml)).unwrap(),
        mbfmu::fmi::variables::Standard::Fmi2,
    );
    let vr = |n: &str| vars.iter().find(|v| v.name == n).unwrap().value_reference;
    for host_value in [None, Some(-2.0)] {
        let (c, _) = instantiate(&dir, &guid_of(&xml));
        assert!(!c.is_null());
        // SAFETY: a live instance and arrays of the stated lengths throughout.
        unsafe {
            assert_eq!(fmi2SetupExperiment(c, 1, 1e-10, 0.0, 0, 0.0), Status::Ok);
            if let Some(v) = host_value {
                assert_eq!(fmi2SetReal(c, [vr("hinge.angle")].as_ptr(), 1, [v].as_ptr()), Status::Ok);
            }
            assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
            assert_eq!(fmi2ExitInitializationMode(c), Status::Ok, "{:?}", messages(c));
        }
        let got = host::get(c, &[vr("hinge.angle"), vr("angle")]);
        let want = host_value.unwrap_or(0.3);
        assert!((got[0] - want).abs() < 1e-12 && (got[1] - want).abs() < 1e-12, "{got:?} vs {want}");
        free(c);
    }
    let o = mbfmu(&["pack", PENDULUM, "--out-dir", &arg(&scratch("pack-bad-state")), "--set", "hinge.angel=1"]);
    assert_bad_input(&o, "did you mean 'hinge.angle'?");
}
