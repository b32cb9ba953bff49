//! The finite-element model of a straight beam along body x: equal 3-D elements, six
//! degrees of freedom per node [u, v, w, θx, θy, θz], the stiffness from linear (axial,
//! torsion) and cubic (bending) shape functions, and a LUMPED (diagonal) mass matrix.
//! Euler–Bernoulli elements, or Timoshenko elements (shear deformation and the section's
//! rotary inertia) when a shear coefficient κ is given.
//!
//! Element of length ℓ: axial EA/ℓ·[1 −1; −1 1]; torsion GJ/ℓ·[1 −1; −1 1]; bending in the
//! x-y plane (v, θz) EIz/((1 + Φ)ℓ³)·[12 6ℓ −12 6ℓ; 6ℓ (4+Φ)ℓ² −6ℓ (2−Φ)ℓ²; −12 −6ℓ 12 −6ℓ;
//! 6ℓ (2−Φ)ℓ² −6ℓ (4+Φ)ℓ²] with Φ = 12EIz/(κGAℓ²) (Φ = 0: Euler–Bernoulli); in the x-z
//! plane (w, θy) the same with Iy and the 6ℓ terms negated (θy = −w'). With Φ > 0 this is
//! the shear-deformable element whose interpolation solves the static Timoshenko
//! equations exactly (Przemieniecki, "Theory of Matrix Structural Analysis", 1968, §5.6).
//!
//! Lumping: each element gives each of its two end nodes half its mass, m_h = ρAℓ/2 (on
//! u, v, w), the torsional inertia of half its length, ρ(Iy + Iz)ℓ/2 (on θx), and about y
//! and z the inertia of its half-length rod about the node, m_h (ℓ/2)²/3 = ρAℓ³/24, plus,
//! for Timoshenko elements, the section's rotary inertia of half its length, ρIyℓ/2 and
//! ρIzℓ/2. (Euler–Bernoulli theory leaves the section's rotary inertia out.) The ρAℓ³/24
//! terms are positive, so M is positive definite, and they vanish as O(ℓ²) relative to
//! the translational lumps: the lumped model converges to the continuous beam's
//! frequencies at O(h²).

use nalgebra::{DMatrix, DVector};

/// The beam's cross-section: area A (m²), second moments Iy, Iz (m⁴) about the section's
/// y and z axes (Iz resists bending in the x-y plane), torsion constant J (m⁴).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    /// Area A (m²).
    pub area: f64,
    /// Second moment about y, Iy (m⁴): bending in the x-z plane.
    pub iy: f64,
    /// Second moment about z, Iz (m⁴): bending in the x-y plane.
    pub iz: f64,
    /// Torsion constant J (m⁴).
    pub j: f64,
}

/// The beam's material: Young's modulus E (Pa), shear modulus G (Pa), density ρ (kg/m³).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Shear modulus G (Pa).
    pub shear: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
}

/// The assembled beam: 6 (N + 1) degrees of freedom, node i's at 6i..6i+6.
#[derive(Clone, Debug)]
pub struct BeamFe {
    /// Node positions along x (m), node 0 at 0, node N at L.
    pub x: Vec<f64>,
    /// The stiffness matrix K.
    pub stiffness: DMatrix<f64>,
    /// The diagonal of the lumped mass matrix M.
    pub mass: DVector<f64>,
}

/// Assemble a beam of `length` made of `elements` equal elements: Euler–Bernoulli, or
/// Timoshenko with shear coefficient κ = `shear_coefficient`.
pub fn assemble(length: f64, elements: usize, s: &Section, m: &Material, shear_coefficient: Option<f64>) -> BeamFe {
    let n = 6 * (elements + 1);
    let l = length / elements as f64;
    let ke = element_stiffness(l, s, m, shear_coefficient);
    let half = m.density * s.area * l / 2.0;
    let rotary = |i: f64| if shear_coefficient.is_some() { m.density * i * l / 2.0 } else { 0.0 };
    let lump = [
        half,
        half,
        half,
        m.density * (s.iy + s.iz) * l / 2.0,
        half * l * l / 12.0 + rotary(s.iy),
        half * l * l / 12.0 + rotary(s.iz),
    ];
    let mut stiffness = DMatrix::zeros(n, n);
    let mut mass = DVector::zeros(n);
    for e in 0..elements {
        let at = 6 * e;
        for (a, row) in ke.iter().enumerate() {
            for (b, v) in row.iter().enumerate() {
                stiffness[(at + a, at + b)] += v;
            }
        }
        for end in [at, at + 6] {
            for (d, v) in lump.iter().enumerate() {
                mass[end + d] += v;
            }
        }
    }
    let x = (0..=elements).map(|i| length * i as f64 / elements as f64).collect();
    BeamFe { x, stiffness, mass }
}

/// The 12 × 12 stiffness of one element of length `l`, DOFs [node 1; node 2]; with a
/// shear coefficient κ, shear-deformable (Timoshenko) bending.
fn element_stiffness(l: f64, s: &Section, m: &Material, shear_coefficient: Option<f64>) -> [[f64; 12]; 12] {
    let mut k = [[0.0; 12]; 12];
    let mut pair = |dofs: [usize; 2], c: f64| {
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                k[i][j] += if a == b { c } else { -c };
            }
        }
    };
    pair([0, 6], m.young * s.area / l);
    pair([3, 9], m.shear * s.j / l);
    let bending = |sign: f64, phi: f64| {
        let c = sign * 6.0 * l;
        let (near, far) = ((4.0 + phi) * l * l, (2.0 - phi) * l * l);
        [[12.0, c, -12.0, c], [c, near, -c, far], [-12.0, -c, 12.0, -c], [c, far, -c, near]]
    };
    for (dofs, ei, sign) in [([1, 5, 7, 11], s.iz, 1.0), ([2, 4, 8, 10], s.iy, -1.0)] {
        let phi = shear_coefficient.map_or(0.0, |kappa| 12.0 * m.young * ei / (kappa * m.shear * s.area * l * l));
        let h = bending(sign, phi);
        let c = m.young * ei / ((1.0 + phi) * l.powi(3));
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                k[i][j] += c * h[a][b];
            }
        }
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// K is symmetric, and rigid translations and rotations (about the beam's origin) give
    /// K r = 0 up to rounding (1e-12 relative to K's largest entry times |r|: sums of a
    /// few terms of size max|K|·|r|), for Euler–Bernoulli and (thick) Timoshenko elements;
    /// the lumped masses add up to ρAL.
    #[test]
    fn stiffness_has_the_six_rigid_motions_as_null_space_and_masses_sum_up() {
        for kappa in [None, Some(5.0 / 6.0)] {
            rigid_null_space(kappa);
        }
    }

    fn rigid_null_space(kappa: Option<f64>) {
        let s = Section { area: 2e-2, iy: 3e-5, iz: 5e-5, j: 6e-5 };
        let m = Material { young: 2e11, shear: 8e10, density: 7800.0 };
        let fe = assemble(1.5, 5, &s, &m, kappa);
        let k = &fe.stiffness;
        assert!((k - k.transpose()).amax() == 0.0);
        let n = fe.x.len();
        for r in 0..6 {
            let mut v = DVector::zeros(6 * n);
            for (i, &x) in fe.x.iter().enumerate() {
                match r {
                    0..=2 => v[6 * i + r] = 1.0,
                    3 => v[6 * i + 3] = 1.0,
                    // rotation about y: w = −x θ, θy = θ; about z: v = x θ, θz = θ
                    4 => {
                        v[6 * i + 2] = -x;
                        v[6 * i + 4] = 1.0
                    }
                    _ => {
                        v[6 * i + 1] = x;
                        v[6 * i + 5] = 1.0
                    }
                }
            }
            assert!((k * &v).amax() <= 1e-12 * k.amax() * v.amax(), "rigid motion {r}");
        }
        let total: f64 = (0..n).map(|i| fe.mass[6 * i]).sum();
        assert!((total - 7800.0 * 2e-2 * 1.5).abs() <= 1e-12 * total);
    }
}
