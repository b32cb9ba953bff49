//! The parsed, validated model: immutable, shared by every simulation and FMU instance.
//! Numeric attributes keep their constant expression so a parameter change can
//! re-evaluate them ([`crate::model::Model::with_params`]).

use super::expr::{Expr, MarkerId};

/// Where something stands in the model file (1-based line and column).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SrcPos {
    /// 1-based line number.
    pub line: usize,
    /// 1-based column, in characters (not bytes); a leading byte-order mark is not counted.
    pub col: usize,
}

/// A constant numeric attribute: its expression (of numbers, `pi`, parameters) and value.
#[derive(Clone, Debug, PartialEq)]
pub struct Num {
    /// The expression as written, kept so that
    /// [`Model::with_params`](crate::model::Model::with_params) can re-evaluate it.
    pub expr: Expr,
    /// Its value with the current parameter values (checked finite).
    pub value: f64,
}

/// A vector attribute of constant expressions.
#[derive(Clone, Debug, PartialEq)]
pub struct NumVec {
    /// The items in written order; the reader fixes their count per attribute (3; 3 or 6
    /// for `inertia`; 6 for bushing `stiffness` and `damping`).
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
    /// No orientation attribute: the frame's axes are the owner's.
    Identity,
    /// `euler313="psi theta phi"` (rad): R = Rz(psi)·Rx(theta)·Rz(phi), body 3-1-3.
    Euler313(NumVec),
    /// `z_axis` and optional `x_axis`, owner components (any length): x is made orthogonal
    /// to z; without it, the owner's x axis (y when |x·z| > 0.9) made orthogonal to z.
    Axes(NumVec, Option<NumVec>),
}

/// `<parameter>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Name, usable in expressions (`[A-Za-z_][A-Za-z0-9_]*`); also the FMI parameter's name.
    pub name: String,
    /// `value`: may use other parameters (evaluated in dependency order); its value is the
    /// FMI start value.
    pub value: Num,
    /// `unit` in FMI syntax (`rad/s`, `N.m`, checked by [`crate::model::units`]); `None`: none.
    pub unit: Option<String>,
    /// `description`, copied to the FMI variable's description.
    pub description: Option<String>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<body>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Body name; its markers are named `name.marker`, its implicit CM marker `name.cm`.
    pub name: String,
    /// Mass (kg), positive.
    pub mass: Num,
    /// Inertia about the centre of mass in body axes (kg·m²), 3 or 6 items: Ixx Iyy Izz
    /// [Ixy Ixz Iyz], entries of the symmetric matrix J (so Ixy = −∫xy dm); positive definite.
    pub inertia: NumVec,
    /// Initial position of the centre of mass in ground (m); assembly may move it so that
    /// the constraints hold.
    pub position: NumVec,
    /// Initial orientation of the body (centre-of-mass) frame relative to ground.
    pub orientation: Orientation,
    /// Initial velocity of the centre of mass (m/s), ground components; `None`: zero.
    pub velocity: Option<NumVec>,
    /// Initial angular velocity (rad/s), ground components; `None`: zero.
    pub angular_velocity: Option<NumVec>,
    /// A `<flexible_body>`'s modal data (`None`: a rigid `<body>`). Its `position` is then
    /// the body frame's origin (the frame of the modal data), not the centre of mass, and
    /// `mass`, `inertia` are the undeformed body's (inertia about the centre of mass).
    pub flex: Option<FlexSpec>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// The modal data of a `<flexible_body>`.
#[derive(Clone, Debug, PartialEq)]
pub struct FlexSpec {
    /// The `modal` attribute as written.
    pub file: String,
    /// The path read (relative paths are relative to the model file's directory).
    pub path: String,
    /// The validated modal data.
    pub data: crate::modal::ModalData,
    /// Initial modal coordinates η(t0), one per mode (`modal_coordinates`; None = 0).
    pub eta0: Option<NumVec>,
    /// Initial modal rates η̇(t0), one per mode (`modal_velocities`; None = 0).
    pub eta_dot0: Option<NumVec>,
}

/// `<marker>` (also the implicit `cm` marker of each body). Full name `body.marker`.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// Full name `owner.marker` (`ground.O`, `arm.tip`; `arm.cm` for the implicit one).
    pub name: String,
    /// Owning body index; `None` = ground.
    pub body: Option<usize>,
    /// Origin in the owner's frame (m): the body's centre-of-mass frame, or ground; zero for
    /// `cm`.
    pub position: NumVec,
    /// Axes relative to the owner's frame (identity for `cm`).
    pub orientation: Orientation,
    /// On a flexible body: the index (into the modal data's nodes) of the node the marker
    /// is attached to; it then follows the node's deflection and small rotation, and its
    /// `position` is the node's.
    pub node: Option<usize>,
    /// Where the `<marker>` starts (for a `cm` marker, where its `<body>` starts).
    pub pos: SrcPos,
}

/// Joint types of the model format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointType {
    /// All relative motion locked: 6 equations.
    Fixed,
    /// Origins coincide, z_i ∥ z_j: rotation about z_j free; 5 equations.
    Revolute,
    /// z_i ∥ z_j, x_i ∥ x_j, origin_i on the z_j line: sliding along z_j free; 5 equations.
    Translational,
    /// z_i ∥ z_j, origin_i on the z_j line: rotation about and sliding along z_j free; 4
    /// equations.
    Cylindrical,
    /// Origins coincide, z_i ⟂ z_j; 4 equations.
    Universal,
    /// Origins coincide; 3 equations.
    Spherical,
    /// z_i ∥ z_j, (o_i − o_j)·z_j = 0: sliding in the x_j y_j plane and rotation
    /// about z_j free; 3 equations.
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
    /// Element name; unique among joints, motions, constraints and forces (load functions
    /// such as `fx(name)` name them).
    pub name: String,
    /// Joint type, which fixes the equations ([`JointType::equations`]).
    pub kind: JointType,
    /// Marker i, index into [`Model::markers`](crate::model::Model::markers); its body is
    /// the action side.
    pub i: MarkerId,
    /// Marker j, index into [`Model::markers`](crate::model::Model::markers), on another body
    /// or on ground; the joint's measures are taken in its axes.
    pub j: MarkerId,
    /// Exact initial rotation az(i, j) about z_j (rad), kept by assembly; revolute and
    /// cylindrical joints only.
    pub ic_angle: Option<Num>,
    /// Exact initial rate of that rotation (rad/s); revolute and cylindrical joints only.
    pub ic_angular_speed: Option<Num>,
    /// Exact initial displacement dz(i, j, j) along z_j (m), kept by assembly;
    /// translational and cylindrical joints only.
    pub ic_displacement: Option<Num>,
    /// Exact initial rate of that displacement (m/s); translational and cylindrical joints
    /// only.
    pub ic_speed: Option<Num>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<motion dof=...>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionDof {
    /// `rotation`: the rotation az(i, j) about z_j (rad) of a revolute or cylindrical joint.
    Rotation,
    /// `translation`: the displacement dz(i, j, j) along z_j (m) of a translational or
    /// cylindrical joint.
    Translation,
}

/// `<motion>`: prescribes a joint's relative rotation/translation along z_j.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// Element name; unique among joints, motions, constraints and forces.
    pub name: String,
    /// The driven joint: index into [`Model::joints`](crate::model::Model::joints).
    pub joint: usize,
    /// Which coordinate of the joint is driven.
    pub dof: MotionDof,
    /// Prescribed value of that coordinate (rad or m): a function of `time` and parameters
    /// only.
    pub function: Expr,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<constraint>`: user holonomic constraint `function(positions, time) = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct UserConstraint {
    /// Element name; unique among joints, motions, constraints and forces.
    pub name: String,
    /// Expression of positions, time and parameters (no velocities, inputs, user states or
    /// loads), held at 0.
    pub function: Expr,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<spring_damper type=...>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpringType {
    /// Along the line between the marker origins, positive pushing i away from j.
    Translational,
    /// About z_j, acting on i.
    Rotational,
}

/// `<spring_damper>`: F = −k (d − length) − c ḋ + preload along the line of sight
/// (d = dm(i, j)), or T = −k (az(i, j) − angle) − c wz(i, j, j) + preload about z_j.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringDamper {
    /// Element name; unique among joints, motions, constraints and forces.
    pub name: String,
    /// Translational (force along the line of sight) or rotational (torque about z_j).
    pub kind: SpringType,
    /// Marker i, index into [`Model::markers`](crate::model::Model::markers): the load acts
    /// on its body.
    pub i: MarkerId,
    /// Marker j, index into [`Model::markers`](crate::model::Model::markers): the reaction acts
    /// on its body; z_j is the rotational axis.
    pub j: MarkerId,
    /// k: N/m (translational) or N·m/rad (rotational).
    pub stiffness: Num,
    /// c: N·s/m (translational) or N·m·s/rad (rotational); 0 when absent.
    pub damping: Num,
    /// Free length (m; translational, `length`, required) or free angle (rad; rotational,
    /// `angle`, 0 when absent).
    pub length: Num,
    /// Constant force (N) or torque (N·m) added to the law, same sign convention; 0 when
    /// absent.
    pub preload: Num,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<sforce type=...>`: translational along line of sight, or rotational about z_j.
#[derive(Clone, Debug, PartialEq)]
pub struct Sforce {
    /// Element name; unique among joints, motions, constraints and forces.
    pub name: String,
    /// Translational (along the line of sight, positive pushing i away from j) or rotational
    /// (about z_j).
    pub kind: SpringType,
    /// Marker i, index into [`Model::markers`](crate::model::Model::markers): the load acts
    /// on its body.
    pub i: MarkerId,
    /// Marker j, index into [`Model::markers`](crate::model::Model::markers): the reaction acts
    /// on its body; z_j is the rotational axis.
    pub j: MarkerId,
    /// The force (N) or torque (N·m); may read anything but a user constraint's load, and the
    /// load of an sforce or gforce only when that force reads no loads.
    pub function: Expr,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<gforce>`: force and torque at marker i in `frame` axes; reaction on j.
#[derive(Clone, Debug, PartialEq)]
pub struct Gforce {
    /// Element name; unique among joints, motions, constraints and forces.
    pub name: String,
    /// Marker i, index into [`Model::markers`](crate::model::Model::markers): the force acts at
    /// its origin, on its body.
    pub i: MarkerId,
    /// Reaction marker: −force and −torque act on its body at the point coinciding with i's
    /// origin; `None`: the reaction goes to ground.
    pub j: Option<MarkerId>,
    /// Marker whose axes the components are given in (moving with it); `None`: ground axes.
    pub frame: Option<MarkerId>,
    /// Force components fx fy fz (N) in `frame` axes; zeros when absent.
    pub force: [Expr; 3],
    /// Torque components tx ty tz (N·m) in `frame` axes; zeros when absent.
    pub torque: [Expr; 3],
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<bushing>`: linear six-component spring-damper in marker j's axes (small angles).
#[derive(Clone, Debug, PartialEq)]
pub struct Bushing {
    /// Element name; unique among joints, motions, constraints and forces.
    pub name: String,
    /// Marker i, index into [`Model::markers`](crate::model::Model::markers): the load acts
    /// on its body.
    pub i: MarkerId,
    /// Marker j, index into [`Model::markers`](crate::model::Model::markers), on another body or
    /// ground: displacement, rotation and law are in its axes; the reaction acts on its body.
    pub j: MarkerId,
    /// kx ky kz (N/m) krx kry krz (N·m/rad).
    pub stiffness: NumVec,
    /// cx cy cz (N·s/m) crx cry crz (N·m·s/rad); `None` (absent): zeros.
    pub damping: Option<NumVec>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<rolling_wheel>`: a thin disc (centre = marker origin, axle = marker z) rolling
/// without slipping on a plane (marker `plane`: origin on it, z = normal; None: ground z = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct RollingWheel {
    /// Element name (shared namespace of non-holonomic constraints).
    pub name: String,
    /// Marker on a body (not ground): origin = wheel centre, z axis = axle.
    pub marker: MarkerId,
    /// Wheel radius (m), positive.
    pub radius: Num,
    /// Marker whose origin lies on the rolling plane and whose z axis is its normal; `None`:
    /// the ground z = 0 plane, normal +z.
    pub plane: Option<MarkerId>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<knife_edge>`: the marker origin has no velocity along the marker's y axis.
#[derive(Clone, Debug, PartialEq)]
pub struct KnifeEdge {
    /// Element name (shared namespace of non-holonomic constraints).
    pub name: String,
    /// Marker on a body (not ground) whose origin has no velocity along its own y axis.
    pub marker: MarkerId,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<velocity_constraint>`: function(q, u, t) = 0, linear in velocities.
#[derive(Clone, Debug, PartialEq)]
pub struct VelocityConstraint {
    /// Element name (shared namespace of non-holonomic constraints).
    pub name: String,
    /// Expression of positions, velocities (it must use some), time and parameters, held
    /// at 0; meant to be linear in the velocities (the reader does not check that).
    pub function: Expr,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<variable>`: a user variable V = function (seed Eq. 7b).
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// Name, usable in expressions (one namespace with parameters, inputs and differentials).
    pub name: String,
    /// The value of V: may read anything a force may, other variables included (a cycle is
    /// an algebraic loop, solved with the equations of motion).
    pub function: Expr,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<differential>`: dX/dt = function, or function = 0 with `dif1(X)` = dX/dt when
/// `implicit` (seed Eq. 7a).
#[derive(Clone, Debug, PartialEq)]
pub struct Differential {
    /// Name X, usable in expressions as `X` (or `dif(X)`) and `dif1(X)` for dX/dt.
    pub name: String,
    /// Initial value X(t0); 0 when absent.
    pub start: Num,
    /// dX/dt when explicit; when implicit, the residual held at 0 (it uses `dif1` of this
    /// state). May read anything a force may.
    pub function: Expr,
    /// `implicit="true"`: `function` is an implicit equation in dX/dt; default false.
    pub implicit: bool,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<input>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    /// Name, usable in expressions; also the FMI input's name (real, continuous).
    pub name: String,
    /// `start`: the FMI start value, in effect until the host sets the input; 0 when absent.
    pub start: Num,
    /// `unit` in FMI syntax (checked by [`crate::model::units`]); `None`: none.
    pub unit: Option<String>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<output>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// The FMI output's name (real, continuous).
    pub name: String,
    /// The output's value: may read anything, accelerations and element loads included.
    pub function: Expr,
    /// `unit` in FMI syntax (checked by [`crate::model::units`]); `None`: none.
    pub unit: Option<String>,
    /// Where the element starts (its `<`).
    pub pos: SrcPos,
}

/// `<linearization><state>`: a position-level user state.
#[derive(Clone, Debug, PartialEq)]
pub struct LinState {
    /// FMI name of the position state (when the engine keeps it); its time derivative, the
    /// velocity state, is `der(name)`.
    pub name: String,
    /// The state as an expression of positions, time and parameters.
    pub function: Expr,
    /// Where the `<state>` starts (its `<`).
    pub pos: SrcPos,
}

/// `<linearization><velocity>`: a velocity-level user candidate.
#[derive(Clone, Debug, PartialEq)]
pub struct LinVelocity {
    /// The FMI name of the velocity state, when the engine picks it.
    pub name: String,
    /// An expression of positions, velocities, time and parameters, linear in velocities
    /// (e.g. a forward speed).
    pub function: Expr,
    /// Where the `<velocity>` starts (its `<`).
    pub pos: SrcPos,
}

/// `<experiment>` (all optional): the defaults of `mbfmu simulate` and the FMU's
/// `DefaultExperiment`. Evaluated once, with the file's parameter values.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Experiment {
    /// Start time (s); `None`: 0.
    pub start: Option<f64>,
    /// Stop time (s).
    pub stop: Option<f64>,
    /// Communication step size (s).
    pub step: Option<f64>,
    /// Integration tolerance (relative and absolute).
    pub tolerance: Option<f64>,
}
