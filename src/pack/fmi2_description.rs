//! `modelDescription.xml` of a model's FMI 2.0 FMU (Model Exchange and/or Co-Simulation).
//!
//! The variables and their value references come from [`crate::fmi::variables`] (shared with
//! the C API). `<ModelStructure>` writes the dependencies of
//! [`crate::linearize::structure`], mapping its indices (states as columns of A, inputs,
//! parameters) to FMI variable indices.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use super::structure::unknowns;
use super::xml::{attr_line, empty_element, escape, real, with_state_starts, write_experiment, write_units};

use crate::fmi::guid::{ENGINE_VERSION, guid, model_identifier};
use crate::fmi::resources::Interfaces;
use crate::fmi::variables::{Causality, Standard, Variable, variables};
use crate::linearize::{FmuLinearization, ModelStructure, StateLayout, StateValues, for_fmu};
use crate::model::Model;

/// The modelDescription.xml that `mbfmu pack` writes for `model`, whose file text is
/// `model_text`: its linearization decided by [`for_fmu`] (an engine run), then
/// [`describe`].
pub fn write(model: &Model, model_text: &str) -> String {
    let FmuLinearization { layout, structure, starts } = for_fmu(model);
    let interfaces = super::Kind::Both.interfaces(&layout).map_or(super::CO_SIMULATION, |(i, _)| i);
    describe(model, &guid(model, model_text), &layout, &structure, &starts, interfaces)
}

/// The modelDescription.xml of the FMU of `model` with the GUID `guid` (see
/// [`crate::fmi::guid`]; `model` is the model as the FMU starts, start values applied), the
/// linearization states `layout` and the dependencies `structure` (of the same selection,
/// see [`for_fmu`]), offering the `interfaces`.
pub fn describe(
    model: &Model,
    guid: &str,
    layout: &StateLayout,
    structure: &ModelStructure,
    starts: &StateValues,
    interfaces: Interfaces,
) -> String {
    let vars = with_state_starts(variables(model, layout, Standard::Fmi2), model, layout, starts);
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    x.push_str("<fmiModelDescription\n");
    attr_line(&mut x, "fmiVersion", "2.0");
    attr_line(&mut x, "modelName", &model.name);
    attr_line(&mut x, "guid", guid);
    attr_line(&mut x, "description", &format!("Multibody model {}", model.name));
    attr_line(&mut x, "generationTool", &format!("mbfmu {ENGINE_VERSION}"));
    attr_line(&mut x, "variableNamingConvention", "structured");
    x.push_str("  numberOfEventIndicators=\"0\">\n");

    let id = model_identifier(&model.name);
    if interfaces.model_exchange {
        let attrs = [
            ("modelIdentifier", id.as_str()),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("providesDirectionalDerivative", "true"),
        ];
        empty_element(&mut x, "ModelExchange", &attrs);
    }
    if interfaces.co_simulation {
        let attrs = [
            ("modelIdentifier", id.as_str()),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("canInterpolateInputs", "true"),
            ("maxOutputDerivativeOrder", "1"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("providesDirectionalDerivative", "true"),
        ];
        empty_element(&mut x, "CoSimulation", &attrs);
    }

    write_units(&mut x, &vars);
    write_experiment(&mut x, model);

    x.push_str("  <ModelVariables>\n");
    for (k, v) in vars.iter().enumerate() {
        write_variable(&mut x, k + 1, v);
    }
    x.push_str("  </ModelVariables>\n");

    write_structure(&mut x, model, &vars, structure);
    x.push_str("</fmiModelDescription>\n");
    x
}

fn write_variable(x: &mut String, index: usize, v: &Variable) {
    let (causality, variability, initial) = match v.causality {
        // Solver settings may change between steps; model parameters only before
        // initialization ends.
        Causality::Parameter if v.target.is_integer() => ("parameter", "tunable", Some("exact")),
        Causality::Parameter => ("parameter", "fixed", Some("exact")),
        Causality::Input => ("input", "continuous", None),
        Causality::Output => ("output", "continuous", Some("calculated")),
        // A state's start is its value in the assembled model (X: the model's start), an
        // iteration start in FMI terms: a value the host sets is met exactly. (As `approx`
        // every state stays an InitialUnknown.)
        Causality::Local if v.start.is_some() => ("local", "continuous", Some("approx")),
        Causality::Local => ("local", "continuous", Some("calculated")),
        Causality::Independent => ("independent", "continuous", None),
    };
    let _ = writeln!(x, "    <!-- index {index} -->");
    let _ = write!(
        x,
        "    <ScalarVariable name=\"{}\" valueReference=\"{}\" causality=\"{causality}\" variability=\"{variability}\"",
        escape(&v.name),
        v.value_reference
    );
    if let Some(i) = initial {
        let _ = write!(x, " initial=\"{i}\"");
    }
    if let Some(d) = &v.description {
        let _ = write!(x, " description=\"{}\"", escape(d));
    }
    if v.target.is_integer() {
        x.push_str(">\n      <Integer");
        if let Some(s) = v.start {
            let _ = write!(x, " start=\"{}\"", s as i64);
        }
        x.push_str("/>\n    </ScalarVariable>\n");
        return;
    }
    x.push_str(">\n      <Real");
    if let Some(k) = v.derivative {
        let _ = write!(x, " derivative=\"{k}\"");
    }
    if let Some(u) = &v.unit {
        let _ = write!(x, " unit=\"{}\"", escape(u));
    }
    // Calculated variables (outputs, derivatives) may not have a start value.
    if let (Some(s), false) = (v.start, matches!(v.causality, Causality::Output)) {
        let _ = write!(x, " start=\"{}\"", real(s));
    }
    x.push_str("/>\n    </ScalarVariable>\n");
}

/// `<Unknown index dependencies dependenciesKind/>` with 1-based `deps`.
fn unknown(x: &mut String, index: usize, deps: &BTreeSet<usize>) {
    let list: Vec<String> = deps.iter().map(|d| d.to_string()).collect();
    let kinds = vec!["dependent"; deps.len()];
    let _ = writeln!(
        x,
        "      <Unknown index=\"{index}\" dependencies=\"{}\" dependenciesKind=\"{}\"/>",
        list.join(" "),
        kinds.join(" ")
    );
}

fn write_structure(x: &mut String, model: &Model, vars: &[Variable], st: &ModelStructure) {
    let u = unknowns(model, vars, st);
    let index = |set: &BTreeSet<usize>| -> BTreeSet<usize> { set.iter().map(|k| k + 1).collect() };
    if u.initial.is_empty() {
        x.push_str("  <ModelStructure/>\n");
        return;
    }
    x.push_str("  <ModelStructure>\n");
    for (tag, list) in [("Outputs", &u.outputs), ("Derivatives", &u.derivatives)] {
        if !list.is_empty() {
            let _ = writeln!(x, "    <{tag}>");
            for (k, d) in list {
                unknown(x, k + 1, &index(d));
            }
            let _ = writeln!(x, "    </{tag}>");
        }
    }
    x.push_str("    <InitialUnknowns>\n");
    for (k, d) in &u.initial {
        unknown(x, k + 1, &index(d));
    }
    x.push_str("    </InitialUnknowns>\n  </ModelStructure>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slider with three inputs: `u` drives an sforce, `v` a gforce, `w` only an output.
    const INPUTS: &str = r#"<multibody name="inputs" version="1">
  <parameter name="m" value="2" unit="kg" description="mass &amp; more"/>
  <parameter name="k" value="3"/>
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="m" inertia="1 1 1" position="0 0 0"/>
  <joint name="j" type="translational" i="b.cm" j="ground.O"/>
  <input name="u" start="1.5" unit="N"/>
  <input name="v"/>
  <input name="w" unit="1"/>
  <sforce name="f" type="translational" i="b.cm" j="ground.O" function="u*k"/>
  <gforce name="g" i="b.cm" force="0, 0, v" torque="0 0 0"/>
  <output name="pos" function="dz(b.cm)" unit="m"/>
  <output name="direct" function="w + vz(b.cm)"/>
  <output name="acc" function="accz(b.cm)" unit="m/s2"/>
  <output name="reaction" function="fz(j)"/>
  <output name="force" function="fz(f) + w"/>
</multibody>"#;

    #[test]
    fn dependencies_follow_inputs_through_forces_and_accelerations() {
        let model = crate::model::load_str(INPUTS, "inputs.xml").unwrap_or_else(|e| panic!("{e}"));
        let structure = for_fmu(&model).structure;
        let d: Vec<Vec<usize>> = structure.outputs.iter().map(|o| o.inputs.iter().copied().collect()).collect();
        assert_eq!(d, [vec![], vec![2], vec![0, 1], vec![0, 1], vec![0, 2]]);
        let xml = write(&model, INPUTS);
        // Indices: m 1, k 2, u 3, v 4, w 5, pos 6, direct 7, acc 8, reaction 9, force 10.
        let outputs = xml.split("<Outputs>").nth(1).and_then(|s| s.split("</Outputs>").next()).unwrap_or_default();
        assert!(outputs.contains(r#"<Unknown index="6" dependencies="" dependenciesKind=""/>"#), "{xml}");
        assert!(outputs.contains(r#"<Unknown index="7" dependencies="5" dependenciesKind="dependent"/>"#));
        assert!(outputs.contains(r#"<Unknown index="8" dependencies="3 4" dependenciesKind="dependent dependent"/>"#));
        assert!(outputs.contains(r#"<Unknown index="10" dependencies="3 5" dependenciesKind="dependent dependent"/>"#));
        let init = xml.split("<InitialUnknowns>").nth(1).unwrap_or_default();
        assert!(init.contains(r#"<Unknown index="6" dependencies="1 2" dependenciesKind="dependent dependent"/>"#));
        assert!(init.contains(r#"<Unknown index="8" dependencies="1 2 3 4" "#));
        assert!(
            xml.contains(r#"<ScalarVariable name="u" valueReference="2" causality="input" variability="continuous">"#)
        );
        assert!(xml.contains(r#"<Real unit="N" start="1.5"/>"#));
        assert!(xml.contains(r#"description="mass &amp; more""#));
        assert!(xml.contains(r#"modelIdentifier="inputs""#));
        assert!(xml.contains(r#"<Unit name="1"/>"#));
        assert!(!xml.contains("<DefaultExperiment"));
        let units: Vec<&str> =
            xml.lines().filter_map(|l| l.trim().strip_prefix("<Unit name=\"")?.split('"').next()).collect();
        assert_eq!(units, ["1", "N", "kg", "m", "m/s2"]);
    }

    #[test]
    fn static_analysis_makes_initial_outputs_depend_on_force_inputs() {
        let text = INPUTS.replace("<output name=\"pos\"", "<analysis static=\"true\"/><output name=\"pos\"");
        let model = crate::model::load_str(&text, "inputs.xml").unwrap_or_else(|e| panic!("{e}"));
        let xml = write(&model, &text);
        let init = xml.split("<InitialUnknowns>").nth(1).unwrap_or_default();
        assert!(init.contains(r#"<Unknown index="6" dependencies="1 2 3 4" "#), "{xml}");
        assert!(init.contains(r#"<Unknown index="7" dependencies="1 2 3 4 5" "#), "{xml}");
    }

    #[test]
    fn a_model_without_outputs_or_units_lists_its_states_with_coordinate_units() {
        let text = r#"<multibody name="bare" version="1">
  <parameter name="m" value="2"/>
  <body name="b" mass="m" inertia="1 1 1" position="0 0 0"/>
</multibody>"#;
        let model = crate::model::load_str(text, "bare.xml").unwrap_or_else(|e| panic!("{e}"));
        let xml = write(&model, text);
        // A free body: six internal states, their velocities and accelerations.
        assert!(xml.contains(r#"name="b.x""#) && xml.contains(r#"name="der(b.phi,2)""#), "{xml}");
        assert!(xml.contains("<Derivatives>"), "{xml}");
        assert!(!xml.contains("<Outputs"), "{xml}");
        // The states carry the units of their coordinates (the model declares none).
        for (var, unit) in [("b.x", "m"), ("b.phi", "rad"), ("der(b.x)", "m/s"), ("der(b.phi,2)", "rad/s2")] {
            let at = xml.find(&format!("name=\"{var}\"")).unwrap_or_else(|| panic!("{var}"));
            let real = &xml[at..at + xml[at..].find("</ScalarVariable>").unwrap()];
            assert!(real.contains(&format!("unit=\"{unit}\"")), "{var}: {real}");
        }
        assert!(xml.contains(r#"<Unit name="rad/s2">"#), "{xml}");
    }
}
