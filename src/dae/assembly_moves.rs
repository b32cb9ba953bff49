//! Warnings of initialization: bodies that assembly moved far from where the model put them.

use super::init::Assembly;
use crate::mechanics::body::NQ;
use crate::model::Model;

/// Assembly moving a body's CM by more than this fraction of the model's size (the
/// diagonal of the box around the initial CM positions and the ground origin, at least
/// 1 m) is reported: the geometry as written is probably not the mechanism meant.
pub const ASSEMBLY_MOVE_FRACTION: f64 = 0.01;

/// Bodies whose CM assembly moved by more than [`ASSEMBLY_MOVE_FRACTION`] of the model's
/// size while making the drawing consistent with the constraints (from `q0`, the model's
/// coordinates, to `assembly.drawn`), as messages naming the body, the distance and the
/// constraints the drawing does not meet. Moves the exact conditions (`ic_angle`,
/// `ic_displacement`, motions at t0) ask for are what the user asked: no warning.
pub(super) fn assembly_moves(model: &Model, q0: &[f64], assembly: &Assembly) -> Vec<String> {
    let q = &assembly.drawn;
    let unmet: Vec<String> = assembly.drawing_unmet.iter().map(|(tag, name, _)| format!("{tag} '{name}'")).collect();
    let cm = |q: &[f64], b: usize| [q[NQ * b], q[NQ * b + 1], q[NQ * b + 2]];
    let (mut lo, mut hi) = ([0.0f64; 3], [0.0f64; 3]);
    for b in 0..model.bodies.len() {
        for (k, x) in cm(q0, b).into_iter().enumerate() {
            lo[k] = lo[k].min(x);
            hi[k] = hi[k].max(x);
        }
    }
    let size = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt().max(1.0);
    (0..model.bodies.len())
        .filter_map(|b| {
            let (a, z) = (cm(q0, b), cm(q, b));
            let d = (0..3).map(|k| (z[k] - a[k]).powi(2)).sum::<f64>().sqrt();
            (d > ASSEMBLY_MOVE_FRACTION * size).then(|| {
                format!(
                    "assembly moved body '{}' by {d:.3e} m (more than {} of the model's size {size:.3e} m): \
                     the drawing disagrees with {}; the initial geometry may not be the mechanism meant",
                    model.bodies[b].name,
                    ASSEMBLY_MOVE_FRACTION,
                    unmet.join(", ")
                )
            })
        })
        .collect()
}
