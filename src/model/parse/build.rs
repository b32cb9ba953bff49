//! Second pass: build every element from its attributes, in file order, validating
//! values and what expressions depend on. The dispatcher, the once-only and body
//! elements, and marker references live here; constraints, forces and user elements
//! each have their own file (`build_constraints`, `build_forces`, `build_user`).

use super::attrs::{El, constant};
use super::load::Loader;
use super::orient::read_orientation;
use super::validate::{check_inertia, check_mass};
use super::xml::XElem;
use crate::model::expr::{self, ElementRef, Expr, MarkerId, Scope};
use crate::model::*;

/// An element expression that reads loads: the element, the attribute, and the loads it
/// reads (checked by [`Loader::check_load_reads`] once every force is known).
pub(super) type LoadReader<'a> = (&'a XElem, &'static str, Vec<ElementRef>);

impl<'a> Loader<'a> {
    /// Build all elements (motions last: they refer to joints of any position).
    pub(crate) fn build_all(&mut self) -> Result<(), ModelError> {
        let root = self.root;
        // Forces and user elements with the loads their expressions read (checked once
        // every force is known).
        let mut load_readers: Vec<LoadReader<'a>> = Vec::new();
        for x in &root.children {
            self.build_element(x, &mut load_readers)?;
        }
        self.build_motions()?;
        for (x, attr, loads) in load_readers {
            self.check_load_reads(x, attr, &loads)?;
        }
        Ok(())
    }

    /// Build one child of the root (except motions), by its tag; forces and user elements
    /// whose expressions read loads are added to `load_readers`.
    fn build_element(&mut self, x: &'a XElem, load_readers: &mut Vec<LoadReader<'a>>) -> Result<(), ModelError> {
        match x.tag.as_str() {
            "gravity" => self.build_gravity(x),
            "ground" => self.build_ground(x),
            "body" => self.build_body(x),
            "flexible_body" => self.build_flexible_body(x),
            "joint" => self.build_joint(x),
            "constraint" => self.build_constraint(x),
            "spring_damper" => self.build_spring_damper(x),
            "sforce" => self.build_sforce(x, load_readers),
            "gforce" => self.build_gforce(x, load_readers),
            "bushing" => self.build_bushing(x),
            "rolling_wheel" => self.build_rolling_wheel(x),
            "knife_edge" => self.build_knife_edge(x),
            "velocity_constraint" => self.build_velocity_constraint(x),
            "variable" => self.build_variable(x, load_readers),
            "differential" => self.build_differential(x, load_readers),
            "input" => self.build_input(x),
            "output" => self.build_output(x),
            "linearization" => self.build_linearization(x),
            "experiment" => self.build_experiment(x),
            "analysis" => self.build_analysis(x),
            _ => Ok(()),
        }
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

    /// `<gravity>`: the gravity vector (value and expressions).
    fn build_gravity(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let g = self.el(x).vec3_req("value")?;
        self.model.gravity = g.v3();
        self.model.gravity_expr = Some(g);
        Ok(())
    }

    /// `<ground>`: its markers (`ground.<name>`, on no body).
    fn build_ground(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        for m in &x.children {
            let mk = self.marker(m, "ground", None)?;
            self.model.markers.push(mk);
        }
        Ok(())
    }

    /// `<body>`: the body, then its `cm` marker, then its own markers.
    fn build_body(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let mass = el.num_req("mass")?;
        check_mass(mass.value).map_err(|m| el.err_at(el.get("mass").map_or(x.pos, |a| a.pos), m))?;
        el.req("inertia")?;
        let inertia = el.num_vec("inertia", &[3, 6])?.unwrap_or(NumVec { items: vec![] });
        check_inertia(&inertia.values()).map_err(|m| el.err_at(el.get("inertia").map_or(x.pos, |a| a.pos), m))?;
        let body = body_with(&el, x, mass, inertia)?;
        let name = body.name.clone();
        let idx = self.push_body(body, [0.0; 3]);
        for m in &x.children {
            let mk = self.marker(m, &name, Some(idx))?;
            self.model.markers.push(mk);
        }
        Ok(())
    }

    /// Add `body` and its implicit `cm` marker at `cm` (body frame); its index.
    pub(super) fn push_body(&mut self, body: Body, cm: [f64; 3]) -> usize {
        let idx = self.model.bodies.len();
        let (name, pos) = (body.name.clone(), body.pos);
        self.model.bodies.push(body);
        self.model.markers.push(Marker {
            name: format!("{name}.cm"),
            body: Some(idx),
            position: NumVec { items: cm.map(constant).to_vec() },
            orientation: Orientation::Identity,
            node: None,
            pos,
        });
        idx
    }

    /// A `<marker>` of `owner` (a body's name, or "ground"), on `body`.
    fn marker(&self, x: &'a XElem, owner: &str, body: Option<usize>) -> Result<Marker, ModelError> {
        let el = self.el(x);
        if let Some(a) = el.get("node") {
            return Err(el.err_at(a.pos, format!("'node' is for markers of a <flexible_body>; '{owner}' is rigid")));
        }
        Ok(Marker {
            name: format!("{owner}.{}", x.label()),
            body,
            position: el.vec3_req("position")?,
            orientation: read_orientation(&el)?,
            node: None,
            pos: x.pos,
        })
    }

    /// `<experiment>`: the default start, stop, step and tolerance.
    fn build_experiment(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let v = |n: &str| el.num(n).map(|o| o.map(|n| n.value));
        self.model.experiment =
            Experiment { start: v("start")?, stop: v("stop")?, step: v("step")?, tolerance: v("tolerance")? };
        Ok(())
    }

    /// `<analysis>`: whether to start from static equilibrium.
    fn build_analysis(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let b = self.el(x).keyword("static", &[("true", true), ("false", false)])?;
        self.model.static_analysis = b.unwrap_or(false);
        Ok(())
    }
}

/// A body element `x` with mass properties `mass`, `inertia`: its frame and initial
/// velocities from the attributes `<body>` and `<flexible_body>` share.
pub(super) fn body_with(el: &El, x: &XElem, mass: Num, inertia: NumVec) -> Result<Body, ModelError> {
    Ok(Body {
        name: x.label().into(),
        mass,
        inertia,
        position: el.vec3_req("position")?,
        orientation: read_orientation(el)?,
        velocity: el.num_vec("velocity", &[3])?,
        angular_velocity: el.num_vec("angular_velocity", &[3])?,
        flex: None,
        pos: x.pos,
    })
}

/// A required marker reference.
pub(super) fn marker_ref(el: &El, attr: &str) -> Result<MarkerId, ModelError> {
    el.req(attr)?;
    opt_marker_ref(el, attr)?.ok_or_else(|| el.err(format!("missing required attribute '{attr}'")))
}

/// An optional marker reference (`body.marker`, `ground.marker`, or a body's name).
pub(super) fn opt_marker_ref(el: &El, attr: &str) -> Result<Option<MarkerId>, ModelError> {
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
