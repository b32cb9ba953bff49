//! Inertia invariants of a modal flexible body: the sums over its nodes that the floating
//! frame of reference equations need, computed once per body so that evaluating the mass
//! matrix and the quadratic-velocity terms costs O(n_m²), whatever the number of nodes.
//!
//! Node i sits at p_i(η) = s_i + Φt_i η in the body frame, with lumped mass m_i and rotary
//! inertia J_i (diagonal, body axes) and small rotation Φr_i η. With φ_ik the translational
//! shape of mode k at node i (column k of Φt_i) and ρ_ik its rotational shape:
//!
//! | Invariant | Definition |
//! |---|---|
//! | `mass` | Σ m_i |
//! | `s0` | Σ m_i s_i |
//! | `psi[k]` | Σ m_i φ_ik |
//! | `p0` | Σ m_i s_i s_iᵀ |
//! | `p1[k]` | Σ m_i s_i φ_ikᵀ |
//! | `p2[k·n_m + l]` | Σ m_i φ_ik φ_ilᵀ |
//! | `j0` | Σ J_i |
//! | `jphi[k]` | Σ J_i ρ_ik |
//! | `modal_mass[k·n_m + l]` | Σ m_i φ_ik·φ_il + ρ_ikᵀ J_i ρ_il (ΦᵀMΦ) |
//!
//! `p2` is the only invariant of size n_m²·9; everything else is linear in n_m.

// Index loops here mirror the subscripts of the formulas they compute.
#![allow(clippy::needless_range_loop)]

use super::data::ModalData;

/// A 3×3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// The inertia invariants of one flexible body (see the module documentation), with its
/// modal stiffness and damping matrices (row-major, n_m × n_m).
#[derive(Clone, Debug, PartialEq)]
pub struct Invariants {
    /// Number of modes n_m.
    pub nm: usize,
    /// Total mass Σ m_i.
    pub mass: f64,
    /// First moment of the undeformed body Σ m_i s_i.
    pub s0: [f64; 3],
    /// Σ m_i φ_ik, per mode.
    pub psi: Vec<[f64; 3]>,
    /// Σ m_i s_i s_iᵀ.
    pub p0: Mat3,
    /// Σ m_i s_i φ_ikᵀ, per mode.
    pub p1: Vec<Mat3>,
    /// Σ m_i φ_ik φ_ilᵀ at `k * nm + l`.
    pub p2: Vec<Mat3>,
    /// Σ J_i (diagonal rotary inertias, summed).
    pub j0: Mat3,
    /// Σ J_i ρ_ik, per mode.
    pub jphi: Vec<[f64; 3]>,
    /// The modal mass ΦᵀMΦ.
    pub modal_mass: Vec<f64>,
    /// Modal stiffness K.
    pub stiffness: Vec<f64>,
    /// Modal damping C.
    pub damping: Vec<f64>,
}

impl Invariants {
    /// The invariants of `data` (one pass over nodes and mode pairs).
    pub fn of(data: &ModalData) -> Invariants {
        let nm = data.modes.len();
        let mut inv = Invariants {
            nm,
            mass: 0.0,
            s0: [0.0; 3],
            psi: vec![[0.0; 3]; nm],
            p0: [[0.0; 3]; 3],
            p1: vec![[[0.0; 3]; 3]; nm],
            p2: vec![[[0.0; 3]; 3]; nm * nm],
            j0: [[0.0; 3]; 3],
            jphi: vec![[0.0; 3]; nm],
            modal_mass: vec![0.0; nm * nm],
            stiffness: data.stiffness_matrix().concat(),
            damping: data.damping_matrix().concat(),
        };
        for (i, node) in data.nodes.iter().enumerate() {
            let (m, s, j) = (node.mass, node.position, node.inertia);
            let phi = |k: usize| -> [f64; 3] { std::array::from_fn(|a| data.modes[k][i][a]) };
            let rho = |k: usize| -> [f64; 3] { std::array::from_fn(|a| data.modes[k][i][3 + a]) };
            inv.mass += m;
            for a in 0..3 {
                inv.s0[a] += m * s[a];
                inv.j0[a][a] += j[a];
                for b in 0..3 {
                    inv.p0[a][b] += m * s[a] * s[b];
                }
            }
            for k in 0..nm {
                let (fk, rk) = (phi(k), rho(k));
                for a in 0..3 {
                    inv.psi[k][a] += m * fk[a];
                    inv.jphi[k][a] += j[a] * rk[a];
                    for b in 0..3 {
                        inv.p1[k][a][b] += m * s[a] * fk[b];
                    }
                }
                for l in 0..nm {
                    let (fl, rl) = (phi(l), rho(l));
                    let p2 = &mut inv.p2[k * nm + l];
                    for a in 0..3 {
                        for b in 0..3 {
                            p2[a][b] += m * fk[a] * fl[b];
                        }
                    }
                    inv.modal_mass[k * nm + l] += (0..3).map(|a| m * fk[a] * fl[a] + j[a] * rk[a] * rl[a]).sum::<f64>();
                }
            }
        }
        inv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modal::data::{ModalDamping, ModalStiffness, Node};

    /// The modal mass from the invariants equals `ModalData::modal_mass` (a separate sum).
    #[test]
    fn modal_mass_matches_the_data_and_sums_are_exact_for_a_two_node_body() {
        let data = ModalData {
            description: None,
            nodes: vec![
                Node { id: 1, position: [0.0, 0.0, 0.0], mass: 2.0, inertia: [0.5, 0.25, 0.0] },
                Node { id: 2, position: [1.0, 0.5, 0.0], mass: 4.0, inertia: [0.5, 0.0, 0.125] },
            ],
            modes: vec![
                vec![[0.5, 0.0, 0.25, 1.0, 0.0, 0.0], [-0.5, 0.0, 0.0, 0.0, 0.0, 2.0]],
                vec![[0.0, 1.0, 0.0, 0.0, 0.5, 0.0], [0.0, -0.25, 0.0, -1.0, 0.0, 0.0]],
            ],
            stiffness: ModalStiffness::Matrix(vec![vec![3.0, 1.0], vec![1.0, 2.0]]),
            damping: ModalDamping::None,
        };
        let inv = Invariants::of(&data);
        assert_eq!(inv.modal_mass, data.modal_mass().concat());
        assert_eq!(inv.mass, 6.0);
        assert_eq!(inv.s0, [4.0, 2.0, 0.0]);
        assert_eq!(inv.psi, vec![[-1.0, 0.0, 0.5], [0.0, 1.0, 0.0]]);
        // p1[0][1][0] = Σ m s_y φ_x = 4 · 0.5 · (−0.5); p2[1][1][1] = 2·1 + 4·(1/16).
        assert_eq!((inv.p1[0][1][0], inv.p2[3][1][1]), (-1.0, 2.25));
        assert_eq!((inv.jphi[0], inv.jphi[1]), ([0.5, 0.0, 0.25], [-0.5, 0.125, 0.0]));
        assert_eq!(inv.stiffness, vec![3.0, 1.0, 1.0, 2.0]);
    }
}
