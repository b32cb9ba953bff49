//! C, its gradient and its Hessians of a joint between markers on rigid bodies (or
//! ground) in closed form, for the Jacobian's Ċ_q and (Pᵀλ)_q. Every equation of the
//! joint table ([`super::joint_table`]) is a sum of dot products x · y of marker-frame
//! vectors, each of which is a body's position (linear in its coordinates), a vector
//! A w fixed in a body (a function of its Euler angles only, second derivatives from
//! [`rotation_second`]) or a constant (ground, a unit vector); the product rule gives the
//! gradient and the Hessian of each dot product in plain numbers.

use super::body::{NQ, Turn, rotation_second, sin_cos};
use super::constraints::ConstraintEl;
use super::coords::nql;
use super::joint_table::{Row, equations, rigid_joint};
use super::system::System;
use crate::geom::{M3, V3};
use crate::model::JointType;

/// A marker-frame vector as a function of the element's local coordinates.
#[derive(Clone, Copy)]
#[allow(clippy::large_enum_variant)] // a short-lived stack value: boxing would only cost
enum Term {
    /// A constant.
    Const(V3<f64>),
    /// The position of the body whose coordinates start at local column `col`.
    Pos { col: usize, x: V3<f64> },
    /// A w of the body whose coordinates start at `col`: value, ∂/∂e_m, ∂²/∂e_m∂e_n.
    Turned { col: usize, v: V3<f64>, d: [V3<f64>; 3], dd: [[V3<f64>; 3]; 3] },
}

impl Term {
    fn value(&self) -> V3<f64> {
        match self {
            Term::Const(v) | Term::Pos { x: v, .. } | Term::Turned { v, .. } => *v,
        }
    }

    /// The first local column of the coordinates the vector depends on and its
    /// derivatives by those three (None: a constant).
    fn firsts(&self) -> Option<(usize, [V3<f64>; 3])> {
        match self {
            Term::Const(_) => None,
            Term::Pos { col, .. } => {
                Some((*col, std::array::from_fn(|r| V3(std::array::from_fn(|c| f64::from(r == c))))))
            }
            Term::Turned { col, d, .. } => Some((col + 3, *d)),
        }
    }
}

/// One joint equation's value, gradient and Hessian (row-major, stride `k`), accumulated.
struct Accum<'a> {
    k: usize,
    c: f64,
    g: &'a mut [f64],
    h: &'a mut [f64],
}

impl Accum<'_> {
    /// Add `sign` · x · y.
    fn dot(&mut self, x: &Term, y: &Term, sign: f64) {
        let (xv, yv, k) = (x.value(), y.value(), self.k);
        self.c += sign * xv.dot(&yv);
        for (a, b) in [(x, &yv), (y, &xv)] {
            if let Some((col, d)) = a.firsts() {
                for (m, dm) in d.iter().enumerate() {
                    self.g[col + m] += sign * dm.dot(b);
                }
            }
            if let Term::Turned { col, dd, .. } = a {
                for (m, row) in dd.iter().enumerate() {
                    let h = &mut self.h[(col + 3 + m) * k + col + 3..][..3];
                    h.iter_mut().zip(row).for_each(|(h, v)| *h += sign * v.dot(b));
                }
            }
        }
        if let (Some((cx, dx)), Some((cy, dy))) = (x.firsts(), y.firsts()) {
            for (m, dxm) in dx.iter().enumerate() {
                for (n, dyn_) in dy.iter().enumerate() {
                    let v = sign * dxm.dot(dyn_);
                    self.h[(cx + m) * k + cy + n] += v;
                    self.h[(cy + n) * k + cx + m] += v;
                }
            }
        }
    }
}

/// A marker's body: the first local column of its coordinates, its position, A and ∂A/∂e,
/// and ∂²A/∂e∂e.
type OnBody = (usize, V3<f64>, Turn<f64>, [[M3<f64>; 3]; 3]);

/// A marker in ground as a function of its body's coordinates.
struct Marker {
    /// Its body (None: ground).
    body: Option<OnBody>,
    s: V3<f64>,
    local_axes: [V3<f64>; 3],
}

impl Marker {
    fn new(sys: &System, el: &ConstraintEl, m: usize, q: &[f64]) -> Marker {
        let g = &sys.markers[m];
        let local_axes = std::array::from_fn(|k| V3(std::array::from_fn(|r| g.rot[r][k])));
        let body = g.body.map(|b| {
            let kb = el.bodies.iter().position(|&x| x == b).expect("a joint's marker body is one of its bodies");
            let qb = &q[NQ * b..NQ * b + NQ];
            let (s, c) = sin_cos(&qb[3..NQ]);
            (NQ * kb, V3([qb[0], qb[1], qb[2]]), Turn::of_sc(&sys.r0[b], s, c), rotation_second(&sys.r0[b], s, c))
        });
        Marker { body, s: V3(g.s), local_axes }
    }

    /// The vector `w` (body axes) in ground.
    fn turned(&self, w: &V3<f64>) -> Term {
        match &self.body {
            None => Term::Const(*w),
            Some((col, _, turn, dda)) => Term::Turned {
                col: *col,
                v: turn.a.mv(w),
                d: std::array::from_fn(|m| turn.da[m].mv(w)),
                dd: std::array::from_fn(|m| std::array::from_fn(|n| dda[m][n].mv(w))),
            },
        }
    }

    /// The marker's position as a sum of two terms.
    fn position(&self) -> [Term; 2] {
        match &self.body {
            None => [Term::Const(self.s), Term::Const(V3([0.0; 3]))],
            Some((col, x, ..)) => [Term::Pos { col: *col, x: *x }, self.turned(&self.s)],
        }
    }

    fn axis(&self, k: usize) -> Term {
        self.turned(&self.local_axes[k])
    }
}

/// C (`c`, neq), its gradient (`grad`, neq × k) and Hessians (`hess`, neq × k × k) over
/// z = (local q, t), k = nq + 1 (the t entries are zero), of a rigid joint of type `kind`
/// with markers `i`, `j` at global `q` (buffers overwritten, sized by the caller).
fn hessians(
    sys: &System,
    el: &ConstraintEl,
    (i, j, kind): (usize, usize, JointType),
    q: &[f64],
    k: usize,
    (c, grad, hess): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let (mi, mj) = (Marker::new(sys, el, i, q), Marker::new(sys, el, j, q));
    let (pi, pj) = (mi.position(), mj.position());
    grad.fill(0.0);
    hess.fill(0.0);
    for (e, eq) in equations(kind).iter().enumerate() {
        let mut acc = Accum { k, c: 0.0, g: &mut grad[e * k..(e + 1) * k], h: &mut hess[e * k * k..(e + 1) * k * k] };
        // d · w with d = p_i − p_j.
        let d_dot = |acc: &mut Accum, w: Term| {
            pi.iter().for_each(|t| acc.dot(t, &w, 1.0));
            pj.iter().for_each(|t| acc.dot(t, &w, -1.0));
        };
        match *eq {
            Row::D(r) => d_dot(&mut acc, Term::Const(V3(std::array::from_fn(|x| f64::from(x == r))))),
            Row::Axes(a, b) => acc.dot(&mi.axis(a), &mj.axis(b), 1.0),
            Row::DAxis(b) => d_dot(&mut acc, mj.axis(b)),
        }
        c[e] = acc.c;
    }
}

/// C, its gradient (neq × k) and Hessians (neq × k × k) over z = (local q, t), k = nq + 1
/// (the t entries are zero).
pub type Second = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The [`Second`] derivatives of `el` when it is a joint whose markers are on rigid
/// bodies or ground, between at most two bodies; None otherwise.
pub fn joint_second(sys: &System, el: &ConstraintEl, q: &[f64]) -> Option<Second> {
    let (mut c, mut grad, mut hess) = (Vec::new(), Vec::new(), Vec::new());
    joint_second_into(sys, el, q, &mut c, &mut grad, &mut hess).then_some((c, grad, hess))
}

/// [`joint_second`] into `c`, `grad` and `hess` (resized, capacities reused; global
/// `q`); false (nothing written) when `el` is not such a joint.
pub fn joint_second_into(
    sys: &System,
    el: &ConstraintEl,
    q: &[f64],
    c: &mut Vec<f64>,
    grad: &mut Vec<f64>,
    hess: &mut Vec<f64>,
) -> bool {
    let Some(joint) = rigid_joint(sys, el) else { return false };
    let nq = nql(sys, &el.bodies);
    if nq != NQ && nq != 2 * NQ {
        return false;
    }
    let (k, neq) = (nq + 1, el.neq);
    c.resize(neq, 0.0);
    grad.resize(neq * k, 0.0);
    hess.resize(neq * k * k, 0.0);
    hessians(sys, el, joint, q, k, (c, grad, hess));
    true
}
