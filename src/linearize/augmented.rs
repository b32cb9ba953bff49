//! The augmented sensitivity system (seed Eq. 34a–34k, Table 1) at one operating point:
//! the unknowns (u̇, q̇, Ẇ, Ṡ, λ, u, q, W, S) differentiated with respect to the virtual
//! states (S̄, W̄) and the inputs v. One sparse matrix ([`super::assemble`]), one sparse
//! LU, the right-hand sides ([`super::rhs`]) solved in blocks split over threads, keeping
//! of each solution only what A, B, C, D need ([`super::sensitivity`]), which are then
//! read off (Eq. 36, [`super::extract`]). Nothing is reduced to the state-space ODE
//! (Eq. 6).

use super::assemble::{Assembled, assemble};
use super::eq34::Eq34;
use super::extract::extract;
use super::linearization::Linearization;
use super::operating_point::OperatingPoint;
use super::partition::check_partition;
use super::rhs::RightHandSides;
use super::select::Selection;
use super::sensitivity::Sensitivities;
use crate::dae::equations::Layout;
use crate::dae::sparse::SparseLu;
use crate::dae::{EngineError, Simulator};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::IndependentRows;

/// The layout of Eq. 34 for `sel` on `sys`, if its states complete the independent
/// constraints to the coordinates (s0 + mr = n, s1 + mn = s0).
fn eq34_layout(sys: &System, lay: Layout, sel: &Selection, rows: &IndependentRows) -> Result<Eq34, EngineError> {
    let (n, mr, mn) = (sys.n(), rows.count, sys.mn);
    let (s0, s1) = (sel.states.len(), sel.velocities.len());
    let eq = Eq34 { n, m: sys.m, mr, mn, s0, s1, nx: lay.nx, nz: lay.nz() };
    if !eq.is_square() {
        return Err(EngineError::Numeric(format!(
            "{s0} position and {s1} velocity states do not complete {mr} independent constraints and {mn} \
             non-holonomic ones to {n} coordinates"
        )));
    }
    Ok(eq)
}

/// The error of a singular Eq. 34: the states no longer parameterize the motion.
pub(super) fn singular(p: &OperatingPoint) -> EngineError {
    let names: Vec<String> =
        p.sel.states.iter().map(|s| s.name.clone()).chain(p.sel.velocities.iter().map(|w| w.name())).collect();
    EngineError::Numeric(format!(
        "at t = {}: the linearization states ({}) no longer parameterize the motion (singular partition); \
         choose user states (<linearization>) that stay independent",
        p.t,
        names.join(", ")
    ))
}

/// How the factored Eq. 34 yields A, B, C, D.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// Whichever of the two needs fewer solves (the default).
    Auto,
    /// One solve per column of [A B; C D] (per state and per input): K x = R_c.
    Columns,
    /// One solve of the transposed system Kᵀ z = g per row of [A B; C D] that is not
    /// exact (Ẇ, Ẋ, an Ṡ without its W; an output once for the state columns and once
    /// for the input columns): the row is then zᵀ R_c for every column c at once.
    Rows,
}

/// Linearize the simulation at its current point in the states of `sel` (Eq. 34, 36).
pub fn linearize(sim: &mut Simulator, sel: &Selection, threads: usize) -> Result<Linearization, EngineError> {
    linearize_with(sim, sel, threads, Route::Auto)
}

/// [`linearize`] by the given route (both give the same matrices to round-off).
pub fn linearize_with(
    sim: &mut Simulator,
    sel: &Selection,
    threads: usize,
    route: Route,
) -> Result<Linearization, EngineError> {
    at_point(sim, sel, |p| factored(p, threads, route))
}

/// Run `f` on the operating point of `sim`'s current state in the states of `sel`, once
/// they are known to partition the coordinates there.
pub(super) fn at_point<R>(
    sim: &mut Simulator,
    sel: &Selection,
    f: impl FnOnce(&OperatingPoint) -> Result<R, EngineError>,
) -> Result<R, EngineError> {
    let (udot, lam) = sim.accelerations()?;
    let (t, ext) = (sim.time(), sim.ext_with(&lam));
    let (q, u) = (sim.q().to_vec(), sim.u().to_vec());
    let sys = sim.system();
    let rows = IndependentRows::of(sys);
    let lay = Layout::of(sys);
    let eq = eq34_layout(sys, lay, sel, &rows)?;
    check_partition(sys, sel, &q, t, &ext)?;
    f(&OperatingPoint { sys, sel, eq, lay, rows, q, u, udot, lam, t, ext })
}

/// Eq. 34 at `p`, factored and solved by `route`.
fn factored(p: &OperatingPoint, threads: usize, route: Route) -> Result<Linearization, EngineError> {
    let eq = p.eq;
    let Assembled { k, values } = assemble(p);
    let rhs = RightHandSides::of(p);
    let sens = Sensitivities::of(p);
    let mut lu = SparseLu::new();
    lu.factor(eq.dim(), &k).map_err(|_| singular(p))?;
    let ncols = eq.ns() + p.ni();
    let jobs = row_jobs(p, &sens);
    let by_rows = match route {
        Route::Auto => jobs.len() < ncols,
        Route::Columns => false,
        Route::Rows => true,
    };
    let sol = if by_rows {
        solve_by_rows(p, &lu, &rhs, &sens, &jobs, threads)
    } else {
        let fill = |col: usize, b: &mut [f64]| rhs.fill(rhs.column(col), b);
        let take = |col: usize, x: &[f64]| sens.keep(rhs.column(col), x);
        lu.solve_columns(ncols, threads, false, fill, take)
    };
    let solves = if by_rows { jobs.len() } else { ncols };
    extract(p, &sens, &sol.ok_or_else(|| singular(p))?, values, solves)
}

/// A row of [A B; C D] to solve for by the transposed system: kept row `r`
/// ([`Sensitivities::keep`]'s order) for the state columns, the input columns, or both.
#[derive(Clone, Copy, Debug)]
struct RowJob {
    r: usize,
    states: bool,
    inputs: bool,
    /// Whether the row's functional has finite weights (else the row is NaN, unsolved).
    finite: bool,
}

/// The rows the transposed route solves for: every kept row but the Ṡ rows that
/// `extract` sets exactly (Ṡ = W); an output's functional differs between state and
/// input columns, so each kind with columns is a job of its own.
fn row_jobs(p: &OperatingPoint, sens: &Sensitivities) -> Vec<RowJob> {
    let (s0, ns, ni) = (p.eq.s0, p.eq.ns(), p.ni());
    let mut jobs: Vec<RowJob> = (0..ns)
        .filter(|&r| r >= s0 || p.sel.velocity_of_state(r).is_none())
        .map(|r| RowJob { r, states: true, inputs: true, finite: true })
        .collect();
    for o in 0..sens.outputs() {
        for (states, wanted) in [(true, ns > 0), (false, ni > 0)] {
            if wanted {
                let finite = sens.row_finite(ns + o, states);
                jobs.push(RowJob { r: ns + o, states, inputs: !states, finite });
            }
        }
    }
    jobs
}

/// The kept values of every column (as the column route's `take` returns them), from one
/// transposed solve per job; rows without a job stay 0 (`extract` sets them), a row
/// whose functional is not finite is NaN.
fn solve_by_rows(
    p: &OperatingPoint,
    lu: &SparseLu,
    rhs: &RightHandSides,
    sens: &Sensitivities,
    jobs: &[RowJob],
    threads: usize,
) -> Option<Vec<Vec<f64>>> {
    let (ns, ncols) = (p.eq.ns(), p.eq.ns() + p.ni());
    let columns = |job: RowJob| (0..ncols).filter(move |&c| if c < ns { job.states } else { job.inputs });
    let fill = |j: usize, g: &mut [f64]| {
        let job = &jobs[j];
        if job.finite {
            sens.functional(job.r, job.states, g);
        }
    };
    let take = |j: usize, z: &[f64]| -> Vec<f64> {
        let job = jobs[j];
        columns(job).map(|c| if job.finite { rhs.apply(rhs.column(c), z) } else { f64::NAN }).collect()
    };
    let rows = lu.solve_columns(jobs.len(), threads, true, fill, take)?;
    let mut sol = vec![vec![0.0; ns + sens.outputs()]; ncols];
    for (job, row) in jobs.iter().zip(&rows) {
        for (c, v) in columns(*job).zip(row) {
            sol[c][job.r] = *v;
        }
    }
    Some(sol)
}
