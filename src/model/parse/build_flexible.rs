//! `<flexible_body>`: a body whose flexibility comes from a modal data file (MODEL_FORMAT.md,
//! "Flexible bodies"), and its markers, each attached to a node of the data.

use super::attrs::constant;
use super::build::body_with;
use super::load::Loader;
use super::orient::read_orientation;
use super::xml::XElem;
use crate::modal::ModalData;
use crate::model::*;
use std::path::Path;

impl<'a> Loader<'a> {
    /// The modal data file of a `<flexible_body>` (its `modal` attribute), read and
    /// validated; errors at the attribute, naming the file and the entry.
    pub(super) fn read_modal_data(&self, x: &'a XElem) -> Result<FlexSpec, ModelError> {
        let el = self.el(x);
        let attr = el.req("modal")?;
        let file = attr.value.clone();
        let path = resolve(&self.model.file, &file);
        let data = crate::modal::read(Path::new(&path)).map_err(|e| el.err_at(attr.pos, format!("modal data: {e}")))?;
        Ok(FlexSpec { file, path, data, eta0: None, eta_dot0: None })
    }

    /// `<flexible_body>` (its modal data read when its name was declared): the body (mass
    /// and inertia of the undeformed body), its `cm` marker (at the undeformed centre of
    /// mass, fixed in the body frame), its node markers and its initial modal state.
    pub(super) fn build_flexible_body(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let idx = self.model.bodies.len();
        let mut spec = match self.flex_data.remove(&idx) {
            Some(s) => s,
            None => self.read_modal_data(x)?,
        };
        let el = self.el(x);
        let n = spec.data.modes.len();
        spec.eta0 = el.num_vec("modal_coordinates", &[n])?;
        spec.eta_dot0 = el.num_vec("modal_velocities", &[n])?;
        let (mass, cm, inertia) = rigid_properties(&spec.data);
        let name = x.label().to_string();
        let j = [inertia[0][0], inertia[1][1], inertia[2][2], inertia[0][1], inertia[0][2], inertia[1][2]];
        let body = body_with(&el, x, constant(mass), NumVec { items: j.map(constant).to_vec() })?;
        let idx = self.push_body(body, cm);
        for m in &x.children {
            let mk = self.node_marker(m, &name, idx, &spec.data, &spec.path)?;
            self.model.markers.push(mk);
        }
        self.model.bodies[idx].flex = Some(spec);
        Ok(())
    }

    /// A `<marker>` of a flexible body: `node` (an id of the data) instead of `position`.
    fn node_marker(
        &self,
        x: &'a XElem,
        owner: &str,
        body: usize,
        data: &ModalData,
        path: &str,
    ) -> Result<Marker, ModelError> {
        let el = self.el(x);
        if let Some(a) = el.get("position") {
            return Err(el.err_at(a.pos, "a marker of a <flexible_body> sits on a node: give 'node', not 'position'"));
        }
        let a =
            el.get("node").ok_or_else(|| el.err("missing required attribute 'node' (a node id of the modal data)"))?;
        let id: u32 = a
            .value
            .trim()
            .parse()
            .map_err(|_| el.err_at(a.pos, format!("node '{}' is not a node id (a whole number)", a.value)))?;
        let node = data.nodes.iter().position(|n| n.id == id).ok_or_else(|| {
            el.err_at(a.pos, format!("node {id} is not in the modal data file '{path}' ({} nodes)", data.nodes.len()))
        })?;
        Ok(Marker {
            name: format!("{owner}.{}", x.label()),
            body: Some(body),
            position: NumVec { items: data.nodes[node].position.map(constant).to_vec() },
            orientation: read_orientation(&el)?,
            node: Some(node),
            pos: x.pos,
        })
    }
}

/// `file` relative to the directory of the model file `model_file` (unless absolute).
fn resolve(model_file: &str, file: &str) -> String {
    let p = Path::new(file);
    if p.is_absolute() {
        return file.to_string();
    }
    match Path::new(model_file).parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(p).display().to_string(),
        _ => file.to_string(),
    }
}

/// Mass, centre of mass (body frame) and inertia about it (body axes) of the undeformed
/// body: its node masses and rotary inertias.
fn rigid_properties(data: &ModalData) -> (f64, [f64; 3], [[f64; 3]; 3]) {
    let mass: f64 = data.nodes.iter().map(|n| n.mass).sum();
    let cm: [f64; 3] = std::array::from_fn(|a| data.nodes.iter().map(|n| n.mass * n.position[a]).sum::<f64>() / mass);
    let mut j = [[0.0; 3]; 3];
    for n in &data.nodes {
        let d: [f64; 3] = std::array::from_fn(|a| n.position[a] - cm[a]);
        let d2 = d.iter().map(|x| x * x).sum::<f64>();
        for a in 0..3 {
            j[a][a] += n.mass * d2 + n.inertia[a];
            for b in 0..3 {
                j[a][b] -= n.mass * d[a] * d[b];
            }
        }
    }
    (mass, cm, j)
}
