//! Products with the linearization one seed at a time, without forming A, B, C, D:
//! Eq. 34 factored once at an operating point, then [A B; C D]·s by one solve of the
//! combined right-hand side Σ s_c R_c (FMI directional derivatives), and vᵀ[A B; C D] by
//! one solve of the transposed system with the combined functional Σ v_r g_r (FMI 3
//! adjoint derivatives; the transposed route of [`super::augmented`]). Where state and
//! input columns differ (an output reads q and u only through state columns) each kind
//! takes its own solve, so a call costs at most two solves and matches the full
//! linearization's entries to round-off.

use super::assemble::{Assembled, assemble};
use super::augmented::{at_point, singular};
use super::eq34::Eq34;
use super::extract::no_finite_derivative;
use super::operating_point::OperatingPoint;
use super::rhs::RightHandSides;
use super::select::Selection;
use super::sensitivity::Sensitivities;
use crate::dae::sparse::SparseLu;
use crate::dae::{EngineError, Simulator};

/// Eq. 34 factored at one operating point, for products with [A B; C D]: the knowns
/// (columns) are the states S, W, X, then the inputs; the unknowns (rows) are Ṡ, Ẇ, Ẋ,
/// then the outputs.
pub struct Seeded {
    eq: Eq34,
    lu: SparseLu,
    rhs: RightHandSides,
    sens: Sensitivities,
    /// For each position state S_k: the velocity state W_j = Ṡ_k, whose row of A is
    /// exactly e_(s0+j) and of B zero (Eq. 34g–h).
    kin: Vec<Option<usize>>,
    ni: usize,
    /// The outputs' names (for messages).
    outputs: Vec<String>,
    /// The error of a solve that fails (the states stop parameterizing the motion).
    singular: String,
    solves: usize,
}

impl Seeded {
    /// Eq. 34 at the current point of `sim` in the states of `sel`, factored.
    pub fn at(sim: &mut Simulator, sel: &Selection) -> Result<Seeded, EngineError> {
        at_point(sim, sel, Seeded::of)
    }

    fn of(p: &OperatingPoint) -> Result<Seeded, EngineError> {
        let Assembled { k, .. } = assemble(p);
        let mut lu = SparseLu::new();
        lu.factor(p.eq.dim(), &k).map_err(|_| singular(p))?;
        let kin = (0..p.eq.s0).map(|k| p.sel.velocity_of_state(k)).collect();
        Ok(Seeded {
            eq: p.eq,
            lu,
            rhs: RightHandSides::of(p),
            sens: Sensitivities::of(p),
            kin,
            ni: p.ni(),
            outputs: p.sys.output_names.clone(),
            singular: singular(p).to_string(),
            solves: 0,
        })
    }

    /// Number of knowns: states, then inputs (columns of [A B; C D]).
    pub fn knowns(&self) -> usize {
        self.eq.ns() + self.ni
    }

    /// Number of unknowns: state derivatives, then outputs (rows of [A B; C D]).
    pub fn unknowns(&self) -> usize {
        self.eq.ns() + self.sens.outputs()
    }

    /// Systems solved with the factorization so far.
    pub fn solves(&self) -> usize {
        self.solves
    }

    /// One solve of Eq. 34 (or its transpose) with the right-hand side `fill` writes into
    /// a zeroed vector; Ok(None) when it writes nothing (the solution is zero), Err when
    /// the solution is not finite.
    fn solve(lu: &SparseLu, eq: &Eq34, transpose: bool, fill: impl Fn(&mut [f64])) -> Result<Option<Vec<f64>>, ()> {
        let mut b = vec![0.0; eq.dim()];
        fill(&mut b);
        if b.iter().all(|v| *v == 0.0) {
            return Ok(None);
        }
        let x = lu.solve_columns(1, 1, transpose, |_, col| col.copy_from_slice(&b), |_, x| x.to_vec());
        x.and_then(|mut v| v.pop()).map(Some).ok_or(())
    }

    /// [`Seeded::solve`], counted, with the error of a singular system.
    fn counted(&mut self, x: Result<Option<Vec<f64>>, ()>) -> Result<Option<Vec<f64>>, EngineError> {
        let x = x.map_err(|_| EngineError::Numeric(self.singular.clone()))?;
        self.solves += x.is_some() as usize;
        Ok(x)
    }

    /// [A B; C D]·`seed` (`seed` over the knowns, the result over the unknowns): one solve
    /// for the state part of the seed and one for its input part.
    pub fn directional(&mut self, seed: &[f64]) -> Result<Vec<f64>, EngineError> {
        let (ns, s0) = (self.eq.ns(), self.eq.s0);
        assert_eq!(seed.len(), self.knowns(), "one seed value per known");
        let mut out = vec![0.0; self.unknowns()];
        for kinematic in [true, false] {
            let cols = if kinematic { 0..ns } else { ns..ns + self.ni };
            let rhs = &self.rhs;
            let fill = |b: &mut [f64]| {
                for c in cols.clone().filter(|&c| seed[c] != 0.0) {
                    rhs.add(rhs.column(c), seed[c], b);
                }
            };
            let x = Seeded::solve(&self.lu, &self.eq, false, fill);
            if let Some(x) = self.counted(x)? {
                for (o, k) in out.iter_mut().zip(self.sens.keep_as(kinematic, &x)) {
                    *o += k;
                }
            }
        }
        for (k, j) in self.kin.iter().enumerate() {
            if let Some(j) = j {
                out[k] = seed[s0 + j];
            }
        }
        for o in 0..self.sens.outputs() {
            out[ns + o] += (0..self.ni).map(|v| self.sens.direct(o, v) * seed[ns + v]).sum::<f64>();
        }
        Ok(out)
    }

    /// `seed`ᵀ·[A B; C D] (`seed` over the unknowns, the result over the knowns): one
    /// transposed solve for the state columns and, when outputs are seeded, one for the
    /// input columns (their functionals differ there).
    pub fn adjoint(&mut self, seed: &[f64]) -> Result<Vec<f64>, EngineError> {
        let (ns, s0) = (self.eq.ns(), self.eq.s0);
        assert_eq!(seed.len(), self.unknowns(), "one seed value per unknown");
        let exact: Vec<bool> = (0..seed.len()).map(|r| r < s0 && self.kin[r].is_some()).collect();
        let outputs_seeded = seed[ns..].iter().any(|v| *v != 0.0);
        let mut out = vec![0.0; self.knowns()];
        let kinds: &[(bool, std::ops::Range<usize>)] =
            if outputs_seeded { &[(true, 0..ns), (false, ns..ns + self.ni)] } else { &[(true, 0..ns + self.ni)] };
        for (kinematic, cols) in kinds.iter().cloned() {
            let nonfinite =
                (0..self.outputs.len()).find(|&o| seed[ns + o] != 0.0 && !self.sens.row_finite(ns + o, kinematic));
            if let Some(o) = nonfinite {
                return Err(no_finite_derivative(&self.outputs[o]));
            }
            let sens = &self.sens;
            let fill = |g: &mut [f64]| {
                for r in (0..seed.len()).filter(|&r| seed[r] != 0.0 && !exact[r]) {
                    sens.add_functional(r, kinematic, seed[r], g);
                }
            };
            let z = Seeded::solve(&self.lu, &self.eq, true, fill);
            if let Some(z) = self.counted(z)? {
                for c in cols {
                    out[c] = self.rhs.apply(self.rhs.column(c), &z);
                }
            }
        }
        for (k, j) in self.kin.iter().enumerate() {
            if let Some(j) = j {
                out[s0 + j] += seed[k];
            }
        }
        for v in 0..self.ni {
            out[ns + v] += (0..self.sens.outputs()).map(|o| seed[ns + o] * self.sens.direct(o, v)).sum::<f64>();
        }
        Ok(out)
    }
}
