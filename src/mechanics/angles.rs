//! What changes as the mechanism moves, apart from its coordinates: the Euler-angle
//! reference frames R0 (re-based away from the 3-1-3 singularity) and the branches of
//! the angle measures (unwrapped continuously). The integrator updates them after each
//! accepted step, assembly after each step of its continuation path. Rotational springs'
//! own branches (`ForceEl::angle_ref`) are recorded with the rest.

use super::body::{FAR_FROM_SINGULAR, NQ, rebased_reference};
use super::coords::{gather_into, rates_into};
use super::local::{AngleRecord, LocalCtx};
use super::system::System;
use crate::ad::{Dual, Real};
use crate::geom::{M3, rot313};

/// A body is re-based when |sin θ| falls below this (its 3-1-3 angles near singular).
const REBASE_SIN_THETA: f64 = 0.3;

impl System {
    /// Re-base the reference frame R0 of every body whose angles in `q` are near the
    /// 3-1-3 singularity or past ±π, so that its orientation reads
    /// [`FAR_FROM_SINGULAR`]; the pose is unchanged. Returns whether any body changed.
    pub fn rebase_frames(&mut self, q: &mut [f64]) -> bool {
        let mut changed = false;
        for b in 0..self.nb() {
            let o = NQ * b;
            let (psi, th, phi) = (q[o + 3], q[o + 4], q[o + 5]);
            let near_singular = th.sin().abs() < REBASE_SIN_THETA;
            let wrapped = psi.abs() > std::f64::consts::PI || phi.abs() > std::f64::consts::PI;
            if near_singular || wrapped {
                let a = M3::cst(&self.r0[b]).mm(&rot313(psi, th, phi)).val();
                self.r0[b] = rebased_reference(&a);
                q[o + 3..o + 6].copy_from_slice(&FAR_FROM_SINGULAR);
                changed = true;
            }
        }
        changed
    }

    /// Store the current value and rate of every angle measure at (t, q, u), so that
    /// expressions stay on its branch. Rates come from one evaluation with scalars seeded
    /// along the motion (q̇ = H(q) u, ṫ = 1; angle measures depend on positions only);
    /// `ext` holds the external values (a shorter slice reads the rest as NaN).
    pub fn record_angles(&mut self, t: f64, q: &[f64], u: &[f64], ext: &[f64]) {
        self.record_angles_with(&mut AngleScratch::default(), t, q, u, ext);
    }

    /// [`System::record_angles`] with reused buffers: once `ws` knows which elements hold
    /// angle measures (from its first use, with this system), only those are evaluated,
    /// and nothing is allocated.
    pub fn record_angles_with(&mut self, ws: &mut AngleScratch, t: f64, q: &[f64], u: &[f64], ext: &[f64]) {
        if self.angle_refs.is_empty() {
            return;
        }
        let first = ws.holders.is_none();
        let mut found = Holders::default();
        {
            let AngleScratch { holders, ids, qd, ud, scalars, out, rec } = ws;
            let all = Holders::default();
            let h = holders.as_ref().unwrap_or(&all);
            let sys = &*self;
            ids.clear();
            ids.extend(0..sys.nb());
            rates_into(sys.nb(), q, u, scalars);
            qd.clear();
            qd.extend(q.iter().zip(scalars.iter()).map(|(&v, &d)| D1 { v, d: [d] }));
            ud.clear();
            ud.extend(u.iter().map(|&v| D1::cst(v)));
            rec.get_mut().clear();
            let mut ctx = LocalCtx::new(sys, ids, qd, ud, &[], D1 { v: t, d: [1.0] }, ext);
            ctx.record = Some(rec);
            // Evaluate element k of a group when it is a holder (or on the first use);
            // note it when it recorded something.
            let visit = |group: &[usize], n: usize, found: &mut Vec<usize>, eval: &mut dyn FnMut(usize)| {
                let mut each = |k: usize| {
                    let before = rec.borrow().len();
                    eval(k);
                    if first && rec.borrow().len() > before {
                        found.push(k);
                    }
                };
                if first { (0..n).for_each(&mut each) } else { group.iter().copied().for_each(&mut each) }
            };
            visit(&h.users, sys.user.len(), &mut found.users, &mut |k| {
                sys.user[k].residual(&ctx);
            });
            visit(&h.constraints, sys.constraints.len(), &mut found.constraints, &mut |k| {
                let el = &sys.constraints[k];
                out.clear();
                out.resize(el.neq, D1::zero());
                el.kind.eval(&ctx, out);
            });
            visit(&h.forces, sys.forces.len(), &mut found.forces, &mut |k| {
                sys.forces[k].load(&ctx);
            });
            visit(&h.outputs, sys.outputs.len(), &mut found.outputs, &mut |k| {
                ctx.eval_expr(&sys.outputs[k], sys.output_bases[k]);
            });
            let (ns, nv) = (sys.lin_states.len(), sys.lin_velocities.len());
            visit(&h.lin, ns + nv, &mut found.lin, &mut |k| {
                let (_, e, b) = if k < ns { &sys.lin_states[k] } else { &sys.lin_velocities[k - ns] };
                ctx.eval_expr(e, *b);
            });
            visit(&h.coords, sys.joint_coords.len(), &mut found.coords, &mut |k| {
                let c = &sys.joint_coords[k];
                ctx.eval_expr(&c.f, c.abase);
            });
            visit(&h.nonholonomic, sys.nonholonomic.len(), &mut found.nonholonomic, &mut |k| {
                let el = &sys.nonholonomic[k];
                out.clear();
                out.resize(el.neq, D1::zero());
                el.kind.eval(&ctx, out);
            });
            drop(ctx);
            for &(g, v, rate) in rec.get_mut().iter() {
                // A measure that could not be evaluated (it reads a value not given) keeps its branch.
                if v.is_finite() {
                    self.angle_refs[g] = v;
                    self.angle_rates[g] = if rate.is_finite() { rate } else { 0.0 };
                }
            }
            self.angle_time = t;
        }
        // Rotational springs keep their own branch (their unwrapped az).
        let springs = if first {
            (0..self.forces.len()).collect()
        } else {
            std::mem::take(&mut ws.holders.as_mut().expect("known").springs)
        };
        for &k in &springs {
            let el = &self.forces[k];
            gather_into(self, &el.bodies, q, &mut ws.scalars);
            let ctx = LocalCtx::new(self, &el.bodies, &ws.scalars, &[], &[], t, ext);
            let a = el.angle(&ctx);
            drop(ctx);
            if first && a.is_some() {
                found.springs.push(k);
            }
            if let Some(a) = a.filter(|a| a.is_finite()) {
                self.forces[k].angle_ref = a;
            }
        }
        match &mut ws.holders {
            Some(h) => h.springs = springs,
            None => ws.holders = Some(found),
        }
    }
}

type D1 = Dual<f64, 1>;

/// The elements of each group that hold angle measures, by index.
#[derive(Clone, Debug, Default)]
struct Holders {
    users: Vec<usize>,
    constraints: Vec<usize>,
    forces: Vec<usize>,
    outputs: Vec<usize>,
    /// Linearization states, then velocities.
    lin: Vec<usize>,
    coords: Vec<usize>,
    nonholonomic: Vec<usize>,
    /// Rotational springs (their own branch).
    springs: Vec<usize>,
}

/// Buffers of [`System::record_angles_with`] for one system, and the elements of it that
/// hold angle measures.
#[derive(Debug, Default)]
pub struct AngleScratch {
    holders: Option<Holders>,
    ids: Vec<usize>,
    qd: Vec<D1>,
    ud: Vec<D1>,
    /// q̇ along the motion, then a rotational spring's local q.
    scalars: Vec<f64>,
    out: Vec<D1>,
    rec: AngleRecord,
}
