//! Holonomic constraint elements C(q, t) = 0 (Eq. 1a): joints, motions, user constraints,
//! and the exact joint initial conditions used during assembly. Their equations are in
//! [`super::constraint_equations`].

use super::measures::StateKind;
use crate::model::expr::{Expr, MarkerId};
use crate::model::{JointType, SrcPos};

/// What a constraint element constrains.
#[derive(Clone, Debug)]
pub enum ConstraintKind {
    /// A joint between markers i and j (equations in the model format's table).
    Joint { kind: JointType, i: MarkerId, j: MarkerId },
    /// Relative rotation of i about z_j equals f(t): x_i·y_j cos f − x_i·x_j sin f = 0.
    Rotation { i: MarkerId, j: MarkerId, f: Expr, abase: usize },
    /// Displacement of i along z_j equals f(t): (p_i − p_j)·z_j − f = 0.
    Translation { i: MarkerId, j: MarkerId, f: Expr, abase: usize },
    /// User constraint f(q, t) = 0.
    User { f: Expr, abase: usize },
    /// A rolling wheel's contact point stays on its plane: (P − o)·n = 0.
    WheelContact { m: MarkerId, radius: f64, plane: Option<MarkerId> },
    /// A start value set on a state: its measure equals `value` (assembly only).
    State { kind: StateKind, value: f64 },
}

/// One constraint element: its equations occupy rows `row..row+neq` of C.
#[derive(Clone, Debug)]
pub struct ConstraintEl {
    /// Name of the model element.
    pub name: String,
    /// What it constrains.
    pub kind: ConstraintKind,
    /// Bodies whose coordinates the equations depend on (global indices).
    pub bodies: Vec<usize>,
    /// Number of equations.
    pub neq: usize,
    /// First row in C (position initial conditions: rows after the m constraints).
    pub row: usize,
    /// The model element it comes from (tag and position), for located messages.
    pub tag: &'static str,
    /// Position of that element in the model file.
    pub pos: SrcPos,
}

impl ConstraintEl {
    /// An element from model element `tag` at `pos`; its rows are laid out later.
    pub fn new(name: String, kind: ConstraintKind, bodies: Vec<usize>, tag: &'static str, pos: SrcPos) -> Self {
        let neq = kind.neq();
        ConstraintEl { name, kind, bodies, neq, row: 0, tag, pos }
    }
}

impl ConstraintKind {
    /// Number of equations.
    pub fn neq(&self) -> usize {
        match self {
            ConstraintKind::Joint { kind, .. } => kind.equations(),
            _ => 1,
        }
    }
}

/// A velocity-level initial condition, linear in u: exact `ic_angular_speed` /
/// `ic_speed`, or a start value set on a velocity state.
#[derive(Clone, Debug)]
pub struct VelocityIc {
    /// Name of the joint or state it belongs to.
    pub name: String,
    /// What it sets.
    pub kind: VelocityIcKind,
    /// Prescribed value.
    pub value: f64,
    /// Bodies it reads (global indices).
    pub bodies: Vec<usize>,
}

/// What a velocity-level initial condition sets.
#[derive(Clone, Debug)]
pub enum VelocityIcKind {
    /// A joint's relative angular velocity about z_j (`angular`) or relative velocity
    /// along z_j, of its markers i and j.
    Joint { angular: bool, i: MarkerId, j: MarkerId },
    /// The time derivative of a position-level measure (a state's `der(S)`).
    Rate(StateKind),
    /// A user velocity expression w(q, u, t), linear in u (a `<velocity>` state).
    User { f: Expr, abase: usize },
}
