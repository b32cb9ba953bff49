//! FMI 3 call-sequence fuzzing: random legal and illegal orders of the FMI 3 exports over
//! every rigid example model, with bad value references, hostile values and steps, wrong array
//! lengths, NULL pointers, FMU-state round trips, derivatives of random subsets, the
//! functions of what the FMU lacks. What must hold: the process survives, no call panics
//! inside (the guard would log "internal error (panic)"), every status is OK, Warning,
//! Discard or Error, no value handed out with fmi3OK is not finite, and the instance is
//! freed cleanly at the end. `MBFMU_FMI3_SEQUENCES` (default 10 per model) sets how many.

use crate::common::host::resources_of;
use crate::common::{guid_of, model_files};
use crate::fmi_sequences::Rng;
use mbfmu::fmi::exports3_common::*;
use mbfmu::fmi::exports3_cs::*;
use mbfmu::fmi::exports3_other::*;
use mbfmu::fmi::types::{Component, FmuStatePtr, Status};
use mbfmu::fmi::variables::{Standard, variables};
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::sync::Mutex;

/// The instance's log: `instanceEnvironment` points to it.
type Log = Mutex<Vec<String>>;

unsafe extern "C" fn log_message(env: *mut c_void, _status: c_int, _category: *const c_char, message: *const c_char) {
    // SAFETY: `env` is the `Log` the test passed; `message` a NUL-terminated string.
    let (log, text) = unsafe { (&*(env as *const Log), CStr::from_ptr(message).to_string_lossy().into_owned()) };
    log.lock().unwrap().push(text);
}

fn allowed(s: Status) -> bool {
    matches!(s, Status::Ok | Status::Warning | Status::Discard | Status::Error)
}

/// One random sequence on the model `path`.
fn sequence(path: &std::path::Path, seed: u64) {
    let (top, _) = resources_of(path, "fmi3");
    let res = CString::new(format!("{}/", top.join("resources").display())).unwrap();
    let token = CString::new(guid_of(path)).unwrap();
    let model = mbfmu::model::load_file(path).unwrap();
    let layout = mbfmu::linearize::StateLayout::at_start(&model);
    let vars = variables(&model, &layout, Standard::Fmi3);
    let n = vars.len() as u32;
    let max_steps = vars.iter().find(|v| v.name == "solver.maxSteps").unwrap().value_reference;
    let log: Box<Log> = Box::new(Mutex::new(Vec::new()));
    let env = &*log as *const Log as *mut c_void;
    let name = c"fuzz";
    // SAFETY: valid strings, a NULL intermediate-variable list of length 0.
    let c: Component = unsafe {
        fmi3InstantiateCoSimulation(
            name.as_ptr(),
            token.as_ptr(),
            res.as_ptr(),
            0,
            1,
            (seed % 2) as u8,
            0,
            std::ptr::null(),
            0,
            env,
            Some(log_message),
            std::ptr::null(),
        )
    };
    assert!(!c.is_null(), "{}: {:?}", path.display(), log.lock().unwrap());
    // SAFETY: one value reference and value.
    assert_eq!(unsafe { fmi3SetInt32(c, &max_steps, 1, &300, 1) }, Status::Ok);
    let mut rng = Rng(seed);
    let mut t = 0.0;
    let mut saved: Vec<FmuStatePtr> = Vec::new();
    for _ in 0..40 {
        let vr: Vec<u32> = (0..1 + rng.below(4)).map(|_| rng.below(n as usize + 2) as u32).collect();
        let mut out = vec![0.0; vr.len()];
        let (mut b1, mut b2, mut b3, mut b4, mut b5) = (0u8, 0u8, 0u8, 0u8, 0u8);
        let mut last = 0.0;
        // SAFETY (every call below): arrays of the lengths passed, or NULL on purpose.
        let status = unsafe {
            match rng.below(16) {
                0 => fmi3EnterInitializationMode(c, 1, 1e-6, 0.0, 0, 0.0),
                1 => fmi3ExitInitializationMode(c),
                2 => fmi3EnterEventMode(c),
                3 => fmi3EnterStepMode(c),
                4 => fmi3UpdateDiscreteStates(c, &mut b1, &mut b2, &mut b3, &mut b4, &mut b5, &mut last),
                5 | 6 => {
                    let h = [0.01, 0.001, 0.0, -1.0, 1e30, f64::NAN][rng.below(6)];
                    let s = fmi3DoStep(c, t, h, 1, &mut b1, &mut b2, &mut b3, &mut last);
                    if matches!(s, Status::Ok | Status::Discard) {
                        t = last;
                    }
                    s
                }
                7 => {
                    let s = fmi3GetFloat64(c, vr.as_ptr(), vr.len(), out.as_mut_ptr(), out.len());
                    if s == Status::Ok {
                        assert!(out.iter().all(|v| v.is_finite()), "{out:?}");
                    }
                    s
                }
                8 => {
                    let v: Vec<f64> = vr.iter().map(|_| rng.real()).collect();
                    fmi3SetFloat64(c, vr.as_ptr(), vr.len(), v.as_ptr(), v.len() + rng.below(2))
                }
                9 | 10 => {
                    let k: Vec<u32> = (0..1 + rng.below(3)).map(|_| rng.below(n as usize) as u32).collect();
                    let seed_v: Vec<f64> = (0..vr.len().max(k.len())).map(|_| rng.real()).collect();
                    let mut sens = vec![0.0; vr.len().max(k.len())];
                    let (ns, nsens) = if rng.below(2) == 0 { (k.len(), vr.len()) } else { (vr.len(), k.len()) };
                    let f = if rng.below(2) == 0 { fmi3GetDirectionalDerivative } else { fmi3GetAdjointDerivative };
                    f(c, vr.as_ptr(), vr.len(), k.as_ptr(), k.len(), seed_v.as_ptr(), ns, sens.as_mut_ptr(), nsens)
                }
                11 => {
                    let mut s: FmuStatePtr = std::ptr::null_mut();
                    let st = fmi3GetFMUState(c, &mut s);
                    if st == Status::Ok {
                        saved.push(s);
                    }
                    st
                }
                12 if !saved.is_empty() => {
                    let s = saved[rng.below(saved.len())];
                    let mut size = 0usize;
                    let st = fmi3SerializedFMUStateSize(c, s, &mut size);
                    if st != Status::Ok {
                        st
                    } else {
                        let mut bytes = vec![0u8; size];
                        assert_eq!(fmi3SerializeFMUState(c, s, bytes.as_mut_ptr(), size), Status::Ok);
                        let mut back: FmuStatePtr = std::ptr::null_mut();
                        assert_eq!(fmi3DeserializeFMUState(c, bytes.as_ptr(), size, &mut back), Status::Ok);
                        let st = fmi3SetFMUState(c, back);
                        if st == Status::Ok {
                            t = {
                                let tv = n - 1;
                                let mut x = 0.0;
                                let _ = fmi3GetFloat64(c, &tv, 1, &mut x, 1);
                                x
                            };
                        }
                        assert_eq!(fmi3FreeFMUState(c, &mut back), Status::Ok);
                        st
                    }
                }
                13 => fmi3GetInt8(c, vr.as_ptr(), vr.len(), std::ptr::null_mut(), vr.len()),
                14 => fmi3Terminate(c),
                _ => {
                    let s = fmi3Reset(c);
                    t = 0.0;
                    if s == Status::Ok {
                        let _ = fmi3SetInt32(c, &max_steps, 1, &300, 1);
                    }
                    s
                }
            }
        };
        assert!(allowed(status), "{}: status {status:?}", path.display());
    }
    for mut s in saved {
        // SAFETY: a state this instance handed out.
        assert_eq!(unsafe { fmi3FreeFMUState(c, &mut s) }, Status::Ok);
    }
    // SAFETY: the live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
    let log = log.lock().unwrap();
    assert!(!log.iter().any(|m| m.contains("internal error (panic)")), "{}: {log:?}", path.display());
}

#[test]
fn random_fmi3_call_sequences_never_crash_or_panic() {
    let per_model: u64 = std::env::var("MBFMU_FMI3_SEQUENCES").ok().and_then(|v| v.parse().ok()).unwrap_or(10);
    // The rigid example models (the flexible ones need their modal data packed beside the
    // layout, which the FMI 2 fuzz covers through the same shell).
    let rigid = model_files().into_iter().filter(|p| p.parent().is_some_and(|d| d.ends_with("models")));
    for (m, path) in rigid.enumerate() {
        let path = &path;
        for k in 0..per_model {
            sequence(path, 1000 * m as u64 + k);
        }
    }
}
