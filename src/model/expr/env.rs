//! What an expression reads when it is evaluated: implemented by the mechanics layer,
//! generic over the scalar so that evaluation with dual numbers gives exact derivatives.

use super::ast::{ElementRef, LoadFn, MarkerId, ModalFn};
use crate::ad::Real;
use crate::geom::{M3, V3};

/// Pose of a marker in ground: origin position and rotation (columns = marker axes).
#[derive(Clone, Copy, Debug)]
pub struct Pose<T: Real> {
    /// Origin position in ground (m).
    pub p: V3<T>,
    /// Rotation from marker to ground axes: its columns are the marker axes in ground.
    pub r: M3<T>,
}

/// Velocity of a marker's origin and its angular velocity, ground components.
#[derive(Clone, Copy, Debug)]
pub struct Twist<T: Real> {
    /// Velocity of the origin (m/s), ground components; the acceleration (m/s²) in what
    /// [`ExprEnv::accel`] returns.
    pub v: V3<T>,
    /// Angular velocity (rad/s), ground components; the angular acceleration (rad/s²) in
    /// what [`ExprEnv::accel`] returns.
    pub w: V3<T>,
}

/// The evaluation environment of an expression.
pub trait ExprEnv<T: Real> {
    /// Simulation time.
    fn time(&self) -> T;
    /// Current value of parameter `i`.
    fn param(&self, i: usize) -> T;
    /// Current value of input `i`.
    fn input(&self, i: usize) -> T;
    /// User variable `i`.
    fn variable(&self, i: usize) -> T;
    /// Differential state `i`.
    fn diff(&self, i: usize) -> T;
    /// Time derivative of differential state `i`.
    fn diff_dot(&self, i: usize) -> T;
    /// Pose of marker `m` in ground.
    fn pose(&self, m: MarkerId) -> Pose<T>;
    /// Velocity and angular velocity of marker `m` (ground components).
    fn twist(&self, m: MarkerId) -> Twist<T>;
    /// Acceleration and angular acceleration of marker `m` (ground components).
    fn accel(&self, m: MarkerId) -> Twist<T>;
    /// Load that element `e` applies on its i marker (ground components).
    fn load(&self, f: LoadFn, e: ElementRef) -> T;
    /// Modal coordinate or rate `k` (from 0) of the flexible body that marker `m` is on;
    /// default NaN (an environment without flexible bodies).
    fn modal(&self, _f: ModalFn, _m: MarkerId, _k: usize) -> T {
        T::cst(f64::NAN)
    }
    /// Continuous (unwrapped) version of an angle measure: the engine keeps each angle
    /// near its previous value. `slot` identifies the measure; default: no unwrapping.
    fn unwrap_angle(&self, _slot: usize, a: T) -> T {
        a
    }
}
