//! What a command can fail with, and the exit code of each kind.

use crate::dae::EngineError;
use crate::model::ModelError;

/// A command failure. `Display` is the message printed to stderr.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad model file: printed as `file:line:col: element 'name': what is wrong`.
    #[error("{0}")]
    Model(#[from] ModelError),
    /// Bad command-line value (e.g. a negative step).
    #[error("error: {0}")]
    Usage(String),
    /// Engine failure (integration, evaluation).
    #[error("error: {0}")]
    Engine(EngineError),
    /// Reading or writing a file or stdout failed.
    #[error("error: {context}: {source}")]
    Io {
        /// What was being read or written.
        context: String,
        source: std::io::Error,
    },
}

impl From<EngineError> for CliError {
    /// A model the engine cannot set up (e.g. not assemblable) is bad input, located.
    fn from(e: EngineError) -> Self {
        match e {
            EngineError::Model(m) => CliError::Model(m),
            other => CliError::Engine(other),
        }
    }
}

impl CliError {
    /// Process exit code: 2 for bad input (model or arguments), 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Model(_) | CliError::Usage(_) => 2,
            CliError::Engine(_) | CliError::Io { .. } => 1,
        }
    }

    /// Wrap an I/O error with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> CliError {
        CliError::Io { context: context.into(), source }
    }
}
