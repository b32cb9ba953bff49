//! The engine's error type.

use crate::model::ModelError;

/// Engine failure.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EngineError {
    /// The model cannot be set up as written (e.g. it cannot be assembled), located at the
    /// element to blame: `file:line:col: element 'name': what is wrong`.
    #[error("{0}")]
    Model(ModelError),
    /// A numerical failure (integration, singular equations).
    #[error("{0}")]
    Numeric(String),
}

impl From<String> for EngineError {
    fn from(s: String) -> Self {
        EngineError::Numeric(s)
    }
}
