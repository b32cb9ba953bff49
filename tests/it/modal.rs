//! Modal data files and the beam generator (`mbfmu::modal`): read(write(x)) == x bit for
//! bit, every validation error with its whole `path: entry: what` message, and the beam's
//! modes against Euler–Bernoulli theory.

use mbfmu::modal::{ModalDamping, ModalData, ModalStiffness, Node, parse, read, write};

/// Two nodes, two mass-normalized modes with frequencies (ΦᵀMΦ = I exactly: sums of
/// binary fractions).
const BASE: &str = r#"{
  "format": "mbfmu-modal",
  "version": 1,
  "nodes": [
    {"id": 1, "position": [0, 0, 0], "mass": 2, "inertia": [0.5, 0.5, 0.5]},
    {"id": 2, "position": [1, 0, 0], "mass": 2, "inertia": [0.5, 0.5, 0.5]}
  ],
  "modes": [
    {"frequency": 3, "shape": [[0.5, 0, 0, 0, 0, 0], [-0.5, 0, 0, 0, 0, 0]]},
    {"frequency": 5, "shape": [[0, 0, 0, 1, 0, 0], [0, 0, 0, -1, 0, 0]]}
  ]
}"#;

/// BASE with a stiffness matrix `k` instead of the frequencies.
fn with_stiffness(k: &str) -> String {
    BASE.replace("\"frequency\": 3, ", "")
        .replace("\"frequency\": 5, ", "")
        .replace("\n  ]\n}", &format!("\n  ],\n  \"stiffness\": {k}\n}}"))
}

fn message(text: &str) -> String {
    parse(text, "m.json").expect_err("must be refused").to_string()
}

#[test]
fn the_base_file_reads() {
    let d = parse(BASE, "m.json").unwrap();
    assert_eq!(d.nodes.len(), 2);
    assert_eq!(d.stiffness, ModalStiffness::Frequencies(vec![3.0, 5.0]));
    assert_eq!(d.damping, ModalDamping::None);
    let k = parse(&with_stiffness("[[4, 1], [1, 9]]"), "m.json").unwrap();
    assert_eq!(k.stiffness, ModalStiffness::Matrix(vec![vec![4.0, 1.0], vec![1.0, 9.0]]));
}

/// Awkward values (0.1 + 0.2, subnormals, −0.0, 1e300, 1/3) survive a write and a read
/// bit for bit: the writer prints the shortest decimal that reads back to the same f64
/// and serde_json (float_roundtrip) reads it correctly rounded.
#[test]
fn read_of_write_is_bit_identical() {
    let odd = [0.1 + 0.2, 5e-324, -0.0, 1e300, 1.0 / 3.0, -2.5e-17];
    let data = ModalData {
        description: Some("odd \"values\"\n€".into()),
        nodes: (0..3)
            .map(|i| Node {
                id: 10 - i,
                position: [odd[i as usize], 1.0 / 7.0, -odd[i as usize + 1]],
                mass: 0.1 + 0.2 * f64::from(i),
                inertia: [0.0, 1e-300, 2.0 / 3.0],
            })
            .collect(),
        modes: (0..2).map(|k| (0..3).map(|i| std::array::from_fn(|j| odd[(i + j + k) % 6] * 3.7)).collect()).collect(),
        stiffness: ModalStiffness::Matrix(vec![vec![2.0 / 3.0, 0.1], vec![0.1, 1e5 + 0.3]]),
        damping: ModalDamping::Matrix(vec![vec![0.0, 0.0], vec![0.0, 1.0 / 3.0]]),
    };
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("modal-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("odd.json");
    std::fs::write(&path, write(&data)).unwrap();
    let back = read(&path).unwrap();
    assert_eq!(back, data);
    let bits = |d: &ModalData| -> Vec<u64> {
        let mut v: Vec<u64> = Vec::new();
        for n in &d.nodes {
            v.extend(n.position.iter().chain([n.mass].iter()).chain(n.inertia.iter()).map(|x| x.to_bits()));
        }
        v.extend(d.modes.iter().flatten().flatten().map(|x| x.to_bits()));
        for m in [d.stiffness_matrix(), d.damping_matrix()] {
            v.extend(m.iter().flatten().map(|x| x.to_bits()));
        }
        v
    };
    assert_eq!(bits(&back), bits(&data));
    // Frequencies and damping ratios too.
    let mut f = parse(BASE, "m.json").unwrap();
    f.stiffness = ModalStiffness::Frequencies(vec![0.1 + 0.2, 1.0 / 3.0]);
    f.damping = ModalDamping::Ratios(vec![0.02, 1e-310]);
    assert_eq!(parse(&write(&f), "w.json").unwrap(), f);
    assert_eq!(write(&parse(&write(&f), "w.json").unwrap()), write(&f));
}

#[test]
fn a_non_symmetric_stiffness_matrix_is_refused() {
    assert_eq!(
        message(&with_stiffness("[[4, 1], [2, 9]]")),
        "m.json: stiffness[0][1]: not symmetric: 1 but stiffness[1][0] = 2"
    );
}

/// A diagonal matrix: its eigenvalues are its diagonal, exactly.
#[test]
fn an_indefinite_stiffness_matrix_is_refused() {
    assert_eq!(
        message(&with_stiffness("[[1, 0], [0, -1]]")),
        "m.json: stiffness: not positive semidefinite: eigenvalue -1e0 (largest magnitude 1e0)"
    );
}

#[test]
fn a_non_square_stiffness_matrix_is_refused() {
    assert_eq!(
        message(&with_stiffness("[[4, 1], [1]]")),
        "m.json: stiffness[1]: expected 2 numbers (one per mode), found 1"
    );
}

#[test]
fn a_shape_with_a_wrong_row_is_refused() {
    let text = BASE.replace("[-0.5, 0, 0, 0, 0, 0]", "[-0.5, 0, 0, 0, 0]");
    assert_eq!(message(&text), "m.json: modes[0].shape[1]: expected 6 numbers, found 5");
}

#[test]
fn a_shape_without_a_row_per_node_is_refused() {
    let text = BASE.replace(", [0, 0, 0, -1, 0, 0]]", "]");
    assert_eq!(
        message(&text),
        "m.json: modes[1].shape: expected 2 rows [dx, dy, dz, rx, ry, rz] (one per node), found 1"
    );
}

#[test]
fn nan_written_as_a_string_is_refused() {
    let text = BASE.replace("[0, 0, 0, -1, 0, 0]", "[0, 0, 0, -1, \"NaN\", 0]");
    assert_eq!(message(&text), "m.json: modes[1].shape[1][4]: expected a finite number, found the string \"NaN\"");
}

#[test]
fn a_missing_field_is_refused() {
    let text = BASE.replace("\"mass\": 2, \"inertia\": [0.5, 0.5, 0.5]}\n  ]", "\"inertia\": [0.5, 0.5, 0.5]}\n  ]");
    assert_eq!(message(&text), "m.json: nodes[1].mass: missing");
}

#[test]
fn a_missing_frequency_is_refused() {
    let text = BASE.replace("\"frequency\": 5, ", "");
    assert_eq!(
        message(&text),
        "m.json: modes[1].frequency: missing (give every mode a frequency, or a \"stiffness\" matrix)"
    );
}

#[test]
fn frequencies_and_a_stiffness_matrix_are_refused_together() {
    let text = BASE.replace("\n  ]\n}", "\n  ],\n  \"stiffness\": [[4, 1], [1, 9]]\n}");
    assert_eq!(
        message(&text),
        "m.json: modes[0].frequency: a mode frequency and a \"stiffness\" matrix are both given; give one of them"
    );
}

#[test]
fn a_duplicate_node_id_is_refused() {
    let text = BASE.replace("{\"id\": 2,", "{\"id\": 1,");
    assert_eq!(message(&text), "m.json: nodes[1].id: duplicate node id 1 (also nodes[0].id)");
}

#[test]
fn a_negative_mass_is_refused() {
    let text = BASE
        .replace("\"mass\": 2, \"inertia\": [0.5, 0.5, 0.5]}\n  ]", "\"mass\": -2, \"inertia\": [0.5, 0.5, 0.5]}\n  ]");
    assert_eq!(message(&text), "m.json: nodes[1].mass: must be > 0, found -2");
}

#[test]
fn a_negative_inertia_is_refused() {
    let text = BASE.replacen("[0.5, 0.5, 0.5]", "[0.5, -0.5, 0.5]", 1);
    assert_eq!(message(&text), "m.json: nodes[0].inertia[1]: must be ≥ 0, found -0.5");
}

#[test]
fn modes_not_mass_normalized_are_refused_with_frequencies() {
    let text = BASE.replace("[0.5, 0, 0, 0, 0, 0], [-0.5,", "[0.5, 0, 0, 0, 0, 0], [0.25,");
    assert_eq!(
        message(&text),
        "m.json: modes[0]: modes given with frequencies must be mass-normalized with respect to the node masses and inertias (ΦᵀMΦ = I to 1e-6), but (ΦᵀMΦ)[0][0] = 0.625"
    );
}

#[test]
fn an_unknown_field_is_refused() {
    let text = BASE.replace("\"frequency\": 5,", "\"frequncy\": 5,");
    assert_eq!(
        message(&text),
        "m.json: modes[1].frequncy: unknown field (expected one of \"frequency\", \"damping_ratio\", \"shape\")"
    );
}

#[test]
fn a_syntax_error_names_line_and_column() {
    let text = BASE.replace("\"mass\": 2, \"inertia\"", "\"mass\": 2 \"inertia\"");
    assert_eq!(message(&text), "m.json:5:48: expected `,` or `}`");
}

#[test]
fn a_wrong_format_tag_is_refused() {
    let text = BASE.replace("mbfmu-modal", "adams-mnf");
    assert_eq!(message(&text), "m.json: format: expected the string \"mbfmu-modal\", found the string \"adams-mnf\"");
}

#[test]
fn a_missing_file_is_an_io_error() {
    let e = read(std::path::Path::new("/nonexistent/m.json")).unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/m.json: "), "{e}");
}
