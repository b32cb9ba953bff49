//! Building the force elements: spring-dampers, sforces, gforces and bushings.

use super::attrs::El;
use super::build::{LoadReader, marker_ref, opt_marker_ref};
use super::load::Loader;
use super::validate::{Allowed, check_body_count, check_deps};
use super::xml::XElem;
use crate::model::expr::{self, Expr, MarkerId};
use crate::model::*;

const SPRING_TYPES: &[(&str, SpringType)] =
    &[("translational", SpringType::Translational), ("rotational", SpringType::Rotational)];

impl<'a> Loader<'a> {
    /// `<spring_damper>`: a translational or rotational spring-damper.
    pub(super) fn build_spring_damper(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let s = spring_damper(&self.el(x))?;
        self.model.spring_dampers.push(s);
        Ok(())
    }

    /// `<sforce>`: one force (along the line of sight of i and j) or torque (about z_j)
    /// component, `function`; the loads it reads go to `load_readers`.
    pub(super) fn build_sforce(
        &mut self,
        x: &'a XElem,
        load_readers: &mut Vec<LoadReader<'a>>,
    ) -> Result<(), ModelError> {
        let el = self.el(x);
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
        Ok(())
    }

    /// `<gforce>`: force and torque at marker i in marker `frame`'s axes, reaction on j;
    /// the loads each component reads go to `load_readers`.
    pub(super) fn build_gforce(
        &mut self,
        x: &'a XElem,
        load_readers: &mut Vec<LoadReader<'a>>,
    ) -> Result<(), ModelError> {
        let el = self.el(x);
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
        Ok(())
    }

    /// `<bushing>`: six stiffnesses (and optional dampings) between markers on two
    /// different bodies.
    pub(super) fn build_bushing(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
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
        Ok(())
    }
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
