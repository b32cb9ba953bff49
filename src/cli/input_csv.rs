//! `--input file.csv` of `simulate` and `linearize`: a header `time,<input>,...` and one
//! row per time; each input is linear between rows, constant before the first and after
//! the last, and jumps where a time repeats (the later row holds from then on) — as
//! fmpy's input arrays. Inputs without a column keep their start values.
//!
//! The engine follows it exactly: at every row time it gets the input values and the
//! slopes of the segment ahead (value and derivative, as `fmi2SetRealInputDerivatives`).

use std::path::Path;

use super::CliError;
use crate::dae::Simulator;
use crate::model::Model;

/// A parsed input table.
#[derive(Clone, Debug, PartialEq)]
pub struct InputTable {
    /// Row times, non-decreasing.
    pub times: Vec<f64>,
    /// (model input index, one value per row).
    pub columns: Vec<(usize, Vec<f64>)>,
}

impl InputTable {
    /// Read `path` against the inputs of `model`; errors name `file:line`.
    pub fn read(path: &Path, model: &Model) -> Result<InputTable, CliError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::Usage(format!("--input {}: cannot be read: {e}", path.display())))?;
        Self::parse(&text, &path.display().to_string(), model)
    }

    /// Parse CSV `text` (named `file` in messages).
    pub fn parse(text: &str, file: &str, model: &Model) -> Result<InputTable, CliError> {
        let err = |line: usize, what: String| CliError::Usage(format!("{file}:{line}: {what}"));
        let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
        let Some((h, header)) = lines.next() else { return Err(err(1, "empty input file".into())) };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        if names.first() != Some(&"time") {
            return Err(err(h + 1, format!("the first column must be 'time', got '{}'", names[0])));
        }
        let known: Vec<&str> = model.inputs.iter().map(|i| i.name.as_str()).collect();
        let mut columns = Vec::new();
        for (c, name) in names.iter().enumerate().skip(1) {
            let Some(k) = known.iter().position(|n| n == name) else {
                return Err(err(
                    h + 1,
                    format!(
                        "column {} '{name}' is not an input of model '{}' (inputs: {})",
                        c + 1,
                        model.name,
                        known.join(", ")
                    ),
                ));
            };
            if columns.iter().any(|(j, _)| *j == k) {
                return Err(err(h + 1, format!("input '{name}' has two columns")));
            }
            columns.push((k, Vec::new()));
        }
        let mut times = Vec::new();
        for (i, line) in lines {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                return Err(err(i + 1, format!("{} values, the header has {}", cells.len(), names.len())));
            }
            let mut row = Vec::with_capacity(cells.len());
            for (c, cell) in cells.iter().enumerate() {
                let v: f64 = cell.parse().ok().filter(|v: &f64| v.is_finite()).ok_or_else(|| {
                    err(i + 1, format!("column {} '{}': '{cell}' is not a finite number", c + 1, names[c]))
                })?;
                row.push(v);
            }
            if let Some(&last) = times.last()
                && row[0] < last
            {
                return Err(err(i + 1, format!("time {} is before the previous row's {last}", row[0])));
            }
            times.push(row[0]);
            for ((_, col), v) in columns.iter_mut().zip(&row[1..]) {
                col.push(*v);
            }
        }
        if times.is_empty() {
            return Err(err(h + 1, "no rows after the header".into()));
        }
        Ok(InputTable { times, columns })
    }

    /// The segment that holds just after `t`: (row index, slope to the next row).
    fn segment(&self, col: &[f64], t: f64) -> (usize, f64) {
        // Last row with time <= t (the later of repeated times).
        let k = self.times.partition_point(|&x| x <= t);
        if k == 0 {
            return (0, 0.0);
        }
        let k = k - 1;
        match self.times.get(k + 1) {
            Some(&t1) if t1 > self.times[k] => (k, (col[k + 1] - col[k]) / (t1 - self.times[k])),
            _ => (k, 0.0),
        }
    }

    /// Value and slope of every column just after `t`: (input index, value, slope).
    pub fn at(&self, t: f64) -> Vec<(usize, f64, f64)> {
        self.columns
            .iter()
            .map(|(i, col)| {
                if t < self.times[0] {
                    return (*i, col[0], 0.0);
                }
                let (k, s) = self.segment(col, t);
                (*i, col[k] + s * (t - self.times[k]), s)
            })
            .collect()
    }

    /// Put the values at `t0` into the model's input start values (before the engine is
    /// built, so initialization and static equilibrium see them).
    pub fn set_start(&self, model: &mut Model, t0: f64) {
        for (i, v, _) in self.at(t0) {
            model.inputs[i].start.value = v;
        }
    }

    /// Give the engine the values and slopes that hold just after its current time.
    pub fn apply(&self, sim: &mut Simulator) -> Result<(), CliError> {
        for (i, v, s) in self.at(sim.time()) {
            sim.set_input(i, v);
            sim.set_input_derivative(i, s);
        }
        sim.resolve_user_unknowns()?;
        Ok(())
    }
}

/// Advance `sim` to `t`, stopping at every row time of `table` on the way to give the
/// engine the next segment.
pub fn advance(sim: &mut Simulator, table: Option<&InputTable>, t: f64) -> Result<(), CliError> {
    if let Some(table) = table {
        let now = sim.time();
        let mut stops: Vec<f64> = table.times.iter().copied().filter(|&x| x > now && x <= t).collect();
        stops.dedup();
        for s in stops {
            sim.advance(s)?;
            table.apply(sim)?;
        }
    }
    if sim.time() < t {
        sim.advance(t)?;
    }
    Ok(())
}
