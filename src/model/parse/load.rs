//! The reading pipeline: XML tree → root checks → names declared → parameters
//! evaluated → elements built and validated.

use super::names::{ModelScope, Namespace, invalid_name};
use super::params;
use super::source::Source;
use super::xml::{self, XElem};
use crate::model::{Experiment, FlexSpec, Model, ModelError, Num, Parameter};
use std::collections::HashMap;

/// State of one model read.
pub(crate) struct Loader<'a> {
    /// The model text and its file label: positions and error messages.
    pub src: &'a Source<'a>,
    /// The `<multibody>` root element.
    pub root: &'a XElem,
    /// Every name the first pass declared; expressions resolve names against it.
    pub scope: ModelScope,
    /// Evaluated parameter values in file order (empty until `evaluate_parameters`).
    pub params: Vec<f64>,
    /// Body names, for duplicate detection.
    pub ns_bodies: Namespace,
    /// Full marker names (`owner.marker`), for duplicate detection.
    pub ns_markers: Namespace,
    /// Joint names to joint index; motions look their joint up here.
    pub ns_joints: Namespace,
    /// Motion names, for duplicate detection.
    pub ns_motions: Namespace,
    /// User constraint names, for duplicate detection.
    pub ns_constraints: Namespace,
    /// Names of spring-dampers, sforces, gforces and bushings: one namespace, numbered
    /// across the four kinds.
    pub ns_forces: Namespace,
    /// Output names (a linearization state may not reuse one).
    pub ns_outputs: Namespace,
    /// Linearization `<state>` and `<velocity>` names: one namespace.
    pub ns_lin: Namespace,
    /// Rolling wheel, knife edge and velocity constraint names: one namespace.
    pub ns_nonholonomic: Namespace,
    /// Once-only elements already seen, with their line.
    pub singletons: HashMap<String, usize>,
    /// The modal data of each flexible body (by body index), read when its name is
    /// declared (expressions check mode numbers against it) and moved into the body when
    /// it is built.
    pub flex_data: HashMap<usize, FlexSpec>,
    /// The model being filled in; returned once every pass has succeeded.
    pub model: Model,
}

/// Read a model from its text; `file` labels messages.
pub(crate) fn load(text: &str, file: &str) -> Result<Model, ModelError> {
    let src = Source::new(text, file);
    let root = xml::read(&src)?;
    let mut l = Loader {
        src: &src,
        root: &root,
        scope: ModelScope::default(),
        params: Vec::new(),
        ns_bodies: Namespace::default(),
        ns_markers: Namespace::default(),
        ns_joints: Namespace::default(),
        ns_motions: Namespace::default(),
        ns_constraints: Namespace::default(),
        ns_forces: Namespace::default(),
        ns_outputs: Namespace::default(),
        ns_lin: Namespace::default(),
        ns_nonholonomic: Namespace::default(),
        singletons: HashMap::new(),
        flex_data: HashMap::new(),
        model: empty_model(file),
    };
    l.check_root()?;
    l.declare_all()?;
    l.evaluate_parameters()?;
    l.build_all()?;
    Ok(l.model)
}

fn empty_model(file: &str) -> Model {
    Model {
        name: String::new(),
        file: file.to_string(),
        parameters: Vec::new(),
        gravity: [0.0; 3],
        gravity_expr: None,
        bodies: Vec::new(),
        markers: Vec::new(),
        joints: Vec::new(),
        motions: Vec::new(),
        constraints: Vec::new(),
        spring_dampers: Vec::new(),
        sforces: Vec::new(),
        gforces: Vec::new(),
        bushings: Vec::new(),
        variables: Vec::new(),
        differentials: Vec::new(),
        rolling_wheels: Vec::new(),
        knife_edges: Vec::new(),
        velocity_constraints: Vec::new(),
        inputs: Vec::new(),
        outputs: Vec::new(),
        lin_states: Vec::new(),
        lin_velocities: Vec::new(),
        experiment: Experiment::default(),
        static_analysis: false,
        state_starts: Vec::new(),
    }
}

impl<'a> Loader<'a> {
    fn check_root(&mut self) -> Result<(), ModelError> {
        let root = self.root;
        let el = self.el(root);
        if root.tag != "multibody" {
            return Err(el.err(format!("root element must be <multibody>, found <{}>", root.tag)));
        }
        el.check_attrs(&["name", "version"], &["name", "version"])?;
        let name = el.req("name")?;
        if let Some(msg) = invalid_name(&name.value, false) {
            return Err(el.err_at(name.pos, msg));
        }
        let version = el.req("version")?;
        if version.value.trim() != "1" {
            let msg = format!("unsupported version '{}' (this reader knows version \"1\")", version.value);
            return Err(el.err_at(version.pos, msg));
        }
        self.model.name = name.value.clone();
        Ok(())
    }

    /// Parameters: parse every value, then evaluate in dependency order.
    fn evaluate_parameters(&mut self) -> Result<(), ModelError> {
        let xs: Vec<&XElem> = self.root.children.iter().filter(|x| x.tag == "parameter").collect();
        let mut exprs = Vec::with_capacity(xs.len());
        let mut names = Vec::with_capacity(xs.len());
        for x in &xs {
            let el = self.el(x);
            let a = el.req("value")?;
            let off = a.value.len() - a.value.trim_start().len();
            exprs.push(el.const_expr(a, a.value[..off].chars().count(), a.value.trim())?);
            names.push(x.label().to_string());
        }
        let values = params::evaluate(&exprs, &names).map_err(|(i, msg)| {
            let x = xs.get(i).copied().unwrap_or(self.root);
            self.el(x).err(msg)
        })?;
        for ((x, e), v) in xs.iter().zip(exprs).zip(&values) {
            let el = self.el(x);
            if !v.is_finite() {
                let at = el.get("value").map_or(x.pos, |a| a.pos);
                return Err(el.err_at(at, format!("'value' evaluates to {v}")));
            }
            self.model.parameters.push(Parameter {
                name: x.label().to_string(),
                value: Num { expr: e, value: *v },
                unit: el.unit()?,
                description: el.get("description").map(|a| a.value.clone()),
                pos: x.pos,
            });
        }
        self.params = values;
        Ok(())
    }
}
