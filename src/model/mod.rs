//! The model layer: parse a model file, validate it, resolve names, evaluate constants.
//! Knows nothing of mechanics, integration or FMI.

pub mod error;
pub mod expr;
pub mod parse;
mod types;
pub mod units;

pub use error::ModelError;
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
    pub name: String,
    /// Path of the file it was read from (for messages).
    pub file: String,
    pub parameters: Vec<Parameter>,
    pub gravity: [f64; 3],
    /// The `<gravity>` expressions (`None`: no gravity); `gravity` holds their values.
    pub gravity_expr: Option<NumVec>,
    pub bodies: Vec<Body>,
    pub markers: Vec<Marker>,
    pub joints: Vec<Joint>,
    pub motions: Vec<Motion>,
    pub constraints: Vec<UserConstraint>,
    pub spring_dampers: Vec<SpringDamper>,
    pub sforces: Vec<Sforce>,
    pub gforces: Vec<Gforce>,
    pub bushings: Vec<Bushing>,
    pub variables: Vec<Variable>,
    pub differentials: Vec<Differential>,
    pub rolling_wheels: Vec<RollingWheel>,
    pub knife_edges: Vec<KnifeEdge>,
    pub velocity_constraints: Vec<VelocityConstraint>,
    pub inputs: Vec<Input>,
    pub outputs: Vec<Output>,
    pub lin_states: Vec<LinState>,
    pub lin_velocities: Vec<LinVelocity>,
    pub experiment: Experiment,
    /// `<analysis static="true"/>`.
    pub static_analysis: bool,
}
