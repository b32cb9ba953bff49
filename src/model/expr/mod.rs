//! Expressions: parse (names resolved through a [`Scope`]), analyse dependencies, and
//! evaluate generically over [`crate::ad::Real`] (exact derivatives via dual numbers).

mod ast;
mod env;
mod parse;
mod scope;

pub use ast::*;
pub use env::{ExprEnv, Pose, Twist};
pub use parse::parse;
pub use scope::{ExprError, NameRef, Scope};
