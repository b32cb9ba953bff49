//! Saved FMU states (2.1.8 Getting and Setting the Complete FMU State): the instance's
//! state-machine state, the host's values and the engine state, and their byte form.

use super::guid::checksum;
use super::instance::{Config, Instance};
use super::state_machine::State;
use crate::dae::SimState;

const MAGIC: &[u8; 8] = b"MBFMUF02";

/// Everything fmi2SetFMUstate needs to put an instance of the same model back.
#[derive(Clone, Debug, PartialEq)]
pub struct FmuState {
    /// GUID of the model: a state restores only into an instance of the same FMU.
    pub guid: String,
    pub state: State,
    pub config: Config,
    pub last_time: f64,
    /// The engine (None before initialization).
    pub sim: Option<SimState>,
}

impl FmuState {
    /// fmi2GetFMUstate. A state taken after fmi2DoStep returned fmi2Discard (StepFailed)
    /// holds the engine at fmi2LastSuccessfulTime, the last accepted integrator step, which
    /// is a valid communication point: it is recorded as StepComplete, so that restoring
    /// it lets the host continue from the time reached (e.g. with a larger
    /// `solver.maxSteps` or a shorter step).
    pub fn capture(inst: &Instance) -> FmuState {
        FmuState {
            guid: inst.guid.clone(),
            state: if inst.state == State::StepFailed { State::StepComplete } else { inst.state },
            config: inst.config.clone(),
            last_time: inst.last_time,
            sim: if inst.dirty { None } else { inst.built.as_ref().map(|b| b.sim.snapshot()) },
        }
    }

    /// fmi2SetFMUstate: into `inst`, which may be another instance of the same model.
    pub fn restore(&self, inst: &mut Instance) -> Result<(), String> {
        if self.guid != inst.guid {
            return Err(format!("the state belongs to FMU {}, not to this FMU {}", self.guid, inst.guid));
        }
        match &self.sim {
            None => {
                inst.built = None;
                inst.dirty = true;
            }
            Some(s) => {
                let reusable = inst.built.as_ref().is_some_and(|b| {
                    !inst.dirty && b.tol.to_bits() == self.config.tol.to_bits() && same(&b.params, &self.config.params)
                });
                if !reusable {
                    inst.built = Some(inst.build(&self.config)?);
                }
                let sim = &mut inst.built.as_mut().expect("built").sim;
                sim.restore(s).map_err(|e| e.to_string())?;
                sim.set_max_steps(self.config.max_steps);
                inst.dirty = false;
            }
        }
        inst.config = self.config.clone();
        inst.last_time = self.last_time;
        inst.state = self.state;
        Ok(())
    }

    /// fmi2SerializeFMUstate: magic, GUID, state, configuration (with `solver.maxSteps`),
    /// engine state.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer(MAGIC.to_vec());
        w.bytes(self.guid.as_bytes());
        w.0.push(State::ALL.iter().position(|s| *s == self.state).expect("listed") as u8);
        let c = &self.config;
        w.f64s(&[c.tol, c.start, c.stop.unwrap_or(f64::NAN), self.last_time]);
        w.0.push(c.stop.is_some() as u8);
        w.f64s(&c.params);
        w.f64s(&c.inputs);
        w.f64s(&c.slopes);
        w.0.extend_from_slice(&(c.max_steps as u64).to_le_bytes());
        match &self.sim {
            Some(s) => {
                w.0.push(1);
                w.bytes(&s.to_bytes());
            }
            None => w.0.push(0),
        }
        let sum = checksum(&w.0);
        w.0.extend_from_slice(&sum.to_le_bytes());
        w.0
    }

    /// fmi2DeSerializeFMUstate: what [`FmuState::to_bytes`] wrote.
    pub fn from_bytes(b: &[u8]) -> Result<FmuState, String> {
        let bad = || "not a serialized state of an mbfmu FMU (or truncated)".to_string();
        let body = b.strip_prefix(MAGIC.as_slice()).ok_or_else(bad)?;
        // The last 8 bytes: checksum of all before them; a changed byte is refused here
        // rather than restored as a corrupted engine state.
        let (body, sum) = body.split_at_checked(body.len().checked_sub(8).ok_or_else(bad)?).ok_or_else(bad)?;
        if checksum(&b[..MAGIC.len() + body.len()]).to_le_bytes() != sum {
            return Err("the serialized state is corrupted (checksum mismatch)".into());
        }
        let mut r = Reader { b: body, pos: 0 };
        let guid = String::from_utf8(r.bytes().ok_or_else(bad)?.to_vec()).map_err(|_| bad())?;
        let state = *State::ALL.get(r.byte().ok_or_else(bad)? as usize).ok_or_else(bad)?;
        let head = r.f64s().ok_or_else(bad)?;
        let has_stop = r.byte().ok_or_else(bad)? == 1;
        let (params, inputs, slopes) =
            (r.f64s().ok_or_else(bad)?, r.f64s().ok_or_else(bad)?, r.f64s().ok_or_else(bad)?);
        let max_steps = r.len().filter(|&n| n >= 1).ok_or_else(bad)?;
        let sim = match r.byte().ok_or_else(bad)? {
            0 => None,
            1 => Some(SimState::from_bytes(r.bytes().ok_or_else(bad)?).map_err(|e| e.to_string())?),
            _ => return Err(bad()),
        };
        if head.len() != 4 || r.pos != r.b.len() {
            return Err(bad());
        }
        let stop = has_stop.then_some(head[2]);
        let config = Config { params, inputs, slopes, tol: head[0], start: head[1], stop, max_steps };
        Ok(FmuState { guid, state, config, last_time: head[3], sim })
    }
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

struct Writer(Vec<u8>);

impl Writer {
    fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(&(b.len() as u64).to_le_bytes());
        self.0.extend_from_slice(b);
    }

    fn f64s(&mut self, v: &[f64]) {
        self.0.extend_from_slice(&(v.len() as u64).to_le_bytes());
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }

    fn byte(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }

    fn len(&mut self) -> Option<usize> {
        usize::try_from(u64::from_le_bytes(self.take(8)?.try_into().ok()?)).ok()
    }

    fn bytes(&mut self) -> Option<&'a [u8]> {
        let n = self.len()?;
        self.take(n)
    }

    fn f64s(&mut self) -> Option<Vec<f64>> {
        let n = self.len()?;
        let raw = self.take(n.checked_mul(8)?)?;
        Some(raw.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect())
    }
}
