//! Building a [`System`] from a validated [`Model`], step by step. The order of the steps
//! fixes the numbering of elements, rows and angle slots (golden files and bit-for-bit
//! reproducibility depend on it): constraints are joints, motions, user constraints,
//! wheel contacts; angle slots go to motions, user constraints, velocity constraints,
//! sforces, gforces, differentials, variables, joint coordinates, outputs, linearization
//! states and velocities, in this order.

use super::body::{FAR_FROM_SINGULAR, NQ, rebased_reference};
use super::constraints::{ConstraintEl, ConstraintKind, VelocityIc, VelocityIcKind};
use super::external::ExtLayout;
use super::forces::{ForceEl, ForceKind};
use super::joint_coords::{JointCoord, joint_coordinates};
use super::nonholonomic::{NonholonomicEl, NonholonomicKind};
use super::system::{BodyProps, FlexBody, MarkerGeom, NodeShape, System};
use super::user::{UserEq, UserKind};
use crate::geom::{M3, V3};
use crate::modal::invariants::Invariants;
use crate::model::expr::{ElementRef, Expr, angle_count, deps};
use crate::model::{MAX_ELEMENT_BODIES, Model, MotionDof, NumVec, Orientation};

/// The external-value entries that expressions read (see [`ExtLayout::read_by`]).
type Reads<'a> = &'a dyn Fn(&[&Expr]) -> Vec<usize>;

impl System {
    /// Build the system from a validated model.
    pub fn from_model(model: &Model) -> Result<System, String> {
        let mut bodies = bodies_and_initial_coordinates(model);
        let flex = flexible_bodies(model);
        let neta: usize = flex.iter().map(|f| f.eta.len()).sum();
        bodies.q_init.resize(bodies.q_init.len() + neta, 0.0);
        bodies.u_init.resize(bodies.u_init.len() + neta, 0.0);
        initial_modal_state(model, &flex, &mut bodies);
        let markers = markers(model);
        let mut slots = AngleSlots::default();
        let (mut constraints, mut ic_constraints, ic_velocities) = constraints_and_ics(model, &markers, &mut slots);
        let mut nonholonomic = nonholonomic_elements(model, &markers, &mut slots);
        let (m, mn) = lay_out_rows(&mut constraints, &mut ic_constraints, &mut nonholonomic);
        let load_refs = load_references(model);
        let acc_bodies = acceleration_bodies(model, &markers);
        let (ni, nx, nv) = (model.inputs.len(), model.differentials.len(), model.variables.len());
        let ext = ExtLayout::new(ni, nx, nv, acc_bodies.len(), neta, load_refs.len());
        let reads = |es: &[&Expr]| ext.read_by(&acc_bodies, &load_refs, &|m| markers[m].body, es);
        let forces = forces(model, &markers, &reads, &mut slots);
        let user = user_rows(model, &markers, &ext, &reads, &mut slots);
        check_elements(model, &nonholonomic, &load_refs, &user, &constraints, &forces)?;
        let measures = measures(model, &mut slots);
        let nj = model.joints.len();
        let (nsd, nsf, ngf) = (model.spring_dampers.len(), model.sforces.len(), model.gforces.len());
        let sys = System {
            params: model.parameters.iter().map(|p| p.value.value).collect(),
            gravity: model.gravity,
            bodies: bodies.props,
            markers,
            r0: bodies.r0,
            first_motion: nj,
            first_user_constraint: nj + model.motions.len(),
            first_sforce: nsd,
            first_gforce: nsd + nsf,
            first_bushing: nsd + nsf + ngf,
            nonholonomic,
            mn,
            user,
            load_refs,
            acc_bodies,
            nx,
            nv,
            x_init: model.differentials.iter().map(|d| d.start.value).collect(),
            constraints,
            m,
            redundant: vec![false; m],
            ic_constraints,
            ic_velocities,
            forces,
            output_bases: measures.output_bases,
            lin_states: measures.lin_states,
            lin_velocities: measures.lin_velocities,
            joint_coords: measures.joint_coords,
            angle_refs: vec![f64::NAN; slots.0],
            angle_rates: vec![f64::NAN; slots.0],
            angle_time: 0.0,
            output_names: model.outputs.iter().map(|o| o.name.clone()).collect(),
            input_names: model.inputs.iter().map(|i| i.name.clone()).collect(),
            outputs: model.outputs.iter().map(|o| o.function.clone()).collect(),
            q_init: bodies.q_init,
            u_init: bodies.u_init,
            flex,
        };
        check_flexible(model, &sys)?;
        Ok(sys)
    }
}

/// Angle-unwrapping slots, handed out in order: each expression gets as many consecutive
/// slots as it has angle measures; the field is the number handed out so far.
#[derive(Default)]
struct AngleSlots(usize);

impl AngleSlots {
    /// The first slot of `e`'s angle measures.
    fn alloc(&mut self, e: &Expr) -> usize {
        let b = self.0;
        self.0 += angle_count(e);
        b
    }
}

/// Mass properties, reference frames R0 and initial coordinates and velocities of the bodies.
struct Bodies {
    props: Vec<BodyProps>,
    r0: Vec<[[f64; 3]; 3]>,
    q_init: Vec<f64>,
    u_init: Vec<f64>,
}

/// Rotation matrix of an orientation attribute (columns = frame axes in owner axes).
fn orientation_matrix(o: &Orientation) -> [[f64; 3]; 3] {
    crate::model::parse::rotation(o)
}

/// The bodies: each starts at angles [`FAR_FROM_SINGULAR`] relative to an R0 that gives
/// it the model's orientation; velocities are the model's (ω in body axes).
fn bodies_and_initial_coordinates(model: &Model) -> Bodies {
    let nb = model.bodies.len();
    let mut props = Vec::with_capacity(nb);
    let (mut q_init, mut u_init, mut r0) = (vec![0.0; NQ * nb], vec![0.0; NQ * nb], Vec::with_capacity(nb));
    for (b, body) in model.bodies.iter().enumerate() {
        let i = body.inertia.values();
        let inertia = if i.len() == 6 {
            [[i[0], i[3], i[4]], [i[3], i[1], i[5]], [i[4], i[5], i[2]]]
        } else {
            [[i[0], 0.0, 0.0], [0.0, i[1], 0.0], [0.0, 0.0, i[2]]]
        };
        props.push(BodyProps { name: body.name.clone(), mass: body.mass.value, inertia });
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
            let wb = M3::cst(&a).tv(&V3(w.v3()));
            u_init[NQ * b + 3..NQ * b + 6].copy_from_slice(&wb.0);
        }
    }
    Bodies { props, r0, q_init, u_init }
}

/// The markers' geometry, model order.
fn markers(model: &Model) -> Vec<MarkerGeom> {
    model
        .markers
        .iter()
        .map(|m| MarkerGeom {
            body: m.body,
            s: m.position.v3(),
            rot: orientation_matrix(&m.orientation),
            node: node_shape(model, m),
        })
        .collect()
}

/// The mode shapes at a marker's node (markers of flexible bodies).
fn node_shape(model: &Model, m: &crate::model::Marker) -> Option<NodeShape> {
    let (b, i) = (m.body?, m.node?);
    let data = &model.bodies[b].flex.as_ref()?.data;
    let part = |o: usize| data.modes.iter().map(|s| [s[i][o], s[i][o + 1], s[i][o + 2]]).collect();
    Some(NodeShape { phi: part(0), rho: part(3) })
}

/// The flexible bodies: their modal coordinates follow the six of every body in q, in
/// body order (see [`super::coords`]).
fn flexible_bodies(model: &Model) -> Vec<FlexBody> {
    let mut next = NQ * model.bodies.len();
    let mut out = Vec::new();
    for (b, body) in model.bodies.iter().enumerate() {
        if let Some(f) = &body.flex {
            let nm = f.data.modes.len();
            out.push(FlexBody { body: b, eta: next..next + nm, inv: Invariants::of(&f.data) });
            next += nm;
        }
    }
    out
}

/// The flexible bodies' initial modal coordinates and rates (`modal_coordinates`,
/// `modal_velocities`; zero when not given) into the initial q and u.
fn initial_modal_state(model: &Model, flex: &[FlexBody], bodies: &mut Bodies) {
    for f in flex {
        let Some(spec) = &model.bodies[f.body].flex else { continue };
        if let Some(v) = &spec.eta0 {
            bodies.q_init[f.eta.clone()].copy_from_slice(&v.values());
        }
        if let Some(v) = &spec.eta_dot0 {
            bodies.u_init[f.eta.clone()].copy_from_slice(&v.values());
        }
    }
}

/// The bodies (sorted, each once) of markers `ms` and of the markers the expressions
/// `exprs` read; ground is none.
fn bodies_of(markers: &[MarkerGeom], ms: &[usize], exprs: &[&Expr]) -> Vec<usize> {
    let mut v: Vec<usize> = ms.iter().filter_map(|&m| markers[m].body).collect();
    for e in exprs {
        v.extend(deps(e).markers.iter().filter_map(|&m| markers[m].body));
    }
    v.sort_unstable();
    v.dedup();
    v
}

/// The holonomic constraints (joints, motions, user constraints, wheel contacts), the
/// joints' exact position initial conditions and their velocity initial conditions.
fn constraints_and_ics(
    model: &Model,
    markers: &[MarkerGeom],
    slots: &mut AngleSlots,
) -> (Vec<ConstraintEl>, Vec<ConstraintEl>, Vec<VelocityIc>) {
    let (mut constraints, ic_constraints, ic_velocities) = joints_and_ics(model, markers);
    constraints.extend(motions(model, markers, slots));
    constraints.extend(user_constraints(model, markers, slots));
    constraints.extend(wheel_contacts(model, markers));
    (constraints, ic_constraints, ic_velocities)
}

/// One constraint per joint, and the joints' initial conditions: position ones
/// (`ic_angle`, `ic_displacement`) as constraints, velocity ones (`ic_angular_speed`,
/// `ic_speed`) as [`VelocityIc`].
fn joints_and_ics(model: &Model, markers: &[MarkerGeom]) -> (Vec<ConstraintEl>, Vec<ConstraintEl>, Vec<VelocityIc>) {
    let mut constraints = Vec::new();
    let mut ic_constraints = Vec::new();
    let mut ic_velocities = Vec::new();
    for jt in &model.joints {
        let bl = bodies_of(markers, &[jt.i, jt.j], &[]);
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
                    kind: VelocityIcKind::Joint { angular, i: jt.i, j: jt.j },
                    value: v.value,
                    bodies: bl.clone(),
                });
            }
        }
    }
    (constraints, ic_constraints, ic_velocities)
}

/// One constraint per motion: its joint's rotation or translation follows f(t).
fn motions(model: &Model, markers: &[MarkerGeom], slots: &mut AngleSlots) -> Vec<ConstraintEl> {
    let mut constraints = Vec::new();
    for mo in &model.motions {
        let jt = &model.joints[mo.joint];
        let bl = bodies_of(markers, &[jt.i, jt.j], &[&mo.function]);
        let (i, j, f, abase) = (jt.i, jt.j, mo.function.clone(), slots.alloc(&mo.function));
        let kind = match mo.dof {
            MotionDof::Rotation => ConstraintKind::Rotation { i, j, f, abase },
            MotionDof::Translation => ConstraintKind::Translation { i, j, f, abase },
        };
        constraints.push(ConstraintEl::new(mo.name.clone(), kind, bl, "motion", mo.pos));
    }
    constraints
}

/// One constraint per user constraint f(q, t) = 0.
fn user_constraints(model: &Model, markers: &[MarkerGeom], slots: &mut AngleSlots) -> Vec<ConstraintEl> {
    let mut constraints = Vec::new();
    for uc in &model.constraints {
        let bl = bodies_of(markers, &[], &[&uc.function]);
        constraints.push(ConstraintEl::new(
            uc.name.clone(),
            ConstraintKind::User { f: uc.function.clone(), abase: slots.alloc(&uc.function) },
            bl,
            "constraint",
            uc.pos,
        ));
    }
    constraints
}

/// The holonomic part of each rolling wheel: its contact point stays on the plane.
fn wheel_contacts(model: &Model, markers: &[MarkerGeom]) -> Vec<ConstraintEl> {
    let mut constraints = Vec::new();
    for w in &model.rolling_wheels {
        let (m, radius, plane) = (w.marker, w.radius.value, w.plane);
        let bl = bodies_of(markers, &wheel_markers(m, plane), &[]);
        let kind = ConstraintKind::WheelContact { m, radius, plane };
        constraints.push(ConstraintEl::new(w.name.clone(), kind, bl, "rolling_wheel", w.pos));
    }
    constraints
}

/// The markers a rolling wheel touches: its own and its plane's, if any.
fn wheel_markers(m: usize, plane: Option<usize>) -> Vec<usize> {
    let mut ms = vec![m];
    ms.extend(plane);
    ms
}

/// The non-holonomic elements: the rolling part of rolling wheels, knife edges, user
/// velocity constraints.
fn nonholonomic_elements(model: &Model, markers: &[MarkerGeom], slots: &mut AngleSlots) -> Vec<NonholonomicEl> {
    let mut nonholonomic = Vec::new();
    for w in &model.rolling_wheels {
        let (m, radius, plane) = (w.marker, w.radius.value, w.plane);
        let bl = bodies_of(markers, &wheel_markers(m, plane), &[]);
        let kind = NonholonomicKind::Rolling { m, radius, plane };
        nonholonomic.push(NonholonomicEl::new(w.name.clone(), kind, bl, "rolling_wheel", w.pos));
    }
    for k in &model.knife_edges {
        let kind = NonholonomicKind::KnifeEdge { m: k.marker };
        let bl = bodies_of(markers, &[k.marker], &[]);
        nonholonomic.push(NonholonomicEl::new(k.name.clone(), kind, bl, "knife_edge", k.pos));
    }
    for v in &model.velocity_constraints {
        let kind = NonholonomicKind::User { f: v.function.clone(), abase: slots.alloc(&v.function) };
        let bl = bodies_of(markers, &[], &[&v.function]);
        nonholonomic.push(NonholonomicEl::new(v.name.clone(), kind, bl, "velocity_constraint", v.pos));
    }
    nonholonomic
}

/// Rows, element after element: non-holonomic ones from 0, holonomic constraints from 0
/// with the position initial conditions after them. Returns (m, mn): the numbers of
/// constraint (initial conditions excluded) and non-holonomic equations.
fn lay_out_rows(
    constraints: &mut [ConstraintEl],
    ic_constraints: &mut [ConstraintEl],
    nonholonomic: &mut [NonholonomicEl],
) -> (usize, usize) {
    let mut mn = 0;
    for el in nonholonomic.iter_mut() {
        el.row = mn;
        mn += el.neq;
    }
    let mut row = 0;
    for c in constraints.iter_mut().chain(ic_constraints.iter_mut()) {
        c.row = row;
        row += c.neq;
    }
    let m = constraints.iter().map(|c| c.neq).sum();
    (m, mn)
}

/// The expressions of force and user elements (sforces, gforces, variables,
/// differentials): those that may read loads and accelerations as external values.
fn force_and_user_exprs(model: &Model) -> Vec<&Expr> {
    let mut es: Vec<&Expr> = model.sforces.iter().map(|s| &s.function).collect();
    es.extend(model.gforces.iter().flat_map(|g| g.force.iter().chain(g.torque.iter())));
    es.extend(model.variables.iter().map(|v| &v.function));
    es.extend(model.differentials.iter().map(|d| &d.function));
    es
}

/// The elements whose loads force and user elements read (`System::load_refs`), in a
/// fixed order (sorted by their debug form), each once.
fn load_references(model: &Model) -> Vec<ElementRef> {
    let mut load_refs: Vec<ElementRef> = Vec::new();
    for e in force_and_user_exprs(model) {
        load_refs.extend(deps(e).loads);
    }
    load_refs.sort_unstable_by_key(|r| format!("{r:?}"));
    load_refs.dedup();
    load_refs
}

/// The bodies whose accelerations force and user elements read, and every flexible body
/// (its mass matrix depends on q) (`System::acc_bodies`), sorted, each once.
fn acceleration_bodies(model: &Model, markers: &[MarkerGeom]) -> Vec<usize> {
    let mut acc_bodies: Vec<usize> = (0..model.bodies.len()).filter(|&b| model.bodies[b].flex.is_some()).collect();
    for e in force_and_user_exprs(model) {
        let d = deps(e);
        if d.level >= 2 {
            acc_bodies.extend(d.markers.iter().filter_map(|&m| markers[m].body));
        }
    }
    acc_bodies.sort_unstable();
    acc_bodies.dedup();
    acc_bodies
}

/// The force elements: spring-dampers, sforces, gforces, bushings.
fn forces(model: &Model, markers: &[MarkerGeom], reads: Reads, slots: &mut AngleSlots) -> Vec<ForceEl> {
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
        let bodies = bodies_of(markers, &[s.i, s.j], &[]);
        forces.push(ForceEl { name: s.name.clone(), kind, bodies, ext_refs: vec![], angle_ref: 0.0 });
    }
    for s in &model.sforces {
        let kind =
            ForceKind::Sforce { kind: s.kind, i: s.i, j: s.j, f: s.function.clone(), abase: slots.alloc(&s.function) };
        forces.push(ForceEl {
            name: s.name.clone(),
            kind,
            bodies: bodies_of(markers, &[s.i, s.j], &[&s.function]),
            ext_refs: reads(&[&s.function]),
            angle_ref: 0.0,
        });
    }
    for g in &model.gforces {
        let mut ms = vec![g.i];
        ms.extend(g.j);
        ms.extend(g.frame);
        let exprs: Vec<&Expr> = g.force.iter().chain(g.torque.iter()).collect();
        let abase = [0, 1, 2, 3, 4, 5].map(|k| slots.alloc(exprs[k]));
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
            bodies: bodies_of(markers, &ms, &exprs),
            ext_refs: reads(&exprs),
            angle_ref: 0.0,
        });
    }
    for b in &model.bushings {
        let six = |v: Option<&NumVec>| -> [f64; 6] {
            let x = v.map(|v| v.values()).unwrap_or_default();
            std::array::from_fn(|a| x.get(a).copied().unwrap_or(0.0))
        };
        let kind = ForceKind::Bushing { i: b.i, j: b.j, k: six(Some(&b.stiffness)), c: six(b.damping.as_ref()) };
        let bodies = bodies_of(markers, &[b.i, b.j], &[]);
        forces.push(ForceEl { name: b.name.clone(), kind, bodies, ext_refs: vec![], angle_ref: 0.0 });
    }
    forces
}

/// The user rows: differentials (own unknown Ẋ_k), then variables (own unknown V_k);
/// explicit differentials and variables read their own unknown.
fn user_rows(
    model: &Model,
    markers: &[MarkerGeom],
    ext: &ExtLayout,
    reads: Reads,
    slots: &mut AngleSlots,
) -> Vec<UserEq> {
    let mut user = Vec::new();
    for (k, d) in model.differentials.iter().enumerate() {
        let kind = if d.implicit { UserKind::Implicit } else { UserKind::Explicit };
        let mut r = reads(&[&d.function]);
        let own = ext.diff_dot(k);
        if kind == UserKind::Explicit && !r.contains(&own) {
            r.push(own);
            r.sort_unstable();
        }
        let (f, bodies, abase) =
            (d.function.clone(), bodies_of(markers, &[], &[&d.function]), slots.alloc(&d.function));
        user.push(UserEq { name: d.name.clone(), kind, f, abase, bodies, ext_refs: r, own });
    }
    for (k, v) in model.variables.iter().enumerate() {
        let mut r = reads(&[&v.function]);
        let own = ext.variable(k);
        if !r.contains(&own) {
            r.push(own);
            r.sort_unstable();
        }
        let (f, bodies, abase) =
            (v.function.clone(), bodies_of(markers, &[], &[&v.function]), slots.alloc(&v.function));
        user.push(UserEq { name: v.name.clone(), kind: UserKind::Variable, f, abase, bodies, ext_refs: r, own });
    }
    user
}

/// What the engine cannot evaluate (the loader refuses these with a location first):
/// an element touching more than [`MAX_ELEMENT_BODIES`] bodies, and a force reading
/// loads that read loads themselves. The first failing check, in this order, is the error:
/// non-holonomic elements, load references, user rows, constraints, forces.
fn check_elements(
    model: &Model,
    nonholonomic: &[NonholonomicEl],
    load_refs: &[ElementRef],
    user: &[UserEq],
    constraints: &[ConstraintEl],
    forces: &[ForceEl],
) -> Result<(), String> {
    let most = MAX_ELEMENT_BODIES;
    let touches = |what: &str, name: &str, n: usize| format!("{what} '{name}' touches {n} bodies (at most {most})");
    if let Some(c) = nonholonomic.iter().find(|c| c.bodies.len() > most) {
        return Err(touches("constraint", &c.name, c.bodies.len()));
    }
    check_load_references(model, load_refs)?;
    if let Some(u) = user.iter().find(|u| u.bodies.len() > most) {
        return Err(format!("'{}' reads {} bodies (at most {most}); split it into variables", u.name, u.bodies.len()));
    }
    if let Some(c) = constraints.iter().find(|c| c.bodies.len() > most) {
        return Err(touches("constraint", &c.name, c.bodies.len()));
    }
    if let Some(f) = forces.iter().find(|f| f.bodies.len() > most) {
        return Err(touches("force", &f.name, f.bodies.len()));
    }
    Ok(())
}

/// No force or user row reads a flexible body's accelerations.
fn check_flexible(model: &Model, sys: &System) -> Result<(), String> {
    for e in force_and_user_exprs(model) {
        let d = deps(e);
        let flexible = d.markers.iter().filter_map(|&m| sys.markers[m].body).find(|&b| sys.flex_of(b).is_some());
        if let (true, Some(b)) = (d.level >= 2, flexible) {
            return Err(format!(
                "a force or user element reads accelerations of flexible body '{}', which is not supported",
                model.bodies[b].name
            ));
        }
    }
    Ok(())
}

/// A load read by a force or user element must not be that of an sforce or gforce that
/// reads loads itself. (Loads of user constraints are refused by the parser: they have none.)
fn check_load_references(model: &Model, load_refs: &[ElementRef]) -> Result<(), String> {
    for r in load_refs {
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
    Ok(())
}

/// The expressions read after the elements, with their angle slots: the joints'
/// free coordinates, outputs, linearization states and velocities.
struct Measures {
    joint_coords: Vec<JointCoord>,
    output_bases: Vec<usize>,
    lin_states: Vec<(String, Expr, usize)>,
    lin_velocities: Vec<(String, Expr, usize)>,
}

/// Angle slots of the joint coordinates, outputs, linearization states and velocities.
fn measures(model: &Model, slots: &mut AngleSlots) -> Measures {
    let joint_coords =
        model.joints.iter().flat_map(|jt| joint_coordinates(jt, &model.markers, &mut |e| slots.alloc(e))).collect();
    let output_bases = model.outputs.iter().map(|o| slots.alloc(&o.function)).collect();
    let lin_states =
        model.lin_states.iter().map(|s| (s.name.clone(), s.function.clone(), slots.alloc(&s.function))).collect();
    let lin_velocities =
        model.lin_velocities.iter().map(|s| (s.name.clone(), s.function.clone(), slots.alloc(&s.function))).collect();
    Measures { joint_coords, output_bases, lin_states, lin_velocities }
}
