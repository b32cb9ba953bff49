//! State names and the measures they name: a `<linearization>` state by its name, a
//! joint's free coordinate (`hinge.angle`), a body's CM coordinate or 3-1-3 angle
//! (`arm.x` … `arm.phi`, angles relative to the body's current reference frame), a
//! flexible body's modal coordinate (`arm.eta2`). Linearization names its states so, and
//! start values set on states by name are resolved here.

use super::measures::StateKind;
use super::system::System;
use crate::model::expr::{Expr, deps};

/// The coordinate names of a body, in q's order (CM position, then 3-1-3 angles).
pub const BODY_COORDS: [&str; 6] = ["x", "y", "z", "psi", "theta", "phi"];

/// The name of the time derivative of the quantity named `name`: `der(name)`, the FMI
/// convention; the one place that writes it ([`derivative_of_name`] reads it).
pub fn derivative_name(name: &str) -> String {
    format!("der({name})")
}

/// The `name` of [`derivative_name`]`(name)`, if `der` is one.
pub fn derivative_of_name(der: &str) -> Option<&str> {
    der.strip_prefix("der(")?.strip_suffix(')')
}

/// The bodies (sorted, once each) whose markers expression `f` reads.
pub fn expr_bodies(sys: &System, f: &Expr) -> Vec<usize> {
    let mut bodies: Vec<usize> = deps(f).markers.iter().filter_map(|&m| sys.markers[m].body).collect();
    bodies.sort_unstable();
    bodies.dedup();
    bodies
}

/// The measure named `name` and the bodies it reads (None: no state has that name).
pub fn measure_by_name(sys: &System, name: &str) -> Option<(StateKind, Vec<usize>)> {
    if let Some((_, f, abase)) = sys.lin_states.iter().find(|s| s.0 == name) {
        return Some((StateKind::User { f: f.clone(), abase: *abase }, expr_bodies(sys, f)));
    }
    if let Some(c) = sys.joint_coords.iter().find(|c| c.name == name) {
        let kind = StateKind::Joint { f: c.f.clone(), abase: c.abase, about: c.about.clone() };
        return Some((kind, expr_bodies(sys, &c.f)));
    }
    let (body, c) = name.rsplit_once('.')?;
    let b = sys.bodies.iter().position(|x| x.name == body)?;
    // A flexible body's modal coordinate `body.etaK` (K from 1, written without zeros in front).
    if let Some(k) = c.strip_prefix("eta").and_then(|k| k.parse::<usize>().ok().filter(|n| n.to_string() == k)) {
        return (1..=sys.modal_range(b).len()).contains(&k).then(|| (StateKind::Modal { k: k - 1 }, vec![b]));
    }
    let k = BODY_COORDS.iter().position(|x| *x == c)?;
    let kind = if k < 3 { StateKind::Position { k } } else { StateKind::Angle { k: k - 3, r0: sys.r0[b] } };
    Some((kind, vec![b]))
}

/// Every position-level state name of the system (for suggestions), in the order
/// [`measure_by_name`] tries them.
pub fn measure_names(sys: &System) -> Vec<String> {
    let mut names: Vec<String> = sys.lin_states.iter().map(|s| s.0.clone()).collect();
    names.extend(sys.joint_coords.iter().map(|c| c.name.clone()));
    for (b, body) in sys.bodies.iter().enumerate() {
        names.extend(BODY_COORDS.iter().map(|c| format!("{}.{c}", body.name)));
        names.extend((1..=sys.modal_range(b).len()).map(|k| format!("{}.eta{k}", body.name)));
    }
    names
}
