//! The linearization states an FMU exposes, as data: their names, units and descriptions,
//! and which velocity state W_j is the derivative of which position state S_k (Eq.
//! 34g–h). Decided once from [`super::selection_at_start`] when the FMU is packed, carried
//! in the FMU as text ([`StateLayout::to_text`]), and turned back into a [`Selection`] on
//! an instance's engine ([`selection_by_name`]).

use super::select::Selection;
use super::states::{StateFn, VelState};
use crate::mechanics::System;
use crate::mechanics::measure_names::measure_by_name;
use crate::model::Model;

/// One linearization state as the FMU names it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateInfo {
    /// Its name: the position state's, `der(S)` or a user `<velocity>`'s.
    pub name: String,
    /// Its unit (m, rad, m/s, rad/s, a user expression's kinematic unit), if it has one.
    pub unit: Option<String>,
    /// What it measures, frame stated (the FMI variable description).
    pub description: String,
}

/// The position states S and velocity states W of a selection, as names and indices.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StateLayout {
    /// Position states S_k.
    pub positions: Vec<StateInfo>,
    /// Velocity states W_j.
    pub velocities: Vec<StateInfo>,
    /// For each W_j, the k with W_j = Ṡ_k.
    velocity_of: Vec<Option<usize>>,
    /// Why there are no states: the selection failed (the located message).
    pub missing: Option<String>,
}

impl StateLayout {
    /// The layout of a selection.
    pub fn of(sel: &Selection) -> StateLayout {
        let info = |name: String, unit: Option<String>, description: String| StateInfo { name, unit, description };
        StateLayout {
            positions: sel.states.iter().map(|s| info(s.name.clone(), s.unit(), s.description())).collect(),
            velocities: sel.velocities.iter().map(|w| info(w.name(), w.unit(), w.description())).collect(),
            velocity_of: (0..sel.velocities.len()).map(|j| sel.state_of_velocity(j)).collect(),
            missing: None,
        }
    }

    /// No states, because of `why`.
    pub fn unavailable(why: String) -> StateLayout {
        StateLayout { missing: Some(why), ..Default::default() }
    }

    /// The layout of [`super::selection_at_start`] (the FMU's states), or none with the
    /// reason when the selection fails.
    pub fn at_start(model: &Model) -> StateLayout {
        match super::selection_at_start(model) {
            Ok(sel) => StateLayout::of(&sel),
            Err(e) => StateLayout::unavailable(e.to_string()),
        }
    }

    /// The index k of the position state whose derivative W_j is (as
    /// [`Selection::state_of_velocity`]).
    pub fn state_of_velocity(&self, j: usize) -> Option<usize> {
        self.velocity_of.get(j).copied().flatten()
    }

    /// The index j of the velocity state W_j = Ṡ_k, if S_k has one.
    pub fn velocity_of_state(&self, k: usize) -> Option<usize> {
        self.velocity_of.iter().position(|o| *o == Some(k))
    }

    /// The layout as text, one state a line, headed by the GUID of the model it belongs
    /// to: read back with [`StateLayout::from_text`].
    pub fn to_text(&self, guid: &str) -> String {
        let opt = |o: Option<&str>| o.map_or(NONE.to_string(), escape);
        let mut t = format!("{HEADER}\nguid\t{}\n", escape(guid));
        for s in &self.positions {
            t += &format!("S\t{}\t{}\t{}\n", escape(&s.name), opt(s.unit.as_deref()), escape(&s.description));
        }
        for (w, of) in self.velocities.iter().zip(&self.velocity_of) {
            let of = of.map_or(NONE.to_string(), |k| k.to_string());
            t += &format!("W\t{}\t{of}\t{}\t{}\n", escape(&w.name), opt(w.unit.as_deref()), escape(&w.description));
        }
        if let Some(why) = &self.missing {
            t += &format!("missing\t{}\n", escape(why));
        }
        t
    }

    /// Parse [`StateLayout::to_text`]'s text, which must belong to the model of `guid`.
    pub fn from_text(text: &str, guid: &str) -> Result<StateLayout, String> {
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
        if lines.next().map(|(_, l)| l) != Some(HEADER) {
            return Err(format!("not a state layout (its first line is not '{HEADER}')"));
        }
        let mut lay = StateLayout::default();
        let mut own = None;
        for (n, line) in lines {
            let f: Vec<&str> = line.split('\t').collect();
            let bad = |what: &str| format!("line {n}: {what}");
            let text = |s: &str| unescape(s).ok_or_else(|| bad("bad escape"));
            let opt = |s: &str| if s == NONE { Ok(None) } else { text(s).map(Some) };
            match f.as_slice() {
                ["guid", g] => own = Some(text(g)?),
                ["S", name, unit, about] => {
                    lay.positions.push(StateInfo { name: text(name)?, unit: opt(unit)?, description: text(about)? })
                }
                ["W", name, of, unit, about] => {
                    let of = if *of == NONE { None } else { Some(of.parse().map_err(|_| bad("bad state index"))?) };
                    lay.velocity_of.push(of);
                    lay.velocities.push(StateInfo { name: text(name)?, unit: opt(unit)?, description: text(about)? });
                }
                ["missing", why] => lay.missing = Some(text(why)?),
                _ => return Err(bad("unknown line")),
            }
        }
        match own {
            Some(g) if g == guid => {}
            Some(g) => return Err(format!("it belongs to the model of GUID {g}, not {guid}")),
            None => return Err("it names no model GUID".into()),
        }
        if lay.velocity_of.iter().flatten().any(|&k| k >= lay.positions.len()) {
            return Err("a velocity state is the derivative of a position state it does not list".into());
        }
        Ok(lay)
    }
}

/// First line of [`StateLayout::to_text`] (format version 1).
const HEADER: &str = "mbfmu state layout 1";
/// A field without value (an escaped field never reads `\-`).
const NONE: &str = "\\-";

/// `\`, tab, newline and carriage return escaped (fields are tab-separated lines).
fn escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('\t', "\\t").replace('\n', "\\n").replace('\r', "\\r")
}

/// The inverse of [`escape`]; None for an unknown escape.
fn unescape(s: &str) -> Option<String> {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        out.push(match chars.next()? {
            '\\' => '\\',
            't' => '\t',
            'n' => '\n',
            'r' => '\r',
            _ => return None,
        });
    }
    Some(out)
}

/// A position state by name: a user state, a joint coordinate (`joint.angle` ...),
/// `body.x|y|z|psi|theta|phi` (the angles relative to the body's reference frame), or a
/// flexible body's modal coordinate `body.etaK`.
fn position_by_name(sys: &System, name: &str) -> Result<StateFn, String> {
    let (kind, bodies) = measure_by_name(sys, name).ok_or_else(|| format!("unknown linearization state '{name}'"))?;
    Ok(StateFn { name: name.to_string(), kind, bodies })
}

/// The selection `layout` names, rebuilt on `sys`: position states by name ([`StateLayout`]
/// order), velocity states as the derivative of the position state the layout relates
/// them to, else a user `<velocity>` or `der(<position function>)` by name. A layout
/// without states because the selection failed gives its reason.
pub fn selection_by_name(sys: &System, layout: &StateLayout) -> Result<Selection, String> {
    if let Some(why) = &layout.missing {
        return Err(why.clone());
    }
    let states = layout.positions.iter().map(|s| position_by_name(sys, &s.name)).collect::<Result<Vec<_>, _>>()?;
    let user = super::states::user_velocities(sys);
    let velocities = (0..layout.velocities.len())
        .map(|j| {
            if let Some(k) = layout.state_of_velocity(j) {
                return Ok(VelState::Derivative(states[k].clone()));
            }
            let w = &layout.velocities[j].name;
            if let Some(v) = user.iter().find(|v| &v.name == w) {
                return Ok(VelState::User(v.clone()));
            }
            let inner = super::states::derivative_of_name(w).ok_or_else(|| format!("unknown velocity state '{w}'"))?;
            position_by_name(sys, inner).map(VelState::Derivative)
        })
        .collect::<Result<Vec<_>, String>>()?;
    let rank = sys.redundant.iter().filter(|r| !**r).count();
    Ok(Selection::new(states, velocities, layout.velocity_of.clone(), vec![], rank))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> StateLayout {
        let info = |name: &str, unit: Option<&str>, description: &str| StateInfo {
            name: name.into(),
            unit: unit.map(str::to_string),
            description: description.into(),
        };
        StateLayout {
            positions: vec![info("a\tb", Some("m"), "x of 'b'\nground\\frame"), info("c", None, "")],
            velocities: vec![info("der(c)", Some("rad/s"), "rate"), info("v", None, "user")],
            velocity_of: vec![Some(1), None],
            missing: None,
        }
    }

    #[test]
    fn the_text_reads_back_to_the_same_layout_for_its_model_only() {
        let lay = layout();
        let text = lay.to_text("{g}");
        assert_eq!(StateLayout::from_text(&text, "{g}"), Ok(lay.clone()));
        assert_eq!(lay.state_of_velocity(0), Some(1));
        assert_eq!(lay.velocity_of_state(1), Some(0));
        assert_eq!(lay.velocity_of_state(0), None);
        let err = StateLayout::from_text(&text, "{other}").unwrap_err();
        assert!(err.contains("{g}") && err.contains("{other}"), "{err}");
        let missing = StateLayout::unavailable("m.xml:3:5: joint 'j': cannot\tclose".into());
        assert_eq!(StateLayout::from_text(&missing.to_text("g"), "g"), Ok(missing));
        for bad in
            ["", "mbfmu state layout 2\nguid\tg\n", "mbfmu state layout 1\n", "mbfmu state layout 1\nguid\tg\nS\ta\n"]
        {
            assert!(StateLayout::from_text(bad, "g").is_err(), "{bad:?}");
        }
        let dangling = "mbfmu state layout 1\nguid\tg\nW\tder(x)\t0\t\\-\td\n";
        assert!(StateLayout::from_text(dangling, "g").unwrap_err().contains("does not list"));
        assert!(StateLayout::from_text("mbfmu state layout 1\nguid\tg\\q\n", "g").unwrap_err().contains("escape"));
    }
}
