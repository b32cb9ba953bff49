//! Linearization states S = s(q, t) (seed Eq. 30, 34f): user expressions, and the internal
//! candidates — the joints' free coordinates, then each body's CM coordinates and its
//! 3-1-3 angles relative to a reference frame fixed at selection time (so the names mean
//! the same at every later point).

use super::jets::{PositionFn, jets};
use crate::ad::Real;
use crate::mechanics::System;
use crate::mechanics::local::LocalCtx;
use crate::mechanics::measure_names::{BODY_COORDS, expr_bodies};
pub use crate::mechanics::measure_names::{derivative_name, derivative_of_name};
pub use crate::mechanics::measures::StateKind;
use crate::model::expr::Expr;

/// A velocity-level state W (seed Eq. 34h): the time derivative of a position-level
/// candidate, or a user `<velocity>` expression w(q, u, t).
#[derive(Clone, Debug, PartialEq)]
pub enum VelState {
    /// W = ṡ(q) of a position-level function s.
    Derivative(StateFn),
    /// A user `<velocity>` expression.
    User(UserVelocity),
}

/// A `<linearization><velocity>` expression.
#[derive(Clone, Debug, PartialEq)]
pub struct UserVelocity {
    /// Its name.
    pub name: String,
    /// The expression w(q, u, t).
    pub f: Expr,
    /// Its angle-unwrapping slot base.
    pub abase: usize,
    /// The bodies it reads (sorted, once each).
    pub bodies: Vec<usize>,
}

impl PositionFn for UserVelocity {
    fn bodies(&self) -> &[usize] {
        &self.bodies
    }
    fn components(&self) -> usize {
        1
    }
    fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]) {
        out[0] = ctx.eval_expr(&self.f, self.abase);
    }
    fn reads_velocities(&self) -> bool {
        true
    }
}

/// w, ẇ of a velocity state with gradients over (local q, local u, local u̇, t).
pub struct VelJet {
    /// w.
    pub w: f64,
    /// ẇ.
    pub wd: f64,
    /// Gradient of w.
    pub dw: Vec<f64>,
    /// Gradient of ẇ.
    pub dwd: Vec<f64>,
}

impl VelState {
    /// Its name: `der(S)` for a derivative, else the user's name.
    pub fn name(&self) -> String {
        match self {
            VelState::Derivative(s) => derivative_name(&s.name),
            VelState::User(u) => u.name.clone(),
        }
    }
    /// Bodies it reads.
    pub fn bodies(&self) -> &[usize] {
        match self {
            VelState::Derivative(s) => &s.bodies,
            VelState::User(u) => &u.bodies,
        }
    }
    /// Value, rate and their exact gradients at (q, u, u̇, t).
    #[allow(clippy::too_many_arguments)]
    pub fn jet(&self, sys: &System, q: &[f64], u: &[f64], udot: &[f64], t: f64, ext: &[f64]) -> VelJet {
        match self {
            VelState::Derivative(s) => {
                let j = jets(sys, s, q, u, udot, t, ext).swap_remove(0);
                VelJet { w: j.g1, wd: j.g2, dw: j.dg1, dwd: j.dg2 }
            }
            VelState::User(v) => {
                let j = jets(sys, v, q, u, udot, t, ext).swap_remove(0);
                VelJet { w: j.g, wd: j.g1, dw: j.dg, dwd: j.dg1 }
            }
        }
    }
}

/// The user's `<velocity>` candidates of the model.
pub fn user_velocities(sys: &System) -> Vec<UserVelocity> {
    sys.lin_velocities
        .iter()
        .map(|(name, f, abase)| UserVelocity {
            name: name.clone(),
            f: f.clone(),
            abase: *abase,
            bodies: expr_bodies(sys, f),
        })
        .collect()
}

/// One linearization state.
#[derive(Clone, Debug, PartialEq)]
pub struct StateFn {
    /// Its name (a user state's, `joint.angle`, `body.x` ...).
    pub name: String,
    /// What it measures.
    pub kind: StateKind,
    /// The bodies it reads (sorted, once each).
    pub bodies: Vec<usize>,
}

impl PositionFn for StateFn {
    fn bodies(&self) -> &[usize] {
        &self.bodies
    }
    fn components(&self) -> usize {
        1
    }
    fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]) {
        out[0] = self.kind.eval(ctx);
    }
}

/// The user's states of the model.
pub fn user_states(sys: &System) -> Vec<StateFn> {
    sys.lin_states
        .iter()
        .map(|(name, f, abase)| {
            let kind = StateKind::User { f: f.clone(), abase: *abase };
            StateFn { name: name.clone(), kind, bodies: expr_bodies(sys, f) }
        })
        .collect()
}

/// The joints' free coordinates as state candidates (joint order).
pub fn joint_states(sys: &System) -> Vec<StateFn> {
    sys.joint_coords
        .iter()
        .map(|c| {
            let kind = StateKind::Joint { f: c.f.clone(), abase: c.abase, about: c.about.clone() };
            StateFn { name: c.name.clone(), kind, bodies: expr_bodies(sys, &c.f) }
        })
        .collect()
}

/// The internal candidate for coordinate q[i]: `body.x|y|z|psi|theta|phi`, angles relative
/// to the body's current reference frame.
pub fn internal_state(sys: &System, i: usize) -> StateFn {
    if let Some(f) = sys.flex.iter().find(|f| f.eta.contains(&i)) {
        let k = i - f.eta.start;
        let name = format!("{}.eta{}", sys.bodies[f.body].name, k + 1);
        return StateFn { name, kind: StateKind::Modal { k }, bodies: vec![f.body] };
    }
    let (b, k) = (i / 6, i % 6);
    let kind = if k < 3 { StateKind::Position { k } } else { StateKind::Angle { k: k - 3, r0: sys.r0[b] } };
    StateFn { name: format!("{}.{}", sys.bodies[b].name, BODY_COORDS[k]), kind, bodies: vec![b] }
}

impl StateFn {
    /// The state's unit: m for a CM coordinate, rad for an angle, that of the kinematic
    /// measure a user state is (none for other expressions).
    pub fn unit(&self) -> Option<String> {
        match &self.kind {
            StateKind::Position { .. } => Some("m".into()),
            StateKind::Angle { .. } => Some("rad".into()),
            StateKind::Modal { .. } => None,
            StateKind::User { f, .. } | StateKind::Joint { f, .. } => {
                crate::model::units::of_expr(f).map(str::to_string)
            }
        }
    }

    /// What the state measures, frame stated (an FMI variable description).
    pub fn description(&self) -> String {
        match &self.kind {
            StateKind::User { .. } => "user linearization state".into(),
            StateKind::Joint { about, .. } => about.clone(),
            StateKind::Position { .. } => {
                let (b, c) = self.name.rsplit_once('.').unwrap_or((&self.name, ""));
                format!("{c} of body '{b}' CM, ground frame")
            }
            StateKind::Modal { k } => {
                let (b, _) = self.name.rsplit_once('.').unwrap_or((&self.name, ""));
                format!(
                    "modal coordinate of mode {} of flexible body '{b}' (mode shapes of its modal data file)",
                    k + 1
                )
            }
            StateKind::Angle { .. } => {
                let (b, c) = self.name.rsplit_once('.').unwrap_or((&self.name, ""));
                format!(
                    "3-1-3 angle {c} of body '{b}' in its fixed reference frame R0 (in which the \
                     orientation the model file gives reads (0, pi/2, 0))"
                )
            }
        }
    }
}

impl VelState {
    /// What it measures (an FMI variable description).
    pub fn description(&self) -> String {
        match self {
            VelState::Derivative(s) => format!("time derivative of: {}", s.description()),
            VelState::User(_) => "user velocity state (non-holonomic model)".into(),
        }
    }

    /// The velocity state's unit (that of Ṡ, or of the user's velocity expression).
    pub fn unit(&self) -> Option<String> {
        match self {
            VelState::Derivative(s) => s.unit().and_then(|u| crate::model::units::per_second(&u)),
            VelState::User(u) => crate::model::units::of_expr(&u.f).map(str::to_string),
        }
    }
}
