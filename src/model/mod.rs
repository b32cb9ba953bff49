//! The model layer: parse a model file, validate it, resolve names, evaluate constants.
//! Knows nothing of mechanics, integration or FMI.

pub mod error;
pub mod expr;
pub mod overrides;
pub mod parse;
mod types;
pub mod units;

pub use error::ModelError;
pub use overrides::{Override, OverrideTarget};
pub use parse::{Summary, load_file, load_str, rotation, try_rotation};
pub use types::*;

/// Most bodies one element may touch: those of its markers and of the markers its
/// expressions measure (ground not counted). The engine differentiates each element over
/// the coordinates of its bodies only; the reader rejects an element touching more.
pub const MAX_ELEMENT_BODIES: usize = 4;

/// A complete, validated model (the parsed file). Bodies are numbered from 0; ground is
/// not a body (`None` where a body index is optional). Markers include each body's `cm`.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// `<multibody name>`: the FMU's modelName, from which its modelIdentifier is derived.
    pub name: String,
    /// Path of the file it was read from (for messages).
    pub file: String,
    /// `<parameter>`s in file order; [`NameRef::Param`](expr::NameRef::Param) indexes them.
    pub parameters: Vec<Parameter>,
    /// Gravity acceleration (m/s²), ground components; zero without `<gravity>`.
    pub gravity: [f64; 3],
    /// The `<gravity>` expressions (`None`: no gravity); `gravity` holds their values.
    pub gravity_expr: Option<NumVec>,
    /// Bodies in file order; a body index (`Some(b)` in [`Marker::body`]) points here.
    pub bodies: Vec<Body>,
    /// Every marker, indexed by [`MarkerId`](expr::MarkerId): those of each `<body>` (its `cm`
    /// first, then its own) and of `<ground>`, in file order.
    pub markers: Vec<Marker>,
    /// `<joint>`s in file order ([`Motion::joint`] indexes them).
    pub joints: Vec<Joint>,
    /// `<motion>`s in file order.
    pub motions: Vec<Motion>,
    /// `<constraint>`s (user holonomic constraints) in file order.
    pub constraints: Vec<UserConstraint>,
    /// `<spring_damper>`s in file order.
    pub spring_dampers: Vec<SpringDamper>,
    /// `<sforce>`s in file order.
    pub sforces: Vec<Sforce>,
    /// `<gforce>`s in file order.
    pub gforces: Vec<Gforce>,
    /// `<bushing>`s in file order.
    pub bushings: Vec<Bushing>,
    /// `<variable>`s in file order (user variables V).
    pub variables: Vec<Variable>,
    /// `<differential>`s in file order (user differential states X).
    pub differentials: Vec<Differential>,
    /// `<rolling_wheel>`s in file order.
    pub rolling_wheels: Vec<RollingWheel>,
    /// `<knife_edge>`s in file order.
    pub knife_edges: Vec<KnifeEdge>,
    /// `<velocity_constraint>`s in file order.
    pub velocity_constraints: Vec<VelocityConstraint>,
    /// `<input>`s in file order: the FMI inputs.
    pub inputs: Vec<Input>,
    /// `<output>`s in file order: the FMI outputs.
    pub outputs: Vec<Output>,
    /// `<linearization><state>`s in file order: user position states, favoured by the
    /// state selection.
    pub lin_states: Vec<LinState>,
    /// `<linearization><velocity>`s in file order: user velocity-level candidates.
    pub lin_velocities: Vec<LinVelocity>,
    /// `<experiment>` (all `None` without one).
    pub experiment: Experiment,
    /// `<analysis static="true"/>`.
    pub static_analysis: bool,
    /// Start values set on states by name (`--set hinge.angle=0.3`, a packed FMU's start
    /// values), met exactly by initialization; resolved against the mechanism by the engine
    /// (`dae::StartValues::named`). Empty as read from a file.
    pub state_starts: Vec<(String, f64)>,
}
