//! Connected components of a mechanism: bodies are connected when a constraint element
//! (joint, motion, user constraint) or a force element touches both, or when a group
//! given by the caller (e.g. the bodies a linearization state reads) contains both. Ground
//! connects nothing. Bodies of different components do not influence each other: the
//! equations of motion (Eq. 13a–13e) of one component involve only its own q, u, λ.

use super::forces::{ForceEl, ForceKind};
use super::system::System;
use crate::model::expr::deps;
use std::collections::BTreeSet;

/// Component index of every body (0, 1, ... in order of first appearance), with the
/// system's elements and the `extra` body groups joining bodies.
pub fn components(sys: &System, extra: &[&[usize]]) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..sys.nb()).collect();
    fn root(parent: &mut [usize], mut b: usize) -> usize {
        while parent[b] != b {
            parent[b] = parent[parent[b]];
            b = parent[b];
        }
        b
    }
    let groups = sys
        .constraints
        .iter()
        .map(|c| c.bodies.as_slice())
        .chain(sys.forces.iter().map(|f| f.bodies.as_slice()))
        .chain(sys.nonholonomic.iter().map(|c| c.bodies.as_slice()))
        .chain(sys.user.iter().map(|u| u.bodies.as_slice()))
        .chain(extra.iter().copied());
    for g in groups {
        for w in g.windows(2) {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut id = vec![usize::MAX; sys.nb()];
    let mut next = 0;
    (0..sys.nb())
        .map(|b| {
            let r = root(&mut parent, b);
            if id[r] == usize::MAX {
                id[r] = next;
                next += 1;
            }
            id[r]
        })
        .collect()
}

/// Inputs (indices) that a force element's functions read.
pub fn force_inputs(el: &ForceEl) -> BTreeSet<usize> {
    match &el.kind {
        ForceKind::SpringDamper { .. } | ForceKind::Bushing { .. } => BTreeSet::new(),
        ForceKind::Sforce { f, .. } => deps(f).inputs.into_iter().collect(),
        ForceKind::Gforce { force, torque, .. } => {
            force.iter().chain(torque.iter()).flat_map(|e| deps(e).inputs).collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_pendulums_and_a_free_body_are_three_components_unless_a_group_joins_them() {
        let text = r#"<multibody name="c" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="a1" mass="1" inertia="1 1 1" position="0 0 -1"><marker name="P" position="0 0 1"/></body>
  <body name="b1" mass="1" inertia="1 1 1" position="3 0 -1"><marker name="P" position="0 0 1"/></body>
  <body name="a2" mass="1" inertia="1 1 1" position="0 0 -2"><marker name="P" position="0 0 1"/></body>
  <body name="free" mass="1" inertia="1 1 1" position="9 0 0"/>
  <joint name="ja" type="revolute" i="a1.P" j="ground.O"/>
  <joint name="jb" type="spherical" i="b1.P" j="ground.O"/>
  <joint name="ja2" type="revolute" i="a2.P" j="a1.cm"/>
  <input name="T"/>
  <gforce name="g" i="b1.cm" torque="0 0 T"/>
</multibody>"#;
        let model = crate::model::load_str(text, "c.xml").unwrap_or_else(|e| panic!("{e}"));
        let sys = System::from_model(&model).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(components(&sys, &[]), [0, 1, 0, 2]);
        assert_eq!(components(&sys, &[&[1, 3]]), [0, 1, 0, 1]);
        assert_eq!(force_inputs(&sys.forces[0]), [0].into());
    }
}
