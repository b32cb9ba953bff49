//! `mbfmu linearize`: simulate to each requested time, linearize there in the states
//! selected at the start (the FMU's: [`selection_at_start`], whatever `--tol`), print the
//! chosen states and the eigenvalue table, and optionally write A, B, C, D (JSON, NumPy
//! .npz, or MATLAB v4 .mat).

use std::io::Write;
use std::path::PathBuf;

use clap::Args;

use super::input_csv::InputTable;
use super::{CliError, SetArgs};
use crate::dae::{BATCH_MAX_STEPS, SimOptions, Simulator};
use crate::linearize::eigen::{eigenvalues, format_table, rows_of_eigenvalues};
use crate::linearize::modes::{equilibrium_residual, format_shift, shift_invert_modes};
use crate::linearize::{Linearization, Selection, linearize, selection_at_start, state_counts, state_values};
use crate::model::Model;
use faer::c64;

/// Integration tolerance when neither `--tol` nor the model's experiment gives one.
pub const DEFAULT_TOL: f64 = 1e-8;

/// Arguments of `mbfmu linearize`.
#[derive(Debug, Args)]
pub struct LinearizeArgs {
    /// Model file.
    pub model: PathBuf,
    /// Comma-separated operating times (default: the experiment's start, else 0).
    #[arg(long, value_delimiter = ',')]
    pub at: Vec<f64>,
    /// Output format of the matrices: table (eigenvalues only), json, npz or mat.
    #[arg(long, default_value = "table")]
    pub format: String,
    /// Where to write json/npz/mat (default: json to stdout; npz/mat need it).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Integration tolerance (default: the experiment's, else 1e-8). The states are
    /// selected as in the FMU, whatever this is.
    #[arg(long)]
    pub tol: Option<f64>,
    /// Most integrator step attempts on the way to each time (and between input rows);
    /// more is an error at the time reached (the FMU's solver.maxSteps bounds one step).
    #[arg(long, value_name = "N", default_value_t = BATCH_MAX_STEPS, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub max_steps: usize,
    /// Find static equilibrium first (as `<analysis static="true"/>`).
    #[arg(long = "static")]
    pub r#static: bool,
    /// Input signals: CSV with a `time` column and one column per input (linear between
    /// rows, as fmpy's input arrays).
    #[arg(long, value_name = "FILE")]
    pub input: Option<PathBuf>,
    /// Parameter values and state start values to use instead of the file's.
    #[command(flatten)]
    pub set: SetArgs,
    /// Threads for the right-hand sides of the augmented system.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Only the K eigenvalues nearest --shift, by shift-invert Arnoldi on the sparse
    /// linearized DAE (its Jacobian pencil), never forming A: for large models. At an
    /// equilibrium only (there the pencil's finite eigenvalues are A's); writes the
    /// table, or JSON with the eigenvalues and no matrices.
    #[arg(long, value_name = "K")]
    pub modes: Option<usize>,
    /// The shift of --modes [rad/s]: real (default 0: the lowest frequencies) or complex,
    /// e.g. `0+62.8i` for the modes nearest 10 Hz.
    #[arg(long, value_name = "SIGMA", default_value = "0", allow_negative_numbers = true, value_parser = parse_shift)]
    pub shift: c64,
}

/// Run the command. The report (states, equilibrium, eigenvalue tables) goes to `out`,
/// except with `--format json` and no `--out`: then `out` gets only the JSON and the
/// report goes to `report` (stderr), so the output pipes into a JSON reader.
pub fn run(args: &LinearizeArgs, out: &mut dyn Write, report: &mut dyn Write) -> Result<(), CliError> {
    let mut model = args.set.load(&args.model)?;
    // --static: start from static equilibrium, as <analysis static="true"/> does.
    model.static_analysis |= args.r#static;
    let t0 = model.experiment.start.unwrap_or(0.0);
    let (tol, times) = settings(args, &model, t0)?;
    let (mut sim, table) = start(args, &mut model, tol, t0)?;
    let json_stdout = args.format == "json" && args.out.is_none();
    let rep: &mut dyn Write = if json_stdout { &mut *report } else { &mut *out };
    if let Some(k) = args.modes {
        // The eigenvalues do not depend on which states are chosen: no selection (at
        // 10 000 links it cost as much as the modes themselves), only their number.
        let items = run_modes(args, k, &mut sim, table.as_ref(), &times, rep)?;
        if args.format == "json" {
            write_json(args, format!("[{}]", items.join(",\n")), out)?;
        }
        return Ok(());
    }
    // The FMU's states: selected on their own configuration, not on this run's tolerance.
    let sel = selection_at_start(&model)?;
    print_selection(&sel, rep).map_err(io_err)?;
    if model.static_analysis {
        print_equilibrium(&mut sim, &sel, t0, rep)?;
    }
    let mut results = Vec::new();
    let mut eigs = Vec::new();
    for &t in &times {
        super::input_csv::advance(&mut sim, table.as_ref(), t)?;
        let lin = linearize(&mut sim, &sel, args.threads)?;
        eigs.push(print_eigenvalues(&lin, &sel, t, rep)?);
        results.push(lin);
    }
    write_matrices(args, &results, &eigs, out)
}

/// `--modes K`: at each time, the K eigenvalues nearest `--shift` from the sparse pencil
/// (no A), printed as a table; returns the JSON object of each time.
fn run_modes(
    args: &LinearizeArgs,
    k: usize,
    sim: &mut Simulator,
    table: Option<&InputTable>,
    times: &[f64],
    rep: &mut dyn Write,
) -> Result<Vec<String>, CliError> {
    if k == 0 {
        return Err(CliError::Usage("--modes 0: expected at least one mode".into()));
    }
    if matches!(args.format.as_str(), "npz" | "mat") {
        return Err(CliError::Usage(format!(
            "--modes writes no matrices: use --format table or json, not {}",
            args.format
        )));
    }
    let (s0, s1, nx) = state_counts(sim.system());
    let finite = s0 + s1 + nx;
    writeln!(
        rep,
        "{finite} states ({s0} positions, {s1} velocities, {nx} differential; the eigenvalues do not depend on \
         which are chosen)"
    )
    .map_err(io_err)?;
    let mut items = Vec::new();
    for &t in times {
        super::input_csv::advance(sim, table, t)?;
        let (j, m, f, mult) = sim.pencil()?;
        let off = equilibrium_residual(&f, &m, &mult);
        if off > EQUILIBRIUM_TOL {
            return Err(CliError::Usage(format!(
                "--modes: t = {t} is not an equilibrium (the equations of motion are off balance by \
                 {off:.1e} relative; 0 at an equilibrium): only there are the sparse pencil's eigenvalues \
                 those of A; linearize without --modes, or start at rest (--static)"
            )));
        }
        let modes = shift_invert_modes(&j, &m, f.len(), k, finite, args.shift)
            .map_err(|e| CliError::Engine(crate::dae::EngineError::Numeric(e)))?;
        let rows = rows_of_eigenvalues(&table_values(&modes.eigenvalues, modes.shift));
        writeln!(
            rep,
            "\nt = {t}: {} eigenvalues nearest {} (shift-invert Arnoldi on the sparse pencil, n = {}, subspace {}, \
             {} solves, {} restarts)",
            modes.eigenvalues.len(),
            format_shift(modes.shift),
            f.len(),
            modes.subspace,
            modes.solves,
            modes.restarts
        )
        .map_err(io_err)?;
        write!(rep, "{}", format_table(&rows)).map_err(io_err)?;
        items.push(format!(
            "{{\"time\": {t:e}, \"route\": \"shift-invert\", \"shift\": [{:e}, {:e}], \"eigenvalues\": {}}}",
            modes.shift.re,
            modes.shift.im,
            json_eigenvalues(&modes.eigenvalues)
        ));
    }
    Ok(items)
}

/// The eigenvalues the table shows: as found for a real shift (conjugate pairs, one row
/// each); for a complex one each stands for its pair, shown with Im ≥ 0, once.
fn table_values(ev: &[c64], shift: c64) -> Vec<c64> {
    if shift.im == 0.0 {
        return ev.to_vec();
    }
    let mut shown: Vec<c64> = Vec::with_capacity(ev.len());
    for z in ev.iter().map(|z| if z.im < 0.0 { z.conj() } else { *z }) {
        if !shown.iter().any(|w| (w - z).norm() <= 1e-10 * z.norm()) {
            shown.push(z);
        }
    }
    shown
}

/// `--shift`: a real number, or a complex one as `RE+IMi`, `RE-IMi` or `IMi` (`j` for `i`
/// too), finite.
fn parse_shift(text: &str) -> Result<c64, String> {
    let bad = || format!("'{text}' is not a finite real or complex number (e.g. 2, -0.5, 0+62.8i, 62.8i)");
    let t = text.trim();
    let num = |s: &str| -> Result<f64, String> {
        let v = match s {
            "" | "+" => 1.0,
            "-" => -1.0,
            _ => s.parse::<f64>().map_err(|_| bad())?,
        };
        if v.is_finite() { Ok(v) } else { Err(bad()) }
    };
    let Some(body) = t.strip_suffix(['i', 'j']) else {
        return if t.is_empty() { Err(bad()) } else { num(t).map(|re| c64::new(re, 0.0)) };
    };
    // The sign that starts the imaginary part: the last + or − not leading and not an exponent's.
    let b = body.as_bytes();
    let split = (1..b.len()).rev().find(|&i| matches!(b[i], b'+' | b'-') && !matches!(b[i - 1], b'e' | b'E'));
    match split {
        // The real part is a number in full (`num`'s lone signs stand for ±1 only in front of i).
        Some(i) => match body[..i].parse::<f64>() {
            Ok(re) if re.is_finite() => Ok(c64::new(re, num(&body[i..])?)),
            _ => Err(bad()),
        },
        None => Ok(c64::new(0.0, num(body)?)),
    }
}

/// Largest relative imbalance of the equations of motion (see [`equilibrium_residual`])
/// that `--modes` accepts as an equilibrium.
const EQUILIBRIUM_TOL: f64 = 1e-6;

/// `[[re, im], …]`.
fn json_eigenvalues(ev: &[c64]) -> String {
    format!("[{}]", ev.iter().map(|z| format!("[{:e}, {:e}]", z.re, z.im)).collect::<Vec<_>>().join(", "))
}

/// An error writing the report or the JSON to their stream.
fn io_err(e: std::io::Error) -> CliError {
    CliError::io("writing output", e)
}

/// The checked tolerance and the sorted operating times (from `--at`, else `t0`), after
/// checking `--format`.
fn settings(args: &LinearizeArgs, model: &Model, t0: f64) -> Result<(f64, Vec<f64>), CliError> {
    let tol = args.tol.or(model.experiment.tolerance).unwrap_or(DEFAULT_TOL);
    if tol.is_nan() || tol <= 0.0 {
        return Err(CliError::Usage(format!("--tol must be positive, got {tol}")));
    }
    let mut times = if args.at.is_empty() { vec![t0] } else { args.at.clone() };
    times.sort_by(f64::total_cmp);
    if let Some(t) = times.iter().find(|t| !t.is_finite() || **t < t0) {
        return Err(CliError::Usage(format!("--at {t}: times must be finite and not before the start {t0}")));
    }
    if !matches!(args.format.as_str(), "table" | "json" | "npz" | "mat") {
        return Err(CliError::Usage(format!("--format {}: expected table, json, npz or mat", args.format)));
    }
    Ok((tol, times))
}

/// The simulator at `t0` (with the `--input` table's first values, which it returns) and
/// its initialization warnings printed.
fn start(
    args: &LinearizeArgs,
    model: &mut Model,
    tol: f64,
    t0: f64,
) -> Result<(Simulator, Option<InputTable>), CliError> {
    let table = args.input.as_deref().map(|p| InputTable::read(p, model)).transpose()?;
    if let Some(t) = &table {
        t.set_start(model, t0);
    }
    let mut sim = Simulator::new(model, SimOptions { tol, max_step: None, max_steps: args.max_steps }, t0)?;
    if let Some(t) = &table {
        t.apply(&mut sim)?;
    }
    super::print_warnings(&sim);
    Ok((sim, table))
}

/// Print the selected states' values at the static equilibrium found at `t0`.
fn print_equilibrium(sim: &mut Simulator, sel: &Selection, t0: f64, rep: &mut dyn Write) -> Result<(), CliError> {
    let v = state_values(sim, sel)?;
    let items: Vec<String> = sel.states.iter().zip(&v.s).map(|(s, x)| format!("{} = {x:.9e}", s.name)).collect();
    writeln!(rep, "static equilibrium at t = {t0}: {}", items.join(", ")).map_err(io_err)?;
    Ok(())
}

/// Print the eigenvalue table of the linearization `lin` at `t`, with a note on the zero
/// eigenvalues that non-holonomic constraints imply.
fn print_eigenvalues(lin: &Linearization, sel: &Selection, t: f64, rep: &mut dyn Write) -> Result<Vec<c64>, CliError> {
    let (s0, s1) = (sel.states.len(), sel.velocities.len());
    let (ev, route) = eigenvalues(&lin.a, s0, s1).map_err(|e| CliError::Engine(e.into()))?;
    let rows = rows_of_eigenvalues(&ev);
    writeln!(rep, "\nt = {t}: {} states, {} eigenvalues ({})", lin.states.len(), lin.a.nrows(), route.describe())
        .map_err(io_err)?;
    write!(rep, "{}", format_table(&rows)).map_err(io_err)?;
    if s1 < s0 {
        writeln!(
            rep,
            "note: at least s0 - s1 = {} eigenvalues are zero because of the non-holonomic constraints: \
             {s0} position states but {s1} velocity states, so {} position combinations only integrate \
             the velocities and never feed back",
            s0 - s1,
            s0 - s1
        )
        .map_err(io_err)?;
    }
    Ok(ev)
}

/// Write A, B, C, D of every linearization as `--format` asks: JSON to `--out` (else to
/// `out`), npz or mat to `--out` (required); nothing for a table.
fn write_matrices(
    args: &LinearizeArgs,
    results: &[Linearization],
    eigs: &[Vec<c64>],
    out: &mut dyn Write,
) -> Result<(), CliError> {
    match args.format.as_str() {
        "json" => write_json(args, to_json(results, eigs), out)?,
        f @ ("npz" | "mat") => {
            let Some(p) = &args.out else { return Err(CliError::Usage(format!("--format {f} needs --out FILE"))) };
            let bytes = if f == "npz" { super::matrices::npz(results) } else { super::matrices::mat_v4(results) };
            std::fs::write(p, bytes?).map_err(|e| CliError::io(format!("writing {}", p.display()), e))?;
        }
        _ => {}
    }
    Ok(())
}

/// JSON text to `--out`, else to `out`.
fn write_json(args: &LinearizeArgs, text: String, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.out {
        Some(p) => std::fs::write(p, text).map_err(|e| CliError::io(format!("writing {}", p.display()), e)),
        None => writeln!(out, "{text}").map_err(io_err),
    }
}

/// Print the selected states and any dropped user states.
pub fn print_selection(sel: &Selection, out: &mut dyn Write) -> std::io::Result<()> {
    let names: Vec<&str> = sel.states.iter().map(|s| s.name.as_str()).collect();
    writeln!(out, "linearization states ({}): {}", names.len(), names.join(", "))?;
    if sel.velocities.len() < sel.states.len() {
        let w: Vec<String> = sel.velocities.iter().map(|w| w.name()).collect();
        writeln!(out, "velocity states ({}, non-holonomic constraints): {}", w.len(), w.join(", "))?;
    }
    if !sel.dropped.is_empty() {
        writeln!(out, "dropped user states (not independent of the others): {}", sel.dropped.join(", "))?;
    }
    Ok(())
}

/// Append `m` as `[[a, b], [c, d]]` (numbers as `{:e}`) to `s`, without a string per
/// entry: at N = 1000 links A alone has 4 million (mostly zero) entries.
fn push_json_matrix(s: &mut String, m: &faer::Mat<f64>) {
    use std::fmt::Write as _;
    s.push('[');
    for i in 0..m.nrows() {
        s.push_str(if i == 0 { "[" } else { ", [" });
        for j in 0..m.ncols() {
            if j > 0 {
                s.push_str(", ");
            }
            let v = m[(i, j)];
            if v == 0.0 {
                // What `{:e}` writes for ±0, without formatting.
                s.push_str(if v.is_sign_negative() { "-0e0" } else { "0e0" });
            } else {
                let _ = write!(s, "{v:e}");
            }
        }
        s.push(']');
    }
    s.push(']');
}

fn json_names(v: &[String]) -> String {
    format!(
        "[{}]",
        v.iter()
            .map(|s| format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\"")))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// The linearizations as a JSON array, each with its eigenvalues (`[[re, im], …]`).
pub fn to_json(results: &[Linearization], eigs: &[Vec<c64>]) -> String {
    let mut s = String::from("[");
    for (k, (l, ev)) in results.iter().zip(eigs).enumerate() {
        if k > 0 {
            s.push_str(",\n");
        }
        s.push_str(&format!(
            "{{\"time\": {:e}, \"states\": {}, \"inputs\": {}, \"outputs\": {}",
            l.time,
            json_names(&l.states),
            json_names(&l.inputs),
            json_names(&l.outputs)
        ));
        for (name, m) in [("A", &l.a), ("B", &l.b), ("C", &l.c), ("D", &l.d)] {
            s.push_str(&format!(", \"{name}\": "));
            push_json_matrix(&mut s, m);
        }
        s.push_str(&format!(", \"eigenvalues\": {}}}", json_eigenvalues(ev)));
    }
    s.push(']');
    s
}
