//! The mechanical system built from a [`Model`]: numbers evaluated, elements indexed,
//! coordinates laid out (q, u: 6 per body).
//!
//! One `System` belongs to one simulation: besides the model's constants it holds the
//! per-body reference frames R0 of the Euler angles, which the integrator re-chooses when
//! a body nears the 3-1-3 singularity (θ = 0 or π).

use super::body::NQ;
use super::constraints::{ConstraintEl, ConstraintKind, VelocityIc};
use super::forces::{ForceEl, ForceKind};
use super::joint_coords::{JointCoord, joint_coordinates};
use super::kernels::MAX_ELEMENT_BODIES;
use super::nonholonomic::{NonholonomicEl, NonholonomicKind};
use super::user::{UserEq, UserKind, ext_refs};
use crate::geom::{M3, rot_x};
use crate::model::expr::{ElementRef, Expr, angle_count, deps};
use crate::model::{Model, MotionDof, Orientation};

/// A marker's fixed geometry: offset `s` and rotation relative to its body (or ground).
#[derive(Clone, Debug)]
pub struct MarkerGeom {
    pub body: Option<usize>,
    pub s: [f64; 3],
    pub rot: [[f64; 3]; 3],
}

/// Mass properties of a body.
#[derive(Clone, Debug)]
pub struct BodyProps {
    pub name: String,
    pub mass: f64,
    /// Inertia about the CM, body axes.
    pub inertia: [[f64; 3]; 3],
}

/// The assembled mechanical system.
#[derive(Clone, Debug)]
pub struct System {
    pub params: Vec<f64>,
    pub gravity: [f64; 3],
    pub bodies: Vec<BodyProps>,
    pub markers: Vec<MarkerGeom>,
    /// Reference frame of each body's Euler angles (A = R0 · R313(e)).
    pub r0: Vec<[[f64; 3]; 3]>,
    /// Holonomic constraints (Eq. 1a), rows laid out consecutively.
    pub constraints: Vec<ConstraintEl>,
    /// Number of constraint equations m.
    pub m: usize,
    /// Constraint rows found redundant at initialization (e.g. a planar loop of revolutes
    /// in 3-D): their multipliers are fixed to 0 and their equations left out, as
    /// production codes do; they still hold, since the independent rows imply them.
    pub redundant: Vec<bool>,
    /// Exact position initial conditions (assembly only), rows after the m constraints.
    pub ic_constraints: Vec<ConstraintEl>,
    /// Exact velocity initial conditions.
    pub ic_velocities: Vec<VelocityIc>,
    pub forces: Vec<ForceEl>,
    /// Non-holonomic constraints g = B u + b = 0, rows laid out consecutively.
    pub nonholonomic: Vec<NonholonomicEl>,
    /// Number of non-holonomic equations.
    pub mn: usize,
    /// User rows (differentials, then variables; seed Eq. 7a–7b).
    pub user: Vec<UserEq>,
    /// Elements whose loads (`fx(name)` ...) forces and user rows read: their six load
    /// components are external values, evaluated from (q, u, λ) (algebraic loops through
    /// constraint forces are solved with the equations of motion).
    pub load_refs: Vec<ElementRef>,
    /// Bodies whose accelerations forces and user rows read: their u̇ become algebraic
    /// unknowns of the DAE (u' = a, M a = Q − Pᵀλ − Bᵀν), part of Z after V.
    pub acc_bodies: Vec<usize>,
    /// Number of differential states X and of variables V.
    pub nx: usize,
    pub nv: usize,
    /// Start values of X.
    pub x_init: Vec<f64>,
    /// Where motions and user constraints start in `constraints` (joints come first),
    /// and sforces and gforces in `forces` (spring-dampers first).
    first_motion: usize,
    first_user_constraint: usize,
    first_sforce: usize,
    first_gforce: usize,
    first_bushing: usize,
    pub output_names: Vec<String>,
    pub input_names: Vec<String>,
    pub outputs: Vec<Expr>,
    /// First angle-unwrapping slot of each output expression.
    pub output_bases: Vec<usize>,
    /// User linearization states `<linearization><state>`: name, s(q, t), angle slot base.
    pub lin_states: Vec<(String, Expr, usize)>,
    /// User velocity candidates `<linearization><velocity>`: name, w(q, u, t), slot base.
    pub lin_velocities: Vec<(String, Expr, usize)>,
    /// The joints' free coordinates (internal state candidates, joint order).
    pub joint_coords: Vec<JointCoord>,
    /// Value of every angle measure at the last accepted step (NaN: none yet); expressions
    /// keep their angles on the branch nearest these, so angles are continuous in time.
    pub angle_refs: Vec<f64>,
    /// Their time derivatives then (NaN: unknown), and that time: an angle is unwrapped
    /// to the branch nearest `angle_refs + angle_rates · (t − angle_time)`.
    pub angle_rates: Vec<f64>,
    pub angle_time: f64,
    /// Initial (unassembled) coordinates and velocities from the model file.
    pub q_init: Vec<f64>,
    pub u_init: Vec<f64>,
}

/// Where an element named in an expression (`fx(name)` ...) lives in the system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementSlot {
    /// Index into `System::constraints`.
    Constraint(usize),
    /// Index into `System::forces`.
    Force(usize),
}

/// Rotation matrix of an orientation attribute (columns = frame axes in owner axes).
pub fn orientation_matrix(o: &Orientation) -> [[f64; 3]; 3] {
    crate::model::parse::rotation(o)
}

/// Angles (0, π/2, 0): far from the 3-1-3 singularity; R0 is chosen so a body starts there.
pub const FAR_FROM_SINGULAR: [f64; 3] = [0.0, std::f64::consts::FRAC_PI_2, 0.0];

/// R0 such that R0 · R313(FAR_FROM_SINGULAR) = `a`.
pub fn rebased_reference(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    M3::cst(a).mm(&rot_x(std::f64::consts::FRAC_PI_2).t()).val()
}

impl System {
    /// Build the system from a validated model.
    pub fn from_model(model: &Model) -> Result<System, String> {
        let params: Vec<f64> = model.parameters.iter().map(|p| p.value.value).collect();
        let nb = model.bodies.len();
        let mut bodies = Vec::with_capacity(nb);
        let (mut q_init, mut u_init, mut r0) = (vec![0.0; NQ * nb], vec![0.0; NQ * nb], Vec::with_capacity(nb));
        for (b, body) in model.bodies.iter().enumerate() {
            let i = body.inertia.values();
            let inertia = if i.len() == 6 {
                [[i[0], i[3], i[4]], [i[3], i[1], i[5]], [i[4], i[5], i[2]]]
            } else {
                [[i[0], 0.0, 0.0], [0.0, i[1], 0.0], [0.0, 0.0, i[2]]]
            };
            bodies.push(BodyProps { name: body.name.clone(), mass: body.mass.value, inertia });
            let a = orientation_matrix(&body.orientation);
            r0.push(rebased_reference(&a));
            let p = body.position.v3();
            q_init[NQ * b..NQ * b + 3].copy_from_slice(&p);
            q_init[NQ * b + 3..NQ * b + 6].copy_from_slice(&FAR_FROM_SINGULAR);
            if let Some(v) = &body.velocity {
                u_init[NQ * b..NQ * b + 3].copy_from_slice(&v.v3());
            }
            if let Some(w) = &body.angular_velocity {
                // Ground components -> body axes: ω' = Aᵀ ω.
                let wb = M3::cst(&a).tv(&crate::geom::V3(w.v3()));
                u_init[NQ * b + 3..NQ * b + 6].copy_from_slice(&wb.0);
            }
        }
        let markers: Vec<MarkerGeom> = model
            .markers
            .iter()
            .map(|m| MarkerGeom { body: m.body, s: m.position.v3(), rot: orientation_matrix(&m.orientation) })
            .collect();
        let body_of = |m: usize| markers[m].body;
        let bodies_of = |ms: &[usize], exprs: &[&Expr]| -> Vec<usize> {
            let mut v: Vec<usize> = ms.iter().filter_map(|&m| body_of(m)).collect();
            for e in exprs {
                v.extend(deps(e).markers.iter().filter_map(|&m| body_of(m)));
            }
            v.sort_unstable();
            v.dedup();
            v
        };

        let mut slots = 0usize;
        let mut alloc = |e: &Expr| {
            let b = slots;
            slots += angle_count(e);
            b
        };
        let mut constraints = Vec::new();
        let mut ic_constraints = Vec::new();
        let mut ic_velocities = Vec::new();
        for jt in &model.joints {
            let bl = bodies_of(&[jt.i, jt.j], &[]);
            constraints.push(ConstraintEl::new(
                jt.name.clone(),
                ConstraintKind::Joint { kind: jt.kind, i: jt.i, j: jt.j },
                bl.clone(),
                "joint",
                jt.pos,
            ));
            if let Some(a) = &jt.ic_angle {
                let kind = ConstraintKind::Rotation { i: jt.i, j: jt.j, f: Expr::Num(a.value), abase: 0 };
                ic_constraints.push(ConstraintEl::new(
                    format!("{} (ic_angle)", jt.name),
                    kind,
                    bl.clone(),
                    "joint",
                    jt.pos,
                ));
            }
            if let Some(d) = &jt.ic_displacement {
                let kind = ConstraintKind::Translation { i: jt.i, j: jt.j, f: Expr::Num(d.value), abase: 0 };
                ic_constraints.push(ConstraintEl::new(
                    format!("{} (ic_displacement)", jt.name),
                    kind,
                    bl.clone(),
                    "joint",
                    jt.pos,
                ));
            }
            for (angular, v) in [(true, &jt.ic_angular_speed), (false, &jt.ic_speed)] {
                if let Some(v) = v {
                    ic_velocities.push(VelocityIc {
                        name: jt.name.clone(),
                        angular,
                        i: jt.i,
                        j: jt.j,
                        value: v.value,
                        bodies: bl.clone(),
                    });
                }
            }
        }
        for mo in &model.motions {
            let jt = &model.joints[mo.joint];
            let bl = bodies_of(&[jt.i, jt.j], &[&mo.function]);
            let (i, j, f, abase) = (jt.i, jt.j, mo.function.clone(), alloc(&mo.function));
            let kind = match mo.dof {
                MotionDof::Rotation => ConstraintKind::Rotation { i, j, f, abase },
                MotionDof::Translation => ConstraintKind::Translation { i, j, f, abase },
            };
            constraints.push(ConstraintEl::new(mo.name.clone(), kind, bl, "motion", mo.pos));
        }
        for uc in &model.constraints {
            let bl = bodies_of(&[], &[&uc.function]);
            constraints.push(ConstraintEl::new(
                uc.name.clone(),
                ConstraintKind::User { f: uc.function.clone(), abase: alloc(&uc.function) },
                bl,
                "constraint",
                uc.pos,
            ));
        }
        let mut nonholonomic = Vec::new();
        for w in &model.rolling_wheels {
            let (m, radius, plane) = (w.marker, w.radius.value, w.plane);
            let mut ms = vec![m];
            ms.extend(plane);
            let bl = bodies_of(&ms, &[]);
            let kind = ConstraintKind::WheelContact { m, radius, plane };
            constraints.push(ConstraintEl::new(w.name.clone(), kind, bl.clone(), "rolling_wheel", w.pos));
            let kind = NonholonomicKind::Rolling { m, radius, plane };
            nonholonomic.push(NonholonomicEl::new(w.name.clone(), kind, bl, "rolling_wheel", w.pos));
        }
        for k in &model.knife_edges {
            let kind = NonholonomicKind::KnifeEdge { m: k.marker };
            nonholonomic.push(NonholonomicEl::new(
                k.name.clone(),
                kind,
                bodies_of(&[k.marker], &[]),
                "knife_edge",
                k.pos,
            ));
        }
        for v in &model.velocity_constraints {
            let kind = NonholonomicKind::User { f: v.function.clone(), abase: alloc(&v.function) };
            let bl = bodies_of(&[], &[&v.function]);
            nonholonomic.push(NonholonomicEl::new(v.name.clone(), kind, bl, "velocity_constraint", v.pos));
        }
        let mut mn = 0;
        for el in nonholonomic.iter_mut() {
            el.row = mn;
            mn += el.neq;
        }
        for c in &nonholonomic {
            if c.bodies.len() > MAX_ELEMENT_BODIES {
                return Err(format!(
                    "constraint '{}' touches {} bodies (at most {MAX_ELEMENT_BODIES})",
                    c.name,
                    c.bodies.len()
                ));
            }
        }
        let mut row = 0;
        for c in constraints.iter_mut().chain(ic_constraints.iter_mut()) {
            c.row = row;
            row += c.neq;
        }
        let m = constraints.iter().map(|c| c.neq).sum();

        let (ni, nx, nv) = (model.inputs.len(), model.differentials.len(), model.variables.len());
        let mut load_refs: Vec<ElementRef> = Vec::new();
        {
            let mut es: Vec<&Expr> = model.sforces.iter().map(|s| &s.function).collect();
            es.extend(model.gforces.iter().flat_map(|g| g.force.iter().chain(g.torque.iter())));
            es.extend(model.variables.iter().map(|v| &v.function));
            es.extend(model.differentials.iter().map(|d| &d.function));
            for e in es {
                load_refs.extend(deps(e).loads);
            }
            load_refs.sort_unstable_by_key(|r| format!("{r:?}"));
            load_refs.dedup();
        }
        // (Loads of user constraints are refused by the parser: they have none.)
        for r in &load_refs {
            let reads_loads = |es: Vec<&Expr>| es.iter().any(|e| !deps(e).loads.is_empty());
            let bad = match *r {
                ElementRef::Sforce(k) if reads_loads(vec![&model.sforces[k].function]) => {
                    Some(format!("sforce '{}' reads loads itself", model.sforces[k].name))
                }
                ElementRef::Gforce(k)
                    if reads_loads(model.gforces[k].force.iter().chain(&model.gforces[k].torque).collect()) =>
                {
                    Some(format!("gforce '{}' reads loads itself", model.gforces[k].name))
                }
                _ => None,
            };
            if let Some(msg) = bad {
                return Err(format!("a force or user element reads a load that cannot be used there: {msg}"));
            }
        }
        let mut acc_bodies: Vec<usize> = Vec::new();
        {
            let mut es: Vec<&Expr> = model.sforces.iter().map(|s| &s.function).collect();
            es.extend(model.gforces.iter().flat_map(|g| g.force.iter().chain(g.torque.iter())));
            es.extend(model.variables.iter().map(|v| &v.function));
            es.extend(model.differentials.iter().map(|d| &d.function));
            for e in es {
                let d = deps(e);
                if d.level >= 2 {
                    acc_bodies.extend(d.markers.iter().filter_map(|&m| body_of(m)));
                }
            }
            acc_bodies.sort_unstable();
            acc_bodies.dedup();
        }
        let refs = |es: &[&Expr]| ext_refs(ni, nx, nv, &acc_bodies, &load_refs, &body_of, es);
        let mut forces = Vec::new();
        for s in &model.spring_dampers {
            let kind = ForceKind::SpringDamper {
                kind: s.kind,
                i: s.i,
                j: s.j,
                k: s.stiffness.value,
                c: s.damping.value,
                length: s.length.value,
                preload: s.preload.value,
            };
            forces.push(ForceEl {
                name: s.name.clone(),
                kind,
                bodies: bodies_of(&[s.i, s.j], &[]),
                ext_refs: vec![],
                angle_ref: 0.0,
            });
        }
        for s in &model.sforces {
            let kind =
                ForceKind::Sforce { kind: s.kind, i: s.i, j: s.j, f: s.function.clone(), abase: alloc(&s.function) };
            forces.push(ForceEl {
                name: s.name.clone(),
                kind,
                bodies: bodies_of(&[s.i, s.j], &[&s.function]),
                ext_refs: refs(&[&s.function]),
                angle_ref: 0.0,
            });
        }
        for g in &model.gforces {
            let mut ms = vec![g.i];
            ms.extend(g.j);
            ms.extend(g.frame);
            let exprs: Vec<&Expr> = g.force.iter().chain(g.torque.iter()).collect();
            let abase = [0, 1, 2, 3, 4, 5].map(|k| alloc(exprs[k]));
            let kind = ForceKind::Gforce {
                i: g.i,
                j: g.j,
                frame: g.frame,
                force: Box::new(g.force.clone()),
                torque: Box::new(g.torque.clone()),
                abase,
            };
            forces.push(ForceEl {
                name: g.name.clone(),
                kind,
                bodies: bodies_of(&ms, &exprs),
                ext_refs: refs(&exprs),
                angle_ref: 0.0,
            });
        }
        for b in &model.bushings {
            let six = |v: Option<&crate::model::NumVec>| -> [f64; 6] {
                let x = v.map(|v| v.values()).unwrap_or_default();
                std::array::from_fn(|a| x.get(a).copied().unwrap_or(0.0))
            };
            let kind = ForceKind::Bushing { i: b.i, j: b.j, k: six(Some(&b.stiffness)), c: six(b.damping.as_ref()) };
            let bodies = bodies_of(&[b.i, b.j], &[]);
            forces.push(ForceEl { name: b.name.clone(), kind, bodies, ext_refs: vec![], angle_ref: 0.0 });
        }
        let mut user = Vec::new();
        for (k, d) in model.differentials.iter().enumerate() {
            let kind = if d.implicit { UserKind::Implicit } else { UserKind::Explicit };
            let mut r = refs(&[&d.function]);
            let own = ni + nx + k;
            if kind == UserKind::Explicit && !r.contains(&own) {
                r.push(own);
                r.sort_unstable();
            }
            let (f, bodies, abase) = (d.function.clone(), bodies_of(&[], &[&d.function]), alloc(&d.function));
            user.push(UserEq { name: d.name.clone(), kind, f, abase, bodies, ext_refs: r, own });
        }
        for (k, v) in model.variables.iter().enumerate() {
            let mut r = refs(&[&v.function]);
            let own = ni + 2 * nx + k;
            if !r.contains(&own) {
                r.push(own);
                r.sort_unstable();
            }
            let (f, bodies, abase) = (v.function.clone(), bodies_of(&[], &[&v.function]), alloc(&v.function));
            user.push(UserEq { name: v.name.clone(), kind: UserKind::Variable, f, abase, bodies, ext_refs: r, own });
        }
        for u in &user {
            if u.bodies.len() > MAX_ELEMENT_BODIES {
                return Err(format!(
                    "'{}' reads {} bodies (at most {MAX_ELEMENT_BODIES}); split it into variables",
                    u.name,
                    u.bodies.len()
                ));
            }
        }
        for c in &constraints {
            if c.bodies.len() > MAX_ELEMENT_BODIES {
                return Err(format!(
                    "constraint '{}' touches {} bodies (at most {MAX_ELEMENT_BODIES})",
                    c.name,
                    c.bodies.len()
                ));
            }
        }
        for f in &forces {
            if f.bodies.len() > MAX_ELEMENT_BODIES {
                return Err(format!(
                    "force '{}' touches {} bodies (at most {MAX_ELEMENT_BODIES})",
                    f.name,
                    f.bodies.len()
                ));
            }
        }
        let joint_coords =
            model.joints.iter().flat_map(|jt| joint_coordinates(jt, &model.markers, &mut alloc)).collect();
        Ok(System {
            params,
            gravity: model.gravity,
            bodies,
            markers,
            r0,
            first_motion: model.joints.len(),
            first_user_constraint: model.joints.len() + model.motions.len(),
            first_sforce: model.spring_dampers.len(),
            first_gforce: model.spring_dampers.len() + model.sforces.len(),
            first_bushing: model.spring_dampers.len() + model.sforces.len() + model.gforces.len(),
            nonholonomic,
            mn,
            user,
            load_refs,
            acc_bodies,
            nx,
            nv: model.variables.len(),
            x_init: model.differentials.iter().map(|d| d.start.value).collect(),
            constraints,
            m,
            redundant: vec![false; m],
            ic_constraints,
            ic_velocities,
            forces,
            output_bases: model.outputs.iter().map(|o| alloc(&o.function)).collect(),
            lin_states: model
                .lin_states
                .iter()
                .map(|s| (s.name.clone(), s.function.clone(), alloc(&s.function)))
                .collect(),
            lin_velocities: model
                .lin_velocities
                .iter()
                .map(|s| (s.name.clone(), s.function.clone(), alloc(&s.function)))
                .collect(),
            joint_coords,
            angle_refs: vec![f64::NAN; slots],
            angle_rates: vec![f64::NAN; slots],
            angle_time: 0.0,
            output_names: model.outputs.iter().map(|o| o.name.clone()).collect(),
            input_names: model.inputs.iter().map(|i| i.name.clone()).collect(),
            outputs: model.outputs.iter().map(|o| o.function.clone()).collect(),
            q_init,
            u_init,
        })
    }

    /// The constraint or force element that `e` names.
    pub fn element_slot(&self, e: ElementRef) -> ElementSlot {
        match e {
            ElementRef::Joint(k) => ElementSlot::Constraint(k),
            ElementRef::Motion(k) => ElementSlot::Constraint(self.first_motion + k),
            ElementRef::Constraint(k) => ElementSlot::Constraint(self.first_user_constraint + k),
            ElementRef::SpringDamper(k) => ElementSlot::Force(k),
            ElementRef::Sforce(k) => ElementSlot::Force(self.first_sforce + k),
            ElementRef::Gforce(k) => ElementSlot::Force(self.first_gforce + k),
            ElementRef::Bushing(k) => ElementSlot::Force(self.first_bushing + k),
        }
    }

    /// Number of bodies.
    pub fn nb(&self) -> usize {
        self.bodies.len()
    }

    /// Number of coordinates n (= number of velocities).
    pub fn n(&self) -> usize {
        NQ * self.bodies.len()
    }
}
