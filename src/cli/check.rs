//! `mbfmu check model.xml`: validate a model and print its summary.

use std::io::Write;
use std::path::Path;

use super::CliError;
use crate::model::parse::load_file;

/// Load and validate `path`, then print the model name and its summary (bodies,
/// coordinates n, constraints m, degrees of freedom) to `out`.
pub fn check(path: &Path, out: &mut dyn Write) -> Result<(), CliError> {
    let model = load_file(path)?;
    let summary = model.summary();
    writeln!(out, "model '{}' ({}): ok", model.name, path.display())
        .and_then(|()| writeln!(out, "{summary}"))
        .map_err(|e| CliError::io("writing to stdout", e))
}
