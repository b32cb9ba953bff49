//! The FMU states an instance handed out (2.1.8): the fmi2FMUstate pointers are the
//! addresses of boxes this set owns, so a pointer the instance did not hand out, or one
//! already freed, is refused instead of dereferenced; whatever the host leaves unfreed is
//! freed with the instance.

use super::fmu_state::FmuState;
use super::types::FmuStatePtr;
use std::collections::HashMap;

/// The live FMU states of one instance, by the address handed to the host.
#[derive(Default)]
pub struct StateHandles {
    live: HashMap<usize, Box<FmuState>>,
}

impl StateHandles {
    /// The state behind `p`.
    pub fn get(&self, p: FmuStatePtr) -> Result<&FmuState, String> {
        self.live.get(&(p as usize)).map(|b| b.as_ref()).ok_or_else(|| unknown(p))
    }

    /// Store `s`: into the live state `old` when not NULL (FMI: a non-NULL `*FMUstate` is
    /// one returned before, to be overwritten), else in a new one. Returns its handle.
    pub fn store(&mut self, old: FmuStatePtr, s: FmuState) -> Result<FmuStatePtr, String> {
        if !old.is_null() {
            **self.live.get_mut(&(old as usize)).ok_or_else(|| unknown(old))? = s;
            return Ok(old);
        }
        let b = Box::new(s);
        let p: *const FmuState = b.as_ref();
        self.live.insert(p as usize, b);
        Ok(p.cast_mut().cast())
    }

    /// Free the state behind `p` (NULL: nothing).
    pub fn free(&mut self, p: FmuStatePtr) -> Result<(), String> {
        if p.is_null() {
            return Ok(());
        }
        self.live.remove(&(p as usize)).map(drop).ok_or_else(|| unknown(p))
    }

    /// How many states are live.
    pub fn len(&self) -> usize {
        self.live.len()
    }

    /// Whether no state is live.
    pub fn is_empty(&self) -> bool {
        self.live.is_empty()
    }
}

fn unknown(p: FmuStatePtr) -> String {
    if p.is_null() {
        return "FMUstate is NULL".into();
    }
    format!("FMUstate {p:p} is not a live state of this instance (freed, or from another instance)")
}
