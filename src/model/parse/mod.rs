//! The model-file reader: XML text → validated [`Model`](crate::model::Model), every
//! error located as `file:line:col: element 'name': message`.
//!
//! One concept per file: `source` (positions), `xml` (element tree), `attrs`
//! (attributes, vectors, constants), `orient` (orientations), `names` (names and
//! the expression scope), `params` (parameter evaluation order), `declare` and
//! `build` (the two passes over elements; `build_constraints`, `build_forces` and
//! `build_user` build each family of elements), `validate` (value and level checks),
//! `model_impl` (queries on a loaded model).

mod attrs;
mod build;
mod build_constraints;
mod build_flexible;
mod build_forces;
mod build_user;
mod declare;
mod load;
mod model_impl;
mod names;
mod orient;
mod params;
mod source;
mod validate;
mod xml;

pub use model_impl::Summary;
pub use orient::{rotation, try_rotation};

use crate::model::{Model, ModelError, SrcPos};
use std::path::Path;

/// Read and validate a model file.
pub fn load_file(path: &Path) -> Result<Model, ModelError> {
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ModelError {
        file: label.clone(),
        pos: SrcPos { line: 1, col: 1 },
        element: "file".into(),
        name: label.clone(),
        msg: format!("cannot read: {e}"),
    })?;
    load_str(&text, &label)
}

/// Read and validate a model from its text; `file_label` names it in messages.
pub fn load_str(text: &str, file_label: &str) -> Result<Model, ModelError> {
    load::load(text, file_label)
}
