//! The mechanical system built from a [`crate::model::Model`] (see [`super::from_model`]):
//! numbers evaluated, elements indexed, coordinates laid out (q, u: 6 per body).
//!
//! One `System` belongs to one simulation: besides the model's constants it holds the
//! per-body reference frames R0 of the Euler angles, which the integrator re-chooses when
//! a body nears the 3-1-3 singularity (θ = 0 or π).

pub use super::body::{FAR_FROM_SINGULAR, rebased_reference};

use super::body::NQ;
use super::constraints::{ConstraintEl, VelocityIc};
use super::forces::ForceEl;
use super::joint_coords::JointCoord;
use super::nonholonomic::NonholonomicEl;
use super::user::UserEq;
use crate::model::expr::{ElementRef, Expr};

/// A marker's fixed geometry: offset `s` and rotation relative to its body (or ground).
#[derive(Clone, Debug)]
pub struct MarkerGeom {
    /// Its body (None: ground).
    pub body: Option<usize>,
    /// Offset from the body's CM, body axes (ground: position).
    pub s: [f64; 3],
    /// Rotation (columns = marker axes in body axes, or in ground).
    pub rot: [[f64; 3]; 3],
    /// On a flexible body: the node's mode shapes, the marker follows its deflection.
    pub node: Option<NodeShape>,
}

/// The shapes of every mode at one node of a flexible body (body axes, per unit modal
/// coordinate): translation φ_k and small rotation ρ_k.
#[derive(Clone, Debug)]
pub struct NodeShape {
    /// Translational shape of each mode.
    pub phi: Vec<[f64; 3]>,
    /// Rotational shape of each mode.
    pub rho: Vec<[f64; 3]>,
}

/// Mass properties of a body.
#[derive(Clone, Debug)]
pub struct BodyProps {
    /// Name of the body.
    pub name: String,
    /// Mass.
    pub mass: f64,
    /// Inertia about the CM, body axes.
    pub inertia: [[f64; 3]; 3],
}

/// The assembled mechanical system.
#[derive(Clone, Debug)]
pub struct System {
    /// Parameter values, model order.
    pub params: Vec<f64>,
    /// Gravity vector (ground).
    pub gravity: [f64; 3],
    /// Mass properties of each body.
    pub bodies: Vec<BodyProps>,
    /// Geometry of each marker (model order).
    pub markers: Vec<MarkerGeom>,
    /// Reference frame of each body's Euler angles (A = R0 · R313(e)).
    pub r0: Vec<[[f64; 3]; 3]>,
    /// Holonomic constraints (Eq. 1a), rows laid out consecutively.
    pub constraints: Vec<ConstraintEl>,
    /// Number of constraint equations m.
    pub m: usize,
    /// Constraint rows found redundant at initialization (e.g. a planar loop of revolutes
    /// in 3-D): their multipliers are fixed to 0 and their equations left out, as
    /// production codes do; they still hold, since the independent rows imply them.
    pub redundant: Vec<bool>,
    /// Exact position initial conditions (assembly only), rows after the m constraints.
    pub ic_constraints: Vec<ConstraintEl>,
    /// Exact velocity initial conditions.
    pub ic_velocities: Vec<VelocityIc>,
    /// Force elements: spring-dampers, sforces, gforces, bushings.
    pub forces: Vec<ForceEl>,
    /// Non-holonomic constraints g = B u + b = 0, rows laid out consecutively.
    pub nonholonomic: Vec<NonholonomicEl>,
    /// Number of non-holonomic equations.
    pub mn: usize,
    /// User rows (differentials, then variables; seed Eq. 7a–7b).
    pub user: Vec<UserEq>,
    /// Elements whose loads (`fx(name)` ...) forces and user rows read: their six load
    /// components are external values, evaluated from (q, u, λ) (algebraic loops through
    /// constraint forces are solved with the equations of motion).
    pub load_refs: Vec<ElementRef>,
    /// Bodies whose accelerations forces and user rows read: their u̇ become algebraic
    /// unknowns of the DAE (u' = a, M a = Q − Pᵀλ − Bᵀν), part of Z after V.
    pub acc_bodies: Vec<usize>,
    /// Number of differential states X.
    pub nx: usize,
    /// Number of variables V.
    pub nv: usize,
    /// Start values of X.
    pub x_init: Vec<f64>,
    /// Index of the first motion in `constraints` (joints come first).
    pub(super) first_motion: usize,
    /// Index of the first user constraint in `constraints` (after the motions).
    pub(super) first_user_constraint: usize,
    /// Index of the first sforce in `forces` (spring-dampers come first).
    pub(super) first_sforce: usize,
    /// Index of the first gforce in `forces`.
    pub(super) first_gforce: usize,
    /// Index of the first bushing in `forces`.
    pub(super) first_bushing: usize,
    /// Names of the outputs.
    pub output_names: Vec<String>,
    /// Names of the inputs (their number is ni).
    pub input_names: Vec<String>,
    /// Output expressions.
    pub outputs: Vec<Expr>,
    /// First angle-unwrapping slot of each output expression.
    pub output_bases: Vec<usize>,
    /// User linearization states `<linearization><state>`: name, s(q, t), angle slot base.
    pub lin_states: Vec<(String, Expr, usize)>,
    /// User velocity candidates `<linearization><velocity>`: name, w(q, u, t), slot base.
    pub lin_velocities: Vec<(String, Expr, usize)>,
    /// The joints' free coordinates (internal state candidates, joint order).
    pub joint_coords: Vec<JointCoord>,
    /// Value of every angle measure at the last accepted step (NaN: none yet); expressions
    /// keep their angles on the branch nearest these, so angles are continuous in time.
    pub angle_refs: Vec<f64>,
    /// Their time derivatives then (NaN: unknown), and that time: an angle is unwrapped
    /// to the branch nearest `angle_refs + angle_rates · (t − angle_time)`.
    pub angle_rates: Vec<f64>,
    /// Time of `angle_refs` and `angle_rates`.
    pub angle_time: f64,
    /// Initial (unassembled) coordinates from the model file.
    pub q_init: Vec<f64>,
    /// Initial velocities from the model file.
    pub u_init: Vec<f64>,
    /// Flexible bodies (model order); their modal coordinates follow the six of every
    /// body in q (see [`super::coords`]).
    pub flex: Vec<FlexBody>,
}

/// A modal flexible body of the system.
#[derive(Clone, Debug)]
pub struct FlexBody {
    /// Its body index.
    pub body: usize,
    /// Where its modal coordinates η sit in q (and η̇ in u).
    pub eta: std::ops::Range<usize>,
    /// Its inertia invariants, stiffness and damping.
    pub inv: crate::modal::invariants::Invariants,
}

/// Where an element named in an expression (`fx(name)` ...) lives in the system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementSlot {
    /// Index into `System::constraints`.
    Constraint(usize),
    /// Index into `System::forces`.
    Force(usize),
}

impl System {
    /// The constraint or force element that `e` names.
    pub fn element_slot(&self, e: ElementRef) -> ElementSlot {
        match e {
            ElementRef::Joint(k) => ElementSlot::Constraint(k),
            ElementRef::Motion(k) => ElementSlot::Constraint(self.first_motion + k),
            ElementRef::Constraint(k) => ElementSlot::Constraint(self.first_user_constraint + k),
            ElementRef::SpringDamper(k) => ElementSlot::Force(k),
            ElementRef::Sforce(k) => ElementSlot::Force(self.first_sforce + k),
            ElementRef::Gforce(k) => ElementSlot::Force(self.first_gforce + k),
            ElementRef::Bushing(k) => ElementSlot::Force(self.first_bushing + k),
        }
    }

    /// Number of bodies.
    pub fn nb(&self) -> usize {
        self.bodies.len()
    }

    /// Number of coordinates n (= number of velocities): six per body, then the modal
    /// coordinates of the flexible bodies.
    pub fn n(&self) -> usize {
        NQ * self.bodies.len() + self.flex.iter().map(|f| f.eta.len()).sum::<usize>()
    }

    /// The global velocity indices of body `b`: its six, then its modal ones.
    pub fn body_dofs(&self, b: usize) -> Vec<usize> {
        self.body_dofs_iter(b).collect()
    }

    /// [`System::body_dofs`] as an iterator (nothing allocated).
    pub fn body_dofs_iter(&self, b: usize) -> impl Iterator<Item = usize> + use<> {
        (NQ * b..NQ * b + NQ).chain(self.modal_range(b))
    }

    /// The flexible body that body `b` is, if any.
    pub fn flex_of(&self, b: usize) -> Option<&FlexBody> {
        self.flex.iter().find(|f| f.body == b)
    }

    /// Where the modal coordinates of all flexible bodies sit in q (and u): after the six of
    /// every body, up to n (empty without flexible bodies).
    pub fn modal_columns(&self) -> std::ops::Range<usize> {
        NQ * self.bodies.len()..self.n()
    }

    /// The body whose coordinate q[`i`] is: its six rigid ones come body by body, then
    /// each flexible body's modal ones.
    pub fn body_of_coordinate(&self, i: usize) -> usize {
        if i < NQ * self.bodies.len() {
            return i / NQ;
        }
        self.flex.iter().find(|f| f.eta.contains(&i)).map_or(self.bodies.len(), |f| f.body)
    }

    /// Where body `b`'s modal coordinates sit in q (empty for a rigid body).
    pub fn modal_range(&self, b: usize) -> std::ops::Range<usize> {
        self.flex.iter().find(|f| f.body == b).map_or(0..0, |f| f.eta.clone())
    }
}
