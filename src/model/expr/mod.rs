//! Expressions: parse (names resolved through a [`Scope`]), analyse dependencies, and
//! evaluate generically over [`crate::ad::Real`] (exact derivatives via dual numbers).

mod ast;
mod env;
#[allow(dead_code)] // TEMPORARY: the stub in stub_api.rs shadows it until the merge.
mod parse;
mod scope;
mod stub_api; // TEMPORARY: remove on merge with branch `expr`.

pub use ast::*;
pub use env::{ExprEnv, Pose, Twist};
pub use scope::{ExprError, NameRef, Scope};
pub use stub_api::{Deps, const_value, deps, function_names, is_constant, parse}; // TEMPORARY
