//! Building the constraint elements: joints, motions, user constraints, and the
//! non-holonomic rolling wheels, knife edges and velocity constraints.

use super::attrs::El;
use super::build::{marker_ref, opt_marker_ref};
use super::load::Loader;
use super::validate::{Allowed, check_body_count, check_deps};
use super::xml::XElem;
use crate::model::expr::{self, MarkerId};
use crate::model::*;

impl<'a> Loader<'a> {
    /// `<joint>`: its type, markers (on two different bodies) and initial conditions.
    pub(super) fn build_joint(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let j = joint(&el)?;
        self.check_bodies(&el, j.i, j.j)?;
        self.model.joints.push(j);
        Ok(())
    }

    /// Joint markers must be on two different bodies (or one on ground).
    pub(super) fn check_bodies(&self, el: &El, i: MarkerId, j: MarkerId) -> Result<(), ModelError> {
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

    /// Every `<motion>`, in file order (after all joints are built).
    pub(super) fn build_motions(&mut self) -> Result<(), ModelError> {
        for x in self.root.children.iter().filter(|x| x.tag == "motion") {
            let m = self.motion(x)?;
            self.model.motions.push(m);
        }
        Ok(())
    }

    /// One `<motion>`: a function of time driving the `dof` of a joint that has it.
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

    /// `<constraint>`: a user position constraint `function` = 0.
    pub(super) fn build_constraint(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let function = el.expr_req("function")?;
        check_deps(&el, "function", &function, Allowed::Positions)?;
        check_body_count(&el, &self.scope, &[], &[("function", &function)], false)?;
        let c = UserConstraint { name: x.label().into(), function, pos: x.pos };
        self.model.constraints.push(c);
        Ok(())
    }

    /// `<rolling_wheel>`: a positive radius, its marker on a body, an optional plane.
    pub(super) fn build_rolling_wheel(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
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
        self.model.rolling_wheels.push(RollingWheel { name: x.label().into(), marker, radius, plane, pos: x.pos });
        Ok(())
    }

    /// `<knife_edge>`: its marker, on a body.
    pub(super) fn build_knife_edge(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let marker = marker_ref(&el, "marker")?;
        if self.scope.marker_body.get(marker).copied().flatten().is_none() {
            return Err(el.err("the knife-edge marker must be on a body, not on ground"));
        }
        self.model.knife_edges.push(KnifeEdge { name: x.label().into(), marker, pos: x.pos });
        Ok(())
    }

    /// `<velocity_constraint>`: a user `function` = 0 that uses velocities.
    pub(super) fn build_velocity_constraint(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let function = el.expr_req("function")?;
        check_deps(&el, "function", &function, Allowed::Velocities)?;
        check_body_count(&el, &self.scope, &[], &[("function", &function)], false)?;
        if expr::deps(&function).level == 0 {
            let at = el.get("function").map_or(x.pos, |a| a.pos);
            return Err(el.err_at(at, "'function' uses no velocities (write a <constraint> instead)"));
        }
        self.model.velocity_constraints.push(VelocityConstraint { name: x.label().into(), function, pos: x.pos });
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
