//! The external values themselves: [inputs; Z; L] with the loads L evaluated at a state
//! (layout in [`super::external`]).

use super::load_components::NLOAD;
use super::loads::load_value;
use super::system::System;

impl System {
    /// The external values [inputs; Z; L] that element contexts read; the loads L are
    /// evaluated at `state` = (q, u, λ) (see [`super::loads`]); without λ (None) they are 0.
    pub fn ext(&self, inputs: &[f64], z: &[f64], state: Option<(&[f64], &[f64], &[f64])>, t: f64) -> Vec<f64> {
        let mut e = Vec::new();
        self.ext_into(inputs, z, state, t, &mut e);
        e
    }

    /// [`System::ext`] into `e` (its capacity reused).
    pub fn ext_into(
        &self,
        inputs: &[f64],
        z: &[f64],
        state: Option<(&[f64], &[f64], &[f64])>,
        t: f64,
        e: &mut Vec<f64>,
    ) {
        e.clear();
        e.reserve(inputs.len() + z.len() + self.ext_layout().nl);
        e.extend_from_slice(inputs);
        e.extend_from_slice(z);
        let base = e.len();
        for &r in &self.load_refs {
            // The loads read the values before them only.
            let v = state.and_then(|s| load_value(self, r, s, t, &e[..base])).unwrap_or([0.0; NLOAD]);
            e.extend_from_slice(&v);
        }
    }
}
