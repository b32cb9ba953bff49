//! Snapshots of a simulation (FMU states): what they hold, their byte form, and taking
//! and restoring them.

use super::bytes::{ByteReader, ByteWriter};
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

/// The magic tag of [`SimState::to_bytes`].
const STATE_MAGIC: &[u8; 8] = b"MBFMUS02";

impl SimState {
    /// Serialize: the magic `MBFMUS02`, then nine f64 arrays ([`ByteWriter::f64s`]):
    /// [t, h, t_in, angle_time], y, r0 (9 per body, row-major), angle_refs, angle_rates,
    /// spring_refs, inputs, slopes, integrator.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = ByteWriter::new(STATE_MAGIC);
        w.f64s(&[self.t, self.h, self.t_in, self.angle_time]);
        w.f64s(&self.y);
        w.f64s(&self.r0.iter().flatten().flatten().copied().collect::<Vec<f64>>());
        for v in [&self.angle_refs, &self.angle_rates, &self.spring_refs, &self.inputs, &self.slopes, &self.integrator]
        {
            w.f64s(v);
        }
        w.finish()
    }

    /// Deserialize what [`SimState::to_bytes`] wrote; anything else is an error.
    pub fn from_bytes(bytes: &[u8]) -> Result<SimState, EngineError> {
        let bad = || EngineError::Numeric("not a serialized mbfmu state".into());
        let mut r = ByteReader::tagged(bytes, STATE_MAGIC).ok_or_else(bad)?;
        let mut arr = || r.f64s().ok_or_else(bad);
        let head = arr()?;
        let y = arr()?;
        let r0f = arr()?;
        let (angle_refs, angle_rates) = (arr()?, arr()?);
        let (spring_refs, inputs, slopes, integrator) = (arr()?, arr()?, arr()?, arr()?);
        if head.len() != 4 || angle_rates.len() != angle_refs.len() || r0f.len() % 9 != 0 || !r.at_end() {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dae::SimOptions;

    /// A small state with every field distinct (and a NaN, which must survive as bits).
    fn small() -> SimState {
        SimState {
            t: 0.25,
            h: 1e-3,
            y: vec![1.0, -2.5, f64::NAN],
            r0: vec![[[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]],
            angle_refs: vec![0.5],
            angle_rates: vec![-0.125],
            angle_time: 0.2,
            spring_refs: vec![3.0],
            inputs: vec![7.0, 8.0],
            slopes: vec![0.0, -1.0],
            t_in: 0.1,
            integrator: vec![1e-3, 0.5, 0.0, 1.0, 0.0],
        }
    }

    /// `small()` as serialized by the codec before `dae::bytes` existed (commit e57e189).
    const SMALL_BYTES: [&str; 7] = [
        "4d42464d555330320400000000000000000000000000d03ffca9f1d24d62503f9a9999999999b93f9a9999999999c93f",
        "0300000000000000000000000000f03f00000000000004c0000000000000f87f0900000000000000000000000000f03f",
        "0000000000000000000000000000000000000000000000000000000000000000000000000000f0bf0000000000000000",
        "000000000000f03f00000000000000000100000000000000000000000000e03f0100000000000000000000000000c0bf",
        "0100000000000000000000000000084002000000000000000000000000001c4000000000000020400200000000000000",
        "0000000000000000000000000000f0bf0500000000000000fca9f1d24d62503f000000000000e03f0000000000000000",
        "000000000000f03f0000000000000000",
    ];

    fn unhex(parts: &[&str]) -> Vec<u8> {
        let s: String = parts.concat();
        (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap()).collect()
    }

    /// The format by its definition: magic, then each array as a u64 length and its
    /// values, all little-endian.
    fn by_definition(s: &SimState) -> Vec<u8> {
        let mut b = b"MBFMUS02".to_vec();
        let r0: Vec<f64> = s.r0.iter().flatten().flatten().copied().collect();
        let head = [s.t, s.h, s.t_in, s.angle_time];
        for v in
            [&head[..], &s.y, &r0, &s.angle_refs, &s.angle_rates, &s.spring_refs, &s.inputs, &s.slopes, &s.integrator]
        {
            b.extend_from_slice(&(v.len() as u64).to_le_bytes());
            v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
        }
        b
    }

    #[test]
    fn states_saved_by_the_earlier_codec_load_and_serialize_to_the_same_bytes() {
        let old = unhex(&SMALL_BYTES);
        assert_eq!(small().to_bytes(), old);
        let back = SimState::from_bytes(&old).unwrap();
        assert_eq!(back.to_bytes(), old);
        assert!(back.y[2].is_nan());
        assert_eq!((back.t, back.h, back.t_in, back.angle_time), (0.25, 1e-3, 0.1, 0.2));
        assert_eq!(back.r0, small().r0);
        assert_eq!(back.integrator, small().integrator);
    }

    #[test]
    fn a_running_simulation_serializes_as_the_format_defines() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/double_pendulum.xml");
        let m = crate::model::parse::load_file(&path).unwrap();
        let mut sim = Simulator::new(&m, SimOptions::default(), 0.0).unwrap();
        sim.advance(0.3).unwrap();
        let snap = sim.snapshot();
        let bytes = snap.to_bytes();
        assert_eq!(bytes, by_definition(&snap));
        assert_eq!(SimState::from_bytes(&bytes).unwrap(), snap);
        // Every truncation and a trailing byte are refused.
        for cut in 0..bytes.len() {
            assert!(SimState::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(SimState::from_bytes(&longer).is_err());
    }
}
