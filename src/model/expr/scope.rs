//! Name resolution for the expression parser.

use super::ast::{ElementRef, MarkerId};

/// What a bare identifier in an expression names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NameRef {
    /// Parameter, index into `Model::parameters`.
    Param(usize),
    /// Input, index into `Model::inputs`.
    Input(usize),
    /// User variable V, index into `Model::variables`.
    Variable(usize),
    /// Differential state X, index into `Model::differentials`.
    Diff(usize),
}

impl NameRef {
    /// The element kind the name belongs to, as a model file spells it.
    pub fn kind(&self) -> &'static str {
        match self {
            NameRef::Param(_) => "parameter",
            NameRef::Input(_) => "input",
            NameRef::Variable(_) => "variable",
            NameRef::Diff(_) => "differential",
        }
    }
}

/// Resolves names while parsing; implemented by the model parser.
pub trait Scope {
    /// A bare identifier (parameter, input, variable, differential).
    fn name(&self, name: &str) -> Option<NameRef>;
    /// A marker: `body.marker`, `ground.marker`, or a bare body name (its `cm`).
    fn marker(&self, name: &str) -> Option<MarkerId>;
    /// An element named in `fx(name)` and the other load functions.
    fn element(&self, name: &str) -> Option<ElementRef>;
    /// A flexible body named in `modal(name, k)`: its `cm` marker and its number of modes.
    fn flexible(&self, name: &str) -> Option<(MarkerId, usize)>;
}

/// A parse error at a character offset of the expression text.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{msg}")]
pub struct ExprError {
    /// 0-based character offset into the expression text.
    pub offset: usize,
    /// What is wrong.
    pub msg: String,
}
