//! The local view of an element: the states of the few bodies it touches, as [`Real`]
//! scalars (f64, or dual numbers seeded on those bodies' coordinates), and the
//! [`ExprEnv`] that expressions read.

use super::body::{NQ, body_frame};
use super::coords::local_modal_range;
use super::external::ExtLayout;
use super::load_components::load_index;
use super::system::System;
use crate::ad::Real;
use crate::geom::{M3, V3};
use crate::model::expr::{ElementRef, Expr, ExprEnv, LoadFn, MarkerId, ModalFn, Pose, Twist, eval};
use std::cell::{Cell, RefCell};

/// State of one body as seen by an element.
#[derive(Clone, Copy, Debug)]
pub struct LocalBody<T: Real> {
    /// CM position (ground).
    pub r: V3<T>,
    /// Rotation (columns = body axes in ground).
    pub a: M3<T>,
    /// CM velocity (ground).
    pub v: V3<T>,
    /// Angular velocity, body axes.
    pub w: V3<T>,
    /// CM acceleration (ground).
    pub acc: V3<T>,
    /// Angular acceleration, body axes.
    pub wdot: V3<T>,
}

/// Recorded angle measures: (global slot, value, rate).
pub type AngleRecord = RefCell<Vec<(usize, f64, f64)>>;

/// Element-local evaluation context.
pub struct LocalCtx<'a, T: Real> {
    /// The system the element belongs to.
    pub sys: &'a System,
    /// Global indices of the bodies this context holds, in local order.
    pub ids: &'a [usize],
    /// State of each body in `ids`, same order.
    pub bodies: Vec<LocalBody<T>>,
    /// Time.
    pub t: T,
    /// External values ext = [inputs; Z; L] (layout: [`ExtLayout`], values:
    /// [`System::ext`]); a shorter slice (e.g. inputs only) reads the missing entries as NaN.
    pub inputs: &'a [f64],
    /// Layout of `inputs`.
    ext: ExtLayout,
    /// Element loads for `fx(...)` (outputs only), as scalars of this context (constants,
    /// or dual numbers seeded on the loads themselves); `None` reads as NaN.
    pub loads: Option<&'a dyn Fn(LoadFn, ElementRef) -> T>,
    /// First global angle slot of the expression being evaluated.
    angle_base: Cell<usize>,
    /// When set, every unwrapped angle is recorded as (global slot, value, rate): the rate
    /// is the first derivative the scalars carry (a time direction, when so seeded).
    pub record: Option<&'a AngleRecord>,
    /// Whether accelerations were given (else they are zero, or external values).
    has_udot: bool,
    /// When set, inputs and user unknowns read these (e.g. seeded dual numbers, same
    /// layout as `inputs`) instead of `inputs`.
    pub input_values: Option<Vec<T>>,
    /// Per local body: its modal coordinates η, rates η̇ and accelerations η̈ (empty for a
    /// rigid body; rates and accelerations zero when not given). Entries past the last
    /// local body are spare buffers, never read.
    modal: Vec<[Vec<T>; 3]>,
}

/// A node marker's offset and rotation in body axes with their rates: ([p, ṗ, p̈],
/// [θ, θ̇, θ̈]).
type NodeMotion<T> = ([V3<T>; 3], [V3<T>; 3]);

/// A node marker's deflection in body axes: Σ_k v_k x_k over the modes.
fn modal_sum<T: Real>(v: &[[f64; 3]], x: &[T]) -> V3<T> {
    let mut s = [T::zero(); 3];
    for (vk, xk) in v.iter().zip(x) {
        for (sc, &c) in s.iter_mut().zip(vk) {
            if c != 0.0 {
                sc.add_scaled(xk, c);
            }
        }
    }
    V3(s)
}

impl<'a, T: Real> LocalCtx<'a, T> {
    /// Build from local coordinates `q` (6 per body, then the modal coordinates of the
    /// flexible ones: [`super::coords`]), velocities `u` and accelerations `udot` (same
    /// layout, may be empty = zero).
    pub fn new(sys: &'a System, ids: &'a [usize], q: &[T], u: &[T], udot: &[T], t: T, inputs: &'a [f64]) -> Self {
        let (mut bodies, mut modal) = spare::take::<T>();
        // Entries past ids.len() are left as they are (never read): their buffers stay.
        if modal.len() < ids.len() {
            modal.resize_with(ids.len(), Default::default);
        }
        for (k, m) in modal.iter_mut().take(ids.len()).enumerate() {
            let r = local_modal_range(sys, ids, k);
            for (part, x) in m.iter_mut().zip([q, u, udot]) {
                part.clear();
                if x.is_empty() {
                    part.resize(r.len(), T::zero());
                } else {
                    part.extend_from_slice(&x[r.clone()]);
                }
            }
        }
        bodies.extend(ids.iter().enumerate().map(|(k, &b)| {
            let (r, a) = body_frame(&q[NQ * k..NQ * k + NQ], &sys.r0[b]);
            let get = |x: &[T], o: usize| {
                if x.is_empty() { V3::zero() } else { V3([x[NQ * k + o], x[NQ * k + o + 1], x[NQ * k + o + 2]]) }
            };
            LocalBody { r, a, v: get(u, 0), w: get(u, 3), acc: get(udot, 0), wdot: get(udot, 3) }
        }));
        LocalCtx {
            sys,
            ids,
            bodies,
            t,
            inputs,
            ext: sys.ext_layout(),
            loads: None,
            has_udot: !udot.is_empty(),
            angle_base: Cell::new(0),
            record: None,
            input_values: None,
            modal,
        }
    }

    /// Modal coordinate `k` of local body `local` (a flexible body).
    pub fn modal_coordinate(&self, local: usize, k: usize) -> T {
        self.modal[local][0][k]
    }

    /// A node marker's body-frame offset p = s + Φt η and rotation θ = Φr η with their
    /// rates up to order `level` (0, 1 or 2; higher rates are left zero): ([p, ṗ, p̈],
    /// [θ, θ̇, θ̈]). None: the marker is rigidly attached.
    fn node_motion(&self, m: MarkerId, level: usize) -> Option<NodeMotion<T>> {
        let shape = self.sys.markers[m].node.as_ref()?;
        let modal = &self.modal[self.local(self.sys.markers[m].body?)];
        let (mut p, mut th) = ([V3::zero(); 3], [V3::zero(); 3]);
        for (l, x) in modal.iter().enumerate().take(level + 1) {
            p[l] = modal_sum(&shape.phi, x);
            th[l] = modal_sum(&shape.rho, x);
        }
        p[0] = self.offset(m) + p[0];
        Some((p, th))
    }

    /// Evaluate expression `e` whose angle measures use global slots from `angle_base`.
    pub fn eval_expr(&self, e: &Expr, angle_base: usize) -> T {
        self.angle_base.set(angle_base);
        eval(e, self)
    }

    /// Local index of global body `b`.
    pub fn local(&self, b: usize) -> usize {
        // A context over all bodies in order (angle recording, whole-system passes) finds
        // b at b: no search, which would make such a pass quadratic in the bodies.
        if self.ids.get(b) == Some(&b) {
            return b;
        }
        self.ids.iter().position(|&x| x == b).expect("element touches body")
    }

    /// Body (local) of marker `m`, or None for ground.
    pub fn marker_body(&self, m: MarkerId) -> Option<&LocalBody<T>> {
        self.sys.markers[m].body.map(|b| &self.bodies[self.local(b)])
    }

    /// Entry `k` of the external values (NaN beyond the slice).
    pub fn ext_value(&self, k: usize) -> T {
        match &self.input_values {
            Some(v) => v.get(k).copied().unwrap_or(T::cst(f64::NAN)),
            None => T::cst(self.inputs.get(k).copied().unwrap_or(f64::NAN)),
        }
    }

    /// Offset of marker `m` from its body's CM, body axes.
    fn offset(&self, m: MarkerId) -> V3<T> {
        V3::cst(self.sys.markers[m].s)
    }
}

impl<T: Real> ExprEnv<T> for LocalCtx<'_, T> {
    fn time(&self) -> T {
        self.t
    }
    fn param(&self, i: usize) -> T {
        T::cst(self.sys.params[i])
    }
    fn input(&self, i: usize) -> T {
        self.ext_value(self.ext.input(i))
    }
    fn variable(&self, i: usize) -> T {
        self.ext_value(self.ext.variable(i))
    }
    fn diff(&self, i: usize) -> T {
        self.ext_value(self.ext.diff(i))
    }
    fn diff_dot(&self, i: usize) -> T {
        self.ext_value(self.ext.diff_dot(i))
    }
    fn pose(&self, m: MarkerId) -> Pose<T> {
        let g = &self.sys.markers[m];
        if let (Some(b), Some(([p, _, _], [th, _, _]))) = (self.marker_body(m), self.node_motion(m, 0)) {
            // The node turns by the small rotation θ: axes (I + θ×) · marker axes.
            let o = T::one();
            let turn = M3([[o, -th.0[2], th.0[1]], [th.0[2], o, -th.0[0]], [-th.0[1], th.0[0], o]]);
            return Pose { p: b.r + b.a.mv(&p), r: b.a.mm(&turn).mm(&M3::cst(&g.rot)) };
        }
        match self.marker_body(m) {
            None => Pose { p: V3::cst(g.s), r: M3::cst(&g.rot) },
            Some(b) => Pose { p: b.r + b.a.mv(&self.offset(m)), r: b.a.mm(&M3::cst(&g.rot)) },
        }
    }
    fn twist(&self, m: MarkerId) -> Twist<T> {
        if let (Some(b), Some(([p, pd, _], [_, thd, _]))) = (self.marker_body(m), self.node_motion(m, 1)) {
            return Twist { v: b.v + b.a.mv(&(b.w.cross(&p) + pd)), w: b.a.mv(&(b.w + thd)) };
        }
        match self.marker_body(m) {
            None => Twist { v: V3::zero(), w: V3::zero() },
            Some(b) => {
                let s = self.offset(m);
                Twist { v: b.v + b.a.mv(&b.w.cross(&s)), w: b.a.mv(&b.w) }
            }
        }
    }
    fn accel(&self, m: MarkerId) -> Twist<T> {
        if let (Some(b), Some(([p, pd, pdd], [_, thd, thdd]))) = (self.marker_body(m), self.node_motion(m, 2)) {
            // Given accelerations only: forces and user rows do not read a flexible
            // body's accelerations (refused when the system is built).
            let two = T::cst(2.0);
            let rel = b.wdot.cross(&p) + b.w.cross(&b.w.cross(&p)) + b.w.cross(&pd).mul_s(two) + pdd;
            return Twist { v: b.acc + b.a.mv(&rel), w: b.a.mv(&(b.wdot + thdd + b.w.cross(&thd))) };
        }
        match self.marker_body(m) {
            None => Twist { v: V3::zero(), w: V3::zero() },
            Some(b) => {
                // Without given accelerations, a body whose accelerations are unknowns of
                // the DAE (`System::acc_bodies`) reads them from the external values.
                let (acc, wdot) = match (self.has_udot, self.sys.markers[m].body.and_then(|g| self.sys.ext_acc(g))) {
                    (false, Some(k)) => {
                        let e = |c: usize| self.ext_value(k + c);
                        (V3([e(0), e(1), e(2)]), V3([e(3), e(4), e(5)]))
                    }
                    _ => (b.acc, b.wdot),
                };
                let s = self.offset(m);
                let rel = wdot.cross(&s) + b.w.cross(&b.w.cross(&s));
                Twist { v: acc + b.a.mv(&rel), w: b.a.mv(&wdot) }
            }
        }
    }
    fn load(&self, f: LoadFn, e: ElementRef) -> T {
        match self.loads {
            Some(l) => l(f, e),
            // Forces and user rows read loads as external values (see `System::load_refs`).
            None => match self.sys.ext_load_of(e, load_index(f)) {
                Some(k) => self.ext_value(k),
                None => T::cst(f64::NAN),
            },
        }
    }
    /// η_k or η̇_k of the body marker `m` is on (NaN for a rigid body or ground; the
    /// parser only lets flexible bodies' modes through).
    fn modal(&self, f: ModalFn, m: MarkerId, k: usize) -> T {
        // self.modal[l] holds η, η̇, η̈: indexed by the measure's derivative level.
        let local = self.sys.markers[m].body.map(|b| self.local(b));
        local.and_then(|l| self.modal[l][usize::from(f.level())].get(k).copied()).unwrap_or(T::cst(f64::NAN))
    }
    /// Angles stay on the branch nearest their value at the last accepted step.
    fn unwrap_angle(&self, slot: usize, a: T) -> T {
        let g = self.angle_base.get() + slot;
        // The branch nearest the reference extrapolated with its rate to this time, so a
        // fast rotation stays continuous over steps longer than half a turn.
        let r = self.sys.angle_refs.get(g).copied().unwrap_or(f64::NAN);
        let rate = self.sys.angle_rates.get(g).copied().filter(|v| v.is_finite()).unwrap_or(0.0);
        let r = r + rate * (self.t.val() - self.sys.angle_time);
        let two_pi = 2.0 * std::f64::consts::PI;
        let out = if r.is_finite() { a + T::cst(two_pi * ((r - a.val()) / two_pi).round()) } else { a };
        if let Some(rec) = self.record {
            rec.borrow_mut().push((g, out.val(), out.tangent()));
        }
        out
    }
}

impl<T: Real> Drop for LocalCtx<'_, T> {
    fn drop(&mut self) {
        spare::give(std::mem::take(&mut self.bodies), std::mem::take(&mut self.modal));
    }
}

/// The buffers of dropped contexts, per scalar type and thread, for the next ones: once
/// warm, building a context allocates nothing (the integrator's step loop, the outputs a
/// co-simulation master reads at every communication point).
mod spare {
    use super::LocalBody;
    use crate::ad::Real;
    use std::any::{Any, TypeId};
    use std::cell::RefCell;

    /// Buffers of one scalar type: (bodies, modal) pairs.
    type Buffers<T> = Vec<(Vec<LocalBody<T>>, Vec<[Vec<T>; 3]>)>;

    /// At most this many buffer pairs are kept per type (contexts alive at once: nested
    /// evaluations hold a few).
    const KEEP: usize = 16;

    thread_local! {
        static SPARE: RefCell<Vec<(TypeId, Box<dyn Any>)>> = const { RefCell::new(Vec::new()) };
    }

    /// Empty `bodies` and a `modal` of any length (entries to be overwritten), from the
    /// spares when there are some.
    pub(super) fn take<T: Real>() -> (Vec<LocalBody<T>>, Vec<[Vec<T>; 3]>) {
        let got = SPARE.try_with(|s| {
            let mut s = s.try_borrow_mut().ok()?;
            let (_, any) = s.iter_mut().find(|(id, _)| *id == TypeId::of::<T>())?;
            any.downcast_mut::<Buffers<T>>()?.pop()
        });
        got.ok().flatten().unwrap_or_default()
    }

    /// Keep a context's buffers for the next one (dropped when the thread ends).
    pub(super) fn give<T: Real>(mut bodies: Vec<LocalBody<T>>, modal: Vec<[Vec<T>; 3]>) {
        if bodies.capacity() == 0 && modal.capacity() == 0 {
            return;
        }
        bodies.clear();
        let _ = SPARE.try_with(|s| {
            let Ok(mut s) = s.try_borrow_mut() else { return };
            if !s.iter().any(|(id, _)| *id == TypeId::of::<T>()) {
                s.push((TypeId::of::<T>(), Box::new(Buffers::<T>::new())));
            }
            let (_, any) = s.iter_mut().find(|(id, _)| *id == TypeId::of::<T>()).expect("just inserted");
            if let Some(list) = any.downcast_mut::<Buffers<T>>()
                && list.len() < KEEP
            {
                list.push((bodies, modal));
            }
        });
    }
}
