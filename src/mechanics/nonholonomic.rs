//! Non-holonomic constraints g(q, u, t) = B(q, t) u + b(q, t) = 0 (seed remark (1) after
//! Eq. 13: the strictly non-holonomic part of C̃): knife edges, the rolling part of rolling
//! wheels, and user velocity constraints. Their multipliers ν enter the equations of motion
//! as Bᵀν (B = ∂g/∂u). Their equations are in [`super::nonholonomic_equations`].

use crate::model::SrcPos;
use crate::model::expr::{Expr, MarkerId};

/// What a non-holonomic element constrains.
#[derive(Clone, Debug)]
pub enum NonholonomicKind {
    /// No velocity of the marker origin along the marker's y axis.
    KnifeEdge { m: MarkerId },
    /// The wheel's material point at the contact has no velocity in the plane (2 rows:
    /// along the rolling direction a × n and across it).
    Rolling { m: MarkerId, radius: f64, plane: Option<MarkerId> },
    /// User expression f(q, u, t) = 0.
    User { f: Expr, abase: usize },
}

/// One non-holonomic element: rows `row..row+neq` of g.
#[derive(Clone, Debug)]
pub struct NonholonomicEl {
    /// Name of the model element.
    pub name: String,
    /// What it constrains.
    pub kind: NonholonomicKind,
    /// Bodies whose coordinates and velocities the equations depend on (global indices).
    pub bodies: Vec<usize>,
    /// Number of equations.
    pub neq: usize,
    /// First row in g.
    pub row: usize,
    /// The model element it comes from, for located messages.
    pub tag: &'static str,
    /// Position of that element in the model file.
    pub pos: SrcPos,
}

impl NonholonomicEl {
    /// An element from model element `tag` at `pos`; its rows are laid out later.
    pub fn new(name: String, kind: NonholonomicKind, bodies: Vec<usize>, tag: &'static str, pos: SrcPos) -> Self {
        let neq = if matches!(kind, NonholonomicKind::Rolling { .. }) { 2 } else { 1 };
        NonholonomicEl { name, kind, bodies, neq, row: 0, tag, pos }
    }
}
