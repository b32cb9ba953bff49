//! The modelDescription.xml of every example model equals its golden file in
//! `modelDescription/` (FMI 2) and `modelDescription/fmi3/` (FMI 3), except the `guid`
//! (`instantiationToken`) and `generationTool` attributes (they carry the engine
//! fingerprint, which changes with every source edit).
//!
//! After an intended change, regenerate the golden files with
//! `MBFMU_BLESS=1 cargo test --release --test it model_description::` and review the diff.

use std::path::Path;

use crate::common::{model_files, root};
use mbfmu::model::load_file;
use mbfmu::pack::{fmi2_description, fmi3_description};

/// Replace the value of attribute `name` (every occurrence) by `*`.
fn blank_attr(xml: &str, name: &str) -> String {
    let key = format!(" {name}=\"");
    let mut out = String::with_capacity(xml.len());
    let mut rest = xml;
    // Attributes are written one per line in the root tag: also match a line start.
    let key_nl = format!("\n  {name}=\"");
    loop {
        let hit = [rest.find(&key), rest.find(&key_nl)].into_iter().flatten().min();
        let Some(i) = hit else { break };
        let start = i + rest[i..].find('"').expect("the key ends with a quote") + 1;
        let Some(len) = rest[start..].find('"') else { break };
        out.push_str(&rest[..start]);
        out.push('*');
        rest = &rest[start + len..];
    }
    out.push_str(rest);
    out
}

fn normalize(xml: &str) -> String {
    blank_attr(&blank_attr(&blank_attr(xml, "guid"), "instantiationToken"), "generationTool")
}

/// The FMI 2 (`fmi3` false) or FMI 3 model description of the model file `path`.
fn generate(path: &Path, fmi3: bool) -> String {
    let text = std::fs::read_to_string(path).expect("model readable");
    let model = load_file(path).unwrap_or_else(|e| panic!("{e}"));
    if fmi3 { fmi3_description::write(&model, &text) } else { fmi2_description::write(&model, &text) }
}

#[test]
fn model_descriptions_match_the_golden_files() {
    let bless = std::env::var_os("MBFMU_BLESS").is_some_and(|v| v == "1");
    let mut failures = Vec::new();
    let models = model_files();
    assert!(models.len() >= 8, "example models found: {}", models.len());
    for (path, fmi3) in models.iter().flat_map(|p| [(p, false), (p, true)]) {
        let stem = path.file_stem().expect("file name").to_string_lossy().into_owned();
        let dir = if fmi3 { root().join("modelDescription/fmi3") } else { root().join("modelDescription") };
        let golden = dir.join(format!("{stem}.xml"));
        let actual = generate(path, fmi3);
        if bless {
            std::fs::create_dir_all(golden.parent().expect("parent")).expect("create modelDescription/");
            std::fs::write(&golden, &actual).expect("write golden file");
            continue;
        }
        let expected = std::fs::read_to_string(&golden).unwrap_or_default();
        let (a, e) = (normalize(&actual), normalize(&expected));
        if a != e {
            let line =
                a.lines().zip(e.lines()).position(|(x, y)| x != y).unwrap_or(a.lines().count().min(e.lines().count()));
            failures.push(format!(
                "{}: differs from the golden file at line {}:\n  generated: {}\n  golden:    {}",
                golden.display(),
                line + 1,
                a.lines().nth(line).unwrap_or("<end of file>"),
                e.lines().nth(line).unwrap_or("<end of file>")
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{}\n\nIf the change is intended, regenerate the golden files with\n  \
         MBFMU_BLESS=1 cargo test --release --test it model_description::\nand review `git diff modelDescription/`.",
        failures.join("\n")
    );
}

#[test]
fn normalization_blanks_only_guid_and_generation_tool() {
    let xml = "<a\n  guid=\"{1}\"\n  generationTool=\"mbfmu 0.1.0+ab\"\n  modelName=\"guid\"/>\n<b guid=\"x\"/>";
    assert_eq!(normalize(xml), "<a\n  guid=\"*\"\n  generationTool=\"*\"\n  modelName=\"guid\"/>\n<b guid=\"*\"/>");
}

#[test]
fn the_guid_and_identifier_are_those_of_the_fmi_module() {
    let path = root().join("models/pendulum.xml");
    let text = std::fs::read_to_string(&path).expect("readable");
    let xml = generate(&path, false);
    assert!(xml.contains(&format!("  guid=\"{}\"\n", crate::common::guid(&text))));
    let xml3 = generate(&path, true);
    assert!(xml3.contains(&format!("  instantiationToken=\"{}\"\n", crate::common::guid(&text))));
    assert!(xml.contains("modelIdentifier=\"pendulum\""));
    assert!(xml.contains(&format!("generationTool=\"mbfmu {}\"", mbfmu::fmi::guid::ENGINE_VERSION)));
}
