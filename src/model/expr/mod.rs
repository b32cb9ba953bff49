//! Expressions: parse (names resolved through a [`Scope`]), analyse dependencies, and
//! evaluate generically over [`crate::ad::Real`] (exact derivatives via dual numbers).

mod ast;
mod deps;
mod env;
mod eval;
mod lexer;
mod parse;
mod scope;
#[cfg(test)]
mod tests;

pub use ast::*;
pub use deps::{Deps, const_value, deps, is_constant};
pub use env::{ExprEnv, Pose, Twist};
pub use eval::{angle_count, eval};
pub use parse::{MAX_DEPTH, function_names, keywords, parse};
pub use scope::{ExprError, NameRef, Scope};
