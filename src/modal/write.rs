//! Writing a [`ModalData`] as a modal data file: JSON in a fixed field order, one node per
//! line and one shape row per line (diffs stay local). Numbers are written in the
//! shortest form that reads back to the same f64 (serde_json's), so
//! `read(write(x)) == x` bit for bit for valid data.

use super::data::{ModalDamping, ModalData, ModalStiffness};
use super::read::{FORMAT, VERSION};

/// The text of the modal data file of `data`. Non-finite numbers (which valid data do not
/// have) are written as `null` and refused when read.
pub fn write(data: &ModalData) -> String {
    let mut s = String::from("{\n");
    s += &format!("  \"format\": {},\n  \"version\": {VERSION},\n", string(FORMAT));
    if let Some(d) = &data.description {
        s += &format!("  \"description\": {},\n", string(d));
    }
    let nodes: Vec<String> = data
        .nodes
        .iter()
        .map(|n| {
            format!(
                "    {{\"id\": {}, \"position\": {}, \"mass\": {}, \"inertia\": {}}}",
                n.id,
                numbers(&n.position),
                number(n.mass),
                numbers(&n.inertia)
            )
        })
        .collect();
    s += &format!("  \"nodes\": [\n{}\n  ],\n", nodes.join(",\n"));
    let modes: Vec<String> = data
        .modes
        .iter()
        .enumerate()
        .map(|(k, shape)| {
            let mut m = String::from("    {\n");
            if let ModalStiffness::Frequencies(f) = &data.stiffness {
                m += &format!("      \"frequency\": {},\n", number(f[k]));
            }
            if let ModalDamping::Ratios(z) = &data.damping {
                m += &format!("      \"damping_ratio\": {},\n", number(z[k]));
            }
            let rows: Vec<String> = shape.iter().map(|r| format!("        {}", numbers(r))).collect();
            m += &format!("      \"shape\": [\n{}\n      ]\n    }}", rows.join(",\n"));
            m
        })
        .collect();
    s += &format!(
        "  \"modes\": [{}]",
        if modes.is_empty() { String::new() } else { format!("\n{}\n  ", modes.join(",\n")) }
    );
    if let ModalStiffness::Matrix(k) = &data.stiffness {
        s += &format!(",\n  \"stiffness\": {}", matrix(k));
    }
    if let ModalDamping::Matrix(c) = &data.damping {
        s += &format!(",\n  \"damping\": {}", matrix(c));
    }
    s + "\n}\n"
}

/// The shortest decimal that reads back to `x` (`null` if not finite).
fn number(x: f64) -> String {
    serde_json::to_string(&x).unwrap_or_else(|_| "null".into())
}

fn numbers(xs: &[f64]) -> String {
    format!("[{}]", xs.iter().map(|&x| number(x)).collect::<Vec<_>>().join(", "))
}

fn string(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

fn matrix(a: &[Vec<f64>]) -> String {
    if a.is_empty() {
        return "[]".into();
    }
    let rows: Vec<String> = a.iter().map(|r| format!("    {}", numbers(r))).collect();
    format!("[\n{}\n  ]", rows.join(",\n"))
}
