//! Applied forces Q(u, q, t) (Eq. 1d / 13a), as generalized forces conjugate to
//! u_b = [v; ω']: a force F at ground point p on body b adds F to Q_v and
//! Aᵀ((p − r) × F) to Q_ω'; a torque τ adds Aᵀτ. The force laws are in
//! [`super::force_laws`].

use crate::ad::Real;
use crate::geom::V3;
use crate::model::SpringType;
use crate::model::expr::{Expr, MarkerId};

/// What a force element is.
#[derive(Clone, Debug)]
pub enum ForceKind {
    /// Translational (along the line of sight) or rotational (about z_j) spring-damper.
    SpringDamper { kind: SpringType, i: MarkerId, j: MarkerId, k: f64, c: f64, length: f64, preload: f64 },
    /// Single-component force of an expression.
    Sforce { kind: SpringType, i: MarkerId, j: MarkerId, f: Expr, abase: usize },
    /// General force/torque at i in `frame` axes, reaction on j.
    Gforce {
        i: MarkerId,
        j: Option<MarkerId>,
        frame: Option<MarkerId>,
        force: Box<[Expr; 3]>,
        torque: Box<[Expr; 3]>,
        abase: [usize; 6],
    },
    /// Linear six-component spring-damper in marker j's axes: translation of i's origin
    /// relative to j's, small-angle rotation vector of i relative to j, and their rates.
    Bushing { i: MarkerId, j: MarkerId, k: [f64; 6], c: [f64; 6] },
}

/// A force element and the bodies its value depends on or acts on.
#[derive(Clone, Debug)]
pub struct ForceEl {
    /// Name of the model element.
    pub name: String,
    /// What the element is.
    pub kind: ForceKind,
    /// Bodies whose coordinates its value depends on or that it acts on (global indices).
    pub bodies: Vec<usize>,
    /// Entries of the external values (inputs, Z, loads) its expressions read.
    pub ext_refs: Vec<usize>,
    /// Reference for unwrapping the rotational angle az(i, j) (kept near it).
    pub angle_ref: f64,
}

/// Force and torque (ground) that an element applies on its i marker.
pub struct Load<T: Real> {
    /// Force, ground components.
    pub force: V3<T>,
    /// Torque about the i marker origin, ground components.
    pub torque: V3<T>,
}

impl ForceEl {
    /// Markers (i, j) between which the element acts.
    pub fn markers(&self) -> (MarkerId, Option<MarkerId>) {
        match &self.kind {
            ForceKind::SpringDamper { i, j, .. } | ForceKind::Sforce { i, j, .. } => (*i, Some(*j)),
            ForceKind::Gforce { i, j, .. } => (*i, *j),
            ForceKind::Bushing { i, j, .. } => (*i, Some(*j)),
        }
    }
}
