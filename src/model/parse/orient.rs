//! Orientation attributes (`euler313` | `z_axis [x_axis]`) and their rotation matrices.

use super::attrs::El;
use crate::model::{ModelError, Orientation};

/// Read the orientation attributes of a body or marker.
pub(crate) fn read_orientation(el: &El) -> Result<Orientation, ModelError> {
    let euler = el.num_vec("euler313", &[3])?;
    let z = el.num_vec("z_axis", &[3])?;
    let x = el.num_vec("x_axis", &[3])?;
    let o = match (euler, z, x) {
        (Some(_), Some(_), _) | (Some(_), None, Some(_)) => {
            let at = el.get("z_axis").or(el.get("x_axis")).map_or(el.x.pos, |a| a.pos);
            return Err(el.err_at(at, "give either euler313 or z_axis [x_axis], not both"));
        }
        (None, None, Some(_)) => {
            let at = el.get("x_axis").map_or(el.x.pos, |a| a.pos);
            return Err(el.err_at(at, "x_axis needs z_axis"));
        }
        (Some(e), None, None) => Orientation::Euler313(e),
        (None, Some(z), x) => Orientation::Axes(z, x),
        (None, None, None) => Orientation::Identity,
    };
    if let Err(msg) = try_rotation(&o) {
        let name = if msg.starts_with("x_axis") { "x_axis" } else { "z_axis" };
        let at = el.get(name).map_or(el.x.pos, |a| a.pos);
        return Err(el.err_at(at, msg));
    }
    Ok(o)
}

/// Rotation matrix of an orientation (row-major; columns are the frame's axes in owner
/// coordinates). A degenerate axis specification (see [`try_rotation`]) gives the identity.
pub fn rotation(o: &Orientation) -> [[f64; 3]; 3] {
    try_rotation(o).unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
}

/// Rotation matrix of an orientation, or why the axes do not define one (zero `z_axis`,
/// `x_axis` zero or parallel to `z_axis`).
pub fn try_rotation(o: &Orientation) -> Result<[[f64; 3]; 3], String> {
    match o {
        Orientation::Identity => Ok([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        Orientation::Euler313(e) => {
            let [psi, theta, phi] = vals(&e.values());
            let (s1, c1) = psi.sin_cos();
            let (s2, c2) = theta.sin_cos();
            let (s3, c3) = phi.sin_cos();
            Ok([
                [c1 * c3 - s1 * c2 * s3, -c1 * s3 - s1 * c2 * c3, s1 * s2],
                [s1 * c3 + c1 * c2 * s3, -s1 * s3 + c1 * c2 * c3, -c1 * s2],
                [s2 * s3, s2 * c3, c2],
            ])
        }
        Orientation::Axes(z, x) => {
            let z = vals(&z.values());
            let nz = norm(z);
            if nz.is_nan() || nz <= f64::MIN_POSITIVE {
                return Err("z_axis is zero".into());
            }
            let z = scale(z, 1.0 / nz);
            let x = match x {
                Some(x) => {
                    let x = vals(&x.values());
                    let nx = norm(x);
                    let xp = sub(x, scale(z, dot(x, z)));
                    let n = norm(xp);
                    if nx.is_nan() || nx <= f64::MIN_POSITIVE || n <= 1e-9 * nx {
                        return Err("x_axis is zero or parallel to z_axis".into());
                    }
                    scale(xp, 1.0 / n)
                }
                None => {
                    let e = if z[0].abs() > 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
                    let xp = sub(e, scale(z, dot(e, z)));
                    scale(xp, 1.0 / norm(xp))
                }
            };
            let y = cross(z, x);
            Ok([[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]])
        }
    }
}

fn vals(v: &[f64]) -> [f64; 3] {
    [0, 1, 2].map(|k| v.get(k).copied().unwrap_or(f64::NAN))
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
