//! Snapshots of a simulation (FMU states): what they hold, their byte form, and taking
//! and restoring them.

use super::error::EngineError;
use super::simulator::Simulator;

/// A complete simulation state: restoring it reproduces the run bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct SimState {
    /// Time.
    pub t: f64,
    /// Next step size.
    pub h: f64,
    /// The DAE unknowns [q; u; Z; λ; ν; μ], Z = (X, Ẋ, V, a) (see
    /// [`crate::dae::equations::Layout`]).
    pub y: Vec<f64>,
    /// Euler-angle reference frames, one per body.
    pub r0: Vec<[[f64; 3]; 3]>,
    /// Branch values of the angle measures in expressions (angle unwrapping).
    pub angle_refs: Vec<f64>,
    /// Rates of the angle measures at `angle_time`.
    pub angle_rates: Vec<f64>,
    /// Time at which `angle_refs` and `angle_rates` were recorded.
    pub angle_time: f64,
    /// Angle-unwrapping references of the rotational springs, one per force element.
    pub spring_refs: Vec<f64>,
    /// Input values at time `t_in`.
    pub inputs: Vec<f64>,
    /// Input slopes (inputs change linearly from `t_in`).
    pub slopes: Vec<f64>,
    /// Reference time of the inputs.
    pub t_in: f64,
    /// The integrator's step history ([`crate::dae::radau::Radau::memory`]).
    pub integrator: Vec<f64>,
}

const STATE_MAGIC: &[u8; 8] = b"MBFMUS02";

impl SimState {
    /// Serialize (little-endian f64 arrays with lengths, behind a magic tag).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = STATE_MAGIC.to_vec();
        let mut arr = |v: &[f64]| {
            b.extend_from_slice(&(v.len() as u64).to_le_bytes());
            for x in v {
                b.extend_from_slice(&x.to_le_bytes());
            }
        };
        arr(&[self.t, self.h, self.t_in, self.angle_time]);
        arr(&self.y);
        arr(&self.r0.iter().flatten().flatten().copied().collect::<Vec<f64>>());
        arr(&self.angle_refs);
        arr(&self.angle_rates);
        arr(&self.spring_refs);
        arr(&self.inputs);
        arr(&self.slopes);
        arr(&self.integrator);
        b
    }

    /// Deserialize what [`SimState::to_bytes`] wrote.
    pub fn from_bytes(bytes: &[u8]) -> Result<SimState, EngineError> {
        let bad = || EngineError::Numeric("not a serialized mbfmu state".into());
        let rest = bytes.strip_prefix(STATE_MAGIC.as_slice()).ok_or_else(bad)?;
        let mut pos = 0usize;
        let mut arr = || -> Result<Vec<f64>, EngineError> {
            let len_bytes = rest.get(pos..pos + 8).ok_or_else(bad)?;
            let n = u64::from_le_bytes(len_bytes.try_into().map_err(|_| bad())?) as usize;
            pos += 8;
            let end = n.checked_mul(8).and_then(|k| k.checked_add(pos)).ok_or_else(bad)?;
            let data = rest.get(pos..end).ok_or_else(bad)?;
            pos = end;
            Ok(data.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect())
        };
        let head = arr()?;
        let y = arr()?;
        let r0f = arr()?;
        let (angle_refs, angle_rates) = (arr()?, arr()?);
        let (spring_refs, inputs, slopes, integrator) = (arr()?, arr()?, arr()?, arr()?);
        if head.len() != 4 || angle_rates.len() != angle_refs.len() || r0f.len() % 9 != 0 || pos != rest.len() {
            return Err(bad());
        }
        let r0 = r0f.chunks_exact(9).map(|c| [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]]).collect();
        Ok(SimState {
            t: head[0],
            h: head[1],
            t_in: head[2],
            angle_time: head[3],
            y,
            r0,
            angle_refs,
            angle_rates,
            spring_refs,
            inputs,
            slopes,
            integrator,
        })
    }
}

impl Simulator {
    /// Everything that determines the future of the simulation (FMU state).
    pub fn snapshot(&self) -> SimState {
        SimState {
            t: self.radau.t,
            h: self.radau.h,
            y: self.radau.y.clone(),
            r0: self.dae.sys.r0.clone(),
            angle_refs: self.dae.sys.angle_refs.clone(),
            angle_rates: self.dae.sys.angle_rates.clone(),
            angle_time: self.dae.sys.angle_time,
            spring_refs: self.dae.sys.forces.iter().map(|f| f.angle_ref).collect(),
            inputs: self.dae.inputs.clone(),
            slopes: self.dae.slopes.clone(),
            t_in: self.dae.t_in,
            integrator: self.radau.memory(),
        }
    }

    /// Return to a snapshot of this model's simulation.
    pub fn restore(&mut self, s: &SimState) -> Result<(), EngineError> {
        let d = &self.dae;
        let fits = s.y.len() == self.radau.y.len()
            && s.r0.len() == d.sys.r0.len()
            && s.angle_refs.len() == d.sys.angle_refs.len()
            && s.angle_rates.len() == d.sys.angle_rates.len()
            && s.spring_refs.len() == d.sys.forces.len()
            && s.inputs.len() == d.inputs.len()
            && s.slopes.len() == d.slopes.len();
        if !fits {
            return Err(EngineError::Numeric("state does not belong to this model".into()));
        }
        self.radau.t = s.t;
        self.radau.h = s.h;
        self.radau.y.clone_from(&s.y);
        self.dae.sys.r0.clone_from(&s.r0);
        self.dae.sys.angle_refs.clone_from(&s.angle_refs);
        self.dae.sys.angle_rates.clone_from(&s.angle_rates);
        self.dae.sys.angle_time = s.angle_time;
        for (f, &a) in self.dae.sys.forces.iter_mut().zip(&s.spring_refs) {
            f.angle_ref = a;
        }
        self.dae.inputs.clone_from(&s.inputs);
        self.dae.slopes.clone_from(&s.slopes);
        self.dae.t_in = s.t_in;
        if !self.radau.set_memory(&s.integrator) {
            self.radau.reset();
        }
        self.acc = None;
        Ok(())
    }
}
