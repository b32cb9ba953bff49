//! Expression parser (stub: replaced by the real parser).

use super::ast::Expr;
use super::scope::{ExprError, Scope};

/// Parse `src` into an [`Expr`], resolving names through `scope`.
pub fn parse(src: &str, scope: &dyn Scope) -> Result<Expr, ExprError> {
    let _ = (src, scope);
    Err(ExprError {
        offset: 0,
        msg: "expression parser not implemented".into(),
    })
}
