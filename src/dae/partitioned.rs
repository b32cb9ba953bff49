//! The engine at a point the host chooses (FMI Model Exchange): the consistent
//! (q, u, Z, λ) at time t whose position states, velocity states and differential states
//! have given values — coordinate partitioning (Wehage & Haug), drift-free because every
//! point is solved from the constraints, never integrated.

use super::error::EngineError;
use super::init;
use super::simulator::Simulator;
use super::start_values::StartValues;
use crate::mechanics::System;
use crate::mechanics::measures::StateKind;
use crate::model::expr::Expr;

/// Largest |C| (and |s − S|) of a placed point, relative to the model's size 1 + max|q|:
/// near round-off, so that derivatives the host differentiates are smooth in the states.
pub const PLACEMENT_TOL: f64 = 1e-12;

/// What [`Simulator::place`] asks of a point before moving there: (system, q, t,
/// external values) → acceptable or why not.
pub type Check<'a> = &'a dyn Fn(&System, &[f64], f64, &[f64]) -> Result<(), EngineError>;

impl Simulator {
    /// Move the engine to time `t` and the point where the values `set` hold: positions
    /// by Newton on [C(q, t); s(q, t) − S] from the current q
    /// ([`init::place_positions`]), velocities from [P; B; w_u] u = [−C_t; −b; W − w_t]
    /// ([`init::assemble_velocities_with`]), the differential states X as given, then Ẋ,
    /// V, the accelerations and multipliers (Eq. 1c–1d, 7). `set` must hold as many
    /// position and velocity conditions as the mechanism has freedoms there (the
    /// linearization states); `check` is asked, with the system, the new q, t and the
    /// external values, whether that point is acceptable before the engine moves there
    /// (the states still parameterize it). The integrator's history is dropped. On an
    /// error the engine is where it was.
    pub fn place(&mut self, t: f64, set: &StartValues, check: Check) -> Result<(), EngineError> {
        if !t.is_finite() {
            return Err(EngineError::Numeric(format!("time {t} is not finite")));
        }
        let sys = &mut self.dae.sys;
        let kept = (sys.angle_refs.clone(), sys.angle_time);
        // The host's states say where the mechanism is, not the time: angle measures stay
        // on the branches of the last point (no extrapolation with their rates to t), and
        // a state that is an angle measure is put on the branch of its value, however far
        // the host moved it (a fast rotor over a long step).
        sys.angle_time = t;
        for p in &set.positions {
            if let StateKind::Joint { f: Expr::Kin(k, ..), abase, .. } | StateKind::User { f: Expr::Kin(k, ..), abase } =
                &p.kind
                && k.is_angle()
                && let Some(r) = sys.angle_refs.get_mut(*abase)
            {
                *r = p.value;
            }
        }
        let placed = self.place_at(t, set, check);
        if placed.is_err() {
            let sys = &mut self.dae.sys;
            (sys.angle_refs, sys.angle_time) = kept;
        }
        placed
    }

    /// [`Simulator::place`] once the angle branches are set.
    fn place_at(&mut self, t: f64, set: &StartValues, check: Check) -> Result<(), EngineError> {
        let lay = self.dae.lay;
        let inputs = self.dae.inputs_at(t);
        let sys = &self.dae.sys;
        let mut q = self.q().to_vec();
        let limit = PLACEMENT_TOL * init::placement::size(&q);
        init::place_positions(sys, &set.positions, &mut q, t, &inputs, limit, &mut self.acc_lu)
            .map_err(EngineError::Numeric)?;
        let mut u = self.u().to_vec();
        let ics: Vec<_> = set
            .velocities
            .iter()
            .map(|v| crate::mechanics::constraints::VelocityIc {
                name: v.name.clone(),
                kind: v.kind.clone(),
                value: v.value,
                bodies: v.bodies.clone(),
            })
            .collect();
        init::assemble_velocities_with(sys, &ics, &q, &mut u, t, &inputs).map_err(EngineError::Numeric)?;
        let mut z = self.user_values().to_vec();
        for &(k, x) in &set.differentials {
            z[k] = x;
        }
        let (udot, lam) = init::consistent_accelerations(sys, &q, &u, t, &inputs, &mut z, &mut self.acc_lu)
            .map_err(EngineError::Numeric)?;
        let mut y = lay.assemble(&q, &u, &z, &lam);
        if let Some(v) = y.iter().find(|v| !v.is_finite()) {
            return Err(EngineError::Numeric(format!("the motion at t = {t} is not finite ({v})")));
        }
        check(sys, &q, t, &lay.ext(sys, &inputs, &y, t))?;
        // Euler frames re-based and angle branches recorded, as after an accepted step.
        super::radau::DaeProblem::accepted(&mut self.dae, t, &mut y);
        self.radau.t = t;
        self.radau.y = y;
        self.radau.reset();
        self.acc = Some((udot, lam));
        Ok(())
    }
}
