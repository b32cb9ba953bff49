//! Checks on values and on what expressions depend on.

use super::attrs::El;
use super::names::ModelScope;
use crate::model::expr::{self, ElementRef, Expr, MarkerId};
use crate::model::{MAX_ELEMENT_BODIES, ModelError};

/// A mass must be positive.
pub(crate) fn check_mass(m: f64) -> Result<(), String> {
    if m > 0.0 { Ok(()) } else { Err(format!("mass must be positive (got {m})")) }
}

/// The inertia matrix `[[Ixx,Ixy,Ixz],[Ixy,Iyy,Iyz],[Ixz,Iyz,Izz]]` must be positive
/// definite (checked by Cholesky factorization); `v` holds 3 or 6 entries.
pub(crate) fn check_inertia(v: &[f64]) -> Result<(), String> {
    let g = |k: usize| v.get(k).copied().unwrap_or(0.0);
    let (xy, xz, yz) = if v.len() == 6 { (g(3), g(4), g(5)) } else { (0.0, 0.0, 0.0) };
    let a = [[g(0), xy, xz], [xy, g(1), yz], [xz, yz, g(2)]];
    let mut l = [[0.0f64; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return Err("inertia is not positive definite".into());
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Ok(())
}

/// What an expression attribute may depend on.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Allowed {
    /// Time and parameters (motion functions).
    Time,
    /// Positions, time, parameters (constraints, linearization states).
    Positions,
    /// Positions, velocities, time, parameters (linearization velocities).
    Velocities,
    /// Forces, variables, differentials: anything.
    Force,
    /// Outputs: anything.
    Any,
}

/// Check that expression `e` of attribute `attr` uses only what `allowed` permits.
pub(crate) fn check_deps(el: &El, attr: &str, e: &Expr, allowed: Allowed) -> Result<(), ModelError> {
    let d = expr::deps(e);
    let at = el.get(attr).map_or(el.x.pos, |a| a.pos);
    if matches!(allowed, Allowed::Force | Allowed::Any) {
        // A user constraint has no markers, hence no load to read.
        if d.loads.iter().any(|r| matches!(r, ElementRef::Constraint(_))) {
            return Err(el.err_at(at, format!("'{attr}' reads the load of a user constraint, which has no load")));
        }
        return Ok(());
    }
    let max_level = if allowed == Allowed::Velocities { 1 } else { 0 };
    let used = if allowed == Allowed::Time && !d.markers.is_empty() {
        Some("marker measures")
    } else if d.level > max_level {
        Some(if d.level >= 2 { "accelerations" } else { "velocities" })
    } else if !d.inputs.is_empty() {
        Some("inputs")
    } else if !d.loads.is_empty() {
        Some("element loads")
    } else if !(d.variables.is_empty() && d.diffs.is_empty() && d.diff_dots.is_empty()) {
        Some("user variables or differentials")
    } else {
        None
    };
    let Some(used) = used else { return Ok(()) };
    let may = match allowed {
        Allowed::Time => "time and parameters",
        Allowed::Velocities => "positions, velocities, time and parameters",
        _ => "positions, time and parameters",
    };
    Err(el.err_at(at, format!("'{attr}' may use only {may} (it uses {used})")))
}

/// An element touches at most [`MAX_ELEMENT_BODIES`] bodies: those of its `markers` and of
/// the markers its expressions (`(attribute, expression)`, in order) measure. The error
/// points at the attribute (or the element) where the count first goes over, and lists
/// every body; `split_hint` adds how forces and user elements can stay within it.
pub(crate) fn check_body_count(
    el: &El,
    scope: &ModelScope,
    markers: &[MarkerId],
    exprs: &[(&str, &Expr)],
    split_hint: bool,
) -> Result<(), ModelError> {
    let mut bodies: Vec<usize> = Vec::new();
    let mut over_at = None;
    let mut add = |ms: &[MarkerId], at| {
        for b in ms.iter().filter_map(|&m| scope.marker_body.get(m).copied().flatten()) {
            if !bodies.contains(&b) {
                bodies.push(b);
                if bodies.len() > MAX_ELEMENT_BODIES && over_at.is_none() {
                    over_at = Some(at);
                }
            }
        }
    };
    add(markers, el.x.pos);
    for (attr, e) in exprs {
        add(&expr::deps(e).markers, el.get(attr).map_or(el.x.pos, |a| a.pos));
    }
    let Some(at) = over_at else { return Ok(()) };
    let names: Vec<&str> = bodies.iter().map(|&b| scope.body_names.get(b).map_or("?", String::as_str)).collect();
    let hint = if split_hint { " (measure some of them in <variable> elements and use those)" } else { "" };
    Err(el.err_at(
        at,
        format!(
            "touches {} bodies ({}); an element may touch at most {MAX_ELEMENT_BODIES}{hint}",
            bodies.len(),
            names.join(", ")
        ),
    ))
}
