//! The mass matrix M(q) of the equations of motion (seed Eq. 13a, M u̇ = Q − Pᵀλ),
//! assembled in this one place. It is block-diagonal, one 6×6 block per body over
//! u_b = [v; ω']: a rigid body's block diag(m I, J) does not depend on q; the functions
//! still take q, so that a body whose block does (a flexible body's, through its modal
//! coordinates) fits the same calls.

use super::body::NQ;
use super::system::System;

/// Entries (row, column, value) of body `b`'s block of M at q, in global numbering, zeros
/// of the inertia tensor included (a stable pattern): m on the three translational
/// diagonal entries, then the 3×3 inertia tensor J (body axes, about the CM).
pub fn body_mass_entries(sys: &System, b: usize, _q: &[f64]) -> impl Iterator<Item = (usize, usize, f64)> {
    let (o, body) = (NQ * b, &sys.bodies[b]);
    let (m, j) = (body.mass, body.inertia);
    let translation = (0..3).map(move |c| (o + c, o + c, m));
    let rotation = (0..9).map(move |k| (o + 3 + k / 3, o + 3 + k % 3, j[k / 3][k % 3]));
    translation.chain(rotation)
}

/// Whether body `b`'s block of M is independent of q (true for rigid bodies).
pub fn constant_mass(_sys: &System, _b: usize) -> bool {
    true
}

/// M_b a for body `b` at q (a: the six accelerations [v̇; ω̇'] of the body).
pub fn body_mass_times(sys: &System, b: usize, q: &[f64], a: &[f64]) -> [f64; NQ] {
    let mut out = [0.0; NQ];
    for (r, c, v) in body_mass_entries(sys, b, q) {
        out[r - NQ * b] += v * a[c - NQ * b];
    }
    out
}

/// Kinetic energy ½ uᵀ M u of body `b` at (q, u) (global vectors).
pub fn body_kinetic_energy(sys: &System, b: usize, q: &[f64], u: &[f64]) -> f64 {
    let ub = &u[NQ * b..NQ * b + NQ];
    let mu = body_mass_times(sys, b, q, ub);
    0.5 * ub.iter().zip(&mu).map(|(x, y)| x * y).sum::<f64>()
}
