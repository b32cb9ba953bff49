//! The equations of motion as the integrator sees them, M y' = f(t, y), with
//! y = [q; u; Z; λ; ν; μ] ([`Layout`]) and
//!   q̇ = H(q)u − C_qᵀμ            (Eq. 13b, with the GGL stabilizing term; μ = 0 exactly)
//!   M u̇ = Q(u, q, Z, v, t) − Pᵀλ − Bᵀν (Eq. 13a, P = C_q H)
//!   X' = Ẋ, 0 = r(q, u, Z, v, t)  (user rows, Eq. 7a–7b; Z = (X, Ẋ, V, a))
//!   0 = C(q, t)                   (Eq. 13e)
//!   0 = g(q, u, t) = B u + b      (non-holonomic, multipliers ν)
//!   0 = C_q H u + C_t             (Eq. 13d)
//! f is [`rhs`] ([`super::residual`]), its exact sparse Jacobian [`jacobian`]
//! ([`super::jacobian`]), M is [`mass_matrix`] (here). The constraint rows come from
//! [`crate::mechanics::constraint_jacobian`], M's blocks from [`crate::mechanics::mass`].

pub use super::jacobian::{JacScratch, jacobian, jacobian_with};
pub use super::layout::Layout;
pub use super::residual::{RhsScratch, rhs};
use super::sparse::Triplets;
use crate::mechanics::System;
use crate::mechanics::mass::{body_mass_entries, constant_mass};

/// The integrator's mass matrix diag(I, M, [I 0 0], 0, 0) of M y' = f; constant: it
/// holds the blocks of bodies whose mass does not depend on q (every rigid body), and
/// u' = a for a body with acceleration unknowns, whose M a enters f instead.
pub fn mass_matrix(sys: &System, lay: Layout, m: &mut Triplets) {
    for i in lay.q_range().chain(lay.x_range()) {
        m.push(i, i, 1.0);
    }
    for b in 0..sys.nb() {
        if sys.acc_bodies.contains(&b) {
            for g in sys.body_dofs(b) {
                m.push(lay.u() + g, lay.u() + g, 1.0); // u' = a
            }
            continue;
        }
        assert!(constant_mass(sys, b), "a body whose mass matrix depends on q must have acceleration unknowns");
        for (r, c, v) in body_mass_entries(sys, b, &sys.q_init) {
            m.push(lay.u() + r, lay.u() + c, v);
        }
    }
}
