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
fn singular(p: &OperatingPoint) -> EngineError {
    let names: Vec<String> =
        p.sel.states.iter().map(|s| s.name.clone()).chain(p.sel.velocities.iter().map(|w| w.name())).collect();
    EngineError::Numeric(format!(
        "at t = {}: the linearization states ({}) no longer parameterize the motion (singular partition); \
         choose user states (<linearization>) that stay independent",
        p.t,
        names.join(", ")
    ))
}

/// Linearize the simulation at its current point in the states of `sel` (Eq. 34, 36).
pub fn linearize(sim: &mut Simulator, sel: &Selection, threads: usize) -> Result<Linearization, EngineError> {
    let (udot, lam) = sim.accelerations()?;
    let (t, ext) = (sim.time(), sim.ext_with(&lam));
    let (q, u) = (sim.q().to_vec(), sim.u().to_vec());
    let sys = sim.system();
    let rows = IndependentRows::of(sys);
    let lay = Layout::of(sys);
    let eq = eq34_layout(sys, lay, sel, &rows)?;
    check_partition(sys, sel, &q, t, &ext)?;
    let p = OperatingPoint { sys, sel, eq, lay, rows, q, u, udot, lam, t, ext };
    let Assembled { k, values } = assemble(&p);
    let rhs = RightHandSides::of(&p);
    let sens = Sensitivities::of(&p);
    let mut lu = SparseLu::new();
    lu.factor(eq.dim(), &k).map_err(|_| singular(&p))?;
    let fill = |col: usize, b: &mut [f64]| rhs.fill(rhs.column(col), b);
    let take = |col: usize, x: &[f64]| sens.keep(rhs.column(col), x);
    let sol = lu.solve_columns(eq.ns() + p.ni(), threads, fill, take).ok_or_else(|| singular(&p))?;
    extract(&p, &sens, &sol, values)
}
