//! `mbfmu run`: the main job on the embedded default model `models/double_pendulum.xml`:
//! the eigenvalue table of its linearization at rest (θ1 = θ2 = 0, states α1, α2), then a
//! 2 s simulation from its release angles with a table of its outputs.

use std::io::Write;

use super::CliError;
use super::simulate::{RunSettings, drive, header};
use crate::dae::{SimOptions, Simulator};
use crate::linearize::eigen::{eigen_table_structured, format_table};
use crate::linearize::{linearize, selection_at_start};
use crate::model::parse::load_str;

/// Name under which the embedded model reports errors.
pub const DEFAULT_MODEL_FILE: &str = "models/double_pendulum.xml";
/// The embedded default model.
pub const DEFAULT_MODEL: &str = include_str!("../../models/double_pendulum.xml");

/// Simulated time span [s] and communication step [s] of `mbfmu run`.
const RUN_END: f64 = 2.0;
const RUN_STEP: f64 = 0.1;

/// Column width of the table.
const WIDTH: usize = 14;

/// Simulate the embedded default model and print an aligned table of time and outputs.
pub fn run(out: &mut dyn Write) -> Result<(), CliError> {
    let model = load_str(DEFAULT_MODEL, DEFAULT_MODEL_FILE)?;
    let io_err = |e| CliError::io("writing to stdout", e);
    // Linearization at the hanging equilibrium: release angles set to 0.
    let mut p = model.param_values();
    for (k, par) in model.parameters.iter().enumerate() {
        if par.name == "th1" || par.name == "th2" {
            p[k] = 0.0;
        }
    }
    let at_rest = model.with_params(&p).map_err(CliError::Usage)?;
    let mut sim = Simulator::new(&at_rest, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0)?;
    let sel = selection_at_start(&at_rest)?;
    let lin = linearize(&mut sim, &sel, 2)?;
    let (rows, _) = eigen_table_structured(&lin.a, sel.states.len(), sel.velocities.len())
        .map_err(|e| CliError::Engine(e.into()))?;
    writeln!(out, "{DEFAULT_MODEL_FILE} at rest (th1 = th2 = 0), linearized in {}:", lin.states.join(", "))
        .map_err(io_err)?;
    write!(out, "{}", format_table(&rows)).map_err(io_err)?;
    writeln!(out).map_err(io_err)?;
    let settings = RunSettings::resolve(&model, Some(RUN_END), Some(RUN_STEP), None)?;
    let points = settings.points()?;
    let opts = SimOptions { tol: settings.tol, max_step: None, ..Default::default() };
    let mut sim = Simulator::new(&model, opts, settings.start)?;

    writeln!(
        out,
        "{}: {} s, step {} s, tolerance {:e}",
        DEFAULT_MODEL_FILE,
        settings.end - settings.start,
        settings.step,
        settings.tol
    )
    .map_err(io_err)?;
    let names = header(&sim, false);
    let widths: Vec<usize> = names.iter().map(|n| n.len().max(WIDTH)).collect();
    let line: Vec<String> = names.iter().zip(&widths).map(|(n, &w)| format!("{n:>w$}")).collect();
    writeln!(out, "{}", line.join(" ")).map_err(io_err)?;
    drive(&mut sim, &points, None, false, |t, values| {
        let mut cells = vec![format!("{t:>w$.3}", w = widths[0])];
        cells.extend(values.iter().zip(&widths[1..]).map(|(v, &w)| format!("{v:>w$.6}")));
        writeln!(out, "{}", cells.join(" ")).map_err(io_err)
    })
}
