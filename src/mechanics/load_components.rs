//! The six components of an element load (`fx fy fz tx ty tz`) and their order, shared
//! by the external values (see [`super::external`]) and the loads themselves (see
//! [`super::loads`]).

use crate::model::expr::LoadFn;

/// Number of load components: force x y z, torque x y z.
pub const NLOAD: usize = 6;

/// Position of `f` among the six components (fx fy fz tx ty tz).
pub fn load_index(f: LoadFn) -> usize {
    match f {
        LoadFn::Fx => 0,
        LoadFn::Fy => 1,
        LoadFn::Fz => 2,
        LoadFn::Tx => 3,
        LoadFn::Ty => 4,
        LoadFn::Tz => 5,
    }
}
