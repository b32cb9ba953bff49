//! The external values ext = [inputs v; Z = (X, Ẋ, V, a); L] that element contexts read
//! besides (q, u, t): where each entry sits ([`ExtLayout`]) and which entries an
//! expression reads. Every offset into ext is computed here; the values themselves are
//! assembled by [`System::ext`] (see [`super::external_values`]).

use super::body::NQ;
use super::load_components::NLOAD;
use super::system::System;
use crate::model::expr::{ElementRef, Expr, deps};
use std::ops::Range;

/// Layout of the external values ext = [inputs v; Z = (X, Ẋ, V, a); L]: the inputs, the
/// user unknowns Z (differential states X, their rates Ẋ, variables V, accelerations a of
/// the bodies in `System::acc_bodies`) and the loads L of the elements in
/// `System::load_refs`, in this order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExtLayout {
    /// Number of inputs v.
    pub ni: usize,
    /// Number of differential states X (and of their rates Ẋ).
    pub nx: usize,
    /// Number of variables V.
    pub nv: usize,
    /// Number of acceleration entries a: 6 per acceleration body (v̇, then ω̇' in body
    /// axes), then the modal accelerations η̈ of the flexible bodies (modal order).
    pub na: usize,
    /// Number of load entries L: NLOAD per load reference.
    pub nl: usize,
}

/// What one entry of ext is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExtEntry {
    /// Input v_i.
    Input(usize),
    /// Entry i of Z = (X, Ẋ, V, a).
    Z(usize),
    /// Load of `System::load_refs[k]` (first field k), component c (second field, in the
    /// order of [`super::load_components::load_index`]).
    Load(usize, usize),
}

impl ExtLayout {
    /// The layout for `ni` inputs, `nx` differential states, `nv` variables, `acc_bodies`
    /// acceleration bodies, `neta` modal coordinates and `load_refs` load references.
    pub(super) fn new(ni: usize, nx: usize, nv: usize, acc_bodies: usize, neta: usize, load_refs: usize) -> ExtLayout {
        ExtLayout { ni, nx, nv, na: NQ * acc_bodies + neta, nl: NLOAD * load_refs }
    }
    /// Index of input v_i.
    pub fn input(&self, i: usize) -> usize {
        i
    }
    /// Index of differential state X_i.
    pub fn diff(&self, i: usize) -> usize {
        self.ni + i
    }
    /// Index of Ẋ_i.
    pub fn diff_dot(&self, i: usize) -> usize {
        self.ni + self.nx + i
    }
    /// Index of variable V_i.
    pub fn variable(&self, i: usize) -> usize {
        self.ni + 2 * self.nx + i
    }
    /// Index of the first acceleration component (v̇, then ω̇' in body axes) of body
    /// `acc_bodies[k]`.
    pub fn acc(&self, k: usize) -> usize {
        self.ni + 2 * self.nx + self.nv + NQ * k
    }
    /// Index of the first load component of `load_refs[k]`.
    pub fn load(&self, k: usize) -> usize {
        self.ni + self.nz() + NLOAD * k
    }
    /// Number of user unknowns Z = (X, Ẋ, V, a).
    pub fn nz(&self) -> usize {
        2 * self.nx + self.nv + self.na
    }
    /// Indices of Z.
    pub fn z_range(&self) -> Range<usize> {
        self.ni..self.ni + self.nz()
    }
    /// Indices of the loads L.
    pub fn loads_range(&self) -> Range<usize> {
        self.ni + self.nz()..self.len()
    }
    /// Number of external values.
    pub fn len(&self) -> usize {
        self.ni + self.nz() + self.nl
    }
    /// Whether there are no external values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// What entry `e` (< `len()`) is.
    pub fn entry(&self, e: usize) -> ExtEntry {
        assert!(e < self.len(), "external value {e} of {}", self.len());
        if e < self.ni {
            ExtEntry::Input(e)
        } else if e < self.ni + self.nz() {
            ExtEntry::Z(e - self.ni)
        } else {
            let l = e - self.ni - self.nz();
            ExtEntry::Load(l / NLOAD, l % NLOAD)
        }
    }

    /// The entries that the expressions `es` read, sorted, each once: inputs, X, Ẋ, V,
    /// the accelerations of those `acc_bodies` whose markers they measure at acceleration
    /// level (`body_of` maps markers to bodies), and the loads of those `load_refs` they read.
    pub(super) fn read_by(
        &self,
        acc_bodies: &[usize],
        load_refs: &[ElementRef],
        body_of: &dyn Fn(usize) -> Option<usize>,
        es: &[&Expr],
    ) -> Vec<usize> {
        let mut r = Vec::new();
        for e in es {
            let d = deps(e);
            if d.level >= 2 {
                for b in d.markers.iter().filter_map(|&m| body_of(m)) {
                    if let Some(k) = acc_bodies.iter().position(|&x| x == b) {
                        r.extend((0..NQ).map(|c| self.acc(k) + c));
                    }
                }
            }
            r.extend(d.inputs.iter().map(|&i| self.input(i)));
            r.extend(d.diffs.iter().map(|&i| self.diff(i)));
            r.extend(d.diff_dots.iter().map(|&i| self.diff_dot(i)));
            r.extend(d.variables.iter().map(|&i| self.variable(i)));
            for l in &d.loads {
                if let Some(k) = load_refs.iter().position(|x| x == l) {
                    r.extend((0..NLOAD).map(|c| self.load(k) + c));
                }
            }
        }
        r.sort_unstable();
        r.dedup();
        r
    }
}

impl System {
    /// Layout of the external values this system's elements read.
    pub fn ext_layout(&self) -> ExtLayout {
        let neta = self.modal_columns().len();
        ExtLayout::new(self.input_names.len(), self.nx, self.nv, self.acc_bodies.len(), neta, self.load_refs.len())
    }
    /// Number of inputs.
    pub fn ni(&self) -> usize {
        self.ext_layout().ni
    }
    /// Number of user unknowns Z = (X, Ẋ, V, a).
    pub fn nz(&self) -> usize {
        self.ext_layout().nz()
    }
    /// Index in ext of the first acceleration component of body `b`, if forces or user
    /// rows read its accelerations.
    pub fn ext_acc(&self, b: usize) -> Option<usize> {
        self.acc_bodies.iter().position(|&x| x == b).map(|k| self.ext_layout().acc(k))
    }
    /// Index in ext of element `e`'s load component `c`, if forces or user rows read that
    /// element's loads.
    pub fn ext_load_of(&self, e: ElementRef, c: usize) -> Option<usize> {
        self.load_refs.iter().position(|x| *x == e).map(|k| self.ext_layout().load(k) + c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_is_where_its_index_says() {
        let lay = ExtLayout::new(2, 3, 1, 2, 0, 1);
        assert_eq!((lay.nz(), lay.len()), (2 * 3 + 1 + 12, 2 + 19 + 6));
        assert_eq!((lay.z_range(), lay.loads_range()), (2..21, 21..27));
        let mut at = Vec::new();
        at.extend((0..2).map(|i| (lay.input(i), ExtEntry::Input(i))));
        at.extend((0..3).map(|i| (lay.diff(i), ExtEntry::Z(i))));
        at.extend((0..3).map(|i| (lay.diff_dot(i), ExtEntry::Z(3 + i))));
        at.push((lay.variable(0), ExtEntry::Z(6)));
        at.extend((0..2).flat_map(|k| (0..NQ).map(move |c| (lay.acc(k) + c, ExtEntry::Z(7 + NQ * k + c)))));
        at.extend((0..NLOAD).map(|c| (lay.load(0) + c, ExtEntry::Load(0, c))));
        assert_eq!(at.iter().map(|&(e, _)| e).collect::<Vec<_>>(), (0..lay.len()).collect::<Vec<_>>());
        for (e, what) in at {
            assert_eq!(lay.entry(e), what);
        }
    }
}
