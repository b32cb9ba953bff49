//! `modelDescription.xml` of a model's FMI 2.0 Co-Simulation FMU.
//!
//! The variables and their value references come from [`crate::fmi::variables`] (shared with
//! the C API). `<ModelStructure>` writes the dependencies of
//! [`crate::linearize::structure`], mapping its indices (states as columns of A, inputs,
//! parameters) to FMI variable indices.

use crate::model::units::{self, BASE_NAMES};
use std::collections::BTreeSet;
use std::fmt::Write as _;

use crate::fmi::guid::{ENGINE_VERSION, guid, model_identifier};
use crate::fmi::variables::{Causality, Target, Variable, variables};
use crate::linearize::{Dependencies, FmuLinearization, ModelStructure, StateLayout, StateValues, for_fmu};
use crate::model::Model;

/// The modelDescription.xml that `mbfmu pack` writes for `model`, whose file text is
/// `model_text`: its linearization decided by [`for_fmu`] (an engine run), then
/// [`describe`].
pub fn write(model: &Model, model_text: &str) -> String {
    let FmuLinearization { layout, structure, starts } = for_fmu(model);
    describe(model, &guid(model, model_text), &layout, &structure, &starts)
}

/// The modelDescription.xml of the FMU of `model` with the GUID `guid` (see
/// [`crate::fmi::guid`]; `model` is the model as the FMU starts, start values applied), the
/// linearization states `layout` and the dependencies `structure` (of the same selection,
/// see [`for_fmu`]).
pub fn describe(
    model: &Model,
    guid: &str,
    layout: &StateLayout,
    structure: &ModelStructure,
    starts: &StateValues,
) -> String {
    let vars = with_state_starts(variables(model, layout), model, layout, starts);
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

    x.push_str("  <CoSimulation\n");
    let id = model_identifier(&model.name);
    for (name, value) in [
        ("modelIdentifier", id.as_str()),
        ("canHandleVariableCommunicationStepSize", "true"),
        ("canGetAndSetFMUstate", "true"),
        ("canSerializeFMUstate", "true"),
        ("canInterpolateInputs", "true"),
        ("maxOutputDerivativeOrder", "1"),
        ("canNotUseMemoryManagementFunctions", "true"),
    ] {
        x.push_str("  ");
        attr_line(&mut x, name, value);
    }
    x.push_str("    providesDirectionalDerivative=\"true\"/>\n");

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

/// `    name="value"` and a newline (attributes of a multi-line start tag).
fn attr_line(x: &mut String, name: &str, value: &str) {
    let _ = writeln!(x, "  {name}=\"{}\"", escape(value));
}

/// Escape text for a double-quoted XML attribute value.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            // Not representable in XML 1.0: drop.
            c if (c as u32) < 0x20 => {}
            c => out.push(c),
        }
    }
    out
}

/// An `xs:double` literal that reads back to the same `f64`: the shorter of Rust's two
/// round-trip formats (`0.5`, `1e-6`), `INF`, `-INF` or `NaN`.
fn real(v: f64) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "INF".into() } else { "-INF".into() };
    }
    let (display, debug) = (format!("{v}"), format!("{v:?}"));
    if debug.len() < display.len() { debug } else { display }
}

fn write_units(x: &mut String, vars: &[Variable]) {
    let units: BTreeSet<&str> = vars.iter().filter_map(|v| v.unit.as_deref()).collect();
    if units.is_empty() {
        return;
    }
    x.push_str("  <UnitDefinitions>\n");
    for u in units {
        match base_unit(u) {
            Some((exps, factor)) => {
                let _ = writeln!(x, "    <Unit name=\"{}\">", escape(u));
                x.push_str("      <BaseUnit");
                for (name, e) in BASE_NAMES.iter().zip(exps) {
                    if e != 0 {
                        let _ = write!(x, " {name}=\"{e}\"");
                    }
                }
                if factor != 1.0 {
                    let _ = write!(x, " factor=\"{}\"", real(factor));
                }
                x.push_str("/>\n    </Unit>\n");
            }
            None => {
                let _ = writeln!(x, "    <Unit name=\"{}\"/>", escape(u));
            }
        }
    }
    x.push_str("  </UnitDefinitions>\n");
}

/// SI exponents (in [`BASE_NAMES`] order) and factor of a unit; `None` for an unparsable
/// or dimensionless one (no `<BaseUnit>` then).
fn base_unit(unit: &str) -> Option<([i32; 8], f64)> {
    let u = units::parse(unit).ok()?;
    (u.exps.iter().any(|e| *e != 0)).then_some((u.exps, u.factor))
}

fn write_experiment(x: &mut String, model: &Model) {
    let e = &model.experiment;
    let attrs: Vec<String> =
        [("startTime", e.start), ("stopTime", e.stop), ("tolerance", e.tolerance), ("stepSize", e.step)]
            .into_iter()
            .filter_map(|(n, v)| v.map(|v| format!(" {n}=\"{}\"", real(v))))
            .collect();
    if !attrs.is_empty() {
        let _ = writeln!(x, "  <DefaultExperiment{}/>", attrs.concat());
    }
}

/// The states' start values: those set when packing as set, others S, W (`der(S)` where
/// it is W) from `starts` (the assembled model), X from the model's `start`. Other locals (derivatives, user variables) have none.
fn with_state_starts(
    mut vars: Vec<Variable>,
    model: &Model,
    layout: &StateLayout,
    starts: &StateValues,
) -> Vec<Variable> {
    for v in &mut vars {
        // A state given a start value when packing (`--set`) has exactly that start.
        if let Some((_, x)) = model.state_starts.iter().find(|(n, _)| *n == v.name) {
            v.start = Some(*x);
            continue;
        }
        v.start = match v.target {
            Target::State(k) => starts.s.get(k).copied(),
            Target::StateDerivative(k) if layout.velocity_of_state(k).is_some() => starts.sd.get(k).copied(),
            Target::Velocity(j) => starts.w.get(j).copied(),
            Target::Diff(k) => Some(model.differentials[k].start.value),
            _ => v.start,
        };
    }
    vars
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
    // FMI index (1-based ModelVariables position) of each parameter, input and state
    // (column of A).
    let mut param_index = vec![0; model.parameters.len()];
    let mut input_index = vec![0; model.inputs.len()];
    let mut state_index = vec![0; vars.iter().filter(|v| v.known.is_some()).count()];
    for (k, v) in vars.iter().enumerate() {
        match v.target {
            Target::Parameter(p) => param_index[p] = k + 1,
            Target::Input(i) => input_index[i] = k + 1,
            _ => {}
        }
        if let Some(c) = v.known {
            state_index[c] = k + 1;
        }
    }
    let fmi = |d: &Dependencies| -> BTreeSet<usize> {
        let states = d.states.iter().map(|&c| state_index[c]);
        states.chain(d.inputs.iter().map(|&i| input_index[i])).collect()
    };
    let none = Dependencies::default();
    let mut unknowns: Vec<(usize, &Dependencies)> = Vec::new(); // (index, at communication points)
    let mut derivatives = Vec::new();
    for (k, v) in vars.iter().enumerate() {
        let d = match v.target {
            Target::Output(o) => &st.outputs[o],
            Target::StateDerivative(i) => &st.position_rates[i],
            Target::VelocityDerivative(j) => &st.velocity_rates[j],
            Target::DiffDerivative(i) => &st.diff_rates[i],
            Target::State(_) | Target::Velocity(_) | Target::Diff(_) => &none,
            _ => continue,
        };
        if matches!(v.target, Target::StateDerivative(_) | Target::VelocityDerivative(_) | Target::DiffDerivative(_)) {
            derivatives.push((k + 1, d));
        }
        unknowns.push((k + 1, d));
    }
    if unknowns.is_empty() {
        x.push_str("  <ModelStructure/>\n");
        return;
    }
    x.push_str("  <ModelStructure>\n");
    let outputs: Vec<&(usize, &Dependencies)> =
        unknowns.iter().filter(|(i, _)| matches!(vars[i - 1].target, Target::Output(_))).collect();
    if !outputs.is_empty() {
        x.push_str("    <Outputs>\n");
        for (index, d) in outputs {
            unknown(x, *index, &fmi(d));
        }
        x.push_str("    </Outputs>\n");
    }
    if !derivatives.is_empty() {
        x.push_str("    <Derivatives>\n");
        for (index, d) in &derivatives {
            unknown(x, *index, &fmi(d));
        }
        x.push_str("    </Derivatives>\n");
    }
    x.push_str("    <InitialUnknowns>\n");
    for (index, d) in &unknowns {
        let init = st.initial(d);
        let params = init.parameters.iter().map(|&p| param_index[p]);
        unknown(x, *index, &params.chain(init.inputs.iter().map(|&i| input_index[i])).collect());
    }
    x.push_str("    </InitialUnknowns>\n  </ModelStructure>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_decompose_into_si_exponents() {
        assert_eq!(base_unit("N.m"), Some(([1, 2, -2, 0, 0, 0, 0, 0], 1.0)));
        assert_eq!(base_unit("N.m.s/rad"), Some(([1, 2, -1, 0, 0, 0, 0, -1], 1.0)));
        assert_eq!(base_unit("kg.m2"), Some(([1, 2, 0, 0, 0, 0, 0, 0], 1.0)));
        assert_eq!(base_unit("m/s2"), Some(([0, 1, -2, 0, 0, 0, 0, 0], 1.0)));
        assert_eq!(base_unit("N.s/m"), Some(([1, 0, -1, 0, 0, 0, 0, 0], 1.0)));
        assert_eq!(base_unit("mol"), Some(([0, 0, 0, 0, 0, 1, 0, 0], 1.0)));
        assert_eq!(base_unit("furlong"), None);
        assert_eq!(base_unit("m/s/s"), None);
        assert_eq!(base_unit(""), None);
        assert_eq!(base_unit("m/m"), None);
        assert_eq!(base_unit("mm"), Some(([0, 1, 0, 0, 0, 0, 0, 0], 1e-3)));
    }

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

    #[test]
    fn reals_round_trip_and_escaping() {
        for v in [0.0, 0.5, 1e-6, 9.80665, 170.0 * std::f64::consts::PI / 180.0, 1e300, -2.5e-12] {
            assert_eq!(real(v).parse::<f64>().ok(), Some(v), "{}", real(v));
        }
        assert_eq!(real(1e-6), "1e-6");
        assert_eq!(real(8.2), "8.2");
        assert_eq!(real(0.0), "0");
        assert_eq!(escape("a<b & \"c\"\n"), "a&lt;b &amp; &quot;c&quot;&#10;");
    }
}
