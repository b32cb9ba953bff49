//! `modelDescription.xml` of a model's FMI 3.0 FMU (Model Exchange, Co-Simulation or
//! both): the same variables as
//! the FMI 2 FMU ([`crate::fmi::variables`], value references unchanged) as `<Float64>`
//! and `<Int32>`, plus the independent variable `time` (FMI 3 requires one; last, so it
//! shifts no other value reference); `<ModelStructure>` names variables by value
//! reference.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use super::structure::unknowns;
use super::xml::{attr_line, empty_element, escape, real, with_state_starts, write_experiment, write_units};
use crate::fmi::guid::{ENGINE_VERSION, guid, model_identifier};
use crate::fmi::logger::CATEGORIES;
use crate::fmi::resources::Interfaces;
use crate::fmi::variables::{Causality, Standard, Variable, variables};
use crate::linearize::{FmuLinearization, ModelStructure, StateLayout, StateValues, for_fmu};
use crate::model::Model;

/// The FMI 3 modelDescription.xml that `mbfmu pack --fmi 3` writes for `model`, whose
/// file text is `model_text` (see [`super::fmi2_description::write`]).
pub fn write(model: &Model, model_text: &str) -> String {
    let FmuLinearization { layout, structure, starts } = for_fmu(model);
    let interfaces = super::Kind::Both.interfaces(&layout).map_or(super::CO_SIMULATION, |(i, _)| i);
    describe(model, &guid(model, model_text), &layout, &structure, &starts, interfaces)
}

/// The modelDescription.xml of the FMI 3.0 FMU of `model` with the instantiation token
/// `token` (the FMI 2 GUID), the linearization states `layout`, their dependencies
/// `structure` and start values `starts`, offering the `interfaces` (see
/// [`super::fmi2_description::describe`]).
pub fn describe(
    model: &Model,
    token: &str,
    layout: &StateLayout,
    structure: &ModelStructure,
    starts: &StateValues,
    interfaces: Interfaces,
) -> String {
    let vars = with_state_starts(variables(model, layout, Standard::Fmi3), model, layout, starts);
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    x.push_str("<fmiModelDescription\n");
    attr_line(&mut x, "fmiVersion", "3.0");
    attr_line(&mut x, "modelName", &model.name);
    attr_line(&mut x, "instantiationToken", token);
    attr_line(&mut x, "description", &format!("Multibody model {}", model.name));
    attr_line(&mut x, "generationTool", &format!("mbfmu {ENGINE_VERSION}"));
    x.push_str("  variableNamingConvention=\"structured\">\n");

    let id = model_identifier(&model.name);
    if interfaces.model_exchange {
        // The fold check of the states' chart runs at each completed integrator step.
        let attrs = [
            ("modelIdentifier", id.as_str()),
            ("canGetAndSetFMUState", "true"),
            ("canSerializeFMUState", "true"),
            ("providesDirectionalDerivatives", "true"),
            ("providesAdjointDerivatives", "true"),
            ("needsCompletedIntegratorStep", "true"),
        ];
        empty_element(&mut x, "ModelExchange", &attrs);
    }
    if interfaces.co_simulation {
        let attrs = [
            ("modelIdentifier", id.as_str()),
            ("canGetAndSetFMUState", "true"),
            ("canSerializeFMUState", "true"),
            ("providesDirectionalDerivatives", "true"),
            ("providesAdjointDerivatives", "true"),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("maxOutputDerivativeOrder", "1"),
            ("hasEventMode", "true"),
            ("canReturnEarlyAfterIntermediateUpdate", "false"),
        ];
        empty_element(&mut x, "CoSimulation", &attrs);
    }

    write_units(&mut x, &vars);
    x.push_str("  <LogCategories>\n");
    for (name, what) in CATEGORIES {
        let _ = writeln!(
            x,
            "    <Category name=\"{}\" description=\"{}\"/>",
            escape(&name.to_string_lossy()),
            escape(what)
        );
    }
    x.push_str("  </LogCategories>\n");
    write_experiment(&mut x, model);

    x.push_str("  <ModelVariables>\n");
    for v in &vars {
        write_variable(&mut x, v, &vars);
    }
    x.push_str("  </ModelVariables>\n");

    write_structure(&mut x, model, &vars, structure);
    x.push_str("</fmiModelDescription>\n");
    x
}

fn write_variable(x: &mut String, v: &Variable, vars: &[Variable]) {
    let (causality, variability, initial) = match v.causality {
        Causality::Independent => ("independent", "continuous", None),
        Causality::Parameter if v.target.is_integer() => ("parameter", "tunable", Some("exact")),
        Causality::Parameter => ("parameter", "fixed", Some("exact")),
        Causality::Input => ("input", "continuous", None),
        Causality::Output => ("output", "continuous", Some("calculated")),
        Causality::Local if v.start.is_some() => ("local", "continuous", Some("approx")),
        Causality::Local => ("local", "continuous", Some("calculated")),
    };
    let element = if v.target.is_integer() { "Int32" } else { "Float64" };
    let _ = write!(
        x,
        "    <{element} name=\"{}\" valueReference=\"{}\" causality=\"{causality}\" variability=\"{variability}\"",
        escape(&v.name),
        v.value_reference
    );
    if let Some(i) = initial {
        let _ = write!(x, " initial=\"{i}\"");
    }
    if let Some(d) = &v.description {
        let _ = write!(x, " description=\"{}\"", escape(d));
    }
    if let Some(u) = &v.unit {
        let _ = write!(x, " unit=\"{}\"", escape(u));
    }
    // FMI 3 names the state by its value reference (FMI 2: its 1-based index).
    if let Some(k) = v.derivative {
        let _ = write!(x, " derivative=\"{}\"", vars[k - 1].value_reference);
    }
    match v.start {
        Some(s) if v.target.is_integer() => {
            let _ = write!(x, " start=\"{}\"", s as i64);
        }
        Some(s) if !matches!(v.causality, Causality::Output) => {
            let _ = write!(x, " start=\"{}\"", real(s));
        }
        _ => {}
    }
    x.push_str("/>\n");
}

/// `<element valueReference dependencies dependenciesKind/>` with `deps` as value
/// references.
fn unknown(x: &mut String, element: &str, vr: u32, deps: &BTreeSet<u32>) {
    let list: Vec<String> = deps.iter().map(|d| d.to_string()).collect();
    let kinds = vec!["dependent"; deps.len()];
    let _ = writeln!(
        x,
        "    <{element} valueReference=\"{vr}\" dependencies=\"{}\" dependenciesKind=\"{}\"/>",
        list.join(" "),
        kinds.join(" ")
    );
}

fn write_structure(x: &mut String, model: &Model, vars: &[Variable], st: &ModelStructure) {
    let u = unknowns(model, vars, st);
    let vr = |set: &BTreeSet<usize>| -> BTreeSet<u32> { set.iter().map(|&k| vars[k].value_reference).collect() };
    if u.initial.is_empty() {
        x.push_str("  <ModelStructure/>\n");
        return;
    }
    x.push_str("  <ModelStructure>\n");
    for (k, d) in &u.outputs {
        unknown(x, "Output", vars[*k].value_reference, &vr(d));
    }
    for (k, d) in &u.derivatives {
        unknown(x, "ContinuousStateDerivative", vars[*k].value_reference, &vr(d));
    }
    for (k, d) in &u.initial {
        unknown(x, "InitialUnknown", vars[*k].value_reference, &vr(d));
    }
    x.push_str("  </ModelStructure>\n");
}
