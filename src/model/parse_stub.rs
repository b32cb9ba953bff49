//! TEMPORARY stub of the model parser (branch `cli`), so the CLI compiles before the real
//! parser is merged. The real `src/model/parse.rs` replaces this file on merge: delete
//! this file and the `#[path]` line in `src/model/mod.rs`.

use std::fmt;
use std::path::Path;

use super::{Model, ModelError, SrcPos};

/// Counts that `mbfmu check` prints.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Summary {
    /// Number of bodies (ground excluded).
    pub bodies: usize,
    /// Number of coordinates n.
    pub coordinates: usize,
    /// Number of constraint equations m.
    pub constraints: usize,
    /// Degrees of freedom.
    pub dof: usize,
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "bodies:             {}", self.bodies)?;
        writeln!(f, "coordinates n:      {}", self.coordinates)?;
        writeln!(f, "constraints m:      {}", self.constraints)?;
        write!(f, "degrees of freedom: {}", self.dof)
    }
}

impl Model {
    /// Counts of bodies, coordinates, constraints and degrees of freedom.
    pub fn summary(&self) -> Summary {
        Summary {
            bodies: self.bodies.len(),
            coordinates: 0,
            constraints: 0,
            dof: 0,
        }
    }
}

fn not_implemented(file: &str) -> ModelError {
    ModelError {
        file: file.to_string(),
        pos: SrcPos { line: 1, col: 1 },
        element: "multibody".into(),
        name: "multibody".into(),
        msg: "model parser not implemented (temporary stub)".into(),
    }
}

/// Read and validate a model file.
pub fn load_file(path: &Path) -> Result<Model, ModelError> {
    Err(not_implemented(&path.display().to_string()))
}

/// Parse and validate model text; `file` names it in messages.
pub fn load_str(text: &str, file: &str) -> Result<Model, ModelError> {
    let _ = text;
    Err(not_implemented(file))
}
