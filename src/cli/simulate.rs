//! `mbfmu simulate model.xml [--end T] [--step H] [--tol E] [--max-steps N] [--out result.csv] [--states] [--stats]`:
//! simulate and write time, every output (and every q and u) as CSV; with `--stats` also
//! the integrator's statistics and the wall time on stderr.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;

use super::input_csv::InputTable;
use super::{CliError, SetArgs};
use crate::dae::radau::Stats;
use crate::dae::{DEFAULT_MAX_STEPS, SimOptions, Simulator};
use crate::model::Model;

/// Defaults when neither the command line nor the model's `<experiment>` gives a value.
const DEFAULT_STOP: f64 = 1.0;
const DEFAULT_STEP: f64 = 0.01;
const DEFAULT_TOL: f64 = 1e-6;

/// Arguments of `mbfmu simulate`.
#[derive(Clone, Debug, Args)]
pub struct SimulateArgs {
    /// Model file (XML, see MODEL_FORMAT.md).
    pub model: PathBuf,
    /// End time [s] (default: the model's <experiment stop>, else 1).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub end: Option<f64>,
    /// Communication step [s] (default: the model's <experiment step>, else 0.01).
    #[arg(long, value_name = "H", allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// Integrator tolerance (default: the model's <experiment tolerance>, else 1e-6).
    #[arg(long, value_name = "E", allow_negative_numbers = true)]
    pub tol: Option<f64>,
    /// Most integrator step attempts per communication step; more is an error at the time
    /// reached (as the FMU's solver.maxSteps).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_STEPS, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub max_steps: usize,
    /// Write the CSV to this file instead of stdout.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Also write every coordinate q and velocity u.
    #[arg(long)]
    pub states: bool,
    /// Start from static equilibrium (as `<analysis static="true"/>`).
    #[arg(long = "static")]
    pub r#static: bool,
    /// At the end of the run (also a failed one), print the integrator's statistics
    /// (step attempts, accepted and rejected steps, Newton iterations, Jacobian
    /// evaluations, factorizations and those the block LU left to the general one,
    /// symbolic analyses, rhs evaluations; totals and per communication step) and the
    /// wall time to stderr.
    #[arg(long)]
    pub stats: bool,
    /// Input signals: CSV with a `time` column and one column per input (linear between
    /// rows, as fmpy's input arrays).
    #[arg(long, value_name = "FILE")]
    pub input: Option<PathBuf>,
    /// Parameter values and state start values to use instead of the file's.
    #[command(flatten)]
    pub set: SetArgs,
}

/// Start, end, step and tolerance of one simulation run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSettings {
    /// Start time (s): the model's `<experiment start>`, else 0 (no command-line option).
    pub start: f64,
    /// End time (s), finite and not before `start`.
    pub end: f64,
    /// Communication step (s), positive: the output interval.
    pub step: f64,
    /// Integrator tolerance (relative and absolute), positive.
    pub tol: f64,
}

impl RunSettings {
    /// Command-line values first, then the model's `<experiment>`, then the defaults
    /// (start 0, end 1, step 0.01, tolerance 1e-6). Rejects non-finite or non-positive
    /// step and tolerance, and an end before the start.
    pub fn resolve(
        model: &Model,
        end: Option<f64>,
        step: Option<f64>,
        tol: Option<f64>,
    ) -> Result<RunSettings, CliError> {
        let ex = &model.experiment;
        let s = RunSettings {
            start: ex.start.unwrap_or(0.0),
            end: end.or(ex.stop).unwrap_or(DEFAULT_STOP),
            step: step.or(ex.step).unwrap_or(DEFAULT_STEP),
            tol: tol.or(ex.tolerance).unwrap_or(DEFAULT_TOL),
        };
        if !s.start.is_finite() || !s.end.is_finite() {
            return Err(CliError::Usage(format!("start {} and end {} must be finite", s.start, s.end)));
        }
        if s.end < s.start {
            return Err(CliError::Usage(format!("end time {} is before the start time {}", s.end, s.start)));
        }
        if !(s.step.is_finite() && s.step > 0.0) {
            return Err(CliError::Usage(format!("step {} must be positive", s.step)));
        }
        if !(s.tol.is_finite() && s.tol > 0.0) {
            return Err(CliError::Usage(format!("tolerance {} must be positive", s.tol)));
        }
        Ok(s)
    }

    /// The communication points, see [`communication_points`].
    pub fn points(&self) -> Result<Vec<f64>, CliError> {
        communication_points(self.start, self.end, self.step)
    }
}

/// Communication points t_k = start + k·step for k = 0..=round((end − start)/step), each
/// computed by multiplication (no accumulated round-off). The last point is `end` itself
/// when it lies within round-off of it. Fails when there would be more than 10⁹ points.
pub fn communication_points(start: f64, end: f64, step: f64) -> Result<Vec<f64>, CliError> {
    let ratio = ((end - start) / step).round();
    if !(0.0..=1e9).contains(&ratio) {
        return Err(CliError::Usage(format!(
            "{ratio} communication steps from {start} to {end} with step {step}: \
             choose a larger step"
        )));
    }
    let n = ratio as usize;
    let mut points: Vec<f64> = (0..=n).map(|k| start + k as f64 * step).collect();
    if let Some(last) = points.last_mut()
        && n > 0
        && (*last - end).abs() <= 1e-9 * step
    {
        *last = end;
    }
    Ok(points)
}

/// Run `sim` through `points` (the first is its current time), following `inputs`,
/// calling `row(t, values)` at each point with the outputs followed, when `with_states`,
/// by the states.
pub fn drive(
    sim: &mut Simulator,
    points: &[f64],
    inputs: Option<&InputTable>,
    with_states: bool,
    mut row: impl FnMut(f64, &[f64]) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let mut values = Vec::new();
    for (k, &t) in points.iter().enumerate() {
        if k > 0 {
            super::input_csv::advance(sim, inputs, t)?;
        }
        values.clear();
        values.extend(sim.outputs()?);
        if with_states {
            values.extend(sim.states());
        }
        row(t, &values)?;
    }
    Ok(())
}

/// The CSV header: `time`, the output names, then (with states) the state names.
pub fn header(sim: &Simulator, with_states: bool) -> Vec<String> {
    let mut names = vec!["time".to_string()];
    names.extend(sim.output_names());
    if with_states {
        names.extend(sim.state_names());
    }
    names
}

/// Write one CSV line; numbers round-trip exactly (`{:.17e}`).
fn write_csv_row(out: &mut dyn Write, t: f64, values: &[f64]) -> std::io::Result<()> {
    write!(out, "{t:.17e}")?;
    for v in values {
        write!(out, ",{v:.17e}")?;
    }
    writeln!(out)
}

/// Run `mbfmu simulate`; the CSV goes to `--out` or else to `stdout`.
pub fn simulate(args: &SimulateArgs, stdout: &mut dyn Write) -> Result<(), CliError> {
    let started = Instant::now();
    let mut model = args.set.load(&args.model)?;
    model.static_analysis |= args.r#static;
    let settings = RunSettings::resolve(&model, args.end, args.step, args.tol)?;
    let points = settings.points()?;
    let opts = SimOptions { tol: settings.tol, max_step: None, max_steps: args.max_steps };
    let table = args.input.as_deref().map(|p| InputTable::read(p, &model)).transpose()?;
    if let Some(t) = &table {
        t.set_start(&mut model, settings.start);
    }
    let mut sim = Simulator::new(&model, opts, settings.start)?;
    if let Some(t) = &table {
        t.apply(&mut sim)?;
    }
    super::print_warnings(&sim);

    let (mut file_out, target) = match &args.out {
        Some(path) => {
            let f = File::create(path).map_err(|e| CliError::io(format!("creating {}", path.display()), e))?;
            (Some(BufWriter::new(f)), path.display().to_string())
        }
        None => (None, "stdout".to_string()),
    };
    let mut buffered_stdout;
    let out: &mut dyn Write = match file_out.as_mut() {
        Some(f) => f,
        None => {
            buffered_stdout = BufWriter::new(stdout);
            &mut buffered_stdout
        }
    };
    let io_err = |e| CliError::io(format!("writing {target}"), e);

    let initialized = started.elapsed();
    writeln!(out, "{}", header(&sim, args.states).join(",")).map_err(io_err)?;
    let mut rows = 0usize;
    let result = drive(&mut sim, &points, table.as_ref(), args.states, |t, values| {
        rows += 1;
        write_csv_row(out, t, values).map_err(io_err)
    });
    // Keep the rows computed before a failure: flush either way, report the first error.
    let flushed = out.flush().map_err(io_err);
    if args.stats {
        // Communication steps completed (a row each, after the start's), and the one that
        // failed, if any: the work counted was spent on all of them.
        let done = rows.saturating_sub(1);
        let taken = if result.is_err() && done + 1 < points.len() { done + 1 } else { done };
        let report = StatsReport {
            stats: sim.stats(),
            communication_steps: taken,
            failed: result.is_err(),
            start: settings.start,
            reached: sim.time(),
            initialization: initialized,
            total: started.elapsed(),
        };
        // Best effort, as the warnings: a closed stderr does not fail the run.
        let _ = report.write(&mut std::io::stderr().lock());
    }
    result.and(flushed)
}

/// What `simulate --stats` prints.
struct StatsReport {
    stats: Stats,
    /// Communication steps taken (the failed one included).
    communication_steps: usize,
    failed: bool,
    start: f64,
    reached: f64,
    /// Wall time to the start of integration (reading, checking, assembling the model).
    initialization: Duration,
    /// Wall time of the whole command.
    total: Duration,
}

impl StatsReport {
    /// One line per count: its label, the total, and the average per communication step.
    fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let s = &self.stats;
        let n = self.communication_steps;
        writeln!(
            w,
            "integrator statistics: {n} communication steps from t = {} to {}{}",
            self.start,
            self.reached,
            if self.failed { " (the last failed)" } else { "" }
        )?;
        writeln!(w, "  {:<22} {:>12}  {:>14}", "", "total", "per comm. step")?;
        let rows = [
            ("steps attempted", s.steps),
            ("accepted steps", s.accepted),
            ("rejected steps", s.rejected),
            ("Newton iterations", s.newton_iterations),
            ("Jacobian evaluations", s.jacobians),
            ("  exact ones", s.exact_jacobians),
            ("factorizations", s.factorizations),
            ("  by the general LU", s.general_factorizations),
            ("symbolic analyses", s.symbolic_analyses),
            ("rhs evaluations", s.rhs_evaluations),
        ];
        for (label, count) in rows {
            let per = if n > 0 { format!("{:.2}", count as f64 / n as f64) } else { "-".to_string() };
            writeln!(w, "  {:<22} {count:>12}  {per:>14}", format!("{label}:"))?;
        }
        let (init, total) = (self.initialization.as_secs_f64(), self.total.as_secs_f64());
        writeln!(
            w,
            "wall time: {total:.3} s (initialization {init:.3} s, integration and output {:.3} s)",
            total - init
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn communication_points_are_multiples_of_the_step_and_end_on_end() {
        let p = communication_points(0.0, 1.0, 0.1).unwrap();
        assert_eq!(p.len(), 11);
        assert_eq!(p[3], 3.0 * 0.1);
        assert_eq!(p[10], 1.0);
        let p = communication_points(0.5, 0.5, 0.1).unwrap();
        assert_eq!(p, vec![0.5]);
    }

    #[test]
    fn communication_points_round_a_non_dividing_step() {
        let p = communication_points(0.0, 1.0, 0.3).unwrap();
        assert_eq!(p.len(), 4);
        assert!((p[3] - 0.9).abs() < 1e-15);
    }

    #[test]
    fn too_many_communication_points_is_a_usage_error() {
        let e = communication_points(0.0, 1e12, 1e-3).unwrap_err();
        assert_eq!(e.exit_code(), 2);
    }

    #[test]
    fn csv_numbers_round_trip() {
        let mut buf = Vec::new();
        let x = 0.1 + 0.2;
        write_csv_row(&mut buf, 1.0 / 3.0, &[x, -1e-300]).unwrap();
        let line = String::from_utf8(buf).unwrap();
        let f: Vec<f64> = line.trim().split(',').map(|s| s.parse().unwrap()).collect();
        assert_eq!(f, vec![1.0 / 3.0, x, -1e-300]);
    }
}
