//! The FMI layer maps indices decided by `linearize`: the FMU's linearization states are
//! those `mbfmu linearize` selects, they reach an instance from the FMU's resources (no
//! engine run at fmi2Instantiate), and a missing or foreign layout is refused there.

use crate::common::{guid, guid_of};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::resources::{LAYOUT_FILE, read_layout};
use mbfmu::fmi::types::CO_SIMULATION;
use mbfmu::fmi::variables::{Target, variables};
use mbfmu::linearize::{StateLayout, selection_at_start, selection_by_name};
use mbfmu::model::parse::{load_file, load_str};
use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use crate::common::host::{self, CALLBACKS, resources};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mbfmu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(args)
        .current_dir(root())
        .env_remove("MBFMU_LIB")
        .stdin(Stdio::null())
        .output()
        .expect("the mbfmu binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A fresh empty directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mbfmu-fmi-layer-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create temp dir");
    d
}

/// Every `*.xml` of `models/`, `models/flexible/` and `tests/models/`, sorted.
fn all_models() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = ["models", "models/flexible", "tests/models"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root().join(d)).expect("readable").map(|e| e.expect("entry").path()))
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    v.sort();
    v
}

/// The `"states": [...]` names of the first linearization of `mbfmu linearize --format json`.
fn json_states(json: &str) -> Vec<String> {
    let list = json.split("\"states\": [").nth(1).and_then(|s| s.split(']').next()).expect("a states list");
    list.split(", ").filter(|s| !s.is_empty()).map(|s| s.trim_matches('"').to_string()).collect()
}

/// The linearization states of a variable list: the knowns that are states, in A's column
/// order (S, W, X).
fn fmu_states(vars: &[mbfmu::fmi::variables::Variable]) -> Vec<String> {
    let mut s: Vec<(usize, String)> = vars.iter().filter_map(|v| Some((v.known?, v.name.clone()))).collect();
    s.sort();
    s.into_iter().map(|(_, n)| n).collect()
}

#[test]
fn mbfmu_linearize_selects_the_states_the_fmu_lists_for_every_model() {
    let dir = temp_dir("states");
    for path in all_models() {
        let stem = path.file_stem().expect("a file name").to_string_lossy().into_owned();
        let p = path.display().to_string();
        let out = dir.join(&stem);
        let o = mbfmu(&["pack", &p, "--out-dir", &out.display().to_string()]);
        assert!(o.status.success(), "{stem}: {}", text(&o.stderr));
        assert!(text(&o.stderr).is_empty(), "{stem} packs without warnings: {}", text(&o.stderr));
        // The FMU's states: its layout resource through variables(), as an instance sees them.
        let layout = read_layout(&out.join("resources"), &guid_of(&path)).unwrap_or_else(|e| panic!("{e}"));
        let model = load_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let fmu = fmu_states(&variables(&model, &layout, mbfmu::fmi::variables::Standard::Fmi2));
        let xml = std::fs::read_to_string(out.join("modelDescription.xml")).expect("written");
        for name in &fmu {
            assert!(xml.contains(&format!("<ScalarVariable name=\"{name}\"")), "{stem}: {name} in modelDescription");
        }
        // The command line's, whatever its integration tolerance.
        for tol in [None, Some("1e-5")] {
            let mut args = vec!["linearize", &p, "--format", "json"];
            args.extend(tol.iter().flat_map(|t| ["--tol", *t]));
            let o = mbfmu(&args);
            assert!(o.status.success(), "{stem} {tol:?}: {}", text(&o.stderr));
            assert_eq!(json_states(&text(&o.stdout)), fmu, "{stem}, --tol {tol:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn velocity_states_relate_to_position_states_by_index() {
    for (name, relation) in [
        ("benchmark_bicycle.xml", vec![Some(0), Some(1), Some(2)]),
        ("chaplygin_sleigh.xml", vec![None, Some(2)]),
        ("double_pendulum.xml", vec![Some(0), Some(1)]),
    ] {
        let model = load_file(&root().join("models").join(name)).unwrap_or_else(|e| panic!("{e}"));
        let sel = selection_at_start(&model).unwrap_or_else(|e| panic!("{e}"));
        let got: Vec<Option<usize>> = (0..sel.velocities.len()).map(|j| sel.state_of_velocity(j)).collect();
        assert_eq!(got, relation, "{name}");
        for (j, k) in relation.iter().enumerate() {
            assert_eq!(k.and_then(|k| sel.velocity_of_state(k)), k.map(|_| j), "{name}");
        }
        // The layout carries the relation, and the selection rebuilt from it has it again.
        let layout = StateLayout::of(&sel);
        let sim = mbfmu::dae::Simulator::new(&model, Default::default(), 0.0).unwrap_or_else(|e| panic!("{e}"));
        let again = selection_by_name(sim.system(), &layout).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(again.states, sel.states, "{name}");
        assert_eq!(again.velocities, sel.velocities, "{name}");
        let rebuilt: Vec<Option<usize>> = (0..again.velocities.len()).map(|j| again.state_of_velocity(j)).collect();
        assert_eq!(rebuilt, relation, "{name}");
        // der(S_k) is the variable of W_j = Ṡ_k; the other velocity states have their own.
        let vars = variables(&model, &layout, mbfmu::fmi::variables::Standard::Fmi2);
        for (j, k) in relation.iter().enumerate() {
            let w = vars.iter().find(|v| v.known == Some(sel.states.len() + j)).expect("a W variable");
            match k {
                Some(k) => assert_eq!(w.target, Target::StateDerivative(*k), "{name}"),
                None => assert_eq!(w.target, Target::Velocity(j), "{name}"),
            }
        }
    }
}

#[test]
fn a_model_whose_states_cannot_be_selected_packs_with_a_located_warning_and_fails_at_initialization() {
    let dir = temp_dir("unassemblable");
    // A crank 25 times the ground link: the four-bar cannot be assembled.
    let src = std::fs::read_to_string(root().join("models/fourbar.xml")).expect("readable");
    let bad = src.replace(r#"<parameter name="a" value="0.2""#, r#"<parameter name="a" value="5""#);
    let model = dir.join("fourbar_long.xml");
    std::fs::write(&model, &bad).expect("write");
    let out = dir.join("fmu");
    let o = mbfmu(&["pack", &model.display().to_string(), "--out-dir", &out.display().to_string()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.starts_with("warning: the FMU has no linearization states"), "{err}");
    assert!(err.contains("fourbar_long.xml:") && err.contains("joint 'rocker_pin'"), "located: {err}");
    let layout = read_layout(&out.join("resources"), &guid(&bad)).unwrap_or_else(|e| panic!("{e}"));
    assert!(layout.positions.is_empty() && layout.missing.as_deref().is_some_and(|m| m.contains("rocker_pin")));
    let xml = std::fs::read_to_string(out.join("modelDescription.xml")).expect("written");
    assert!(!xml.contains("crank_pivot.angle"), "no states listed");

    // The FMU instantiates; its initialization fails with the engine's message.
    let uri = CString::new(format!("file://{}", out.join("resources").display())).expect("no NUL");
    let g = CString::new(guid(&bad)).expect("no NUL");
    // SAFETY: valid NUL-terminated strings and callbacks; a live instance, freed once.
    unsafe {
        let c = host::instantiate(c"bad".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), 0, 0);
        assert!(!c.is_null());
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), mbfmu::fmi::types::Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), mbfmu::fmi::types::Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), mbfmu::fmi::types::Status::Error);
        let msgs = host::messages(c).join("\n");
        assert!(msgs.contains("model.xml:") && msgs.contains("joint 'rocker_pin'"), "{msgs}");
        host::free(c);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// fmi2Instantiate on the resources directory `res` of model `model_text`.
fn instantiate_at(res: &Path, model_text: &str) -> bool {
    let path = res.to_str().expect("UTF-8").replace('%', "%25").replace(' ', "%20");
    let uri = CString::new(format!("file://{path}")).expect("no NUL");
    let g = CString::new(guid(model_text)).expect("no NUL");
    // SAFETY: valid NUL-terminated strings and callbacks; a live instance, freed once.
    unsafe {
        let c = fmi2Instantiate(c"i".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), &CALLBACKS, 0, 0);
        let made = !c.is_null();
        fmi2FreeInstance(c);
        made
    }
}

#[test]
fn a_missing_unreadable_or_foreign_layout_fails_instantiation_without_a_panic() {
    let pendulum = std::fs::read_to_string(root().join("models/pendulum.xml")).expect("readable");
    let other = format!("{pendulum}\n<!-- another text, another GUID -->\n");
    let (top, _) = resources(&pendulum, "layout");
    let res = top.join("resources");
    assert!(instantiate_at(&res, &pendulum), "as packed");
    let file = res.join(LAYOUT_FILE);
    let good = std::fs::read_to_string(&file).expect("written by the host helper");
    let foreign = mbfmu::pack::layout_file(&other, "other.xml").expect("a model").0;
    let refusals: [(&[u8], &str); 3] =
        [(b"garbage\n", "not a state layout"), (b"mbfmu state layout 1\nS\tx\n", "line 2"), (&foreign, "belongs to")];
    for (bytes, why) in refusals {
        std::fs::write(&file, bytes).expect("write");
        assert!(!instantiate_at(&res, &pendulum), "{why}");
        let e = read_layout(&res, &guid(&pendulum)).unwrap_err();
        assert!(e.contains(why) && e.contains(LAYOUT_FILE), "{e}");
    }
    std::fs::remove_file(&file).expect("remove");
    assert!(!instantiate_at(&res, &pendulum), "missing");
    assert!(read_layout(&res, &guid(&pendulum)).unwrap_err().contains("cannot read"));
    std::fs::write(&file, good).expect("restore");
    assert!(instantiate_at(&res, &pendulum), "restored");
    let _ = std::fs::remove_dir_all(&top);
}

#[test]
fn the_layout_file_reads_back_to_the_selection_at_start_for_every_model() {
    for path in all_models() {
        // Under its own path: a flexible body's modal data file is found beside it.
        let (model_text, label) = (std::fs::read_to_string(&path).expect("readable"), path.display().to_string());
        let model = load_str(&model_text, &label).unwrap_or_else(|e| panic!("{e}"));
        let (bytes, warning) = mbfmu::pack::layout_file(&model_text, &label).expect("a model");
        assert_eq!(warning, None, "{}", path.display());
        let read = StateLayout::from_text(&text(&bytes), &guid_of(&path)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(read, StateLayout::at_start(&model), "{}", path.display());
    }
}
