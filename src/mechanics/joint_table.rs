//! The equations of each joint type as dot products of its marker frames (the model
//! format's joint table, as [`super::constraint_equations`] writes them generically), for
//! the closed-form derivatives of [`super::joint_gradient`] and [`super::joint_hessian`].

use super::body::NQ;
use super::constraints::{ConstraintEl, ConstraintKind};
use super::coords::nql;
use super::system::System;
use crate::model::JointType;

/// One equation of a joint, over the marker frames i and j and d = p_i − p_j.
#[derive(Clone, Copy)]
pub enum Row {
    /// Component c of d.
    D(usize),
    /// Axis a of marker i · axis b of marker j.
    Axes(usize, usize),
    /// d · axis b of marker j.
    DAxis(usize),
}

/// The equations of each joint type, in the order of the model format's table.
pub fn equations(kind: JointType) -> &'static [Row] {
    use Row::*;
    match kind {
        JointType::Fixed => &[D(0), D(1), D(2), Axes(2, 0), Axes(2, 1), Axes(0, 1)],
        JointType::Revolute => &[D(0), D(1), D(2), Axes(2, 0), Axes(2, 1)],
        JointType::Translational => &[Axes(2, 0), Axes(2, 1), Axes(0, 1), DAxis(0), DAxis(1)],
        JointType::Cylindrical => &[Axes(2, 0), Axes(2, 1), DAxis(0), DAxis(1)],
        JointType::Universal => &[D(0), D(1), D(2), Axes(2, 2)],
        JointType::Spherical => &[D(0), D(1), D(2)],
        JointType::Planar => &[Axes(2, 0), Axes(2, 1), DAxis(2)],
    }
}

/// The markers (i, j) and type of `el` when it is a joint whose markers are on rigid
/// bodies or ground (None: flexible nodes, other constraints).
pub fn rigid_joint(sys: &System, el: &ConstraintEl) -> Option<(usize, usize, JointType)> {
    let ConstraintKind::Joint { kind, i, j } = &el.kind else { return None };
    let rigid = nql(sys, &el.bodies) == NQ * el.bodies.len();
    let nodes = sys.markers[*i].node.is_some() || sys.markers[*j].node.is_some();
    (rigid && !nodes && equations(*kind).len() == el.neq).then_some((*i, *j, *kind))
}
