//! `mbfmu modal beam ...`: generate the modal data file of a straight beam
//! ([`crate::modal::beam()`]: Euler–Bernoulli elements, lumped mass, free-interface or
//! Craig–Bampton modes) and write it (`-o FILE`, or stdout).

use std::io::Write;
use std::path::PathBuf;

use clap::{ArgGroup, Args, Subcommand};

use super::CliError;
use crate::modal::{BeamSpec, Material, ModalStiffness, Reduction, Section, beam, write};

/// Arguments of `mbfmu modal`.
#[derive(Clone, Debug, Args)]
pub struct ModalArgs {
    /// What to generate.
    #[command(subcommand)]
    pub command: ModalCommand,
}

/// The generators of `mbfmu modal`.
#[derive(Clone, Debug, Subcommand)]
pub enum ModalCommand {
    /// A straight beam along body x (node 0 at x = 0, node N at x = L): N Euler–Bernoulli
    /// (or, with --timoshenko, Timoshenko) elements, lumped mass, n modes mass-normalized
    /// with respect to the node masses.
    Beam(BeamArgs),
}

/// Arguments of `mbfmu modal beam` (SI units).
#[derive(Clone, Debug, Args)]
#[command(group(ArgGroup::new("shear_modulus").required(true).args(["shear", "poisson"])))]
pub struct BeamArgs {
    /// Length L (m).
    #[arg(long, allow_negative_numbers = true)]
    pub length: f64,
    /// Number N of equal elements (nodes 0 to N).
    #[arg(long)]
    pub elements: usize,
    /// Number n of modes to write (rigid-body modes are never written).
    #[arg(long)]
    pub modes: usize,
    /// Cross-section area A (m²).
    #[arg(long, allow_negative_numbers = true)]
    pub area: f64,
    /// Second moment Iy (m⁴): bending in the x-z plane.
    #[arg(long, allow_negative_numbers = true)]
    pub iy: f64,
    /// Second moment Iz (m⁴): bending in the x-y plane.
    #[arg(long, allow_negative_numbers = true)]
    pub iz: f64,
    /// Torsion constant J (m⁴).
    #[arg(long, allow_negative_numbers = true)]
    pub j: f64,
    /// Young's modulus E (Pa).
    #[arg(long, allow_negative_numbers = true)]
    pub young: f64,
    /// Shear modulus G (Pa).
    #[arg(long, allow_negative_numbers = true)]
    pub shear: Option<f64>,
    /// Poisson's ratio ν, for G = E / (2 (1 + ν)).
    #[arg(long, allow_negative_numbers = true)]
    pub poisson: Option<f64>,
    /// Density ρ (kg/m³).
    #[arg(long, allow_negative_numbers = true)]
    pub density: f64,
    /// Timoshenko elements (shear deformation and the section's rotary inertia) with this
    /// shear coefficient κ (5/6 for a solid rectangle, 0.9 for a solid circle); default:
    /// Euler–Bernoulli elements.
    #[arg(long, value_name = "KAPPA", allow_negative_numbers = true)]
    pub timoshenko: Option<f64>,
    /// Damping ratio ζ of every mode (default: undamped).
    #[arg(long, allow_negative_numbers = true)]
    pub damping: Option<f64>,
    /// Craig–Bampton reduction with these interface node ids (all six DOFs of each)
    /// instead of free-interface modes.
    #[arg(long, value_name = "ID,ID", value_delimiter = ',', requires = "fixed_modes")]
    pub craig_bampton: Option<Vec<u32>>,
    /// Number k of fixed-interface normal modes of the Craig–Bampton basis.
    #[arg(long, value_name = "K", requires = "craig_bampton")]
    pub fixed_modes: Option<usize>,
    /// Fix this node's six DOFs (a cantilever; then no rigid-body mode is dropped).
    #[arg(long, value_name = "ID")]
    pub clamp: Option<u32>,
    /// Write the modal data file here (default: stdout).
    #[arg(short = 'o', long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// Run `mbfmu modal ...`.
pub fn run(args: &ModalArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.command {
        ModalCommand::Beam(b) => run_beam(b, out),
    }
}

/// The generator's spec from the arguments; a bad value is a usage error.
pub fn beam_spec(a: &BeamArgs) -> Result<BeamSpec, CliError> {
    let shear = match (a.shear, a.poisson) {
        (Some(g), _) => g,
        (None, Some(nu)) => {
            if !(nu > -1.0 && nu < 0.5) {
                return Err(CliError::Usage(format!("--poisson {nu}: must be in (-1, 0.5)")));
            }
            a.young / (2.0 * (1.0 + nu))
        }
        (None, None) => return Err(CliError::Usage("give --shear or --poisson".into())),
    };
    let reduction = match (&a.craig_bampton, a.fixed_modes) {
        (Some(ids), Some(k)) => Reduction::CraigBampton { interface: ids.clone(), fixed_modes: k },
        _ => Reduction::FreeInterface,
    };
    Ok(BeamSpec {
        length: a.length,
        elements: a.elements,
        section: Section { area: a.area, iy: a.iy, iz: a.iz, j: a.j },
        material: Material { young: a.young, shear, density: a.density },
        modes: a.modes,
        damping: a.damping,
        clamp: a.clamp,
        reduction,
        shear_coefficient: a.timoshenko,
    })
}

/// Generate and write; with `-o`, print one line saying what was written.
fn run_beam(a: &BeamArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let data = beam(&beam_spec(a)?).map_err(CliError::Usage)?;
    let text = write(&data);
    match &a.out {
        None => out.write_all(text.as_bytes()).map_err(|e| CliError::io("writing to stdout", e)),
        Some(path) => {
            std::fs::write(path, &text).map_err(|e| CliError::io(format!("writing {}", path.display()), e))?;
            let f = match &data.stiffness {
                ModalStiffness::Frequencies(f) => f.clone(),
                ModalStiffness::Matrix(_) => Vec::new(),
            };
            let list: Vec<String> = f.iter().map(|f| format!("{f:.6}")).collect();
            writeln!(
                out,
                "{} nodes, {} modes ({} Hz) -> {}",
                data.nodes.len(),
                f.len(),
                list.join(", "),
                path.display()
            )
            .map_err(|e| CliError::io("writing to stdout", e))
        }
    }
}
