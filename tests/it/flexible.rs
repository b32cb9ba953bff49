//! `<flexible_body>` in the model reader: the modal data file it names is read and
//! validated, its markers sit on nodes, and every error names the element's
//! `file:line:col` (plus, for bad data, the data file's path and entry).

use mbfmu::model::load_str;
use std::path::PathBuf;

/// Two nodes 1 m apart on x, each 2 kg; two mass-normalized modes.
const DATA: &str = r#"{
  "format": "mbfmu-modal",
  "version": 1,
  "nodes": [
    {"id": 1, "position": [0, 0, 0], "mass": 2, "inertia": [0.5, 0.25, 0.25]},
    {"id": 7, "position": [1, 0, 0], "mass": 2, "inertia": [0.5, 0.25, 0.25]}
  ],
  "modes": [
    {"frequency": 3, "shape": [[0, 0.5, 0, 0, 0, 0], [0, -0.5, 0, 0, 0, 0]]},
    {"frequency": 5, "shape": [[0, 0, 0, 1, 0, 0], [0, 0, 0, -1, 0, 0]]}
  ]
}"#;

/// A directory of its own for each test, holding `arm.json` = `data`.
fn dir_with(test: &str, data: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("flexible-model").join(test);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("arm.json"), data).unwrap();
    dir
}

/// A model with one flexible body whose markers are `markers` (XML), read as if from
/// `dir/m.xml`.
fn model_text(markers: &str) -> String {
    format!(
        r#"<multibody name="f" version="1">
  <flexible_body name="arm" modal="arm.json" position="1 2 3">
{markers}
  </flexible_body>
</multibody>
"#
    )
}

fn load_in(dir: &std::path::Path, text: &str) -> Result<mbfmu::model::Model, String> {
    let label = dir.join("m.xml").display().to_string();
    load_str(text, &label).map_err(|e| e.to_string())
}

#[test]
fn a_flexible_body_reads_with_its_data_and_node_markers() {
    let dir = dir_with("reads", DATA);
    let m = load_in(&dir, &model_text(r#"    <marker name="tip" node="7" z_axis="0 1 0"/>"#)).unwrap();
    let b = &m.bodies[0];
    let flex = b.flex.as_ref().expect("a flexible body");
    assert_eq!((flex.file.as_str(), flex.data.modes.len()), ("arm.json", 2));
    assert_eq!(flex.path, dir.join("arm.json").display().to_string());
    // Mass and inertia of the undeformed body: 4 kg, centre of mass at x = 0.5;
    // Iyy = Izz = 2 · 2 · 0.5² + 2 · 0.25 = 1.5, Ixx = 2 · 0.5 (exact in binary).
    assert_eq!(b.mass.value, 4.0);
    assert_eq!(b.inertia.values(), vec![1.0, 1.5, 1.5, 0.0, 0.0, 0.0]);
    let cm = m.markers.iter().find(|k| k.name == "arm.cm").unwrap();
    assert_eq!((cm.position.v3(), cm.node), ([0.5, 0.0, 0.0], None));
    let tip = m.markers.iter().find(|k| k.name == "arm.tip").unwrap();
    assert_eq!((tip.position.v3(), tip.node, tip.body), ([1.0, 0.0, 0.0], Some(1), Some(0)));
}

/// Each bad input is refused with the element's position and what is wrong.
#[test]
fn bad_flexible_bodies_are_refused_where_they_are_written() {
    let dir = dir_with("errors", DATA);
    let at = |s: &str| format!("{}:{s}", dir.join("m.xml").display());
    let cases = [
        (
            r#"    <marker name="tip" node="9"/>"#,
            at(&format!(
                "3:24: marker 'tip': node 9 is not in the modal data file '{}' (2 nodes)",
                dir.join("arm.json").display()
            )),
        ),
        (
            r#"    <marker name="tip" node="x1"/>"#,
            at("3:24: marker 'tip': node 'x1' is not a node id (a whole number)"),
        ),
        (
            r#"    <marker name="tip"/>"#,
            at("3:5: marker 'tip': missing required attribute 'node' (a node id of the modal data)"),
        ),
        (
            r#"    <marker name="tip" node="1" position="0 0 0"/>"#,
            at("3:33: marker 'tip': a marker of a <flexible_body> sits on a node: give 'node', not 'position'"),
        ),
    ];
    for (markers, expected) in cases {
        assert_eq!(load_in(&dir, &model_text(markers)).unwrap_err(), expected);
    }
    // `node` on a rigid body's marker.
    let rigid = r#"<multibody name="f" version="1">
  <body name="b" mass="1" inertia="1 1 1" position="0 0 0"><marker name="p" node="1"/></body>
</multibody>
"#;
    assert_eq!(
        load_in(&dir, rigid).unwrap_err(),
        at("2:77: marker 'p': 'node' is for markers of a <flexible_body>; 'b' is rigid")
    );
}

/// Bad modal data: the message holds the element's position, the data file's path and
/// the entry at fault.
#[test]
fn bad_modal_data_names_the_element_the_file_and_the_entry() {
    let cases = [
        (
            DATA.replace(
                "\"mass\": 2, \"inertia\": [0.5, 0.25, 0.25]}\n  ]",
                "\"mass\": -2, \"inertia\": [0.5, 0.25, 0.25]}\n  ]",
            ),
            "nodes[1].mass",
        ),
        (DATA.replace("[0, -0.5, 0, 0, 0, 0]]", "[0, -0.5, 0, 0, 0]]"), "modes[0].shape[1]"),
        (
            DATA.replace("\"frequency\": 3, ", "")
                .replace("\"frequency\": 5, ", "")
                .replace("\n  ]\n}", "\n  ],\n  \"stiffness\": [[4, 1], [2, 9]]\n}"),
            "stiffness",
        ),
        (
            DATA.replace("\"frequency\": 3, ", "")
                .replace("\"frequency\": 5, ", "")
                .replace("\n  ]\n}", "\n  ],\n  \"stiffness\": [[1, 2], [2, 1]]\n}"),
            "stiffness",
        ),
        (DATA.replace("\"mass\": 2, \"inertia\"", "\"mass\": \"NaN\", \"inertia\""), "nodes[0].mass"),
    ];
    for (k, (data, entry)) in cases.iter().enumerate() {
        let dir = dir_with(&format!("data{k}"), data);
        let e = load_in(&dir, &model_text(r#"    <marker name="tip" node="7"/>"#)).unwrap_err();
        let head = format!(
            "{}:2:29: flexible_body 'arm': modal data: {}: {entry}",
            dir.join("m.xml").display(),
            dir.join("arm.json").display()
        );
        assert!(e.starts_with(&head), "case {k}: {e}\nexpected it to start with {head}");
    }
    let dir = dir_with("missing", DATA);
    let e = load_in(&dir, &model_text("").replace("arm.json", "none.json")).unwrap_err();
    assert!(e.contains(":2:29: flexible_body 'arm': modal data: ") && e.contains("none.json"), "{e}");
}

/// Initial modal coordinates and rates, and expressions reading modes: read with the
/// body's mode count; a wrong count or mode number is refused at the attribute.
#[test]
fn modal_initial_conditions_and_modal_measures_are_read_and_checked() {
    let dir = dir_with("modal-ics", DATA);
    let text = |attrs: &str, f: &str| {
        format!(
            r#"<multibody name="f" version="1">
  <output name="y" function="{f}"/>
  <flexible_body name="arm" modal="arm.json" position="1 2 3" {attrs}/>
  <body name="r" mass="1" inertia="1 1 1" position="0 0 0"/>
</multibody>
"#
        )
    };
    // An expression before the body it reads: modes are known from the first pass.
    let m =
        load_in(&dir, &text(r#"modal_coordinates="0.1 -0.2" modal_velocities="0 3""#, "modal_rate(arm, 2)")).unwrap();
    let f = m.bodies[0].flex.as_ref().unwrap();
    assert_eq!(f.eta0.as_ref().map(|v| v.values()), Some(vec![0.1, -0.2]));
    assert_eq!(f.eta_dot0.as_ref().map(|v| v.values()), Some(vec![0.0, 3.0]));
    // A parameter in them is re-evaluated with new parameter values (FMU parameters, sweeps).
    let with_param =
        text(r#"modal_coordinates="a 2*a""#, "1").replace("<output", "<parameter name=\"a\" value=\"1\"/>\n  <output");
    let m = load_in(&dir, &with_param).unwrap().with_params(&[0.25]).unwrap();
    assert_eq!(m.bodies[0].flex.as_ref().unwrap().eta0.as_ref().map(|v| v.values()), Some(vec![0.25, 0.5]));
    let at = |s: &str| format!("{}:{s}", dir.join("m.xml").display());
    let cases = [
        (
            text(r#"modal_coordinates="0.1""#, "1"),
            at("3:63: flexible_body 'arm': attribute 'modal_coordinates' needs 2 items, found 1"),
        ),
        (
            text("", "modal(arm, 3)"),
            at("2:41: output 'y': bad expression in 'function': mode 3 of 'arm': it has modes 1 to 2"),
        ),
        (
            text("", "modal(r, 1)"),
            at(
                "2:36: output 'y': bad expression in 'function': 'r' is not a flexible body: 'modal' reads a <flexible_body>'s modes",
            ),
        ),
    ];
    for (t, want) in cases {
        assert_eq!(load_in(&dir, &t).unwrap_err(), want);
    }
}
