//! Modal data file errors: `path: entry: what is wrong`, the entry named as a path into
//! the JSON document (`nodes[3].mass`, `modes[2].shape[7]`); syntax errors as
//! `path:line:column: what is wrong`.

/// An error reading a modal data file. `Display` is the whole message.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModalError {
    /// A well-formed document with a wrong entry.
    #[error("{path}: {entry}: {what}")]
    Entry {
        /// The file (as given).
        path: String,
        /// Where in the document: `nodes[3].mass`, `stiffness[0][1]`, `format`.
        entry: String,
        /// What is wrong.
        what: String,
    },
    /// Not JSON.
    #[error("{path}:{line}:{column}: {what}")]
    Syntax {
        /// The file (as given).
        path: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// What is wrong.
        what: String,
    },
    /// The file cannot be read.
    #[error("{path}: {what}")]
    Io {
        /// The file (as given).
        path: String,
        /// The operating system's message.
        what: String,
    },
}
