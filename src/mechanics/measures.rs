//! What a linearization state measures (seed Eq. 30: S = s(q, t)), as data the layers
//! below linearization hold too: initialization meets start values set on states.
//! Evaluated in [`super::measure_values`].

use crate::model::expr::Expr;

/// What a state measures.
#[derive(Clone, Debug, PartialEq)]
pub enum StateKind {
    /// A `<linearization><state>` expression.
    User {
        /// The expression s(q, t).
        f: Expr,
        /// Its angle-unwrapping slot base.
        abase: usize,
    },
    /// A joint's free coordinate (`sys.joint_coords`).
    Joint {
        /// The coordinate as an expression.
        f: Expr,
        /// Its angle-unwrapping slot base.
        abase: usize,
        /// What it measures, frame stated.
        about: String,
    },
    /// CM coordinate k (x, y, z) of a body, ground frame.
    Position {
        /// 0, 1, 2: x, y, z.
        k: usize,
    },
    /// Modal coordinate k of a flexible body.
    Modal {
        /// 0-based mode index.
        k: usize,
    },
    /// 3-1-3 angle k (ψ, θ, φ) of a body relative to the fixed frame `r0`.
    Angle {
        /// 0, 1, 2: ψ, θ, φ.
        k: usize,
        /// The body's reference frame, fixed at selection time.
        r0: [[f64; 3]; 3],
    },
}
