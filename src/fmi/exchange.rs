//! Model Exchange (FMI 2.0, chapter 3) on an instance: the host owns time and the
//! continuous states x = [S; W; X] (the linearization states, in the order of
//! `<Derivatives>`), the engine answers at the point they define
//! ([`crate::linearize::exchange`]: coordinate partitioning). Setting time or states only
//! records them; the point is solved once, when something is read there.

use super::instance::Instance;
use super::interface::{Exchange, Interface};
use super::state_machine::State;
use crate::linearize::{accept_step, place_states, state_derivatives, state_vector};

impl Instance {
    /// Err unless this is a Model Exchange instance.
    pub(super) fn exchange_only(&self) -> Result<(), String> {
        match self.interface {
            Interface::ModelExchange => Ok(()),
            Interface::CoSimulation => Err("a Model Exchange function, and this is a Co-Simulation instance".into()),
        }
    }

    /// EnterContinuousTimeMode (Model Exchange instances only: an FMI 3 Co-Simulation
    /// instance in Event Mode goes on to Step Mode).
    pub fn enter_continuous_time_mode(&mut self) -> Result<(), String> {
        self.exchange_only()?;
        self.state = State::ContinuousTimeMode;
        Ok(())
    }

    /// fmi3GetNumberOfContinuousStates: the number of linearization states.
    pub fn continuous_state_count(&self) -> Result<usize, String> {
        self.exchange_only()?;
        Ok(self.state_count())
    }

    /// At the end of initialization: x and time are the engine's.
    pub(super) fn start_exchange(&mut self) -> Result<(), String> {
        let b = self.built.as_mut().ok_or("no engine (not initialized)")?;
        let sel = b.sel.as_ref().map_err(|e| format!("no continuous states: {e}"))?;
        let x = state_vector(&mut b.sim, sel).map_err(|e| format!("the states cannot be evaluated: {e}"))?;
        let accepted = Some(b.sim.accepted_point());
        self.exchange = Exchange { time: b.sim.time(), x, placed: true, accepted };
        Ok(())
    }

    /// Solve the point of (time, x) if the engine is not there (Model Exchange after
    /// initialization; otherwise nothing to do). A point the states do not determine is
    /// an error naming the states, and the engine stays at the last point.
    pub(super) fn place_if_exchange(&mut self) -> Result<(), String> {
        if self.interface != Interface::ModelExchange || self.exchange.placed {
            return Ok(());
        }
        let Some(b) = self.built.as_mut() else { return Ok(()) };
        if self.dirty {
            return Ok(());
        }
        let sel = b.sel.as_ref().map_err(|e| format!("no continuous states: {e}"))?;
        let (t, x) = (self.exchange.time, &self.exchange.x);
        place_states(&mut b.sim, sel, t, x).map_err(|e| format!("the continuous states cannot be met: {e}"))?;
        self.last_time = t;
        self.exchange.placed = true;
        Ok(())
    }

    /// fmi2SetTime.
    pub fn set_time(&mut self, t: f64) -> Result<(), String> {
        self.exchange_only()?;
        if !t.is_finite() {
            return Err(format!("time {t} is not finite"));
        }
        if t.to_bits() != self.exchange.time.to_bits() {
            self.exchange.time = t;
            self.exchange.placed = false;
        }
        Ok(())
    }

    /// fmi2SetContinuousStates: all checked, then recorded.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Result<(), String> {
        self.exchange_only()?;
        self.check_count(x.len(), "nx")?;
        if let Some((k, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(format!("state {k} ('{}') is {v}, not a finite number", self.state_name(k)));
        }
        let same = x.iter().zip(&self.exchange.x).all(|(a, b)| a.to_bits() == b.to_bits());
        if !same {
            self.exchange.x.copy_from_slice(x);
            self.exchange.placed = false;
        }
        Ok(())
    }

    /// fmi2GetContinuousStates: x as set (or as initialization left it).
    pub fn continuous_states(&mut self, out: &mut [f64]) -> Result<(), String> {
        self.exchange_only()?;
        self.check_count(out.len(), "nx")?;
        if self.exchange.x.len() != out.len() {
            // In Initialization Mode: the states of the engine as the values set make it.
            self.simulator()?;
            let b = self.built.as_mut().expect("built");
            let sel = b.sel.as_ref().map_err(|e| format!("no continuous states: {e}"))?;
            let x = state_vector(&mut b.sim, sel).map_err(|e| format!("the states cannot be evaluated: {e}"))?;
            out.copy_from_slice(&x);
            return Ok(());
        }
        out.copy_from_slice(&self.exchange.x);
        Ok(())
    }

    /// fmi2GetDerivatives, fmi3GetContinuousStateDerivatives: ẋ = [Ṡ; Ẇ; Ẋ] at (time, x);
    /// in Initialization Mode (FMI 3) at the point the values set so far assemble.
    pub fn derivatives(&mut self, out: &mut [f64]) -> Result<(), String> {
        self.exchange_only()?;
        self.check_count(out.len(), "nx")?;
        if self.state == State::InitializationMode {
            self.simulator()?;
        } else {
            self.place_if_exchange()?;
        }
        let b = self.built.as_mut().ok_or("no engine (not initialized)")?;
        let sel = b.sel.as_ref().map_err(|e| format!("no continuous states: {e}"))?;
        let d = state_derivatives(&mut b.sim, sel).map_err(|e| format!("the derivatives cannot be evaluated: {e}"))?;
        out.copy_from_slice(&d);
        if let Some((k, v)) = out.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(format!(
                "the derivative of state {k} ('{}') is {v} at t = {}: the motion overflows",
                self.state_name(k),
                self.exchange.time
            ));
        }
        Ok(())
    }

    /// fmi2GetNominalsOfContinuousStates: 1 for every state (the states are in SI units
    /// of the mechanism's own size).
    pub fn nominals(&self, out: &mut [f64]) -> Result<(), String> {
        self.exchange_only()?;
        self.check_count(out.len(), "nx")?;
        out.fill(1.0);
        Ok(())
    }

    /// fmi2GetEventIndicators: the model has none.
    pub fn event_indicators(&self, n: usize) -> Result<(), String> {
        self.exchange_only()?;
        if n != 0 {
            return Err(format!("ni = {n}, but the model has no event indicators (numberOfEventIndicators = 0)"));
        }
        Ok(())
    }

    /// fmi2CompletedIntegratorStep: the point of the accepted step is solved (its angle
    /// branches recorded, its Euler frames re-based), so later points continue from it,
    /// and checked to be the one the motion from the last accepted step continues to
    /// (else an error: the states went through a fold of their chart on the way).
    pub fn completed_integrator_step(&mut self) -> Result<(), String> {
        self.exchange_only()?;
        self.place_if_exchange()?;
        let Some(b) = self.built.as_mut() else { return Ok(()) };
        let sel = b.sel.as_ref().map_err(|e| format!("no continuous states: {e}"))?;
        let e = &mut self.exchange;
        let next = accept_step(&mut b.sim, sel, &e.x, e.accepted.as_ref()).map_err(|e| e.to_string())?;
        e.accepted = Some(next);
        Ok(())
    }

    /// Err unless `n` (argument `what`) is the number of continuous states.
    fn check_count(&self, n: usize, what: &str) -> Result<(), String> {
        let ns = self.state_count();
        if n != ns {
            return Err(format!("{what} = {n}, but the model has {ns} continuous states"));
        }
        Ok(())
    }

    /// The name of continuous state k.
    fn state_name(&self, k: usize) -> &str {
        self.vars.iter().find(|v| v.known == Some(k)).map_or("?", |v| v.name.as_str())
    }
}
