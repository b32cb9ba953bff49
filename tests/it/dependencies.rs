//! `<ModelStructure>` dependencies are structural: two separate mechanisms get separate
//! lists, and every partial derivative that fmi2GetDirectionalDerivative returns outside
//! the declared dependencies is exactly zero (every example model, moving).

use crate::common::guid;
use crate::common::host::{CALLBACKS, resources};
use crate::common::model_dir;
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::types::{CO_SIMULATION, Component, Status};
use mbfmu::model::parse::load_str;
use mbfmu::pack::fmi2_description::write;
use std::collections::BTreeMap;
use std::ffi::CString;

/// Two pendulums that do not touch: `a` hangs freely; `b` is driven by the input T. The
/// input U is read by an output only.
const TWIN: &str = r#"<multibody name="twin" version="1">
  <gravity value="0 0 -9.81"/>
  <ground>
    <marker name="O" position="0 0 0" z_axis="0 1 0"/>
    <marker name="O2" position="2 0 0" z_axis="0 1 0"/>
  </ground>
  <body name="a" mass="1" inertia="0.01 0.01 0.01" position="0.3 0 -0.4">
    <marker name="P" position="-0.3 0 0.4" z_axis="0 1 0"/>
  </body>
  <body name="b" mass="2" inertia="0.02 0.02 0.02" position="2.5 0 0">
    <marker name="P" position="-0.5 0 0" z_axis="0 1 0"/>
  </body>
  <joint name="ha" type="revolute" i="a.P" j="ground.O"/>
  <joint name="hb" type="revolute" i="b.P" j="ground.O2"/>
  <input name="T" start="0.3"/>
  <input name="U" start="0"/>
  <sforce name="drive" type="rotational" i="b.P" j="ground.O2" function="T - 0.1*wz(b.P, ground.O2)"/>
  <output name="ya" function="az(a.P, ground.O)"/>
  <output name="yb" function="wz(b.P, ground.O2) + U"/>
  <output name="accb" function="accx(b.cm)"/>
  <output name="acca" function="accz(a.cm)"/>
  <output name="fa" function="fz(ha)"/>
  <output name="fb" function="fx(hb)"/>
  <output name="td" function="tz(drive)"/>
  <output name="t" function="time"/>
  <experiment tolerance="1e-10"/>
</multibody>"#;

/// The same two pendulums with one linearization state reading both: it joins them.
fn twin_joined() -> String {
    TWIN.replace(
        "<experiment",
        r#"<linearization><state name="sum" function="az(a.P, ground.O) + az(b.P, ground.O2)"/></linearization>
  <experiment"#,
    )
}

/// Dependencies of each `<Unknown>` of a section (Outputs, Derivatives), by index.
fn section(xml: &str, name: &str) -> BTreeMap<usize, Vec<usize>> {
    let open = format!("<{name}>");
    let close = format!("</{name}>");
    let body = xml.split(&open).nth(1).and_then(|s| s.split(&close).next()).unwrap_or_default();
    let attr = |line: &str, a: &str| -> String {
        let key = format!(" {a}=\"");
        line.split(&key).nth(1).and_then(|s| s.split('"').next()).unwrap_or_default().to_string()
    };
    body.lines()
        .filter(|l| l.contains("<Unknown"))
        .map(|l| {
            let index = attr(l, "index").parse().unwrap();
            let deps = attr(l, "dependencies").split_whitespace().map(|d| d.parse().unwrap()).collect();
            (index, deps)
        })
        .collect()
}

/// (index, name, causality) of every ModelVariable.
fn variables(xml: &str) -> Vec<(usize, String, String)> {
    let attr = |line: &str, a: &str| -> String {
        let key = format!(" {a}=\"");
        line.split(&key).nth(1).and_then(|s| s.split('"').next()).unwrap_or_default().to_string()
    };
    xml.lines()
        .filter(|l| l.contains("<ScalarVariable"))
        .enumerate()
        .map(|(k, l)| (k + 1, attr(l, "name"), attr(l, "causality")))
        .collect()
}

#[test]
fn two_separate_pendulums_get_separate_dependency_lists() {
    let model = load_str(TWIN, "twin.xml").unwrap_or_else(|e| panic!("{e}"));
    let xml = write(&model, TWIN);
    // Indices: T 1, U 2, outputs 3..10, states ha.angle 11, hb.angle 12, der() 13 14,
    // der(,2) 15 16.
    let names: Vec<String> = variables(&xml).into_iter().map(|v| v.1).collect();
    assert_eq!(names[10..12], ["ha.angle", "hb.angle"], "{names:?}");
    let outputs = section(&xml, "Outputs");
    let want: [(usize, &[usize]); 8] = [
        (3, &[11, 13]),    // ya: positions of a
        (4, &[2, 12, 14]), // yb: velocities of b, and U directly
        (5, &[1, 12, 14]), // accb: accelerations of b feel T
        (6, &[11, 13]),    // acca: a has no input
        (7, &[11, 13]),    // fa: a's hinge load
        (8, &[1, 12, 14]), // fb: b's hinge load feels T through λ
        (9, &[1, 12, 14]), // td: the drive's torque reads T and b's velocity
        (10, &[]),         // t: time only
    ];
    for (index, deps) in want {
        assert_eq!(outputs[&index], deps, "output {index}\n{xml}");
    }
    let derivatives = section(&xml, "Derivatives");
    assert_eq!(derivatives[&13], [13]);
    assert_eq!(derivatives[&14], [14]);
    assert_eq!(derivatives[&15], [11, 13]);
    assert_eq!(derivatives[&16], [1, 12, 14]);
    // A state reading both pendulums joins them into one mechanism.
    let text = twin_joined();
    let model = load_str(&text, "twin.xml").unwrap_or_else(|e| panic!("{e}"));
    let xml = write(&model, &text);
    let outputs = section(&xml, "Outputs");
    assert_eq!(outputs[&3], [11, 12, 13, 14], "{xml}");
    assert_eq!(outputs[&5], [1, 11, 12, 13, 14], "{xml}");
}

/// Every directional derivative outside the declared dependencies of `text`'s FMU, after
/// `t_end` s of motion: (checked entries, entries that are not exactly zero).
fn undeclared_entries(text: &str, t_end: f64) -> (usize, Vec<String>) {
    let model = load_str(text, "model.xml").unwrap_or_else(|e| panic!("{e}"));
    let xml = write(&model, text);
    let vars = variables(&xml);
    let mut unknowns = section(&xml, "Outputs");
    unknowns.extend(section(&xml, "Derivatives"));
    let derivatives = section(&xml, "Derivatives");
    // Knowns: the states (the variables the Derivatives are derivatives of) and the inputs.
    let mut knowns: Vec<usize> = vars.iter().filter(|v| v.2 == "input").map(|v| v.0).collect();
    let states: Vec<usize> = xml
        .lines()
        .filter(|l| l.contains("<Real derivative=\""))
        .filter_map(|l| l.split("derivative=\"").nth(1)?.split('"').next()?.parse().ok())
        .collect();
    knowns.extend(&states);
    assert_eq!(states.len(), derivatives.len());
    let (name, g, uri) = (c"deps", CString::new(guid(text)).unwrap(), resources(text, "deps").1);
    // SAFETY: valid strings and callbacks; the instance lives until freed below, and every
    // array passed has the length given with it.
    unsafe {
        let c: Component = fmi2Instantiate(name.as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), &CALLBACKS, 0, 0);
        assert!(!c.is_null());
        assert_eq!(fmi2SetupExperiment(c, 1, 1e-9, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok);
        assert_eq!(fmi2DoStep(c, 0.0, t_end, 1), Status::Ok);
        let mut checked = 0;
        let mut bad = Vec::new();
        for (&u, deps) in &unknowns {
            for &k in knowns.iter().filter(|k| !deps.contains(k)) {
                let (uvr, kvr) = ((u - 1) as u32, (k - 1) as u32);
                let mut out = f64::NAN;
                assert_eq!(fmi2GetDirectionalDerivative(c, &uvr, 1, &kvr, 1, &1.0, &mut out), Status::Ok);
                checked += 1;
                if out != 0.0 {
                    bad.push(format!("d {} / d {} = {out:e}", vars[u - 1].1, vars[k - 1].1));
                }
            }
        }
        fmi2FreeInstance(c);
        (checked, bad)
    }
}

#[test]
fn directional_derivatives_outside_the_declared_dependencies_are_exactly_zero() {
    let mut texts: Vec<(String, String)> = std::fs::read_dir(model_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .map(|p| (p.file_stem().unwrap().to_string_lossy().into_owned(), std::fs::read_to_string(&p).unwrap()))
        .collect();
    texts.sort();
    assert!(texts.len() >= 7);
    texts.push(("twin".into(), TWIN.into()));
    texts.push(("twin_joined".into(), twin_joined()));
    let mut failures = Vec::new();
    for (name, text) in &texts {
        let (checked, bad) = undeclared_entries(text, 0.2);
        eprintln!("{name}: {checked} undeclared entries checked, {} nonzero", bad.len());
        failures.extend(bad.into_iter().map(|b| format!("{name}: {b}")));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
