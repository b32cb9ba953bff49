//! C, C_q and the Hessians of a joint between markers on rigid bodies (or ground) in
//! closed form. The integrator needs C and C_q at every evaluation of f(t, y) (the
//! constraint rows and −Pᵀλ, −C_qᵀμ) and the Hessians at every Jacobian (Ċ_q, (Pᵀλ)_q),
//! where the general dual-number kernels ([`super::kernels::constraint_first_ad`],
//! nested duals for the Hessians) carry 13 (or 13 × 13) derivative lanes through every
//! operation. Here each body's rotation and its three partial derivatives are formed once
//! and the gradient is written out; the Hessians come from [`super::joint_hessian`], in
//! closed form too. The equations are those of
//! [`super::constraint_equations`] (the model format's joint table); a test holds the
//! two to round-off.

use super::body::{NQ, Turn};
use super::constraints::ConstraintEl;
#[cfg(test)]
use super::coords::nql;
use super::joint_table::{Row, equations, rigid_joint};
use super::system::System;
use crate::ad::Real;
use crate::geom::{M3, V3};
use crate::model::JointType;

/// A marker in ground: position, axes, and their derivatives by its body's Euler angles.
struct Frame<T: Real> {
    /// First local column of its body's coordinates (None: ground).
    col: Option<usize>,
    p: V3<T>,
    /// Axes in ground (axes[k] = k-th axis).
    axes: [V3<T>; 3],
    /// Axes in body axes.
    local_axes: [V3<T>; 3],
    /// ∂A/∂(ψ, θ, φ) of its body.
    da: [M3<T>; 3],
    /// ∂p/∂(ψ, θ, φ): dp[k] = ∂A/∂e_k · s (s: the offset in body axes).
    dp: [V3<T>; 3],
}

impl<T: Real> Frame<T> {
    /// Marker `m` of element `el`; `qb(k)` gives the six coordinates of the element's
    /// local body k, `turns` the [`Turn`] of every body (None: computed here from `qb`).
    fn new<'q>(
        sys: &System,
        el: &ConstraintEl,
        m: usize,
        qb: impl Fn(usize) -> &'q [T],
        turns: Option<&[Turn<T>]>,
    ) -> Frame<T>
    where
        T: 'q,
    {
        let g = &sys.markers[m];
        let local_axes: [V3<T>; 3] = std::array::from_fn(|k| V3(std::array::from_fn(|r| T::cst(g.rot[r][k]))));
        let s = V3(g.s.map(T::cst));
        let Some(b) = g.body else {
            let zero = [V3([T::zero(); 3]); 3];
            return Frame { col: None, p: s, axes: local_axes, local_axes, da: [M3([[T::zero(); 3]; 3]); 3], dp: zero };
        };
        let kb = el.bodies.iter().position(|&x| x == b).expect("a joint's marker body is one of its bodies");
        let qb = qb(kb);
        let own;
        let turn = match turns {
            Some(t) => &t[b],
            None => {
                own = Turn::of(&sys.r0[b], &qb[3..NQ]);
                &own
            }
        };
        Frame {
            col: Some(NQ * kb),
            p: V3([qb[0], qb[1], qb[2]]) + turn.a.mv(&s),
            axes: std::array::from_fn(|k| turn.a.mv(&local_axes[k])),
            local_axes,
            da: turn.da,
            dp: std::array::from_fn(|k| turn.da[k].mv(&s)),
        }
    }

    /// ∂(A v)/∂(ψ, θ, φ) for a vector `v` in body axes.
    fn d(&self, v: &V3<T>) -> [V3<T>; 3] {
        std::array::from_fn(|k| self.da[k].mv(v))
    }

    /// Add `sign` · `w` · `dv` to the Euler-angle entries of the gradient row `g`, `dv`
    /// the derivatives of a vector by its body's Euler angles (`dp`, or [`Frame::d`]).
    fn add_turn(&self, g: &mut [T], dv: &[V3<T>; 3], w: &V3<T>, sign: f64) {
        if let Some(c) = self.col {
            for k in 0..3 {
                g[c + 3 + k] += w.dot(&dv[k]).scale(sign);
            }
        }
    }

    /// Add `sign` · `w` · ∂p/∂(its body's coordinates) to the gradient row `g`.
    fn add_point(&self, g: &mut [T], w: &V3<T>, sign: f64) {
        if let Some(c) = self.col {
            for k in 0..3 {
                g[c + k] += w.0[k].scale(sign);
            }
            self.add_turn(g, &self.dp, w, sign);
        }
    }
}

/// C and C_q (row-major neq × nq, into `c` and `cq`) of a rigid joint with marker frames
/// `fi`, `fj`.
fn rows<T: Real>(kind: JointType, fi: &Frame<T>, fj: &Frame<T>, c: &mut [T], cq: &mut [T]) {
    let eqs = equations(kind);
    let nq = cq.len() / eqs.len();
    cq.fill(T::zero());
    let d = fi.p - fj.p;
    for (e, eq) in eqs.iter().enumerate() {
        let g = &mut cq[e * nq..(e + 1) * nq];
        match *eq {
            Row::D(k) => {
                let unit = V3(std::array::from_fn(|r| if r == k { T::one() } else { T::zero() }));
                c[e] = d.0[k];
                fi.add_point(g, &unit, 1.0);
                fj.add_point(g, &unit, -1.0);
            }
            Row::Axes(a, b) => {
                c[e] = fi.axes[a].dot(&fj.axes[b]);
                fi.add_turn(g, &fi.d(&fi.local_axes[a]), &fj.axes[b], 1.0);
                fj.add_turn(g, &fj.d(&fj.local_axes[b]), &fi.axes[a], 1.0);
            }
            Row::DAxis(b) => {
                c[e] = d.dot(&fj.axes[b]);
                fi.add_point(g, &fj.axes[b], 1.0);
                fj.add_point(g, &fj.axes[b], -1.0);
                fj.add_turn(g, &fj.d(&fj.local_axes[b]), &d, 1.0);
            }
        }
    }
}

/// C and C_q (local, row-major neq × nq; C_t is zero: a joint does not depend on time)
/// of `el` when it is a joint whose markers are on rigid bodies or ground; None
/// otherwise, for the general kernel. The integrator calls [`joint_first_into`]; this
/// form serves the test that holds the closed form to the dual-number kernels.
#[cfg(test)]
pub fn joint_first(sys: &System, el: &ConstraintEl, q: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
    rigid_joint(sys, el)?;
    let (mut c, mut cq) = (vec![0.0; el.neq], vec![0.0; el.neq * nql(sys, &el.bodies)]);
    joint_first_into(sys, el, q, None, &mut c, &mut cq);
    Some((c, cq))
}

/// [`joint_first`] into `c` (neq) and `cq` (neq × nq), with the bodies' turns (global q,
/// `turns` indexed by body; None: computed here); false (nothing written) when `el` is not
/// such a joint.
pub fn joint_first_into(
    sys: &System,
    el: &ConstraintEl,
    q: &[f64],
    turns: Option<&[Turn<f64>]>,
    c: &mut [f64],
    cq: &mut [f64],
) -> bool {
    let Some((i, j, kind)) = rigid_joint(sys, el) else { return false };
    let qb = |k: usize| &q[NQ * el.bodies[k]..NQ * el.bodies[k] + NQ];
    let (fi, fj) = (Frame::new(sys, el, i, qb, turns), Frame::new(sys, el, j, qb, turns));
    rows(kind, &fi, &fj, c, cq);
    true
}
