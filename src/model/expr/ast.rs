//! Expression syntax tree, with every name already resolved to an index.

/// Index of a marker in `Model::markers`.
pub type MarkerId = usize;

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

/// Plain math functions (argument counts in [`MathFn::arity`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MathFn {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Log,
    Sqrt,
    Abs,
    Sign,
    Min,
    Max,
    /// `step(x, x0, h0, x1, h1)`: cubic step.
    Step,
    /// `if(c, a, b)`: a where c > 0, else b.
    If,
}

/// Kinematic measures between markers: `f(i[, j[, k]])`; `None` = ground frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KinFn {
    Dx,
    Dy,
    Dz,
    Dm,
    Vx,
    Vy,
    Vz,
    Vm,
    Vr,
    Wx,
    Wy,
    Wz,
    Wm,
    Accx,
    Accy,
    Accz,
    Wdtx,
    Wdty,
    Wdtz,
    Ax,
    Ay,
    Az,
    Psi,
    Theta,
    Phi,
    Yaw,
    Pitch,
    Roll,
}

/// Derivative level a kinematic measure needs: 0 positions, 1 velocities, 2 accelerations.
impl KinFn {
    /// 0 = positions, 1 = velocities, 2 = accelerations.
    pub fn level(self) -> u8 {
        use KinFn::*;
        match self {
            Vx | Vy | Vz | Vm | Vr | Wx | Wy | Wz | Wm => 1,
            Accx | Accy | Accz | Wdtx | Wdty | Wdtz => 2,
            _ => 0,
        }
    }
}

/// Element loads `fx(name) fy fz tx ty tz`: on the element's i marker, ground components.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadFn {
    Fx,
    Fy,
    Fz,
    Tx,
    Ty,
    Tz,
}

/// Modal measures of a flexible body: `modal(body, k)` (coordinate η_k) and
/// `modal_rate(body, k)` (its rate η̇_k).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModalFn {
    /// η_k, as the modal data's shapes scale it.
    Coordinate,
    /// η̇_k (1/s in the same scale).
    Rate,
}

impl ModalFn {
    /// 0 = positions, 1 = velocities (as [`KinFn::level`]).
    pub fn level(self) -> u8 {
        match self {
            ModalFn::Coordinate => 0,
            ModalFn::Rate => 1,
        }
    }
}

/// What a load function names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementRef {
    /// Index into `Model::joints`.
    Joint(usize),
    /// Index into `Model::motions`.
    Motion(usize),
    /// Index into `Model::constraints` (a user constraint has no load: the reader rejects it).
    Constraint(usize),
    /// Index into `Model::spring_dampers`.
    SpringDamper(usize),
    /// Index into `Model::sforces`.
    Sforce(usize),
    /// Index into `Model::gforces`.
    Gforce(usize),
    /// Index into `Model::bushings`.
    Bushing(usize),
}

/// An expression node.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A number literal (`pi` too).
    Num(f64),
    /// `time` (s).
    Time,
    /// Parameter, index into `Model::parameters`.
    Param(usize),
    /// Input, index into `Model::inputs`.
    Input(usize),
    /// User variable, index into `Model::variables`.
    Variable(usize),
    /// `dif(name)` or a bare differential name.
    Diff(usize),
    /// `dif1(name)`.
    DiffDot(usize),
    /// Unary minus.
    Neg(Box<Expr>),
    /// `lhs op rhs`.
    Bin(BinOp, Box<Expr>, Box<Expr>),
    /// A math function and its arguments.
    Math(MathFn, Vec<Expr>),
    /// Kinematic measure with markers i, j, k (j, k `None` = ground).
    Kin(KinFn, MarkerId, Option<MarkerId>, Option<MarkerId>),
    /// A load component of an element: `fx(name)` ...
    Load(LoadFn, ElementRef),
    /// A modal coordinate or rate of a flexible body: the body's `cm` marker and the mode
    /// index from 0 (`modal(arm, 1)` is mode index 0).
    Modal(ModalFn, MarkerId, usize),
}
