//! Names: validity rules, namespaces (duplicate detection) and the expression [`Scope`].

use crate::model::expr::{ElementRef, MarkerId, NameRef, Scope, function_names};
use std::collections::HashMap;

/// Why `name` is not a valid element name, if it is not.
pub(crate) fn invalid_name(name: &str, is_marker: bool) -> Option<String> {
    let mut chars = name.chars();
    let ok_start = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if !ok_start || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Some(format!("invalid name '{name}' (names are [A-Za-z_][A-Za-z0-9_]*)"));
    }
    if matches!(name, "pi" | "time" | "ground") {
        return Some(format!("invalid name '{name}' (reserved word)"));
    }
    if is_marker && name == "cm" {
        return Some("invalid name 'cm' (reserved for the implicit centre-of-mass marker)".into());
    }
    if function_names().contains(&name) {
        return Some(format!("invalid name '{name}' (it is a function name)"));
    }
    None
}

/// The names declared so far, by kind, with the line of each declaration.
#[derive(Default)]
pub(crate) struct Namespace {
    seen: HashMap<String, (usize, usize)>,
}

impl Namespace {
    /// Declare `name` (index `idx`, at `line`); returns the line of an earlier declaration.
    pub fn declare(&mut self, name: &str, idx: usize, line: usize) -> Result<(), usize> {
        if let Some(&(_, l)) = self.seen.get(name) {
            return Err(l);
        }
        self.seen.insert(name.to_string(), (idx, line));
        Ok(())
    }
    /// Index of a declared name.
    pub fn get(&self, name: &str) -> Option<usize> {
        self.seen.get(name).map(|&(i, _)| i)
    }
    /// Line of a declared name.
    pub fn line(&self, name: &str) -> Option<usize> {
        self.seen.get(name).map(|&(_, l)| l)
    }
}

/// Everything a name in the model can refer to; implements the expression [`Scope`].
#[derive(Default)]
pub(crate) struct ModelScope {
    /// Bare names: parameters, inputs, variables and differentials (one namespace, so an
    /// expression is unambiguous), with the line each was declared on.
    pub names: HashMap<String, (NameRef, usize)>,
    /// Full marker names (`body.m`, `ground.m`, `body.cm`) to index.
    pub markers: HashMap<String, MarkerId>,
    /// Owning body of each marker (`None` = ground), by marker index.
    pub marker_body: Vec<Option<usize>>,
    /// Body names by index.
    pub body_names: Vec<String>,
    /// Body name to the index of its `cm` marker.
    pub body_cm: HashMap<String, MarkerId>,
    /// Elements that load functions can name (joints, motions, constraints, forces).
    pub elements: HashMap<String, (ElementRef, &'static str, usize)>,
    /// Flexible body name to its `cm` marker and number of modes (`modal(body, k)`).
    pub flexible: HashMap<String, (MarkerId, usize)>,
}

impl Scope for ModelScope {
    fn name(&self, name: &str) -> Option<NameRef> {
        self.names.get(name).map(|&(r, _)| r)
    }
    fn marker(&self, name: &str) -> Option<MarkerId> {
        self.markers.get(name).or_else(|| self.body_cm.get(name)).copied()
    }
    fn element(&self, name: &str) -> Option<ElementRef> {
        self.elements.get(name).map(|&(r, _, _)| r)
    }
    fn flexible(&self, name: &str) -> Option<(MarkerId, usize)> {
        self.flexible.get(name).copied()
    }
}
