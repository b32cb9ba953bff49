//! The parsed, validated model: immutable, shared by every simulation and FMU instance.
//! Numeric attributes keep their constant expression so a parameter change can
//! re-evaluate them ([`crate::model::Model::with_params`]).

use super::expr::{Expr, MarkerId};

/// Where something stands in the model file (1-based line and column).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SrcPos {
    pub line: usize,
    pub col: usize,
}

/// A constant numeric attribute: its expression (of numbers, `pi`, parameters) and value.
#[derive(Clone, Debug, PartialEq)]
pub struct Num {
    pub expr: Expr,
    pub value: f64,
}

/// A vector attribute of constant expressions.
#[derive(Clone, Debug, PartialEq)]
pub struct NumVec {
    pub items: Vec<Num>,
}

impl NumVec {
    /// The values as a 3-vector (panics if the length is not 3; the parser guarantees it).
    pub fn v3(&self) -> [f64; 3] {
        [self.items[0].value, self.items[1].value, self.items[2].value]
    }
    /// All values.
    pub fn values(&self) -> Vec<f64> {
        self.items.iter().map(|n| n.value).collect()
    }
}

/// How an orientation was written (relative to the owner frame).
#[derive(Clone, Debug, PartialEq)]
pub enum Orientation {
    Identity,
    Euler313(NumVec),
    /// z axis, optional x axis.
    Axes(NumVec, Option<NumVec>),
}

/// `<parameter>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub value: Num,
    pub unit: Option<String>,
    pub description: Option<String>,
    pub pos: SrcPos,
}

/// `<body>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    pub name: String,
    pub mass: Num,
    /// 3 or 6 items: Ixx Iyy Izz [Ixy Ixz Iyz].
    pub inertia: NumVec,
    pub position: NumVec,
    pub orientation: Orientation,
    pub velocity: Option<NumVec>,
    pub angular_velocity: Option<NumVec>,
    pub pos: SrcPos,
}

/// `<marker>` (also the implicit `cm` marker of each body). Full name `body.marker`.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    pub name: String,
    /// Owning body index; `None` = ground.
    pub body: Option<usize>,
    pub position: NumVec,
    pub orientation: Orientation,
    pub pos: SrcPos,
}

/// Joint types of the model format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointType {
    Fixed,
    Revolute,
    Translational,
    Cylindrical,
    Universal,
    Spherical,
    Planar,
}

impl JointType {
    /// Number of constraint equations.
    pub fn equations(self) -> usize {
        match self {
            JointType::Fixed => 6,
            JointType::Revolute | JointType::Translational => 5,
            JointType::Cylindrical | JointType::Universal => 4,
            JointType::Spherical | JointType::Planar => 3,
        }
    }
}

/// `<joint>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointType,
    pub i: MarkerId,
    pub j: MarkerId,
    pub ic_angle: Option<Num>,
    pub ic_angular_speed: Option<Num>,
    pub ic_displacement: Option<Num>,
    pub ic_speed: Option<Num>,
    pub pos: SrcPos,
}

/// `<motion dof=...>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionDof {
    Rotation,
    Translation,
}

/// `<motion>`: prescribes a joint's relative rotation/translation along z_j.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    pub name: String,
    pub joint: usize,
    pub dof: MotionDof,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<constraint>`: user holonomic constraint `function(positions, time) = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct UserConstraint {
    pub name: String,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<spring_damper type=...>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpringType {
    Translational,
    Rotational,
}

/// `<spring_damper>`.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringDamper {
    pub name: String,
    pub kind: SpringType,
    pub i: MarkerId,
    pub j: MarkerId,
    pub stiffness: Num,
    pub damping: Num,
    /// Free length (translational) or free angle (rotational); 0 when absent for rotational.
    pub length: Num,
    pub preload: Num,
    pub pos: SrcPos,
}

/// `<sforce type=...>`: translational along line of sight, or rotational about z_j.
#[derive(Clone, Debug, PartialEq)]
pub struct Sforce {
    pub name: String,
    pub kind: SpringType,
    pub i: MarkerId,
    pub j: MarkerId,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<gforce>`: force and torque at marker i in `frame` axes; reaction on j.
#[derive(Clone, Debug, PartialEq)]
pub struct Gforce {
    pub name: String,
    pub i: MarkerId,
    pub j: Option<MarkerId>,
    pub frame: Option<MarkerId>,
    pub force: [Expr; 3],
    pub torque: [Expr; 3],
    pub pos: SrcPos,
}

/// `<bushing>`: linear six-component spring-damper in marker j's axes (small angles).
#[derive(Clone, Debug, PartialEq)]
pub struct Bushing {
    pub name: String,
    pub i: MarkerId,
    pub j: MarkerId,
    /// kx ky kz krx kry krz.
    pub stiffness: NumVec,
    /// cx cy cz crx cry crz (zeros when absent).
    pub damping: Option<NumVec>,
    pub pos: SrcPos,
}

/// `<rolling_wheel>`: a thin disc (centre = marker origin, axle = marker z) rolling
/// without slipping on a plane (marker `plane`: origin on it, z = normal; None: ground z = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct RollingWheel {
    pub name: String,
    pub marker: MarkerId,
    pub radius: Num,
    pub plane: Option<MarkerId>,
    pub pos: SrcPos,
}

/// `<knife_edge>`: the marker origin has no velocity along the marker's y axis.
#[derive(Clone, Debug, PartialEq)]
pub struct KnifeEdge {
    pub name: String,
    pub marker: MarkerId,
    pub pos: SrcPos,
}

/// `<velocity_constraint>`: function(q, u, t) = 0, linear in velocities.
#[derive(Clone, Debug, PartialEq)]
pub struct VelocityConstraint {
    pub name: String,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<variable>`: a user variable V = function (seed Eq. 7b).
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    pub name: String,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<differential>`: dX/dt = function, or function = 0 with `dif1(X)` = dX/dt when
/// `implicit` (seed Eq. 7a).
#[derive(Clone, Debug, PartialEq)]
pub struct Differential {
    pub name: String,
    pub start: Num,
    pub function: Expr,
    pub implicit: bool,
    pub pos: SrcPos,
}

/// `<input>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    pub name: String,
    pub start: Num,
    pub unit: Option<String>,
    pub pos: SrcPos,
}

/// `<output>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    pub name: String,
    pub function: Expr,
    pub unit: Option<String>,
    pub pos: SrcPos,
}

/// `<linearization><state>`: a position-level user state.
#[derive(Clone, Debug, PartialEq)]
pub struct LinState {
    pub name: String,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<linearization><velocity>`: a velocity-level user candidate.
#[derive(Clone, Debug, PartialEq)]
pub struct LinVelocity {
    pub name: String,
    pub function: Expr,
    pub pos: SrcPos,
}

/// `<experiment>` (all optional).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Experiment {
    pub start: Option<f64>,
    pub stop: Option<f64>,
    pub step: Option<f64>,
    pub tolerance: Option<f64>,
}
