//! XML pieces both model descriptions share: attribute escaping, `xs:double` literals,
//! `<UnitDefinitions>`, `<DefaultExperiment>`, and the states' start values.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use crate::fmi::variables::{Target, Variable};
use crate::linearize::{StateLayout, StateValues};
use crate::model::Model;
use crate::model::units::{self, BASE_NAMES};

/// `    name="value"` and a newline (attributes of a multi-line start tag).
pub(super) fn attr_line(x: &mut String, name: &str, value: &str) {
    let _ = writeln!(x, "  {name}=\"{}\"", escape(value));
}

/// An empty element `<tag .../>` indented by two, one attribute a line, the last one
/// closing the tag (the interface elements of both FMI versions).
pub(super) fn empty_element(x: &mut String, tag: &str, attrs: &[(&str, &str)]) {
    let _ = write!(x, "  <{tag}");
    for (name, value) in attrs {
        let _ = write!(x, "\n    {name}=\"{}\"", escape(value));
    }
    x.push_str("/>\n");
}

/// Escape text for a double-quoted XML attribute value.
pub(super) fn escape(s: &str) -> String {
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
pub(super) fn real(v: f64) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "INF".into() } else { "-INF".into() };
    }
    let (display, debug) = (format!("{v}"), format!("{v:?}"));
    if debug.len() < display.len() { debug } else { display }
}

pub(super) fn write_units(x: &mut String, vars: &[Variable]) {
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
pub(super) fn base_unit(unit: &str) -> Option<([i32; 8], f64)> {
    let u = units::parse(unit).ok()?;
    (u.exps.iter().any(|e| *e != 0)).then_some((u.exps, u.factor))
}

pub(super) fn write_experiment(x: &mut String, model: &Model) {
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
pub(super) fn with_state_starts(
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
