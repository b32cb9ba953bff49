//! First pass: check every element's tag and attributes, declare every name (so that
//! references may point forward), and number markers (each body's `cm` first).

use super::attrs::El;
use super::load::Loader;
use super::names::{Namespace, invalid_name};
use super::xml::XElem;
use crate::model::ModelError;
use crate::model::expr::{ElementRef, NameRef};

/// Elements of the format that this version does not read yet.
const UNSUPPORTED: &[&str] = &[];

/// Allowed and required attributes of each supported element.
pub(crate) fn schema(tag: &str) -> Option<(&'static [&'static str], &'static [&'static str])> {
    Some(match tag {
        "multibody" => (&["name", "version"], &["name", "version"]),
        "parameter" => (&["name", "value", "description", "unit"], &["name", "value"]),
        "gravity" => (&["value"], &["value"]),
        "ground" | "linearization" => (&[], &[]),
        "body" => (
            &["name", "mass", "inertia", "position", "euler313", "z_axis", "x_axis", "velocity", "angular_velocity"],
            &["name", "mass", "inertia", "position"],
        ),
        "flexible_body" => (
            &[
                "name",
                "modal",
                "position",
                "euler313",
                "z_axis",
                "x_axis",
                "velocity",
                "angular_velocity",
                "modal_coordinates",
                "modal_velocities",
            ],
            &["name", "modal", "position"],
        ),
        // `position` is required unless `node` is given (checked when built).
        "marker" => (&["name", "position", "node", "euler313", "z_axis", "x_axis"], &["name"]),
        "joint" => (
            &["name", "type", "i", "j", "ic_angle", "ic_angular_speed", "ic_displacement", "ic_speed"],
            &["name", "type", "i", "j"],
        ),
        "motion" => (&["name", "joint", "dof", "function"], &["name", "joint", "dof", "function"]),
        "constraint" | "state" | "velocity" => (&["name", "function"], &["name", "function"]),
        "spring_damper" => (
            &["name", "type", "i", "j", "stiffness", "damping", "length", "angle", "preload"],
            &["name", "type", "i", "j", "stiffness"],
        ),
        "sforce" => (&["name", "type", "i", "j", "function"], &["name", "type", "i", "j", "function"]),
        "gforce" => (&["name", "i", "j", "frame", "force", "torque"], &["name", "i"]),
        "bushing" => (&["name", "i", "j", "stiffness", "damping"], &["name", "i", "j", "stiffness"]),
        "variable" => (&["name", "function"], &["name", "function"]),
        "rolling_wheel" => (&["name", "marker", "radius", "plane"], &["name", "marker", "radius"]),
        "knife_edge" => (&["name", "marker"], &["name", "marker"]),
        "velocity_constraint" => (&["name", "function"], &["name", "function"]),
        "differential" => (&["name", "start", "function", "implicit"], &["name", "function"]),
        "input" => (&["name", "start", "unit"], &["name"]),
        "output" => (&["name", "function", "unit"], &["name", "function"]),
        "experiment" => (&["start", "stop", "step", "tolerance"], &[]),
        "analysis" => (&["static"], &[]),
        _ => return None,
    })
}

/// Which child elements an element may hold.
fn children_allowed(tag: &str) -> &'static [&'static str] {
    match tag {
        "body" | "flexible_body" | "ground" => &["marker"],
        "linearization" => &["state", "velocity"],
        _ => &[],
    }
}

impl<'a> Loader<'a> {
    /// Check an element's tag, attributes and children's tags (recursively).
    pub(crate) fn check_element(&self, x: &'a XElem, parent: &str) -> Result<(), ModelError> {
        let el = self.el(x);
        if UNSUPPORTED.contains(&x.tag.as_str()) {
            return Err(el.err("element not supported yet"));
        }
        let allowed_here: &[&str] = if parent == "multibody" {
            &[
                "parameter",
                "gravity",
                "ground",
                "body",
                "flexible_body",
                "joint",
                "motion",
                "constraint",
                "spring_damper",
                "sforce",
                "gforce",
                "bushing",
                "rolling_wheel",
                "knife_edge",
                "velocity_constraint",
                "variable",
                "differential",
                "input",
                "output",
                "linearization",
                "experiment",
                "analysis",
            ]
        } else {
            children_allowed(parent)
        };
        let Some((allowed, required)) = schema(&x.tag) else {
            return Err(el.err("unknown element"));
        };
        if !allowed_here.contains(&x.tag.as_str()) {
            return Err(el.err(format!("element <{}> is not allowed inside <{parent}>", x.tag)));
        }
        el.check_attrs(allowed, required)?;
        for c in &x.children {
            self.check_element(c, &x.tag)?;
        }
        Ok(())
    }

    /// Check the `name` attribute of `x` and declare it in `ns`; returns the name.
    fn declare(
        &self,
        ns: &mut Namespace,
        x: &'a XElem,
        kind: &str,
        idx: usize,
        is_marker: bool,
    ) -> Result<String, ModelError> {
        let el = self.el(x);
        let a = el.req("name")?;
        if let Some(msg) = invalid_name(&a.value, is_marker) {
            return Err(el.err_at(a.pos, msg));
        }
        let full = match (is_marker, kind) {
            (true, owner) => format!("{owner}.{}", a.value),
            _ => a.value.clone(),
        };
        ns.declare(&full, idx, x.pos.line).map_err(|line| {
            let what = if is_marker { "marker" } else { kind };
            el.err_at(a.pos, format!("duplicate {what} name '{}' (first defined at line {line})", a.value))
        })?;
        Ok(full)
    }

    /// Declare a bare name usable in expressions (parameters and inputs share these).
    fn declare_bare(&mut self, x: &'a XElem, kind: &'static str, r: NameRef) -> Result<(), ModelError> {
        let mut tmp = Namespace::default();
        let name = self.declare(&mut tmp, x, kind, 0, false)?;
        if let Some(&(prev, line)) = self.scope.names.get(&name) {
            let prev_kind = prev.kind();
            let el = self.el(x);
            let at = el.get("name").map_or(x.pos, |a| a.pos);
            let msg = if prev_kind == kind {
                format!("duplicate {kind} name '{name}' (first defined at line {line})")
            } else {
                format!("name '{name}' is already used by {prev_kind} at line {line}")
            };
            return Err(el.err_at(at, msg));
        }
        self.scope.names.insert(name, (r, x.pos.line));
        Ok(())
    }

    /// Declare an element that load functions (`fx(name)` ...) can name.
    fn declare_element(
        &mut self,
        x: &'a XElem,
        kind: &'static str,
        r: ElementRef,
        idx: usize,
    ) -> Result<(), ModelError> {
        let name = self.declare_in(x, kind, idx)?;
        if let Some(&(_, prev, line)) = self.scope.elements.get(&name) {
            let el = self.el(x);
            let at = el.get("name").map_or(x.pos, |a| a.pos);
            return Err(el.err_at(
                at,
                format!("name '{name}' is already used by {prev} at line {line} (load functions need unique names)"),
            ));
        }
        self.scope.elements.insert(name, (r, kind, x.pos.line));
        Ok(())
    }

    fn declare_markers(&mut self, x: &'a XElem, owner: &str, body: Option<usize>) -> Result<(), ModelError> {
        for m in &x.children {
            let idx = self.scope.marker_body.len();
            let mut ns = std::mem::take(&mut self.ns_markers);
            let res = self.declare(&mut ns, m, owner, idx, true);
            self.ns_markers = ns;
            let full = res?;
            self.scope.markers.insert(full, idx);
            self.scope.marker_body.push(body);
        }
        Ok(())
    }

    /// Reject a second occurrence of a once-only element.
    fn once(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        if let Some(line) = self.singletons.get(&x.tag) {
            let msg = format!("only one <{}> element is allowed (first at line {line})", x.tag);
            return Err(self.el(x).err(msg));
        }
        self.singletons.insert(x.tag.clone(), x.pos.line);
        Ok(())
    }

    /// The first pass over the root's children.
    pub(crate) fn declare_all(&mut self) -> Result<(), ModelError> {
        let root = self.root;
        let mut n = Counts::default();
        for x in &root.children {
            self.check_element(x, "multibody")?;
            self.declare_child(x, &mut n)?;
        }
        Ok(())
    }

    /// Declare the names of one child of the root, numbered among its kind by `n`.
    fn declare_child(&mut self, x: &'a XElem, n: &mut Counts) -> Result<(), ModelError> {
        match x.tag.as_str() {
            "parameter" => self.declare_bare(x, "parameter", NameRef::Param(next(&mut n.params))),
            "input" => self.declare_bare(x, "input", NameRef::Input(next(&mut n.inputs))),
            "body" | "flexible_body" => self.declare_body(x, next(&mut n.bodies)),
            "ground" => self.declare_ground(x),
            "joint" => {
                let k = next(&mut n.joints);
                self.declare_element(x, "joint", ElementRef::Joint(k), k)
            }
            "motion" => {
                let k = next(&mut n.motions);
                self.declare_element(x, "motion", ElementRef::Motion(k), k)
            }
            "constraint" => {
                let k = next(&mut n.constraints);
                self.declare_element(x, "constraint", ElementRef::Constraint(k), k)
            }
            "spring_damper" => {
                let r = ElementRef::SpringDamper(next(&mut n.springs));
                self.declare_element(x, "force", r, next(&mut n.forces))
            }
            "sforce" => self.declare_element(x, "force", ElementRef::Sforce(next(&mut n.sforces)), next(&mut n.forces)),
            "gforce" => self.declare_element(x, "force", ElementRef::Gforce(next(&mut n.gforces)), next(&mut n.forces)),
            "bushing" => {
                let r = ElementRef::Bushing(next(&mut n.bushings));
                self.declare_element(x, "force", r, next(&mut n.forces))
            }
            "rolling_wheel" | "knife_edge" | "velocity_constraint" => {
                self.declare_in(x, "non-holonomic constraint", next(&mut n.nonholonomic)).map(drop)
            }
            "variable" => self.declare_bare(x, "variable", NameRef::Variable(next(&mut n.variables))),
            "differential" => self.declare_bare(x, "differential", NameRef::Diff(next(&mut n.diffs))),
            "output" => self.declare_in(x, "output", next(&mut n.outputs)).map(drop),
            "linearization" => self.declare_linearization(x, &mut n.lin),
            "gravity" | "experiment" | "analysis" => self.once(x),
            _ => Ok(()),
        }
    }

    /// `<body>` number `idx`: its name, its `cm` marker (numbered first), then its own
    /// markers.
    fn declare_body(&mut self, x: &'a XElem, idx: usize) -> Result<(), ModelError> {
        let name = self.declare_in(x, "body", idx)?;
        let cm = self.scope.marker_body.len();
        self.scope.marker_body.push(Some(idx));
        self.scope.markers.insert(format!("{name}.cm"), cm);
        self.scope.body_cm.insert(name.clone(), cm);
        self.scope.body_names.push(name.clone());
        if x.tag == "flexible_body" {
            let spec = self.read_modal_data(x)?;
            self.scope.flexible.insert(name.clone(), (cm, spec.data.modes.len()));
            self.flex_data.insert(idx, spec);
        }
        self.declare_markers(x, &name, Some(idx))
    }

    /// `<ground>` (once only): its markers, on no body.
    fn declare_ground(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        self.once(x)?;
        self.declare_markers(x, "ground", None)
    }

    /// `<linearization>` (once only): its states and velocities, numbered on from `n`.
    fn declare_linearization(&mut self, x: &'a XElem, n: &mut usize) -> Result<(), ModelError> {
        self.once(x)?;
        for c in &x.children {
            self.declare_in(c, "linearization state", next(n))?;
        }
        Ok(())
    }

    /// Check the `name` of `x` and declare it in the namespace of `kind` (see
    /// [`Self::namespace`]); returns the name.
    fn declare_in(&mut self, x: &'a XElem, kind: &str, idx: usize) -> Result<String, ModelError> {
        let mut ns = std::mem::take(self.namespace(kind));
        let res = self.declare(&mut ns, x, kind, idx, false);
        *self.namespace(kind) = ns;
        res
    }

    /// The namespace of a kind of named element (every other kind: forces).
    fn namespace(&mut self, kind: &str) -> &mut Namespace {
        match kind {
            "body" => &mut self.ns_bodies,
            "joint" => &mut self.ns_joints,
            "motion" => &mut self.ns_motions,
            "constraint" => &mut self.ns_constraints,
            "non-holonomic constraint" => &mut self.ns_nonholonomic,
            "output" => &mut self.ns_outputs,
            "linearization state" => &mut self.ns_lin,
            _ => &mut self.ns_forces,
        }
    }

    /// An attribute reader for `x` with the current scope and parameter values.
    pub(crate) fn el(&self, x: &'a XElem) -> El<'_> {
        El { x, src: self.src, scope: &self.scope, params: &self.params }
    }
}

/// How many elements of each kind the first pass has numbered so far.
#[derive(Default)]
struct Counts {
    params: usize,
    inputs: usize,
    bodies: usize,
    joints: usize,
    motions: usize,
    constraints: usize,
    springs: usize,
    sforces: usize,
    gforces: usize,
    bushings: usize,
    nonholonomic: usize,
    variables: usize,
    diffs: usize,
    forces: usize,
    outputs: usize,
    lin: usize,
}

/// The next number of a count: its current value, then one more.
fn next(count: &mut usize) -> usize {
    let k = *count;
    *count += 1;
    k
}
