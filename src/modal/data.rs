//! The modal data of one flexible body (floating frame of reference): its nodes with their
//! lumped masses and rotary inertias, its mode shapes at those nodes, and its modal
//! stiffness and damping.
//!
//! With the lumped mass matrix M = diag(m_i, m_i, m_i, Ixx_i, Iyy_i, Izz_i) over the nodes
//! and the shape matrix Φ (one column per mode, six rows per node), the modal mass is
//! ΦᵀMΦ ([`ModalData::modal_mass`]). Modes given with frequencies f_k are mass-normalized
//! (ΦᵀMΦ = I) and their modal stiffness is K = diag((2π f_k)²); otherwise the file gives K.
//! Damping ratios ζ_k give the modal damping C = diag(2 ζ_k ω_k); otherwise the file may
//! give C.

/// A node of a flexible body: where it sits in the body frame and its lumped mass.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Node id, unique within the body (what markers and interfaces name).
    pub id: u32,
    /// Position in the body frame (m).
    pub position: [f64; 3],
    /// Lumped mass (kg), > 0.
    pub mass: f64,
    /// Rotary inertia about the node in body axes [Ixx, Iyy, Izz] (kg m²), each ≥ 0.
    pub inertia: [f64; 3],
}

/// The modal stiffness of a body.
#[derive(Clone, Debug, PartialEq)]
pub enum ModalStiffness {
    /// Natural frequency f_k (Hz) of each mode, modes mass-normalized with respect to the
    /// lumped mass matrix: K = diag((2π f_k)²).
    Frequencies(Vec<f64>),
    /// The full symmetric, positive semidefinite n_m × n_m stiffness matrix (row-major).
    Matrix(Vec<Vec<f64>>),
}

/// The modal damping of a body.
#[derive(Clone, Debug, PartialEq)]
pub enum ModalDamping {
    /// Undamped.
    None,
    /// Damping ratio ζ_k ≥ 0 of each mode (needs [`ModalStiffness::Frequencies`]):
    /// C = diag(2 ζ_k ω_k).
    Ratios(Vec<f64>),
    /// The full symmetric, positive semidefinite n_m × n_m damping matrix (row-major).
    Matrix(Vec<Vec<f64>>),
}

/// The modal data of one flexible body, as a modal data file holds it (see
/// MODEL_FORMAT.md, "Modal data files"). Values read by [`super::read`] are validated.
#[derive(Clone, Debug, PartialEq)]
pub struct ModalData {
    /// Free text saying where the data come from.
    pub description: Option<String>,
    /// The nodes, in file order.
    pub nodes: Vec<Node>,
    /// The mode shapes: `modes[k][i]` = [dx, dy, dz, rx, ry, rz] of mode k at node i (body
    /// axes; translations in m, rotations in rad, per unit modal coordinate).
    pub modes: Vec<Vec<[f64; 6]>>,
    /// Modal stiffness.
    pub stiffness: ModalStiffness,
    /// Modal damping.
    pub damping: ModalDamping,
}

impl ModalData {
    /// The lumped mass matrix's diagonal entry of each node's six degrees of freedom:
    /// [m, m, m, Ixx, Iyy, Izz].
    pub fn node_mass_diagonal(node: &Node) -> [f64; 6] {
        let [ixx, iyy, izz] = node.inertia;
        [node.mass, node.mass, node.mass, ixx, iyy, izz]
    }

    /// The modal mass ΦᵀMΦ (n_m × n_m) with respect to the lumped mass matrix.
    pub fn modal_mass(&self) -> Vec<Vec<f64>> {
        let diag: Vec<[f64; 6]> = self.nodes.iter().map(Self::node_mass_diagonal).collect();
        let n = self.modes.len();
        let mut m = vec![vec![0.0; n]; n];
        for (a, pa) in self.modes.iter().enumerate() {
            for (b, pb) in self.modes.iter().enumerate().skip(a) {
                let s: f64 = diag
                    .iter()
                    .zip(pa.iter().zip(pb))
                    .map(|(d, (x, y))| (0..6).map(|j| x[j] * d[j] * y[j]).sum::<f64>())
                    .sum();
                m[a][b] = s;
                m[b][a] = s;
            }
        }
        m
    }

    /// The modal stiffness matrix K (n_m × n_m): diag((2π f_k)²) or the given matrix.
    pub fn stiffness_matrix(&self) -> Vec<Vec<f64>> {
        match &self.stiffness {
            ModalStiffness::Frequencies(f) => diagonal(f.iter().map(|f| (2.0 * std::f64::consts::PI * f).powi(2))),
            ModalStiffness::Matrix(k) => k.clone(),
        }
    }

    /// The modal damping matrix C (n_m × n_m): zero, diag(2 ζ_k ω_k), or the given matrix.
    pub fn damping_matrix(&self) -> Vec<Vec<f64>> {
        let n = self.modes.len();
        match (&self.damping, &self.stiffness) {
            (ModalDamping::None, _) => vec![vec![0.0; n]; n],
            (ModalDamping::Ratios(z), ModalStiffness::Frequencies(f)) => {
                diagonal(z.iter().zip(f).map(|(z, f)| 2.0 * z * 2.0 * std::f64::consts::PI * f))
            }
            // Ratios without frequencies are refused when reading.
            (ModalDamping::Ratios(_), ModalStiffness::Matrix(_)) => vec![vec![0.0; n]; n],
            (ModalDamping::Matrix(c), _) => c.clone(),
        }
    }
}

/// A square matrix with the given diagonal.
fn diagonal(d: impl ExactSizeIterator<Item = f64>) -> Vec<Vec<f64>> {
    let n = d.len();
    let mut m = vec![vec![0.0; n]; n];
    for (i, v) in d.enumerate() {
        m[i][i] = v;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_nodes() -> ModalData {
        ModalData {
            description: None,
            nodes: vec![
                Node { id: 1, position: [0.0; 3], mass: 2.0, inertia: [0.5, 0.0, 0.0] },
                Node { id: 2, position: [1.0, 0.0, 0.0], mass: 2.0, inertia: [0.5, 0.0, 0.0] },
            ],
            modes: vec![
                vec![[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], [-0.5, 0.0, 0.0, 0.0, 0.0, 0.0]],
                vec![[0.0, 0.0, 0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, -1.0, 0.0, 0.0]],
            ],
            stiffness: ModalStiffness::Frequencies(vec![1.0, 2.0]),
            damping: ModalDamping::Ratios(vec![0.1, 0.0]),
        }
    }

    /// Sums of a few exact binary fractions: the comparisons are exact.
    #[test]
    fn modal_mass_stiffness_and_damping_follow_their_definitions() {
        let d = two_nodes();
        assert_eq!(d.modal_mass(), vec![vec![1.0, 0.0], vec![0.0, 1.0]]);
        let w = |f: f64| 2.0 * std::f64::consts::PI * f;
        assert_eq!(d.stiffness_matrix(), vec![vec![w(1.0).powi(2), 0.0], vec![0.0, w(2.0).powi(2)]]);
        assert_eq!(d.damping_matrix(), vec![vec![2.0 * 0.1 * w(1.0), 0.0], vec![0.0, 0.0]]);
    }
}
