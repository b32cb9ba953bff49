//! The external values themselves: [inputs; Z; L] with the loads L evaluated at a state
//! (layout in [`super::external`]).

use super::load_components::NLOAD;
use super::loads::load_value;
use super::system::System;

impl System {
    /// The external values [inputs; Z; L] that element contexts read; the loads L are
    /// evaluated at `state` = (q, u, λ) (see [`super::loads`]); without λ (None) they are 0.
    pub fn ext(&self, inputs: &[f64], z: &[f64], state: Option<(&[f64], &[f64], &[f64])>, t: f64) -> Vec<f64> {
        let mut e = Vec::with_capacity(inputs.len() + z.len() + self.ext_layout().nl);
        e.extend_from_slice(inputs);
        e.extend_from_slice(z);
        let base = e.clone();
        for &r in &self.load_refs {
            let v = state.and_then(|s| load_value(self, r, s, t, &base)).unwrap_or([0.0; NLOAD]);
            e.extend_from_slice(&v);
        }
        e
    }
}
