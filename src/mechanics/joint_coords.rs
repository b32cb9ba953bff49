//! Joint coordinates: the relative motions a joint leaves free, written as kinematic
//! measures of its markers (i relative to j) so that they read like the model
//! (`hinge.angle`, `rail.displacement`). State selection (seed Eq. 33) takes them as
//! internal candidates before body coordinates; a motion on a joint makes the coordinate
//! it drives dependent, so only the motion's free coordinate remains.

use crate::model::expr::{Expr, KinFn, MarkerId};
use crate::model::{Joint, JointType, Marker};

/// How a joint coordinate ranks among the internal candidates of state selection.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CoordRank {
    /// A coordinate of a revolute, translational, cylindrical or planar joint to ground.
    Grounded,
    /// The same, between two moving bodies.
    Relative,
    /// One of a spherical joint's yaw, pitch, roll (three angles with a singularity).
    Spherical,
}

/// One free coordinate of a joint: `f` measures marker i relative to marker j.
#[derive(Clone, Debug, PartialEq)]
pub struct JointCoord {
    /// `joint.angle`, `joint.displacement`, `joint.dx` ...
    pub name: String,
    /// What it measures, frame stated (for FMI variable descriptions).
    pub about: String,
    /// The measure of i relative to j.
    pub f: Expr,
    /// First angle-unwrapping slot of `f`.
    pub abase: usize,
    /// Its rank among the internal candidates.
    pub rank: CoordRank,
}

/// The free coordinates of `joint` (none for fixed and universal joints), angle slots
/// taken from `alloc`. `markers` are the model's (full names, bodies).
pub fn joint_coordinates(joint: &Joint, markers: &[Marker], alloc: &mut impl FnMut(&Expr) -> usize) -> Vec<JointCoord> {
    let (i, j) = (joint.i, joint.j);
    let (mi, mj) = (&markers[i].name, &markers[j].name);
    let kin = |f: KinFn, k: Option<MarkerId>| Expr::Kin(f, i, Some(j), k);
    let along = |axis: &str| format!("displacement of {mi} along {axis} of {mj}");
    let ypr = |a: &str| format!("{a} of {mi} relative to {mj}, z-y-x angles");
    let angle = ("angle", kin(KinFn::Az, None), format!("rotation of {mi} about z of {mj}"));
    let disp = ("displacement", kin(KinFn::Dz, Some(j)), along("z"));
    let list = match joint.kind {
        JointType::Revolute => vec![angle],
        JointType::Translational => vec![disp],
        JointType::Cylindrical => vec![angle, disp],
        JointType::Planar => {
            vec![("dx", kin(KinFn::Dx, Some(j)), along("x")), ("dy", kin(KinFn::Dy, Some(j)), along("y")), angle]
        }
        JointType::Spherical => vec![
            ("yaw", kin(KinFn::Yaw, None), ypr("yaw")),
            ("pitch", kin(KinFn::Pitch, None), ypr("pitch")),
            ("roll", kin(KinFn::Roll, None), ypr("roll")),
        ],
        JointType::Fixed | JointType::Universal => vec![],
    };
    let grounded = markers[i].body.is_none() || markers[j].body.is_none();
    let rank = match joint.kind {
        JointType::Spherical => CoordRank::Spherical,
        _ if grounded => CoordRank::Grounded,
        _ => CoordRank::Relative,
    };
    let kind = format!("{:?}", joint.kind).to_lowercase();
    list.into_iter()
        .map(|(coord, f, what)| JointCoord {
            name: format!("{}.{coord}", joint.name),
            about: format!("{what} ({kind} joint '{}')", joint.name),
            abase: alloc(&f),
            f,
            rank,
        })
        .collect()
}
