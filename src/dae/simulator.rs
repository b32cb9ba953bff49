//! Public face of the engine: build, initialize, advance, read results.

use super::equations::{self, Layout};
use super::init;
use super::radau::{DEFAULT_MAX_STEPS, DaeProblem, Radau, Stats};
use super::sparse::{SparseLu, Triplets};
use crate::ad::Real;
use crate::geom::{M3, V3, rot313};
use crate::mechanics::System;
use crate::mechanics::body::{NQ, body_frame};
use crate::mechanics::loads::{load_index, load_value};
use crate::mechanics::local::LocalCtx;
use crate::mechanics::system::{FAR_FROM_SINGULAR, rebased_reference};
use crate::model::expr::{ElementRef, LoadFn};
use crate::model::{Model, ModelError};

/// Engine failure.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EngineError {
    /// The model cannot be set up as written (e.g. it cannot be assembled), located at the
    /// element to blame: `file:line:col: element 'name': what is wrong`.
    #[error("{0}")]
    Model(ModelError),
    /// A numerical failure (integration, singular equations).
    #[error("{0}")]
    Numeric(String),
}

impl From<String> for EngineError {
    fn from(s: String) -> Self {
        EngineError::Numeric(s)
    }
}

/// Integrator options.
#[derive(Clone, Copy, Debug)]
pub struct SimOptions {
    /// Local error tolerance (relative and absolute) of positions and velocities; also
    /// the assembly tolerance of the constraints.
    pub tol: f64,
    /// Largest step the integrator may take (None: unlimited).
    pub max_step: Option<f64>,
    /// Most integrator step attempts (accepted and rejected) per [`Simulator::advance`]
    /// call; more is an error at the time reached (default [`DEFAULT_MAX_STEPS`]).
    pub max_steps: usize,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions { tol: 1e-6, max_step: None, max_steps: DEFAULT_MAX_STEPS }
    }
}

/// Kinematic state of one body, ground components.
#[derive(Clone, Copy, Debug)]
pub struct BodyState {
    /// CM position.
    pub position: [f64; 3],
    /// Rotation matrix (row-major; columns = body axes in ground).
    pub rotation: [[f64; 3]; 3],
    /// CM velocity.
    pub velocity: [f64; 3],
    /// Angular velocity.
    pub angular_velocity: [f64; 3],
}

/// A complete simulation state: restoring it reproduces the run bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct SimState {
    pub t: f64,
    /// Next step size.
    pub h: f64,
    /// [q; u; λ; μ].
    pub y: Vec<f64>,
    /// Euler-angle reference frames.
    pub r0: Vec<[[f64; 3]; 3]>,
    /// Angle-unwrapping references of expressions (values, rates, their time) and of
    /// rotational springs.
    pub angle_refs: Vec<f64>,
    pub angle_rates: Vec<f64>,
    pub angle_time: f64,
    pub spring_refs: Vec<f64>,
    pub inputs: Vec<f64>,
    pub slopes: Vec<f64>,
    pub t_in: f64,
    /// The integrator's step history ([`crate::dae::radau::Radau::memory`]).
    pub integrator: Vec<f64>,
}

const STATE_MAGIC: &[u8; 8] = b"MBFMUS02";

impl SimState {
    /// Serialize (little-endian f64 arrays with lengths, behind a magic tag).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = STATE_MAGIC.to_vec();
        let mut arr = |v: &[f64]| {
            b.extend_from_slice(&(v.len() as u64).to_le_bytes());
            for x in v {
                b.extend_from_slice(&x.to_le_bytes());
            }
        };
        arr(&[self.t, self.h, self.t_in, self.angle_time]);
        arr(&self.y);
        arr(&self.r0.iter().flatten().flatten().copied().collect::<Vec<f64>>());
        arr(&self.angle_refs);
        arr(&self.angle_rates);
        arr(&self.spring_refs);
        arr(&self.inputs);
        arr(&self.slopes);
        arr(&self.integrator);
        b
    }

    /// Deserialize what [`SimState::to_bytes`] wrote.
    pub fn from_bytes(bytes: &[u8]) -> Result<SimState, EngineError> {
        let bad = || EngineError::Numeric("not a serialized mbfmu state".into());
        let rest = bytes.strip_prefix(STATE_MAGIC.as_slice()).ok_or_else(bad)?;
        let mut pos = 0usize;
        let mut arr = || -> Result<Vec<f64>, EngineError> {
            let len_bytes = rest.get(pos..pos + 8).ok_or_else(bad)?;
            let n = u64::from_le_bytes(len_bytes.try_into().map_err(|_| bad())?) as usize;
            pos += 8;
            let end = n.checked_mul(8).and_then(|k| k.checked_add(pos)).ok_or_else(bad)?;
            let data = rest.get(pos..end).ok_or_else(bad)?;
            pos = end;
            Ok(data.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect())
        };
        let head = arr()?;
        let y = arr()?;
        let r0f = arr()?;
        let (angle_refs, angle_rates) = (arr()?, arr()?);
        let (spring_refs, inputs, slopes, integrator) = (arr()?, arr()?, arr()?, arr()?);
        if head.len() != 4 || angle_rates.len() != angle_refs.len() || r0f.len() % 9 != 0 || pos != rest.len() {
            return Err(bad());
        }
        let r0 = r0f.chunks_exact(9).map(|c| [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]]).collect();
        Ok(SimState {
            t: head[0],
            h: head[1],
            t_in: head[2],
            angle_time: head[3],
            y,
            r0,
            angle_refs,
            angle_rates,
            spring_refs,
            inputs,
            slopes,
            integrator,
        })
    }
}

/// The multibody DAE handed to the integrator.
struct MultibodyDae {
    sys: System,
    lay: Layout,
    /// Input values at time `t_in`, and their slopes (linear interpolation over a step).
    inputs: Vec<f64>,
    slopes: Vec<f64>,
    t_in: f64,
}

impl DaeProblem for MultibodyDae {
    fn dim(&self) -> usize {
        self.lay.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), String> {
        equations::rhs(&self.sys, self.lay, t, y, &self.inputs_at(t), f);
        if f.iter().all(|v| v.is_finite()) { Ok(()) } else { Err("non-finite equations".into()) }
    }
    fn jacobian(&mut self, t: f64, y: &[f64], j: &mut Triplets) -> Result<(), String> {
        equations::jacobian(&self.sys, self.lay, t, y, &self.inputs_at(t), j);
        Ok(())
    }
    fn mass(&self, m: &mut Triplets) {
        equations::mass_matrix(&self.sys, self.lay, m);
    }
    fn index(&self) -> Vec<u8> {
        // q, u, X and the index-1 user unknowns (Ẋ, V): error-controlled; accelerations a
        // (solved with λ from the velocity constraints), λ, ν, μ: index 2.
        let a0 = self.lay.acc();
        (0..self.lay.dim()).map(|i| if i < a0 { 0 } else { 2 }).collect()
    }
    fn accepted(&mut self, t: f64, y: &mut [f64]) -> bool {
        let mut changed = false;
        for b in 0..self.sys.nb() {
            let o = NQ * b;
            let (th, psi, phi) = (y[o + 4], y[o + 3], y[o + 5]);
            let near_singular = th.sin().abs() < 0.3;
            let wrapped = psi.abs() > std::f64::consts::PI || phi.abs() > std::f64::consts::PI;
            if near_singular || wrapped {
                // Re-base: choose R0 so the body's current orientation has angles (0, π/2, 0).
                let a = M3::cst(&self.sys.r0[b]).mm(&rot313(psi, th, phi)).val();
                self.sys.r0[b] = rebased_reference(&a);
                y[o + 3..o + 6].copy_from_slice(&FAR_FROM_SINGULAR);
                changed = true;
            }
        }
        let n = self.lay.n;
        let ext = self.lay.ext(&self.sys, &self.inputs_at(t), y, t);
        self.record_angles(t, &y[..n], &y[n..2 * n], &ext);
        let inputs = ext;
        for k in 0..self.sys.forces.len() {
            let el = &self.sys.forces[k];
            let ql = crate::mechanics::kernels::gather(&el.bodies, &y[..n]);
            let ctx = LocalCtx::new(&self.sys, &el.bodies, &ql, &[], &[], t, &inputs);
            if let Some(a) = el.angle(&ctx) {
                self.sys.forces[k].angle_ref = a;
            }
        }
        changed
    }
}

impl MultibodyDae {
    /// Inputs at time t: held values plus slope · (t − t_in).
    fn inputs_at(&self, t: f64) -> Vec<f64> {
        self.inputs.iter().zip(&self.slopes).map(|(v, s)| v + s * (t - self.t_in)).collect()
    }

    /// Store the current value and rate of every angle measure, so expressions stay on
    /// its branch. Rates come from one evaluation with scalars seeded along the motion
    /// (q̇ = H(q) u, ṫ = 1; angle measures depend on positions only).
    fn record_angles(&mut self, t: f64, q: &[f64], u: &[f64], inputs: &[f64]) {
        if self.sys.angle_refs.is_empty() {
            return;
        }
        let rec = std::cell::RefCell::new(Vec::new());
        {
            let sys = &self.sys;
            let ids: Vec<usize> = (0..sys.nb()).collect();
            type D1 = crate::ad::Dual<f64, 1>;
            let mut qd: Vec<D1> = Vec::with_capacity(q.len());
            for (qb, ub) in q.chunks_exact(NQ).zip(u.chunks_exact(NQ)) {
                let rate = crate::mechanics::body::qdot(qb, ub);
                qd.extend(qb.iter().zip(rate).map(|(&v, d)| D1 { v, d: [d] }));
            }
            let ud: Vec<D1> = u.iter().map(|&v| D1::cst(v)).collect();
            let mut ctx = LocalCtx::new(sys, &ids, &qd, &ud, &[], D1 { v: t, d: [1.0] }, inputs);
            ctx.record = Some(&rec);
            for ue in &sys.user {
                ue.residual(&ctx);
            }
            for el in &sys.constraints {
                let mut out = vec![D1::zero(); el.neq];
                el.kind.eval(&ctx, &mut out);
            }
            for el in &sys.forces {
                el.load(&ctx);
            }
            for (e, &b) in sys.outputs.iter().zip(&sys.output_bases) {
                ctx.eval_expr(e, b);
            }
            for (_, e, b) in sys.lin_states.iter().chain(&sys.lin_velocities) {
                ctx.eval_expr(e, *b);
            }
            for c in &sys.joint_coords {
                ctx.eval_expr(&c.f, c.abase);
            }
            for el in &sys.nonholonomic {
                let mut out = vec![D1::zero(); el.neq];
                el.kind.eval(&ctx, &mut out);
            }
        }
        for (g, v, rate) in rec.into_inner() {
            self.sys.angle_refs[g] = v;
            self.sys.angle_rates[g] = rate;
        }
        self.sys.angle_time = t;
    }
}

/// Assembly moving a body's CM by more than this fraction of the model's size (the
/// diagonal of the box around the initial CM positions and the ground origin, at least
/// 1 m) is reported: the geometry as written is probably not the mechanism meant.
pub const ASSEMBLY_MOVE_FRACTION: f64 = 0.01;

/// A running simulation of one model.
pub struct Simulator {
    dae: MultibodyDae,
    radau: Radau,
    acc_lu: SparseLu,
    /// Accelerations and multipliers at the current time (None: not yet computed).
    acc: Option<(Vec<f64>, Vec<f64>)>,
    /// What initialization wants the user to know (bodies that assembly moved far).
    warnings: Vec<String>,
}

/// Bodies whose CM assembly moved by more than [`ASSEMBLY_MOVE_FRACTION`] of the model's
/// size, as messages naming the body and the distance.
fn assembly_moves(model: &Model, q0: &[f64], q: &[f64]) -> Vec<String> {
    let cm = |q: &[f64], b: usize| [q[NQ * b], q[NQ * b + 1], q[NQ * b + 2]];
    let (mut lo, mut hi) = ([0.0f64; 3], [0.0f64; 3]);
    for b in 0..model.bodies.len() {
        for (k, x) in cm(q0, b).into_iter().enumerate() {
            lo[k] = lo[k].min(x);
            hi[k] = hi[k].max(x);
        }
    }
    let size = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt().max(1.0);
    (0..model.bodies.len())
        .filter_map(|b| {
            let (a, z) = (cm(q0, b), cm(q, b));
            let d = (0..3).map(|k| (z[k] - a[k]).powi(2)).sum::<f64>().sqrt();
            (d > ASSEMBLY_MOVE_FRACTION * size).then(|| {
                format!(
                    "assembly moved body '{}' by {d:.3e} m (more than {} of the model's size {size:.3e} m): \
                     the initial geometry may not be the mechanism meant",
                    model.bodies[b].name, ASSEMBLY_MOVE_FRACTION
                )
            })
        })
        .collect()
}

impl Simulator {
    /// Build the equations and initialize at `t0` (assembly, consistent velocities,
    /// accelerations and multipliers).
    pub fn new(model: &Model, opts: SimOptions, t0: f64) -> Result<Simulator, EngineError> {
        let mut sys = System::from_model(model).map_err(EngineError::Numeric)?;
        let inputs: Vec<f64> = model.inputs.iter().map(|i| i.start.value).collect();
        let lay = Layout::of(&sys);
        let mut q = sys.q_init.clone();
        let mut u = sys.u_init.clone();
        let assembly_tol = (opts.tol * 1e-3).max(1e-14);
        sys.redundant = init::redundant_rows(&sys, &q, t0, &inputs);
        init::assemble_positions(&sys, &mut q, t0, &inputs, assembly_tol).map_err(|e| match e.element {
            Some(b) => EngineError::Model(ModelError {
                file: model.file.clone(),
                pos: b.0.pos,
                element: b.0.tag.into(),
                name: b.0.name.clone(),
                msg: if b.0.neq > 1 { format!("{} (equation {} of {})", e.msg, b.1, b.0.neq) } else { e.msg },
            }),
            None => EngineError::Numeric(e.msg),
        })?;
        let (sys_q0, assembled) = (sys.q_init.clone(), q.clone());
        let mut z = vec![0.0; lay.nz()];
        z[..lay.nx].copy_from_slice(&sys.x_init);
        if model.static_analysis {
            u.iter_mut().for_each(|v| *v = 0.0);
            init::user_unknowns(&sys, &q, &u, None, t0, &inputs, &mut z).map_err(EngineError::Numeric)?;
            init::static_equilibrium(&sys, &mut q, &mut z, t0, &inputs, assembly_tol).map_err(EngineError::Numeric)?;
        }
        init::assemble_velocities(&sys, &q, &mut u, t0, &inputs).map_err(EngineError::Numeric)?;
        let mut acc_lu = SparseLu::new();
        let (udot, lam) = init::consistent_accelerations(&sys, &q, &u, t0, &inputs, &mut z, &mut acc_lu)
            .map_err(EngineError::Numeric)?;
        let mut y = vec![0.0; lay.dim()];
        y[..lay.n].copy_from_slice(&q);
        y[lay.u()..lay.u() + lay.n].copy_from_slice(&u);
        y[lay.z()..lay.z() + lay.nz()].copy_from_slice(&z);
        y[lay.lam()..lay.lam() + lay.m + lay.mn].copy_from_slice(&lam); // λ then ν
        let slopes = vec![0.0; inputs.len()];
        let mut dae = MultibodyDae { sys, lay, inputs, slopes, t_in: t0 };
        dae.accepted(t0, &mut y);
        let mut radau = Radau::new(&dae, t0, y, opts.tol);
        if let Some(h) = opts.max_step {
            radau.max_step = h;
        }
        radau.max_steps = opts.max_steps.max(1);
        let warnings = assembly_moves(model, &sys_q0, &assembled);
        Ok(Simulator { dae, radau, acc_lu, acc: Some((udot, lam)), warnings })
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.radau.t
    }

    /// Change the limit on integrator step attempts per [`Simulator::advance`] call (at
    /// least 1).
    pub fn set_max_steps(&mut self, n: usize) {
        self.radau.max_steps = n.max(1);
    }

    /// The limit on integrator step attempts per [`Simulator::advance`] call.
    pub fn max_steps(&self) -> usize {
        self.radau.max_steps
    }

    /// Integrate to `t_end` exactly (the last step lands on it). On an error (the step
    /// limit, a step-size collapse) the simulation stays at the last accepted step:
    /// [`Simulator::time`] is the time reached.
    pub fn advance(&mut self, t_end: f64) -> Result<(), EngineError> {
        if t_end < self.radau.t {
            return Err(EngineError::Numeric(format!("cannot integrate backwards from {} to {t_end}", self.radau.t)));
        }
        self.acc = None;
        // Each call recomputes the Jacobian from (t, y): a communication point is a restart
        // point, so a saved state (with the step history) reproduces the run exactly.
        self.radau.restart();
        self.radau.advance(&mut self.dae, t_end).map_err(EngineError::Numeric)
    }

    /// Integrator statistics so far.
    pub fn stats(&self) -> Stats {
        self.radau.stats
    }

    /// The mechanical system (with its current Euler-angle reference frames).
    pub fn system(&self) -> &System {
        &self.dae.sys
    }

    /// Current coordinates q.
    pub fn q(&self) -> &[f64] {
        &self.radau.y[..self.dae.lay.n]
    }

    /// Current velocities u.
    pub fn u(&self) -> &[f64] {
        let l = self.dae.lay;
        &self.radau.y[l.u()..l.u() + l.n]
    }

    /// Accelerations u̇ and multipliers λ at the current time (Eq. 1c–1d).
    pub fn accelerations(&mut self) -> Result<(Vec<f64>, Vec<f64>), EngineError> {
        if self.acc.is_none() {
            let (q, u) = (self.q().to_vec(), self.u().to_vec());
            let s = &self.dae;
            let t = self.radau.t;
            self.acc = Some(if s.sys.load_refs.is_empty() && s.sys.acc_bodies.is_empty() {
                let ext = self.ext();
                init::accelerations(&s.sys, &q, &u, t, &ext, &mut self.acc_lu).map_err(EngineError::Numeric)?
            } else {
                // Loads in the loop: λ (and the loads) solved together, as at initialization.
                let mut z = self.user_values().to_vec();
                let inputs = s.inputs_at(t);
                init::consistent_accelerations(&s.sys, &q, &u, t, &inputs, &mut z, &mut self.acc_lu)
                    .map_err(EngineError::Numeric)?
            });
        }
        Ok(self.acc.clone().expect("just computed"))
    }

    /// Names of the model's `<output>`s, in order.
    pub fn output_names(&self) -> Vec<String> {
        self.dae.sys.output_names.clone()
    }

    /// Values of the `<output>`s at the current time.
    pub fn outputs(&mut self) -> Result<Vec<f64>, EngineError> {
        let (udot, lam) = self.accelerations()?;
        let sys = &self.dae.sys;
        let ids: Vec<usize> = (0..sys.nb()).collect();
        let ctx_loads = |f: LoadFn, e: ElementRef| self.load_component(f, e, &lam);
        let inputs = self.ext_with(&lam);
        let mut ctx = LocalCtx::new(sys, &ids, self.q(), self.u(), &udot, self.radau.t, &inputs);
        ctx.loads = Some(&ctx_loads);
        Ok(sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| ctx.eval_expr(e, b)).collect())
    }

    /// Component `f` of the load element `e` applies on its i marker (NaN if it has none),
    /// from [`crate::mechanics::loads`].
    fn load_component(&self, f: LoadFn, e: ElementRef, lam: &[f64]) -> f64 {
        let t = self.radau.t;
        load_value(&self.dae.sys, e, (self.q(), self.u(), lam), t, &self.ext_with(lam))
            .map_or(f64::NAN, |l| l[load_index(f)])
    }

    /// Largest |g_i(q, u, t)| over the non-holonomic constraints at the current time.
    pub fn nonholonomic_residual(&self) -> f64 {
        let s = &self.dae.sys;
        let ext = self.ext();
        let (_, g) = equations::nonholonomic_b(s, self.q(), self.u(), self.radau.t, &ext);
        g.iter().fold(0.0, |a: f64, v| a.max(v.abs()))
    }

    /// Largest |C_i(q, t)| over the holonomic constraints at the current time.
    pub fn constraint_residual(&self) -> f64 {
        let s = &self.dae.sys;
        s.constraints
            .iter()
            .flat_map(|el| {
                crate::mechanics::kernels::constraint_values(
                    s,
                    el,
                    self.q(),
                    self.radau.t,
                    &self.dae.inputs_at(self.radau.t),
                )
            })
            .fold(0.0, |a: f64, v| a.max(v.abs()))
    }

    /// State of body `b` (model order).
    pub fn body_state(&self, b: usize) -> BodyState {
        let o = NQ * b;
        let (r, a) = body_frame(&self.q()[o..o + NQ], &self.dae.sys.r0[b]);
        let u = self.u();
        let w = a.mv(&V3([u[o + 3], u[o + 4], u[o + 5]]));
        BodyState { position: r.0, rotation: a.0, velocity: [u[o], u[o + 1], u[o + 2]], angular_velocity: w.0 }
    }

    /// Kinetic + gravitational potential + spring potential energy.
    pub fn mechanical_energy(&self) -> f64 {
        let s = &self.dae.sys;
        let (q, u) = (self.q(), self.u());
        let mut e = 0.0;
        for (b, body) in s.bodies.iter().enumerate() {
            let o = NQ * b;
            let v = &u[o..o + 3];
            let w = V3([u[o + 3], u[o + 4], u[o + 5]]);
            let jw = M3::cst(&body.inertia).mv(&w);
            e += 0.5 * body.mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + 0.5 * w.dot(&jw);
            e -= body.mass * (0..3).map(|c| s.gravity[c] * q[o + c]).sum::<f64>();
        }
        for el in &s.forces {
            let ql = crate::mechanics::kernels::gather(&el.bodies, q);
            let ul = crate::mechanics::kernels::gather(&el.bodies, u);
            let inputs = self.ext();
            let ctx = LocalCtx::new(s, &el.bodies, &ql, &ul, &[], self.radau.t, &inputs);
            e += el.potential(&ctx);
        }
        e
    }

    /// Names of every coordinate q and velocity u (`body.x`, ..., `body.wz`).
    pub fn state_names(&self) -> Vec<String> {
        let qn = ["x", "y", "z", "psi", "theta", "phi"];
        let un = ["vx", "vy", "vz", "wx", "wy", "wz"];
        let s = &self.dae.sys;
        let mut v: Vec<String> =
            s.bodies.iter().flat_map(|b| qn.iter().map(move |c| format!("{}.{c}", b.name))).collect();
        v.extend(s.bodies.iter().flat_map(|b| un.iter().map(move |c| format!("{}.{c}", b.name))));
        v
    }

    /// Current q and u, in the order of [`Simulator::state_names`]. Angles are relative
    /// to each body's current reference frame; `wx..wz` are body-axis components.
    pub fn states(&self) -> Vec<f64> {
        let mut v = self.q().to_vec();
        v.extend_from_slice(self.u());
        v
    }

    /// Everything that determines the future of the simulation (FMU state).
    pub fn snapshot(&self) -> SimState {
        SimState {
            t: self.radau.t,
            h: self.radau.h,
            y: self.radau.y.clone(),
            r0: self.dae.sys.r0.clone(),
            angle_refs: self.dae.sys.angle_refs.clone(),
            angle_rates: self.dae.sys.angle_rates.clone(),
            angle_time: self.dae.sys.angle_time,
            spring_refs: self.dae.sys.forces.iter().map(|f| f.angle_ref).collect(),
            inputs: self.dae.inputs.clone(),
            slopes: self.dae.slopes.clone(),
            t_in: self.dae.t_in,
            integrator: self.radau.memory(),
        }
    }

    /// Return to a snapshot of this model's simulation.
    pub fn restore(&mut self, s: &SimState) -> Result<(), EngineError> {
        let d = &self.dae;
        let fits = s.y.len() == self.radau.y.len()
            && s.r0.len() == d.sys.r0.len()
            && s.angle_refs.len() == d.sys.angle_refs.len()
            && s.angle_rates.len() == d.sys.angle_rates.len()
            && s.spring_refs.len() == d.sys.forces.len()
            && s.inputs.len() == d.inputs.len()
            && s.slopes.len() == d.slopes.len();
        if !fits {
            return Err(EngineError::Numeric("state does not belong to this model".into()));
        }
        self.radau.t = s.t;
        self.radau.h = s.h;
        self.radau.y.clone_from(&s.y);
        self.dae.sys.r0.clone_from(&s.r0);
        self.dae.sys.angle_refs.clone_from(&s.angle_refs);
        self.dae.sys.angle_rates.clone_from(&s.angle_rates);
        self.dae.sys.angle_time = s.angle_time;
        for (f, &a) in self.dae.sys.forces.iter_mut().zip(&s.spring_refs) {
            f.angle_ref = a;
        }
        self.dae.inputs.clone_from(&s.inputs);
        self.dae.slopes.clone_from(&s.slopes);
        self.dae.t_in = s.t_in;
        if !self.radau.set_memory(&s.integrator) {
            self.radau.reset();
        }
        self.acc = None;
        Ok(())
    }

    /// First time derivatives of the `<output>`s at the current time (FMI
    /// `fmi2GetRealOutputDerivatives`, order 1).
    ///
    /// Exact (by dual numbers along the motion: q̇ = H u, u̇ from the equations of motion,
    /// input slopes, time) for outputs of positions, velocities, time and inputs. Outputs of
    /// accelerations also need the jerk, taken from the integrator's collocation polynomial
    /// over the last step (zero right after a state was restored); loads count as constant.
    pub fn output_derivatives(&mut self) -> Result<Vec<f64>, EngineError> {
        use crate::ad::{Dual, Real};
        type D = Dual<f64, 1>;
        let (udot, lam) = self.accelerations()?;
        let n = self.dae.lay.n;
        let jerk = self.radau.derivatives_at_end().map(|(_, d2)| d2[n..2 * n].to_vec());
        let (q, u) = (self.q().to_vec(), self.u().to_vec());
        let qd: Vec<f64> = (0..self.dae.sys.nb())
            .flat_map(|b| crate::mechanics::body::qdot(&q[NQ * b..NQ * b + NQ], &u[NQ * b..NQ * b + NQ]))
            .collect();
        let mk = |v: &[f64], d: &[f64]| -> Vec<D> { v.iter().zip(d).map(|(&v, &d)| D { v, d: [d] }).collect() };
        let qv = mk(&q, &qd);
        let uv = mk(&u, &udot);
        let av = mk(&udot, jerk.as_deref().unwrap_or(&vec![0.0; n]));
        let t = self.radau.t;
        let inputs = self.ext();
        let lay = self.dae.lay;
        // Rates of the external values: input slopes; X' = Ẋ; Ẋ', V' from the collocation
        // polynomial (zero right after a restore).
        let mut rates = self.dae.slopes.clone();
        let zd = self.radau.derivatives_at_end().map(|(d1, _)| d1[lay.z()..lay.z() + lay.nz()].to_vec());
        for i in 0..lay.nz() {
            rates.push(if i < lay.nx { self.user_values()[lay.nx + i] } else { zd.as_ref().map_or(0.0, |d| d[i]) });
        }
        let sys = &self.dae.sys;
        let ids: Vec<usize> = (0..sys.nb()).collect();
        let ctx_loads = |f: LoadFn, e: ElementRef| D::cst(self.load_component(f, e, &lam));
        let mut ctx = LocalCtx::new(sys, &ids, &qv, &uv, &av, D { v: t, d: [1.0] }, &inputs);
        ctx.input_values = Some(mk(&inputs, &rates));
        ctx.loads = Some(&ctx_loads);
        Ok(sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| ctx.eval_expr(e, b).d[0]).collect())
    }

    /// The external values [inputs; Z] at the current time (see [`System::ext`]).
    pub fn ext(&self) -> Vec<f64> {
        self.dae.lay.ext(&self.dae.sys, &self.dae.inputs_at(self.radau.t), &self.radau.y, self.radau.t)
    }

    /// The external values with the element loads evaluated at multipliers `lam` (those of
    /// [`Simulator::accelerations`], so outputs and linearization see one consistent λ).
    pub fn ext_with(&self, lam: &[f64]) -> Vec<f64> {
        let (n, m, t) = (self.dae.lay.n, self.dae.sys.m, self.radau.t);
        let y = &self.radau.y;
        let state = (&y[..n], &y[n..2 * n], &lam[..m]);
        let mut z = self.user_values().to_vec();
        // Acceleration unknowns: those of the same solve as λ.
        if let Some((udot, _)) = &self.acc {
            let a0 = self.dae.lay.acc() - self.dae.lay.z();
            for (k, &b) in self.dae.sys.acc_bodies.iter().enumerate() {
                z[a0 + NQ * k..a0 + NQ * k + NQ].copy_from_slice(&udot[NQ * b..NQ * b + NQ]);
            }
        }
        self.dae.sys.ext(&self.dae.inputs_at(t), &z, Some(state), t)
    }

    /// Current user unknowns Z = (X, Ẋ, V).
    pub fn user_values(&self) -> &[f64] {
        let l = &self.dae.lay;
        &self.radau.y[l.z()..l.z() + l.nz()]
    }

    /// Number of inputs.
    pub fn n_inputs(&self) -> usize {
        self.dae.inputs.len()
    }

    /// Current input values.
    pub fn inputs(&self) -> Vec<f64> {
        self.dae.inputs_at(self.radau.t)
    }

    /// Current slope of input `i` (0 unless set by [`Simulator::set_input_derivative`]).
    pub fn input_slope(&self, i: usize) -> f64 {
        self.dae.slopes[i]
    }

    /// Set input `i` from now on: held constant (slope 0) until changed.
    pub fn set_input(&mut self, i: usize, v: f64) {
        self.rebase_inputs();
        self.dae.inputs[i] = v;
        self.dae.slopes[i] = 0.0;
        self.acc = None;
    }

    /// Warnings of initialization (bodies that assembly moved far), for the user.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Re-solve, at the current point, the unknowns that follow the inputs at once: the
    /// algebraic user unknowns Ẋ, V (seed Eq. 7b holds at every instant) and the
    /// acceleration unknowns, with the multipliers, as at initialization. Called after
    /// inputs change at a communication point, so that outputs, user variables and the
    /// linearization read there see the new inputs.
    pub fn resolve_user_unknowns(&mut self) -> Result<(), EngineError> {
        let l = &self.dae.lay;
        if l.nz() == l.nx {
            return Ok(());
        }
        let (z0, nz, lam0) = (l.z(), l.nz(), l.lam());
        let (q, u) = (self.q().to_vec(), self.u().to_vec());
        let t = self.radau.t;
        let mut z = self.user_values().to_vec();
        let inputs = self.dae.inputs_at(t);
        let (udot, lam) = init::consistent_accelerations(&self.dae.sys, &q, &u, t, &inputs, &mut z, &mut self.acc_lu)
            .map_err(EngineError::Numeric)?;
        self.radau.y[z0..z0 + nz].copy_from_slice(&z);
        self.radau.y[lam0..lam0 + lam.len()].copy_from_slice(&lam);
        self.acc = Some((udot, lam));
        Ok(())
    }

    /// Set the time derivative of input `i`: from now on it changes linearly (FMI
    /// `fmi2SetRealInputDerivatives`, order 1) until set again.
    pub fn set_input_derivative(&mut self, i: usize, slope: f64) {
        self.rebase_inputs();
        self.dae.slopes[i] = slope;
        self.acc = None;
    }

    /// Move the inputs' reference time to now (values unchanged).
    fn rebase_inputs(&mut self) {
        let t = self.radau.t;
        self.dae.inputs = self.dae.inputs_at(t);
        self.dae.t_in = t;
    }
}
