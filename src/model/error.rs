//! Model errors: `file:line:col: element 'name': what is wrong`.

use super::SrcPos;

/// A model-file error with its location.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}:{}:{}: {element} '{name}': {msg}", pos.line, pos.col)]
pub struct ModelError {
    /// File label (its path, or the label given to `load_str`).
    pub file: String,
    /// Where the error is: the offending attribute or character, else the element's `<`
    /// (1:1 when the file cannot be read).
    pub pos: SrcPos,
    /// Element tag (`joint`, `body`, ...).
    pub element: String,
    /// Element name (or the tag when it has none).
    pub name: String,
    /// What is wrong.
    pub msg: String,
}
