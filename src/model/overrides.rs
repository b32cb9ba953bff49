//! Start-value overrides `NAME=VALUE` (the command line's `--set`, a packed FMU's
//! `resources/start_values.txt`): parsing, resolution of the names against a model, and
//! the model with the values applied. One place for every user of overrides, so that the
//! CLI commands and the FMU agree on what a name means and on every error message.
//!
//! A name resolves to a model parameter ([`OverrideTarget::Parameter`]), applied with the
//! re-evaluation the FMU does when a parameter is set before initialization
//! ([`Model::with_params`]), or else to a state ([`OverrideTarget::State`]: `hinge.angle`,
//! `der(hinge.angle)`, `body.x`, a `<linearization>` state, a differential), kept by name
//! in [`Model::state_starts`]: only the mechanism knows its states, so the engine resolves
//! those names (`dae::StartValues::named`, which also reports an unknown one).

use crate::model::Model;

/// What an override sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OverrideTarget {
    /// Index into [`Model::parameters`]: the parameter's value.
    Parameter(usize),
    /// A state's start value (the override's name is the state's).
    State,
}

/// One resolved override: the name as given, what it sets, and the value.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The name as given.
    pub name: String,
    /// What it sets.
    pub target: OverrideTarget,
    /// The value (finite).
    pub value: f64,
}

/// Parse `NAME=VALUE` (VALUE a finite real number, as Rust's `f64` parser reads it; white
/// space around either side is ignored).
pub fn parse_assignment(s: &str) -> Result<(String, f64), String> {
    let Some((name, value)) = s.split_once('=') else {
        return Err(format!("'{s}' is not NAME=VALUE"));
    };
    let (name, value) = (name.trim(), value.trim());
    if name.is_empty() {
        return Err(format!("'{s}' has no name before '='"));
    }
    let v: f64 = value.parse().map_err(|_| format!("{name}={value}: '{value}' is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{name}={value}: the value must be finite"));
    }
    Ok((name.to_string(), v))
}

/// Levenshtein edit distance between `a` and `b` (in characters).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diag + usize::from(ca != cb)).min(row[j] + 1).min(row[j + 1] + 1);
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The candidate closest to `name` when it is close enough to be a likely typo: at most a
/// third of the longer name's characters (at least 1) edited; ties go to the first.
pub fn closest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (edit_distance(name, c), c))
        .filter(|(d, c)| *d <= (name.chars().count().max(c.chars().count()) / 3).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// `"; did you mean 'x'?"` when a candidate is close to `name` ([`closest`]), else empty.
pub fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    closest(name, candidates).map(|c| format!("; did you mean '{c}'?")).unwrap_or_default()
}

/// The text of a start values file: one `name=value` line per override, in the order
/// given, each value written so that it reads back exactly (Rust's shortest round-trip
/// form).
pub fn start_values_text(overrides: &[Override]) -> String {
    overrides.iter().map(|o| format!("{}={}\n", o.name, o.value)).collect()
}

/// Read a start values file ([`start_values_text`]): `name=value` lines; blank lines and
/// lines starting with `#` are skipped. Errors name the line.
pub fn parse_start_values(text: &str) -> Result<Vec<(String, f64)>, String> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|(k, l)| parse_assignment(l).map_err(|e| format!("line {}: {e}", k + 1)))
        .collect()
}

impl Model {
    /// What the name `name` may set: a parameter, else a state (resolved by the engine).
    /// An input is an error.
    pub fn override_target(&self, name: &str) -> Result<OverrideTarget, String> {
        if let Some(k) = self.parameters.iter().position(|p| p.name == name) {
            return Ok(OverrideTarget::Parameter(k));
        }
        if self.inputs.iter().any(|i| i.name == name) {
            return Err(format!("'{name}' is an input, not a parameter (inputs are given with --input)"));
        }
        Ok(OverrideTarget::State)
    }

    /// The error for a name that is neither a parameter nor one of the states `states`,
    /// with the closest of all those names as a suggestion.
    pub fn unknown_override(&self, name: &str, states: &[String]) -> String {
        let params = self.parameters.iter().map(|p| p.name.as_str());
        let hint = did_you_mean(name, params.chain(states.iter().map(String::as_str)));
        let known = if self.parameters.is_empty() { " (the model has no parameters)" } else { "" };
        format!("model '{}' has no parameter '{name}'{known}{hint} (nor a state of that name)", self.name)
    }

    /// Resolve `NAME=VALUE` pairs: every name known ([`Model::override_target`]), no
    /// target set twice, every value finite. Returned in the model's order of targets
    /// (parameters in file order), so that equal sets of overrides give equal lists.
    pub fn resolve_overrides(&self, pairs: &[(String, f64)]) -> Result<Vec<Override>, String> {
        let mut out: Vec<Override> = Vec::with_capacity(pairs.len());
        for (name, value) in pairs {
            let target = self.override_target(name)?;
            if !value.is_finite() {
                return Err(format!("{name}={value}: the value must be finite"));
            }
            if out.iter().any(|o| o.target == target && (target != OverrideTarget::State || o.name == *name)) {
                return Err(format!("'{name}' is set twice"));
            }
            out.push(Override { name: name.clone(), target, value: *value });
        }
        // Parameters in file order, then states in the order given (a stable sort).
        out.sort_by_key(|o| match o.target {
            OverrideTarget::Parameter(k) => k,
            OverrideTarget::State => usize::MAX,
        });
        Ok(out)
    }

    /// A copy with the overrides applied: parameters set and every attribute that uses
    /// them re-evaluated and re-validated, as when an FMU's parameter is set before
    /// initialization ([`Model::with_params`]; a parameter whose value is an expression of
    /// others is a parameter of its own and keeps its value); state start values added to
    /// [`Model::state_starts`]. No overrides: a plain copy.
    pub fn with_overrides(&self, overrides: &[Override]) -> Result<Model, String> {
        let mut p = self.param_values();
        let mut states = Vec::new();
        for o in overrides {
            match o.target {
                OverrideTarget::Parameter(k) => p[k] = o.value,
                OverrideTarget::State => states.push((o.name.clone(), o.value)),
            }
        }
        let mut m = if overrides.iter().any(|o| o.target != OverrideTarget::State) {
            self.with_params(&p)?
        } else {
            self.clone()
        };
        m.state_starts.extend(states);
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODEL: &str = r#"<multibody name="m" version="1">
  <parameter name="mass" value="2"/>
  <parameter name="length" value="1"/>
  <body name="b" mass="mass" inertia="1 1 1" position="length 0 0"/>
</multibody>"#;

    fn model() -> Model {
        crate::model::parse::load_str(MODEL, "m.xml").unwrap()
    }

    #[test]
    fn edit_distance_counts_insertions_deletions_substitutions() {
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("lenght", "length"), 2);
        assert_eq!(edit_distance("mass", "mass"), 0);
        assert_eq!(closest("lenght", ["mass", "length"]), Some("length"));
        assert_eq!(closest("zzz", ["mass", "length"]), None);
    }

    #[test]
    fn assignments_parse_or_say_what_is_wrong() {
        assert_eq!(parse_assignment("L=2").unwrap(), ("L".to_string(), 2.0));
        assert_eq!(parse_assignment(" L = -1.5e-3 ").unwrap(), ("L".to_string(), -1.5e-3));
        assert!(parse_assignment("L2").unwrap_err().contains("not NAME=VALUE"));
        assert!(parse_assignment("L=two").unwrap_err().contains("'two' is not a number"));
        assert!(parse_assignment("L=inf").unwrap_err().contains("finite"));
        assert!(parse_assignment("L=NaN").unwrap_err().contains("finite"));
        assert!(parse_assignment("=2").unwrap_err().contains("no name"));
    }

    #[test]
    fn overrides_resolve_sort_and_apply() {
        let m = model();
        let o = m.resolve_overrides(&[("length".into(), 3.0), ("mass".into(), 5.0)]).unwrap();
        assert_eq!(
            o.iter().map(|o| o.target).collect::<Vec<_>>(),
            [OverrideTarget::Parameter(0), OverrideTarget::Parameter(1)]
        );
        let m2 = m.with_overrides(&o).unwrap();
        assert_eq!(m2.bodies[0].mass.value, 5.0);
        assert_eq!(m2.bodies[0].position.values()[0], 3.0);
        assert_eq!(m2.param_values(), [5.0, 3.0]);
        let text = start_values_text(&o);
        assert_eq!(text, "mass=5\nlength=3\n");
        assert_eq!(parse_start_values(&text).unwrap(), [("mass".to_string(), 5.0), ("length".to_string(), 3.0)]);
        let x = 0.1 + 0.2;
        let one = m.resolve_overrides(&[("mass".into(), x)]).unwrap();
        assert_eq!(parse_start_values(&start_values_text(&one)).unwrap()[0].1.to_bits(), x.to_bits());
    }

    #[test]
    fn bad_overrides_are_errors_naming_the_problem() {
        let m = model();
        let o = m.resolve_overrides(&[("lenght".into(), 1.0)]).unwrap();
        assert_eq!(o[0].target, OverrideTarget::State);
        let e = m.unknown_override("lenght", &["b.x".into()]);
        assert!(e.contains("no parameter 'lenght'; did you mean 'length'?"), "{e}");
        let e = m.resolve_overrides(&[("mass".into(), 1.0), ("mass".into(), 2.0)]).unwrap_err();
        assert!(e.contains("'mass' is set twice"), "{e}");
        let o = m.resolve_overrides(&[("mass".into(), -1.0)]).unwrap();
        let e = m.with_overrides(&o).unwrap_err();
        assert!(e.contains("body 'b'"), "{e}");
        assert!(parse_start_values("mass=1\nbad\n").unwrap_err().starts_with("line 2:"));
    }
}
