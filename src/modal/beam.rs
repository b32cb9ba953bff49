//! `mbfmu modal beam`: the modal data of a straight beam along body x (node 0 at x = 0,
//! node N at x = L), from its finite-element model ([`super::beam_fe`]: Euler–Bernoulli
//! or Timoshenko elements, lumped mass matrix M) reduced to n modes in one of two ways:
//!
//! - free-interface normal modes: K φ = ω² M φ ([`super::eigen`]); the six rigid-body
//!   modes (the six smallest eigenvalues, checked to be ≈ 0) are dropped, the next n kept;
//! - Craig–Bampton ([`super::craig_bampton`]): constraint modes of the interface nodes
//!   plus k fixed-interface modes, the reduced system orthonormalized, its six rigid-body
//!   modes dropped, the first n kept.
//!
//! With `clamp`, one node's six DOFs are fixed (a cantilever) and no rigid mode is dropped.
//! The modes written are mass-normalized with respect to exactly the lumped node masses
//! and inertias written (ΦᵀMΦ = I, ΦᵀKΦ = diag(ω²)), so the file gives frequencies.

use nalgebra::DMatrix;

use super::beam_fe::{Material, Section, assemble};
use super::craig_bampton::{basis, orthonormal_modes};
use super::data::{ModalDamping, ModalData, ModalStiffness, Node};
use super::eigen::generalized_eigen;

/// The six smallest eigenvalues of a free structure are taken as rigid when each is at
/// most RIGID_TOL × the seventh plus 1e-12 × the largest (the rounding of the
/// eigensolver, eps × ‖M^{-1/2} K M^{-1/2}‖).
pub const RIGID_TOL: f64 = 1e-6;

/// The largest number of elements: the eigensolvers are dense, O((6N)³) time and
/// O((6N)²) memory (500 elements: 3006 DOFs, about 100 s on one core; 64 elements: well
/// under a second).
pub const MAX_ELEMENTS: usize = 500;

/// How the beam's modes are obtained.
#[derive(Clone, Debug, PartialEq)]
pub enum Reduction {
    /// Free-interface normal modes.
    FreeInterface,
    /// Craig–Bampton with these interface node ids and this many fixed-interface modes.
    CraigBampton {
        /// Interface node ids (all six DOFs of each).
        interface: Vec<u32>,
        /// Number k of fixed-interface normal modes.
        fixed_modes: usize,
    },
}

/// What to generate.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamSpec {
    /// Length L (m).
    pub length: f64,
    /// Number N of equal elements (nodes 0..=N).
    pub elements: usize,
    /// Cross-section.
    pub section: Section,
    /// Material.
    pub material: Material,
    /// Number n of modes to write.
    pub modes: usize,
    /// Damping ratio of every mode, if any.
    pub damping: Option<f64>,
    /// Node id whose six DOFs are fixed (a cantilever), if any.
    pub clamp: Option<u32>,
    /// Free-interface or Craig–Bampton.
    pub reduction: Reduction,
    /// Timoshenko elements (shear deformation, section rotary inertia) with this shear
    /// coefficient κ (5/6 for a solid rectangle, 0.9 for a solid circle); None:
    /// Euler–Bernoulli.
    pub shear_coefficient: Option<f64>,
}

/// The modal data of the beam `spec` describes; the error says which value is wrong.
pub fn beam(spec: &BeamSpec) -> Result<ModalData, String> {
    check(spec)?;
    let fe = assemble(spec.length, spec.elements, &spec.section, &spec.material, spec.shear_coefficient);
    let n_all = fe.mass.len();
    let clamped: Vec<usize> = spec.clamp.map_or(Vec::new(), |c| (6 * c as usize..6 * c as usize + 6).collect());
    let free: Vec<usize> = (0..n_all).filter(|d| !clamped.contains(d)).collect();
    let k = fe.stiffness.select_rows(&free).select_columns(&free);
    let m = DMatrix::from_diagonal(&fe.mass.select_rows(&free));
    let (lam, phi) = match &spec.reduction {
        Reduction::FreeInterface => {
            generalized_eigen(&k, &m).ok_or("the lumped mass matrix is not positive definite")?
        }
        Reduction::CraigBampton { interface, fixed_modes } => {
            let dofs: Vec<usize> = interface
                .iter()
                .flat_map(|&id| {
                    (6 * id as usize..6 * id as usize + 6).map(|d| free.iter().position(|&f| f == d).unwrap_or(0))
                })
                .collect();
            orthonormal_modes(&k, &m, &basis(&k, &m, &dofs, *fixed_modes)?)?
        }
    };
    let rigid = if spec.clamp.is_some() { 0 } else { 6 };
    if lam.len() < rigid + spec.modes {
        return Err(format!(
            "--modes {}: the model has only {} flexible modes",
            spec.modes,
            lam.len() - rigid.min(lam.len())
        ));
    }
    if rigid > 0 {
        let largest = lam.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        let bound = RIGID_TOL * lam[rigid] + 1e-12 * largest;
        if let Some(i) = (0..rigid).find(|&i| lam[i].abs() > bound) {
            return Err(format!("internal: rigid-body mode {i} has eigenvalue {:e} (bound {bound:e})", lam[i]));
        }
    }
    let shapes = (rigid..rigid + spec.modes)
        .map(|c| {
            let mut full = vec![0.0; n_all];
            for (r, &d) in free.iter().enumerate() {
                full[d] = phi[(r, c)];
            }
            full.chunks(6).map(|s| std::array::from_fn(|j| s[j])).collect()
        })
        .collect();
    let frequencies: Vec<f64> =
        lam[rigid..rigid + spec.modes].iter().map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)).collect();
    let nodes =
        fe.x.iter()
            .enumerate()
            .map(|(i, &x)| Node {
                id: i as u32,
                position: [x, 0.0, 0.0],
                mass: fe.mass[6 * i],
                inertia: [fe.mass[6 * i + 3], fe.mass[6 * i + 4], fe.mass[6 * i + 5]],
            })
            .collect();
    Ok(ModalData {
        description: Some(describe(spec)),
        nodes,
        modes: shapes,
        damping: spec.damping.map_or(ModalDamping::None, |z| ModalDamping::Ratios(vec![z; frequencies.len()])),
        stiffness: ModalStiffness::Frequencies(frequencies),
    })
}

/// Every value finite and in range; ids name nodes.
fn check(spec: &BeamSpec) -> Result<(), String> {
    let s = &spec.section;
    let m = &spec.material;
    let positive = [
        ("--length", spec.length),
        ("--area", s.area),
        ("--iy", s.iy),
        ("--iz", s.iz),
        ("--j", s.j),
        ("--young", m.young),
        ("--shear", m.shear),
        ("--density", m.density),
    ];
    if let Some((name, v)) = positive.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        return Err(format!("{name} {v}: must be a finite number > 0"));
    }
    if !(1..=MAX_ELEMENTS).contains(&spec.elements) {
        return Err(format!(
            "--elements {}: must be from 1 to {MAX_ELEMENTS} (the eigensolver is dense)",
            spec.elements
        ));
    }
    if spec.modes == 0 {
        return Err("--modes 0: must be at least 1".into());
    }
    if let Some(k) = spec.shear_coefficient.filter(|k| !(k.is_finite() && *k > 0.0)) {
        return Err(format!("--timoshenko {k}: the shear coefficient must be a finite number > 0"));
    }
    if let Some(z) = spec.damping.filter(|z| !(z.is_finite() && *z >= 0.0)) {
        return Err(format!("--damping {z}: must be a finite number ≥ 0"));
    }
    let last = spec.elements as u32;
    let node = |what: &str, id: u32| {
        if id > last { Err(format!("{what} {id}: no such node (nodes are 0 to {last})")) } else { Ok(()) }
    };
    if let Some(c) = spec.clamp {
        node("--clamp", c)?;
    }
    if let Reduction::CraigBampton { interface, .. } = &spec.reduction {
        if interface.is_empty() {
            return Err("--craig-bampton: give at least one interface node id".into());
        }
        for (i, &id) in interface.iter().enumerate() {
            node("--craig-bampton", id)?;
            if interface[..i].contains(&id) {
                return Err(format!("--craig-bampton: node {id} is given twice"));
            }
            if spec.clamp == Some(id) {
                return Err(format!("--craig-bampton: node {id} is the clamped node"));
            }
        }
    }
    Ok(())
}

/// The description written into the file.
fn describe(spec: &BeamSpec) -> String {
    let (s, m) = (&spec.section, &spec.material);
    let how = match &spec.reduction {
        Reduction::FreeInterface => "free-interface normal modes".to_string(),
        Reduction::CraigBampton { interface, fixed_modes } => {
            let ids: Vec<String> = interface.iter().map(u32::to_string).collect();
            format!(
                "Craig-Bampton, interface nodes {}, {fixed_modes} fixed-interface modes, orthonormalized",
                ids.join(",")
            )
        }
    };
    let clamp = spec.clamp.map_or(String::new(), |c| format!(", node {c} clamped"));
    let theory =
        spec.shear_coefficient.map_or("Euler-Bernoulli".to_string(), |k| format!("Timoshenko (kappa = {k:?})"));
    format!(
        "mbfmu modal beam: L = {:?} m, {} {theory} elements, lumped mass; A = {:?}, Iy = {:?}, Iz = {:?}, J = {:?}, E = {:?}, G = {:?}, rho = {:?}; {how}{clamp}",
        spec.length, spec.elements, s.area, s.iy, s.iz, s.j, m.young, m.shear, m.density
    )
}
