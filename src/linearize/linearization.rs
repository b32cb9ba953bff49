//! The result of a linearization: A, B, C, D at one operating point (seed Eq. 36), with
//! the names of the states, inputs and outputs.

use faer::Mat;

/// A, B, C, D at one operating point, with the names of states, inputs and outputs.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// Time of the operating point.
    pub time: f64,
    /// State names: S, then W (`der(S)`), then the differential states X.
    pub states: Vec<String>,
    /// Input names, in the model's order.
    pub inputs: Vec<String>,
    /// Output names, in the model's order.
    pub outputs: Vec<String>,
    /// A (ns × ns), B (ns × ni), C (no × ns), D (no × ni), ns = s0 + s1 + nx.
    pub a: Mat<f64>,
    /// See [`Linearization::a`].
    pub b: Mat<f64>,
    /// See [`Linearization::a`].
    pub c: Mat<f64>,
    /// See [`Linearization::a`].
    pub d: Mat<f64>,
    /// Values of the states (S, W, X) at the operating point.
    pub x: Vec<f64>,
    /// Systems solved with Eq. 34's LU: one per column of [A B] (states and inputs), or
    /// one per row of [A B; C D] that is not exact (the transposed route), whichever is
    /// fewer.
    pub solves: usize,
}
