//! The mass matrix M(q) of the equations of motion (seed Eq. 13a, M u̇ = Q − Pᵀλ),
//! assembled in this one place. It is block-diagonal, one block per body over its
//! velocities: a rigid body's 6×6 block diag(m I, J) over [v; ω'] does not depend on q; a
//! flexible body's (6 + n_m)² block over [v; ω'; η̇] does, through its orientation and
//! modal coordinates ([`super::flexible`]).

use super::body::NQ;
use super::coords::gather;
use super::flexible;
use super::system::System;

/// Entries (row, column, value) of body `b`'s block of M at q, in global numbering, zeros
/// included (a stable pattern): for a rigid body m on the three translational diagonal
/// entries, then the 3×3 inertia tensor J (body axes, about the CM); for a flexible body
/// its whole block, column by column.
pub fn body_mass_entries(sys: &System, b: usize, q: &[f64]) -> Vec<(usize, usize, f64)> {
    if let Some(f) = sys.flex_of(b) {
        let dofs = sys.body_dofs(b);
        let qb = gather(sys, &[b], q);
        let mut out = Vec::with_capacity(dofs.len() * dofs.len());
        for (c, &gc) in dofs.iter().enumerate() {
            let e: Vec<f64> = (0..dofs.len()).map(|r| if r == c { 1.0 } else { 0.0 }).collect();
            let col = flexible::body_mass_times(&f.inv, &sys.r0[b], &qb, &e);
            out.extend(dofs.iter().zip(col).map(|(&gr, v)| (gr, gc, v)));
        }
        return out;
    }
    rigid_mass_entries(sys, b).collect()
}

/// The entries of [`body_mass_entries`] for rigid body `b`.
fn rigid_mass_entries(sys: &System, b: usize) -> impl Iterator<Item = (usize, usize, f64)> {
    let (o, body) = (NQ * b, &sys.bodies[b]);
    let (m, j) = (body.mass, body.inertia);
    let translation = (0..3).map(move |c| (o + c, o + c, m));
    let rotation = (0..9).map(move |k| (o + 3 + k / 3, o + 3 + k % 3, j[k / 3][k % 3]));
    translation.chain(rotation)
}

/// Whether body `b`'s block of M is independent of q (rigid bodies).
pub fn constant_mass(sys: &System, b: usize) -> bool {
    sys.flex_of(b).is_none()
}

/// M_b a for body `b` at q (a: the body's accelerations, in the order of
/// [`System::body_dofs`]: [v̇; ω̇'] then η̈).
pub fn body_mass_times(sys: &System, b: usize, q: &[f64], a: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    body_mass_times_into(sys, b, q, a, &mut out);
    out
}

/// [`body_mass_times`] into `out` (its capacity reused; a flexible body's allocates).
pub fn body_mass_times_into(sys: &System, b: usize, q: &[f64], a: &[f64], out: &mut Vec<f64>) {
    if let Some(f) = sys.flex_of(b) {
        *out = flexible::body_mass_times(&f.inv, &sys.r0[b], &gather(sys, &[b], q), a);
        return;
    }
    out.clear();
    out.resize(NQ, 0.0);
    for (r, c, v) in rigid_mass_entries(sys, b) {
        out[r - NQ * b] += v * a[c - NQ * b];
    }
}

/// Kinetic energy ½ uᵀ M u of body `b` at (q, u) (global vectors).
pub fn body_kinetic_energy(sys: &System, b: usize, q: &[f64], u: &[f64]) -> f64 {
    let ub = gather(sys, &[b], u);
    let mu = body_mass_times(sys, b, q, &ub);
    0.5 * ub.iter().zip(&mu).map(|(x, y)| x * y).sum::<f64>()
}
