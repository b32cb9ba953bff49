//! `mbfmu check model.xml`: validate a model, assemble it, and print honest counts:
//! equations, independent equations, the redundant ones by element, and the degrees of
//! freedom at position and velocity level ([`crate::dae::counts`]), in the configuration
//! the linearization states are selected from ([`selection_options`]).

use std::io::Write;
use std::path::Path;

use super::{CliError, SetArgs};
use crate::dae::Simulator;
use crate::dae::counts::{Counts, counts};
use crate::linearize::tolerances::selection_options;

/// Load, validate and assemble `path` (with the `--set` overrides), then print the model name and its counts to `out`.
pub fn check(path: &Path, set: &SetArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let model = set.load(path)?;
    let t0 = model.experiment.start.unwrap_or(0.0);
    let sim = Simulator::new(&model, selection_options(), t0)?;
    super::print_warnings(&sim);
    let c = counts(sim.system(), sim.q(), sim.u(), t0, &sim.inputs(), &sim.ext());
    writeln!(out, "model '{}' ({}): ok", model.name, path.display())
        .and_then(|()| write!(out, "{}", report(model.bodies.len(), &c)))
        .map_err(|e| CliError::io("writing to stdout", e))
}

/// The counts as text, one line per level.
pub fn report(bodies: usize, c: &Counts) -> String {
    let plural = |k: usize, one: &str, many: &str| format!("{k} {}", if k == 1 { one } else { many });
    let mut s =
        format!("{}, {}\n", plural(bodies, "body", "bodies"), plural(c.coordinates, "coordinate", "coordinates"));
    let redundant: usize = c.redundant.iter().map(|(_, k)| k).sum();
    let named: Vec<String> = c.redundant.iter().map(|(e, k)| format!("{e}: {k}")).collect();
    s += &format!(
        "positions: {}, {} independent, {} redundant{}; {}\n",
        plural(c.equations, "constraint equation", "constraint equations"),
        c.independent,
        redundant,
        if named.is_empty() { String::new() } else { format!(" ({})", named.join(", ")) },
        plural(c.dof(), "degree of freedom", "degrees of freedom"),
    );
    if c.nonholonomic > 0 {
        s += &format!(
            "velocities: {}, {} independent; {}\n",
            plural(c.nonholonomic, "non-holonomic equation", "non-holonomic equations"),
            c.nonholonomic_independent,
            plural(c.velocity_dof(), "velocity degree of freedom", "velocity degrees of freedom"),
        );
    }
    s
}
