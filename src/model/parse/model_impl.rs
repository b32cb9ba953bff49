//! Queries on a loaded [`Model`]: parameter values, re-evaluation with new parameter
//! values, marker lookup and a size summary.

use super::orient::try_rotation;
use super::validate::{check_inertia, check_mass};
use crate::model::expr::const_value;
use crate::model::{Model, Num, NumVec, Orientation};
use std::fmt;

/// Size of a model: bodies, coordinates (6 per body), constraint equations, and their
/// difference, the degrees of freedom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Summary {
    /// Number of bodies (ground not counted).
    pub bodies: usize,
    /// 6 · bodies.
    pub coordinates: usize,
    /// Holonomic equations: joints + motions + user constraints + wheel contacts.
    pub constraints: usize,
    /// coordinates − constraints.
    pub dof: isize,
    /// Non-holonomic equations (2 per rolling wheel, 1 per knife edge and velocity
    /// constraint): velocity-level degrees of freedom = dof − this.
    pub nonholonomic: usize,
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} bodies, {} coordinates, {} constraint equations, {} degrees of freedom",
            self.bodies, self.coordinates, self.constraints, self.dof
        )?;
        if self.nonholonomic > 0 {
            write!(
                f,
                "; {} non-holonomic equations, {} velocity degrees of freedom",
                self.nonholonomic,
                self.dof - self.nonholonomic as isize
            )?;
        }
        Ok(())
    }
}

fn orientation_nums(o: &mut Orientation) -> Vec<&mut Num> {
    match o {
        Orientation::Identity => vec![],
        Orientation::Euler313(e) => e.items.iter_mut().collect(),
        Orientation::Axes(z, x) => {
            let mut v: Vec<&mut Num> = z.items.iter_mut().collect();
            if let Some(x) = x {
                v.extend(x.items.iter_mut());
            }
            v
        }
    }
}

fn vec_nums(v: &mut NumVec) -> impl Iterator<Item = &mut Num> {
    v.items.iter_mut()
}

impl Model {
    /// The evaluated value of every parameter, in file order.
    pub fn param_values(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.value.value).collect()
    }

    /// Index in [`Model::markers`] of a marker by full name (`body.marker`, `ground.marker`,
    /// `body.cm`); a bare body name means its `cm` marker.
    pub fn marker_index(&self, full_name: &str) -> Option<usize> {
        self.markers.iter().position(|m| m.name == full_name).or_else(|| {
            let b = self.bodies.iter().position(|b| b.name == full_name)?;
            self.markers.iter().position(|m| m.body == Some(b) && m.name == format!("{full_name}.cm"))
        })
    }

    /// The modal data of the flexible bodies, in body order, as [`crate::modal::write`]
    /// gives them: their values, not their files' formatting (what identifies an FMU
    /// beyond the model text).
    pub fn modal_data_texts(&self) -> Vec<String> {
        self.bodies.iter().filter_map(|b| b.flex.as_ref()).map(|f| crate::modal::write(&f.data)).collect()
    }

    /// Every constant attribute (not the parameters' own values), for re-evaluation.
    fn nums_mut(&mut self) -> Vec<&mut Num> {
        let mut v: Vec<&mut Num> = Vec::new();
        if let Some(g) = &mut self.gravity_expr {
            v.extend(vec_nums(g));
        }
        for b in &mut self.bodies {
            v.push(&mut b.mass);
            v.extend(vec_nums(&mut b.inertia));
            v.extend(vec_nums(&mut b.position));
            v.extend(orientation_nums(&mut b.orientation));
            for w in [&mut b.velocity, &mut b.angular_velocity].into_iter().flatten() {
                v.extend(vec_nums(w));
            }
            if let Some(f) = &mut b.flex {
                v.extend([&mut f.eta0, &mut f.eta_dot0].into_iter().flatten().flat_map(vec_nums));
            }
        }
        for m in &mut self.markers {
            v.extend(vec_nums(&mut m.position));
            v.extend(orientation_nums(&mut m.orientation));
        }
        for j in &mut self.joints {
            let ics = [&mut j.ic_angle, &mut j.ic_angular_speed, &mut j.ic_displacement, &mut j.ic_speed];
            v.extend(ics.into_iter().flatten());
        }
        for s in &mut self.spring_dampers {
            v.extend([&mut s.stiffness, &mut s.damping, &mut s.length, &mut s.preload]);
        }
        for b in &mut self.bushings {
            v.extend(vec_nums(&mut b.stiffness));
            v.extend(b.damping.iter_mut().flat_map(vec_nums));
        }
        for w in &mut self.rolling_wheels {
            v.push(&mut w.radius);
        }
        for d in &mut self.differentials {
            v.push(&mut d.start);
        }
        for i in &mut self.inputs {
            v.push(&mut i.start);
        }
        v
    }

    /// A copy with new parameter values (`values[i]` overrides parameter `i`'s expression)
    /// and every constant attribute re-evaluated; errors when the count is wrong or a value
    /// becomes invalid (non-finite, non-positive mass, inertia not positive definite,
    /// degenerate axes, non-positive wheel radius).
    pub fn with_params(&self, values: &[f64]) -> Result<Model, String> {
        if values.len() != self.parameters.len() {
            return Err(format!("expected {} parameter values, got {}", self.parameters.len(), values.len()));
        }
        let mut m = self.clone();
        for (p, &v) in m.parameters.iter_mut().zip(values) {
            if !v.is_finite() {
                return Err(format!("parameter '{}': value {v} is not finite", p.name));
            }
            p.value.value = v;
        }
        for n in m.nums_mut() {
            n.value = const_value(&n.expr, values);
            if !n.value.is_finite() {
                return Err(format!("an attribute evaluates to {} with these parameters", n.value));
            }
        }
        if let Some(g) = &m.gravity_expr {
            m.gravity = g.v3();
        }
        for b in &m.bodies {
            check_mass(b.mass.value).map_err(|e| format!("body '{}': {e}", b.name))?;
            check_inertia(&b.inertia.values()).map_err(|e| format!("body '{}': {e}", b.name))?;
            try_rotation(&b.orientation).map_err(|e| format!("body '{}': {e}", b.name))?;
        }
        for mk in &m.markers {
            try_rotation(&mk.orientation).map_err(|e| format!("marker '{}': {e}", mk.name))?;
        }
        for w in &m.rolling_wheels {
            if w.radius.value <= 0.0 {
                return Err(format!("rolling_wheel '{}': radius must be positive (got {})", w.name, w.radius.value));
            }
        }
        Ok(m)
    }

    /// Bodies, coordinates, constraint equations and degrees of freedom.
    pub fn summary(&self) -> Summary {
        let bodies = self.bodies.len();
        let coordinates = 6 * bodies;
        let constraints = self.joints.iter().map(|j| j.kind.equations()).sum::<usize>()
            + self.motions.len()
            + self.constraints.len()
            + self.rolling_wheels.len();
        let dof = coordinates as isize - constraints as isize;
        let nonholonomic = 2 * self.rolling_wheels.len() + self.knife_edges.len() + self.velocity_constraints.len();
        Summary { bodies, coordinates, constraints, dof, nonholonomic }
    }
}
