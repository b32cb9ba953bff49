//! The `mbfmu` command line: `check`, `simulate`, `pack`, `linearize`, `modal`, `run`. One file per command; `main.rs`
//! only calls [`main`].
//!
//! Exit codes: 0 success; 2 bad input (model error `file:line:col: element 'name': what is
//! wrong`, or bad command-line values); 1 engine or I/O failure. Nothing here panics on
//! bad input.

mod check;
mod error;
mod input_csv;
mod install;
mod linearize;
mod matrices;
mod modal;
mod pack;
mod run;
mod simulate;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

pub use error::CliError;
pub use linearize::LinearizeArgs;
pub use modal::{BeamArgs, ModalArgs, ModalCommand};
pub use pack::PackArgs;
pub use simulate::{SimulateArgs, communication_points};

/// Multibody model file -> simulation, FMI 2.0 FMU with exact linearization.
#[derive(Debug, Parser)]
#[command(name = "mbfmu", version, about)]
pub struct Cli {
    /// The subcommand and its arguments.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Validate a model file and print bodies, coordinates n, constraints m and degrees of
    /// freedom.
    Check {
        /// Model file (XML, see MODEL_FORMAT.md).
        model: PathBuf,
        /// Parameter values and state start values to use instead of the file's.
        #[command(flatten)]
        set: SetArgs,
    },
    /// Simulate a model and write time, every output (and with --states every q and u)
    /// as CSV.
    Simulate(SimulateArgs),
    /// Build the model's FMI 2.0 Co-Simulation FMU: a zip file (-o) and/or an unzipped
    /// directory (--out-dir).
    Pack(PackArgs),
    /// Linearize a model at one or more times: chosen states, eigenvalue table, and A, B,
    /// C, D as json, npz or mat.
    Linearize(LinearizeArgs),
    /// Generate a modal data file of a flexible body (see MODEL_FORMAT.md, "Modal data
    /// files"): `mbfmu modal beam ...`.
    Modal(ModalArgs),
    /// Install this mbfmu with the FMU library embedded as PREFIX/bin/mbfmu (default
    /// PREFIX: ~/.local), so that `mbfmu pack` works from anywhere.
    Install(install::InstallArgs),
    /// Run the embedded default model (models/double_pendulum.xml) for 2 s and print a
    /// table of its outputs.
    Run,
}

/// Parse the process arguments, run the command, and return its exit code.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with code 0; usage errors to stderr with code 2.
            let _ = e.print();
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
        }
    };
    // A panic is a bug: report it as an engine failure (exit 1), not a crash.
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(|| execute(&cli.command));
    let _ = std::panic::take_hook();
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        // A closed pipe (`mbfmu simulate m.xml | head`) is the reader's choice, not a failure.
        Ok(Err(CliError::Io { source, .. })) if source.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("{e}");
            ExitCode::from(e.exit_code())
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            eprintln!("error: internal error (please report): {what}");
            ExitCode::from(1)
        }
    }
}

/// `--set NAME=VALUE` (repeatable): start values instead of the model file's (parameters
/// and states), shared by `check`, `simulate`, `linearize` and `pack`. Parsed and resolved
/// by [`crate::model::overrides`], so that every command reads them alike.
#[derive(Clone, Debug, Default, Args)]
pub struct SetArgs {
    /// Use VALUE for the parameter NAME (repeatable): every attribute using it is
    /// re-evaluated, as when an FMU's parameter is set before initialization; or start
    /// the state NAME (`hinge.angle`, `der(hinge.angle)`, `arm.x`, a differential) at VALUE,
    /// met exactly by initialization.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}

impl SetArgs {
    /// The `NAME=VALUE` pairs; a malformed one is a usage error (exit 2).
    pub fn pairs(&self) -> Result<Vec<(String, f64)>, CliError> {
        self.set
            .iter()
            .map(|s| crate::model::overrides::parse_assignment(s).map_err(|e| CliError::Usage(format!("--set {e}"))))
            .collect()
    }

    /// Load the model file `path` with these overrides applied (an unknown name, a name set
    /// twice or a value the model rejects: a usage error, exit 2).
    pub fn load(&self, path: &std::path::Path) -> Result<crate::model::Model, CliError> {
        let model = crate::model::parse::load_file(path)?;
        let pairs = self.pairs()?;
        if pairs.is_empty() {
            return Ok(model);
        }
        let usage = |e: String| CliError::Usage(format!("--set: {e}"));
        let overrides = model.resolve_overrides(&pairs).map_err(usage)?;
        let model = model.with_overrides(&overrides).map_err(usage)?;
        crate::dae::StartValues::check_names(&model).map_err(usage)?;
        Ok(model)
    }
}

/// Print the engine's initialization warnings (bodies that assembly moved far) to stderr.
pub(crate) fn print_warnings(sim: &crate::dae::Simulator) {
    for w in sim.warnings() {
        eprintln!("warning: {w}");
    }
}

/// Run one command, writing its normal output to stdout.
pub fn execute(command: &Command) -> Result<(), CliError> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    match command {
        Command::Check { model, set } => check::check(model, set, &mut out),
        Command::Simulate(args) => simulate::simulate(args, &mut out),
        Command::Pack(args) => pack::run(args, &mut out),
        Command::Linearize(args) => linearize::run(args, &mut out, &mut std::io::stderr().lock()),
        Command::Modal(args) => modal::run(args, &mut out),
        Command::Install(args) => install::run(args, &mut out),
        Command::Run => run::run(&mut out),
    }
}
