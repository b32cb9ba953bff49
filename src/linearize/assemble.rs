//! The matrix of the augmented system (seed Eq. 34a–34k, Table 1) at an operating point,
//! one function per block of rows, pushed in this order. Rows and columns are placed
//! through [`Eq34`] only.

use super::eq34::{Eq34, Equation, Unknown};
use super::jets::jets;
use super::operating_point::OperatingPoint;
use crate::dae::equations::jacobian;
use crate::dae::layout::Slot;
use crate::dae::sparse::Triplets;
use crate::mechanics::System;
use crate::mechanics::coords::{global_column, nql};
use crate::mechanics::mass::{body_mass_entries, constant_mass};

/// The matrix of Eq. 34, with the values of the position and velocity states (S, then W)
/// that its rows 34f and 34h evaluate.
pub(super) struct Assembled {
    /// The matrix (rows: [`Equation`], columns: [`Unknown`]).
    pub k: Triplets,
    /// S, then W, at the operating point.
    pub values: Vec<f64>,
}

/// Assemble Eq. 34 at `p`.
pub(super) fn assemble(p: &OperatingPoint) -> Assembled {
    let mut k = Triplets::new();
    dae_rows(p, &mut k);
    for i in 0..p.eq.nx {
        k.push(p.eq.row_at(Equation::XBar, i), p.eq.at(Unknown::Z, i), 1.0); // X = X̄
    }
    for i in 0..p.eq.n {
        k.push(p.eq.row_at(Equation::Eq34b, i), p.eq.at(Unknown::QDot, i), 1.0); // q̇ of 34b
    }
    mass_rows(p, &mut k);
    acceleration_constraint_rows(p, &mut k);
    let values = state_rows(p, &mut k);
    Assembled { k, values }
}

/// The unknown of Eq. 34 that entry `i` of the DAE vector y is (μ is not one).
fn unknown_of(eq: &Eq34, slot: Slot) -> Option<usize> {
    Some(match slot {
        Slot::Q(i) => eq.at(Unknown::Q, i),
        Slot::U(i) => eq.at(Unknown::U, i),
        Slot::Z(i) => eq.at(Unknown::Z, i),
        Slot::Lambda(i) => eq.at(Unknown::Lambda, i),
        Slot::Nu(i) => eq.at(Unknown::Nu, i),
        Slot::Mu(_) => return None,
    })
}

/// The row of Eq. 34 that row `r` of the DAE's f becomes, and its sign there (Eq. 34a–b
/// are written −f): q̇ = H u → 34b, the force balance → 34a, the user rows → Eq. 7, C →
/// 34e, g and Ċ → 34d. None for X' = Ẋ (the rate of X is the unknown Ẋ itself) and for
/// redundant constraint rows (their λ = 0 is 34c).
pub(super) fn equation_of(p: &OperatingPoint, r: usize) -> Option<(usize, f64)> {
    let (eq, nx) = (&p.eq, p.lay.nx);
    let independent = |i: usize| p.rows.of_row[i];
    Some(match p.lay.slot(r) {
        Slot::Q(i) => (eq.row_at(Equation::Eq34b, i), -1.0),
        Slot::U(i) => (eq.row_at(Equation::Eq34a, i), -1.0),
        Slot::Z(i) if i < nx => return None,
        Slot::Z(i) => (eq.row_at(Equation::Eq7, i - nx), 1.0),
        Slot::Lambda(i) => (eq.row_at(Equation::Eq34e, independent(i)?), 1.0),
        // 34d holds Ċ of the independent rows, then g.
        Slot::Nu(i) => (eq.row_at(Equation::Eq34d, eq.mr + i), 1.0),
        Slot::Mu(i) => (eq.row_at(Equation::Eq34d, independent(i)?), 1.0),
    })
}

/// Eq. 34a, 34b, 34d, 34e and the user rows (Eq. 7a–7b), from the integrator's exact
/// Jacobian of f = [H u; Q − Pᵀλ − Bᵀν; X' = Ẋ, r; C; g; Ċ] at μ = 0.
fn dae_rows(p: &OperatingPoint, k: &mut Triplets) {
    let (lay, xl) = (p.lay, p.sys.ext_layout());
    let y = lay.assemble(&p.q, &p.u, &p.ext[xl.z_range()], &p.lam);
    let mut jac = Triplets::new();
    jacobian(p.sys, lay, p.t, &y, &p.ext[..p.ni()], &mut jac);
    for (at, &v) in jac.idx.iter().zip(&jac.vals) {
        let Some(col) = unknown_of(&p.eq, lay.slot(at.col)) else { continue };
        if let Some((row, sign)) = equation_of(p, at.row) {
            k.push(row, col, sign * v);
        }
    }
}

/// M u̇ of Eq. 34a (u̇ = a for a body with acceleration unknowns, whose force balance is
/// a user row). M is taken as it is at q: a mass matrix that depends on q would add
/// ∂(M u̇)/∂q to the q columns.
fn mass_rows(p: &OperatingPoint, k: &mut Triplets) {
    let (sys, eq) = (p.sys, &p.eq);
    for b in 0..sys.nb() {
        if sys.acc_bodies.contains(&b) {
            for g in sys.body_dofs(b) {
                k.push(eq.row_at(Equation::Eq34a, g), eq.at(Unknown::UDot, g), 1.0);
            }
            continue;
        }
        debug_assert!(constant_mass(sys, b), "Eq. 34a lacks ∂(M u̇)/∂q");
        for (r, c, v) in body_mass_entries(sys, b, &p.q) {
            k.push(eq.row_at(Equation::Eq34a, r), eq.at(Unknown::UDot, c), v);
        }
    }
}

/// Which derivatives a row's local gradient holds: over (q, u), or over (q, u, u̇).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Through {
    Velocities,
    Accelerations,
}

/// Push `sign` · a local gradient `dz` over (q, u[, u̇]) of `bodies` (6 entries per body
/// and level) into `row`.
#[allow(clippy::too_many_arguments)]
fn push_gradient(
    sys: &System,
    eq: &Eq34,
    k: &mut Triplets,
    row: usize,
    bodies: &[usize],
    dz: &[f64],
    sign: f64,
    to: Through,
) {
    let nql = nql(sys, bodies);
    for a in 0..nql {
        let g = global_column(sys, bodies, a);
        k.push(row, eq.at(Unknown::Q, g), sign * dz[a]);
        k.push(row, eq.at(Unknown::U, g), sign * dz[nql + a]);
        if to == Through::Accelerations {
            k.push(row, eq.at(Unknown::UDot, g), sign * dz[2 * nql + a]);
        }
    }
}

/// Eq. 34c: C̈(u̇, u, q, t) = 0 (λ = 0 on a redundant row) and ġ(u̇, u, q, t) = 0, exact
/// gradients from the time jets.
fn acceleration_constraint_rows(p: &OperatingPoint, k: &mut Triplets) {
    let (sys, eq) = (p.sys, &p.eq);
    for el in &sys.constraints {
        for (e, jet) in jets(sys, el, &p.q, &p.u, &p.udot, p.t, &p.ext).iter().enumerate() {
            let row = eq.row_at(Equation::Eq34c, el.row + e);
            if sys.redundant[el.row + e] {
                k.push(row, eq.at(Unknown::Lambda, el.row + e), 1.0);
            } else {
                push_gradient(sys, eq, k, row, &el.bodies, &jet.dg2, 1.0, Through::Accelerations);
            }
        }
    }
    for el in &sys.nonholonomic {
        for (e, jet) in jets(sys, el, &p.q, &p.u, &p.udot, p.t, &p.ext).iter().enumerate() {
            let row = eq.row_at(Equation::Eq34c, eq.m + el.row + e);
            push_gradient(sys, eq, k, row, &el.bodies, &jet.dg1, 1.0, Through::Accelerations);
        }
    }
}

/// Eq. 34f, 34g, 34k for each position state S; 34h, 34i, 34j for each velocity state W.
/// Returns the values of S, then W.
fn state_rows(p: &OperatingPoint, k: &mut Triplets) -> Vec<f64> {
    use Equation::*;
    let (sys, eq) = (p.sys, &p.eq);
    let mut values = Vec::with_capacity(eq.s0 + eq.s1);
    for (i, st) in p.sel.states.iter().enumerate() {
        let jet = &jets(sys, st, &p.q, &p.u, &p.udot, p.t, &p.ext)[0];
        values.push(jet.g);
        k.push(eq.row_at(Eq34f, i), eq.at(Unknown::S, i), 1.0);
        push_gradient(sys, eq, k, eq.row_at(Eq34f, i), &st.bodies, &jet.dg, -1.0, Through::Velocities);
        k.push(eq.row_at(Eq34g, i), eq.at(Unknown::SDot, i), 1.0);
        push_gradient(sys, eq, k, eq.row_at(Eq34g, i), &st.bodies, &jet.dg1, -1.0, Through::Velocities);
        k.push(eq.row_at(Eq34k, i), eq.at(Unknown::S, i), 1.0);
    }
    for (i, ws) in p.sel.velocities.iter().enumerate() {
        let jet = ws.jet(sys, &p.q, &p.u, &p.udot, p.t, &p.ext);
        values.push(jet.w);
        k.push(eq.row_at(Eq34h, i), eq.at(Unknown::W, i), 1.0);
        push_gradient(sys, eq, k, eq.row_at(Eq34h, i), ws.bodies(), &jet.dw, -1.0, Through::Velocities);
        k.push(eq.row_at(Eq34i, i), eq.at(Unknown::WDot, i), 1.0);
        push_gradient(sys, eq, k, eq.row_at(Eq34i, i), ws.bodies(), &jet.dwd, -1.0, Through::Accelerations);
        k.push(eq.row_at(Eq34j, i), eq.at(Unknown::W, i), 1.0);
    }
    values
}
