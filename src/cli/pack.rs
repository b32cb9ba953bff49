//! `mbfmu pack model.xml -o model.fmu` and/or `--out-dir DIR` [`--fmi 3`] [`--kind
//! me|cs|both`]: build the model's FMI 2.0 (or 3.0) FMU (see [`crate::pack`]).

use std::io::Write;
use std::path::PathBuf;

use clap::{ArgGroup, Args};

use super::{CliError, SetArgs};
use crate::fmi::variables::Standard;
use crate::pack::{Kind, PackError, pack_with};

/// Arguments of `mbfmu pack` (at least one of `--out` and `--out-dir`).
#[derive(Clone, Debug, Args)]
#[command(group(ArgGroup::new("destination").required(true).multiple(true).args(["out", "out_dir"])))]
pub struct PackArgs {
    /// Model file (XML, see MODEL_FORMAT.md).
    pub model: PathBuf,
    /// Write the FMU (a zip archive) to this file.
    #[arg(short = 'o', long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the FMU's files, unzipped, into this directory.
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// FMI version of the FMU: 2 (FMI 2.0, the default) or 3 (FMI 3.0).
    #[arg(long, value_name = "VERSION", default_value = "2", value_parser = ["2", "3"])]
    pub fmi: String,
    /// Interfaces of the FMU: me (Model Exchange: the host integrates the linearization
    /// states), cs (Co-Simulation: the FMU integrates), or both in one FMU (the default),
    /// in either FMI version.
    #[arg(long, value_name = "KIND", default_value = "both", value_parser = ["me", "cs", "both"])]
    pub kind: String,
    /// Start values instead of the file's: the FMU's default (and modelDescription
    /// `start`) of each parameter set.
    #[command(flatten)]
    pub set: SetArgs,
}

impl From<PackError> for CliError {
    fn from(e: PackError) -> Self {
        match e {
            PackError::Model(m) => CliError::Model(m),
            PackError::StartValue(e) => CliError::Usage(format!("--set: {e}")),
            PackError::Unsupported(e) => CliError::Usage(e),
            PackError::Io { context, source } => CliError::Io { context, source },
            PackError::LibraryNotFound(msg) => {
                CliError::io("locating the FMU library", std::io::Error::new(std::io::ErrorKind::NotFound, msg))
            }
        }
    }
}

/// Pack the FMU and print one line: modelIdentifier, GUID and where it was written (and
/// what the FMU lacks, as warnings on stderr).
pub fn run(args: &PackArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let standard = if args.fmi == "3" { Standard::Fmi3 } else { Standard::Fmi2 };
    let kind = match args.kind.as_str() {
        "me" => Kind::ModelExchange,
        "cs" => Kind::CoSimulation,
        _ => Kind::Both,
    };
    let (out_file, out_dir) = (args.out.as_deref(), args.out_dir.as_deref());
    let packed = pack_with(&args.model, &args.set.pairs()?, standard, kind, out_file, out_dir)?;
    packed.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
    let dest: Vec<String> = args.out.iter().chain(&args.out_dir).map(|p| p.display().to_string()).collect();
    writeln!(out, "packed FMU '{}' guid {} -> {}", packed.model_identifier, packed.guid, dest.join(", "))
        .map_err(|e| CliError::io("writing to stdout", e))
}
