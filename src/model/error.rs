//! Model errors: `file:line:col: element 'name': what is wrong`.

use super::SrcPos;

/// A model-file error with its location.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}:{}:{}: {element} '{name}': {msg}", pos.line, pos.col)]
pub struct ModelError {
    pub file: String,
    pub pos: SrcPos,
    /// Element tag (`joint`, `body`, ...).
    pub element: String,
    /// Element name (or the tag when it has none).
    pub name: String,
    pub msg: String,
}
