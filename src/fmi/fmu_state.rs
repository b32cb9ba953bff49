//! Saved FMU states (2.1.8 Getting and Setting the Complete FMU State): the instance's
//! state-machine state, the host's values and the engine state, and their byte form.

use super::config::Config;
use super::guid::checksum;
use super::interface::Exchange;
use super::state_machine::State;
use crate::dae::bytes::{ByteReader, ByteWriter};
use crate::dae::{Accepted, SimState};

const MAGIC: &[u8; 8] = b"MBFMUF02";

/// Everything fmi2SetFMUstate needs to put an instance of the same model back.
#[derive(Clone, Debug, PartialEq)]
pub struct FmuState {
    /// GUID of the model: a state restores only into an instance of the same FMU.
    pub guid: String,
    /// The instance's state-machine state when the FMU state was taken.
    pub state: State,
    /// The host's choices then: parameter and input values, input slopes, experiment,
    /// `solver.maxSteps`.
    pub config: Config,
    /// fmi2LastSuccessfulTime then (s).
    pub last_time: f64,
    /// The engine (None before initialization).
    pub sim: Option<SimState>,
    /// Model Exchange: the time and states the host set (None: Co-Simulation).
    pub exchange: Option<Exchange>,
}

impl FmuState {
    /// fmi2SerializeFMUstate: the magic `MBFMUF02`, GUID, state, configuration (with
    /// `solver.maxSteps`), engine state, for Model Exchange [time, placed] and x, and a
    /// checksum of all before it.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = ByteWriter::new(MAGIC);
        w.bytes(self.guid.as_bytes());
        w.u8(State::ALL.iter().position(|s| *s == self.state).expect("listed") as u8);
        let c = &self.config;
        w.f64s(&[c.tol, c.start, c.stop.unwrap_or(f64::NAN), self.last_time]);
        w.u8(c.stop.is_some() as u8);
        w.f64s(&c.params);
        w.f64s(&c.inputs);
        w.f64s(&c.slopes);
        w.u64(c.max_steps as u64);
        match &self.sim {
            Some(s) => {
                w.u8(1);
                w.bytes(&s.to_bytes());
            }
            None => w.u8(0),
        }
        if let Some(e) = &self.exchange {
            w.f64s(&[e.time, if e.placed { 1.0 } else { 0.0 }]);
            w.f64s(&e.x);
            if let Some(a) = &e.accepted {
                w.f64s(&[a.t]);
                w.f64s(&a.q);
                w.f64s(&a.qdot);
                w.f64s(&a.frames);
            }
        }
        let sum = checksum(w.as_slice());
        w.u64(sum);
        w.finish()
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
        let mut r = ByteReader::new(body);
        let guid = String::from_utf8(r.bytes().ok_or_else(bad)?.to_vec()).map_err(|_| bad())?;
        let state = *State::ALL.get(r.u8().ok_or_else(bad)? as usize).ok_or_else(bad)?;
        let head = r.f64s().ok_or_else(bad)?;
        let has_stop = r.u8().ok_or_else(bad)? == 1;
        let (params, inputs, slopes) =
            (r.f64s().ok_or_else(bad)?, r.f64s().ok_or_else(bad)?, r.f64s().ok_or_else(bad)?);
        let max_steps = r.usize().filter(|&n| n >= 1).ok_or_else(bad)?;
        let sim = match r.u8().ok_or_else(bad)? {
            0 => None,
            1 => Some(SimState::from_bytes(r.bytes().ok_or_else(bad)?).map_err(|e| e.to_string())?),
            _ => return Err(bad()),
        };
        let exchange = if r.at_end() {
            None
        } else {
            let th = r.f64s().filter(|h| h.len() == 2).ok_or_else(bad)?;
            let x = r.f64s().ok_or_else(bad)?;
            let accepted = if r.at_end() {
                None
            } else {
                let t = r.f64s().filter(|t| t.len() == 1).ok_or_else(bad)?[0];
                let (q, qdot, frames) =
                    (r.f64s().ok_or_else(bad)?, r.f64s().ok_or_else(bad)?, r.f64s().ok_or_else(bad)?);
                Some(Accepted { t, q, qdot, frames })
            };
            Some(Exchange { time: th[0], x, placed: th[1] == 1.0, accepted })
        };
        if head.len() != 4 || !r.at_end() {
            return Err(bad());
        }
        let stop = has_stop.then_some(head[2]);
        let config = Config { params, inputs, slopes, tol: head[0], start: head[1], stop, max_steps };
        Ok(FmuState { guid, state, config, last_time: head[3], sim, exchange })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// States serialized by the codec before `dae::bytes` existed (commit e57e189): GUID
    /// `{0123abcd-0000-1111-2222-333344445555}`, params [9.81, 1.5], inputs [7, 8], slopes
    /// [0, −1], tol 1e-6, start 0, last time 0.25, `solver.maxSteps` 12345; the first
    /// StepComplete with stop 10 and a small engine state, the second Instantiated without
    /// stop or engine.
    const WITH_ENGINE: [&str; 11] = [
        "4d42464d5546303226000000000000007b30313233616263642d303030302d313131312d323232322d33333333343434",
        "34353535357d0204000000000000008dedb5a0f7c6b03e00000000000000000000000000002440000000000000d03f01",
        "02000000000000001f85eb51b89e2340000000000000f83f02000000000000000000000000001c400000000000002040",
        "02000000000000000000000000000000000000000000f0bf39300000000000000130010000000000004d42464d555330",
        "320400000000000000000000000000d03ffca9f1d24d62503f9a9999999999b93f9a9999999999c93f03000000000000",
        "00000000000000f03f00000000000004c0000000000000f87f0900000000000000000000000000f03f00000000000000",
        "00000000000000000000000000000000000000000000000000000000000000f0bf0000000000000000000000000000f0",
        "3f00000000000000000100000000000000000000000000e03f0100000000000000000000000000c0bf01000000000000",
        "00000000000000084002000000000000000000000000001c400000000000002040020000000000000000000000000000",
        "00000000000000f0bf0500000000000000fca9f1d24d62503f000000000000e03f0000000000000000000000000000f0",
        "3f00000000000000009c3d212cb75d1e0a",
    ];
    const WITHOUT_ENGINE: [&str; 4] = [
        "4d42464d5546303226000000000000007b30313233616263642d303030302d313131312d323232322d33333333343434",
        "34353535357d0004000000000000008dedb5a0f7c6b03e0000000000000000000000000000f87f000000000000d03f00",
        "02000000000000001f85eb51b89e2340000000000000f83f02000000000000000000000000001c400000000000002040",
        "02000000000000000000000000000000000000000000f0bf393000000000000000872e31260fb3d386",
    ];

    fn unhex(parts: &[&str]) -> Vec<u8> {
        let s: String = parts.concat();
        (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap()).collect()
    }

    #[test]
    fn states_saved_by_the_earlier_codec_load_and_serialize_to_the_same_bytes() {
        for (hex, state, stop, engine) in [
            (&WITH_ENGINE[..], State::StepComplete, Some(10.0), true),
            (&WITHOUT_ENGINE[..], State::Instantiated, None, false),
        ] {
            let old = unhex(hex);
            let s = FmuState::from_bytes(&old).unwrap();
            assert_eq!(s.to_bytes(), old);
            assert_eq!(s.guid, "{0123abcd-0000-1111-2222-333344445555}");
            assert_eq!(s.state, state);
            let want = Config {
                params: vec![9.81, 1.5],
                inputs: vec![7.0, 8.0],
                slopes: vec![0.0, -1.0],
                tol: 1e-6,
                start: 0.0,
                stop,
                max_steps: 12345,
            };
            assert_eq!(s.config, want);
            assert_eq!(s.last_time, 0.25);
            assert_eq!(s.sim.is_some(), engine);
            if let Some(sim) = &s.sim {
                assert_eq!((sim.t, sim.h, sim.y.len(), sim.integrator.len()), (0.25, 1e-3, 3, 5));
                assert!(sim.y[2].is_nan());
            }
            // A changed byte fails the checksum; a cut is refused.
            let mut bad = old.clone();
            bad[20] ^= 1;
            assert!(FmuState::from_bytes(&bad).unwrap_err().contains("checksum"));
            for cut in 0..old.len() {
                assert!(FmuState::from_bytes(&old[..cut]).is_err(), "cut at {cut}");
            }
        }
    }
}
