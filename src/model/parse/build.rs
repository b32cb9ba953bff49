//! Second pass: build every element from its attributes, in file order, validating
//! values and what expressions depend on.

use super::attrs::{El, constant};
use super::load::Loader;
use super::orient::read_orientation;
use super::validate::{Allowed, check_body_count, check_deps, check_inertia, check_mass};
use super::xml::XElem;
use crate::model::expr::{self, ElementRef, Expr, MarkerId, Scope};
use crate::model::*;

const SPRING_TYPES: &[(&str, SpringType)] =
    &[("translational", SpringType::Translational), ("rotational", SpringType::Rotational)];

impl<'a> Loader<'a> {
    /// Build all elements (motions last: they refer to joints of any position).
    pub(crate) fn build_all(&mut self) -> Result<(), ModelError> {
        let root = self.root;
        // Forces and user elements with the loads their expressions read (checked once
        // every force is known).
        let mut load_readers: Vec<(&'a XElem, &'static str, Vec<ElementRef>)> = Vec::new();
        for x in &root.children {
            let el = self.el(x);
            match x.tag.as_str() {
                "gravity" => {
                    let g = el.vec3_req("value")?;
                    self.model.gravity = g.v3();
                    self.model.gravity_expr = Some(g);
                }
                "ground" => {
                    for m in &x.children {
                        let mk = self.marker(m, "ground", None)?;
                        self.model.markers.push(mk);
                    }
                }
                "body" => self.body(x)?,
                "joint" => {
                    let j = joint(&el)?;
                    self.check_bodies(&el, j.i, j.j)?;
                    self.model.joints.push(j);
                }
                "constraint" => {
                    let function = el.expr_req("function")?;
                    check_deps(&el, "function", &function, Allowed::Positions)?;
                    check_body_count(&el, &self.scope, &[], &[("function", &function)], false)?;
                    let c = UserConstraint { name: x.label().into(), function, pos: x.pos };
                    self.model.constraints.push(c);
                }
                "spring_damper" => {
                    let s = spring_damper(&el)?;
                    self.model.spring_dampers.push(s);
                }
                "sforce" => {
                    let function = el.expr_req("function")?;
                    check_deps(&el, "function", &function, Allowed::Force)?;
                    let s = Sforce {
                        name: x.label().into(),
                        kind: el.keyword_req("type", SPRING_TYPES)?,
                        i: marker_ref(&el, "i")?,
                        j: marker_ref(&el, "j")?,
                        function,
                        pos: x.pos,
                    };
                    check_body_count(&el, &self.scope, &[s.i, s.j], &[("function", &s.function)], true)?;
                    load_readers.push((x, "function", expr::deps(&s.function).loads));
                    self.model.sforces.push(s);
                }
                "gforce" => {
                    let force = el.expr_vec3("force")?;
                    let torque = el.expr_vec3("torque")?;
                    for (attr, es) in [("force", &force), ("torque", &torque)] {
                        for e in es {
                            check_deps(&el, attr, e, Allowed::Force)?;
                        }
                    }
                    let g = Gforce {
                        name: x.label().into(),
                        i: marker_ref(&el, "i")?,
                        j: opt_marker_ref(&el, "j")?,
                        frame: opt_marker_ref(&el, "frame")?,
                        force,
                        torque,
                        pos: x.pos,
                    };
                    let markers: Vec<MarkerId> = [Some(g.i), g.j, g.frame].into_iter().flatten().collect();
                    let exprs: Vec<(&str, &Expr)> =
                        g.force.iter().map(|e| ("force", e)).chain(g.torque.iter().map(|e| ("torque", e))).collect();
                    check_body_count(&el, &self.scope, &markers, &exprs, true)?;
                    for (attr, e) in exprs {
                        load_readers.push((x, attr, expr::deps(e).loads));
                    }
                    self.model.gforces.push(g);
                }
                "bushing" => {
                    let (i, j) = (marker_ref(&el, "i")?, marker_ref(&el, "j")?);
                    self.check_bodies(&el, i, j)?;
                    self.model.bushings.push(Bushing {
                        name: x.label().into(),
                        i,
                        j,
                        stiffness: el.num_vec("stiffness", &[6])?.ok_or_else(|| el.err("missing 'stiffness'"))?,
                        damping: el.num_vec("damping", &[6])?,
                        pos: x.pos,
                    });
                }
                "rolling_wheel" => {
                    let radius = el.num_req("radius")?;
                    if radius.value.is_nan() || radius.value <= 0.0 {
                        let at = el.get("radius").map_or(x.pos, |a| a.pos);
                        return Err(el.err_at(at, format!("radius must be positive (got {})", radius.value)));
                    }
                    let marker = marker_ref(&el, "marker")?;
                    if self.scope.marker_body.get(marker).copied().flatten().is_none() {
                        return Err(el.err("the wheel marker must be on a body, not on ground"));
                    }
                    let plane = opt_marker_ref(&el, "plane")?;
                    self.model.rolling_wheels.push(RollingWheel {
                        name: x.label().into(),
                        marker,
                        radius,
                        plane,
                        pos: x.pos,
                    });
                }
                "knife_edge" => {
                    let marker = marker_ref(&el, "marker")?;
                    if self.scope.marker_body.get(marker).copied().flatten().is_none() {
                        return Err(el.err("the knife-edge marker must be on a body, not on ground"));
                    }
                    self.model.knife_edges.push(KnifeEdge { name: x.label().into(), marker, pos: x.pos });
                }
                "velocity_constraint" => {
                    let function = el.expr_req("function")?;
                    check_deps(&el, "function", &function, Allowed::Velocities)?;
                    check_body_count(&el, &self.scope, &[], &[("function", &function)], false)?;
                    if expr::deps(&function).level == 0 {
                        let at = el.get("function").map_or(x.pos, |a| a.pos);
                        return Err(el.err_at(at, "'function' uses no velocities (write a <constraint> instead)"));
                    }
                    self.model.velocity_constraints.push(VelocityConstraint {
                        name: x.label().into(),
                        function,
                        pos: x.pos,
                    });
                }
                "variable" => {
                    let function = el.expr_req("function")?;
                    check_deps(&el, "function", &function, Allowed::Force)?;
                    check_body_count(&el, &self.scope, &[], &[("function", &function)], true)?;
                    load_readers.push((x, "function", expr::deps(&function).loads));
                    self.model.variables.push(Variable { name: x.label().into(), function, pos: x.pos });
                }
                "differential" => {
                    let function = el.expr_req("function")?;
                    check_deps(&el, "function", &function, Allowed::Force)?;
                    check_body_count(&el, &self.scope, &[], &[("function", &function)], true)?;
                    load_readers.push((x, "function", expr::deps(&function).loads));
                    let implicit = el.keyword("implicit", &[("true", true), ("false", false)])?.unwrap_or(false);
                    let me = self.model.differentials.len();
                    if implicit && !expr::deps(&function).diff_dots.contains(&me) {
                        let at = el.get("function").map_or(x.pos, |a| a.pos);
                        return Err(el.err_at(at, format!("implicit: 'function' must use dif1({})", x.label())));
                    }
                    self.model.differentials.push(Differential {
                        name: x.label().into(),
                        start: el.num_or("start", 0.0)?,
                        function,
                        implicit,
                        pos: x.pos,
                    });
                }
                "input" => {
                    let input =
                        Input { name: x.label().into(), start: el.num_or("start", 0.0)?, unit: el.unit()?, pos: x.pos };
                    self.model.inputs.push(input);
                }
                "output" => {
                    let function = el.expr_req("function")?;
                    check_deps(&el, "function", &function, Allowed::Any)?;
                    self.model.outputs.push(Output { name: x.label().into(), function, unit: el.unit()?, pos: x.pos });
                }
                "linearization" => self.linearization(x)?,
                "experiment" => {
                    let v = |n: &str| el.num(n).map(|o| o.map(|n| n.value));
                    self.model.experiment = Experiment {
                        start: v("start")?,
                        stop: v("stop")?,
                        step: v("step")?,
                        tolerance: v("tolerance")?,
                    };
                }
                "analysis" => {
                    let b = el.keyword("static", &[("true", true), ("false", false)])?;
                    self.model.static_analysis = b.unwrap_or(false);
                }
                _ => {}
            }
        }
        for x in root.children.iter().filter(|x| x.tag == "motion") {
            let m = self.motion(x)?;
            self.model.motions.push(m);
        }
        for (x, attr, loads) in load_readers {
            self.check_load_reads(x, attr, &loads)?;
        }
        Ok(())
    }

    /// A force or user element may read the load of an sforce or gforce only when that
    /// force's own expressions read no loads (the engine evaluates such loads first,
    /// from positions, velocities and user states alone).
    fn check_load_reads(&self, x: &XElem, attr: &str, loads: &[ElementRef]) -> Result<(), ModelError> {
        for r in loads {
            let (tag, name, exprs, line): (&str, &str, Vec<&Expr>, usize) = match *r {
                ElementRef::Sforce(k) => match self.model.sforces.get(k) {
                    Some(s) => ("sforce", &s.name, vec![&s.function], s.pos.line),
                    None => continue,
                },
                ElementRef::Gforce(k) => match self.model.gforces.get(k) {
                    Some(g) => ("gforce", &g.name, g.force.iter().chain(&g.torque).collect(), g.pos.line),
                    None => continue,
                },
                _ => continue,
            };
            if exprs.iter().any(|e| !expr::deps(e).loads.is_empty()) {
                let el = self.el(x);
                let at = el.get(attr).map_or(x.pos, |a| a.pos);
                return Err(el.err_at(
                    at,
                    format!(
                        "'{attr}' reads the load of {tag} '{name}' (line {line}), which reads loads itself; \
                         forces and user elements may read only loads that read no loads"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn body(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let mass = el.num_req("mass")?;
        check_mass(mass.value).map_err(|m| el.err_at(el.get("mass").map_or(x.pos, |a| a.pos), m))?;
        el.req("inertia")?;
        let inertia = el.num_vec("inertia", &[3, 6])?.unwrap_or(NumVec { items: vec![] });
        check_inertia(&inertia.values()).map_err(|m| el.err_at(el.get("inertia").map_or(x.pos, |a| a.pos), m))?;
        let body = Body {
            name: x.label().into(),
            mass,
            inertia,
            position: el.vec3_req("position")?,
            orientation: read_orientation(&el)?,
            velocity: el.num_vec("velocity", &[3])?,
            angular_velocity: el.num_vec("angular_velocity", &[3])?,
            pos: x.pos,
        };
        let idx = self.model.bodies.len();
        let name = body.name.clone();
        self.model.bodies.push(body);
        self.model.markers.push(Marker {
            name: format!("{name}.cm"),
            body: Some(idx),
            position: NumVec { items: vec![constant(0.0), constant(0.0), constant(0.0)] },
            orientation: Orientation::Identity,
            pos: x.pos,
        });
        for m in &x.children {
            let mk = self.marker(m, &name, Some(idx))?;
            self.model.markers.push(mk);
        }
        Ok(())
    }

    fn marker(&self, x: &'a XElem, owner: &str, body: Option<usize>) -> Result<Marker, ModelError> {
        let el = self.el(x);
        Ok(Marker {
            name: format!("{owner}.{}", x.label()),
            body,
            position: el.vec3_req("position")?,
            orientation: read_orientation(&el)?,
            pos: x.pos,
        })
    }

    /// Joint markers must be on two different bodies (or one on ground).
    fn check_bodies(&self, el: &El, i: MarkerId, j: MarkerId) -> Result<(), ModelError> {
        let bi = self.scope.marker_body.get(i).copied().flatten();
        let bj = self.scope.marker_body.get(j).copied().flatten();
        if bi == bj {
            let on = match bi.and_then(|b| self.scope.body_names.get(b)) {
                Some(b) => format!("the same body '{b}'"),
                None => "ground".to_string(),
            };
            return Err(el.err(format!("markers i and j are both on {on}")));
        }
        Ok(())
    }

    fn motion(&self, x: &'a XElem) -> Result<Motion, ModelError> {
        let el = self.el(x);
        let a = el.req("joint")?;
        let name = a.value.trim();
        let joint =
            self.ns_joints.get(name).ok_or_else(|| el.err_at(el.value_pos(a, 0), format!("unknown joint '{name}'")))?;
        let dof =
            el.keyword_req("dof", &[("rotation", MotionDof::Rotation), ("translation", MotionDof::Translation)])?;
        let kind = self.model.joints.get(joint).map(|j| j.kind);
        let ok = matches!(
            (dof, kind),
            (MotionDof::Rotation, Some(JointType::Revolute | JointType::Cylindrical))
                | (MotionDof::Translation, Some(JointType::Translational | JointType::Cylindrical))
        );
        if !ok {
            let (need, dof_name) = match dof {
                MotionDof::Rotation => ("revolute or cylindrical", "rotation"),
                MotionDof::Translation => ("translational or cylindrical", "translation"),
            };
            let has = kind.map_or("unknown", joint_type_name);
            let at = el.get("dof").map_or(x.pos, |a| a.pos);
            return Err(el.err_at(at, format!("dof '{dof_name}' needs a {need} joint; joint '{name}' is {has}")));
        }
        let function = el.expr_req("function")?;
        check_deps(&el, "function", &function, Allowed::Time)?;
        Ok(Motion { name: x.label().into(), joint, dof, function, pos: x.pos })
    }

    fn linearization(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        for c in &x.children {
            let el = self.el(c);
            let function = el.expr_req("function")?;
            let (name, pos) = (c.label().to_string(), c.pos);
            // A linearization state is a named quantity of the model, like parameters,
            // inputs, outputs, differentials and variables: its name is theirs to share.
            let clash = match self.scope.names.get(&name) {
                Some(&(r, line)) => Some((r.kind(), line)),
                None => self.ns_outputs.line(&name).map(|line| ("output", line)),
            };
            if let Some((kind, line)) = clash {
                let at = el.get("name").map_or(c.pos, |a| a.pos);
                return Err(el.err_at(at, format!("name '{name}' is already used by {kind} at line {line}")));
            }
            if c.tag == "state" {
                check_deps(&el, "function", &function, Allowed::Positions)?;
                self.model.lin_states.push(LinState { name, function, pos });
            } else {
                check_deps(&el, "function", &function, Allowed::Velocities)?;
                self.model.lin_velocities.push(LinVelocity { name, function, pos });
            }
        }
        Ok(())
    }
}

const JOINT_TYPES: &[(&str, JointType)] = &[
    ("fixed", JointType::Fixed),
    ("revolute", JointType::Revolute),
    ("translational", JointType::Translational),
    ("cylindrical", JointType::Cylindrical),
    ("universal", JointType::Universal),
    ("spherical", JointType::Spherical),
    ("planar", JointType::Planar),
];

fn joint_type_name(t: JointType) -> &'static str {
    JOINT_TYPES.iter().find(|(_, k)| *k == t).map_or("?", |(n, _)| n)
}

fn joint(el: &El) -> Result<Joint, ModelError> {
    let kind = el.keyword_req("type", JOINT_TYPES)?;
    let rot = matches!(kind, JointType::Revolute | JointType::Cylindrical);
    let tra = matches!(kind, JointType::Translational | JointType::Cylindrical);
    for (attr, ok, types) in [
        ("ic_angle", rot, "revolute and cylindrical"),
        ("ic_angular_speed", rot, "revolute and cylindrical"),
        ("ic_displacement", tra, "translational and cylindrical"),
        ("ic_speed", tra, "translational and cylindrical"),
    ] {
        if let (Some(a), false) = (el.get(attr), ok) {
            let msg = format!("attribute '{attr}' is not allowed on a {} joint (only {types})", joint_type_name(kind));
            return Err(el.err_at(a.pos, msg));
        }
    }
    Ok(Joint {
        name: el.x.label().into(),
        kind,
        i: marker_ref(el, "i")?,
        j: marker_ref(el, "j")?,
        ic_angle: el.num("ic_angle")?,
        ic_angular_speed: el.num("ic_angular_speed")?,
        ic_displacement: el.num("ic_displacement")?,
        ic_speed: el.num("ic_speed")?,
        pos: el.x.pos,
    })
}

fn spring_damper(el: &El) -> Result<SpringDamper, ModelError> {
    let kind = el.keyword_req("type", SPRING_TYPES)?;
    let (len_attr, other) = match kind {
        SpringType::Translational => ("length", "angle"),
        SpringType::Rotational => ("angle", "length"),
    };
    if let Some(a) = el.get(other) {
        let t = if kind == SpringType::Translational { "translational" } else { "rotational" };
        let msg = format!("attribute '{other}' is not allowed on a {t} spring_damper (use '{len_attr}')");
        return Err(el.err_at(a.pos, msg));
    }
    let length = match kind {
        SpringType::Translational => el.num_req("length")?,
        SpringType::Rotational => el.num_or("angle", 0.0)?,
    };
    Ok(SpringDamper {
        name: el.x.label().into(),
        kind,
        i: marker_ref(el, "i")?,
        j: marker_ref(el, "j")?,
        stiffness: el.num_req("stiffness")?,
        damping: el.num_or("damping", 0.0)?,
        length,
        preload: el.num_or("preload", 0.0)?,
        pos: el.x.pos,
    })
}

/// A required marker reference.
fn marker_ref(el: &El, attr: &str) -> Result<MarkerId, ModelError> {
    el.req(attr)?;
    opt_marker_ref(el, attr)?.ok_or_else(|| el.err(format!("missing required attribute '{attr}'")))
}

/// An optional marker reference (`body.marker`, `ground.marker`, or a body's name).
fn opt_marker_ref(el: &El, attr: &str) -> Result<Option<MarkerId>, ModelError> {
    let Some(a) = el.get(attr) else {
        return Ok(None);
    };
    let name = a.value.trim();
    let lead = a.value.len() - a.value.trim_start().len();
    let hint = if name == "ground" { " (ground has no cm marker: name one, ground.<marker>)" } else { "" };
    el.scope
        .marker(name)
        .map(Some)
        .ok_or_else(|| el.err_at(el.value_pos(a, lead), format!("unknown marker '{name}'{hint}")))
}
