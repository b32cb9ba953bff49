//! Expression parser: recursive descent over the tokens of [`super::lexer`].
//!
//! Grammar (lowest precedence first):
//! ```text
//! sum     := product (('+' | '-') product)*
//! product := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary ('^' unary)?          // right-associative; -x^2 = -(x^2)
//! primary := number | name | name '(' args ')' | '(' sum ')'
//! ```

use super::ast::{BinOp, ElementRef, Expr, KinFn, LoadFn, MarkerId, MathFn, ModalFn};
use super::lexer::{Tok, Token, lex};
use super::scope::{ExprError, NameRef, Scope};

/// Deepest allowed expression tree (guards the recursive parser, evaluator and `Drop`
/// against stack overflow on hostile input).
pub const MAX_DEPTH: usize = 200;

/// Every function name of the language, in no particular order (the model parser forbids
/// them, and the keywords `pi` and `time`, as element names).
pub fn function_names() -> &'static [&'static str] {
    FUNCTION_NAMES
}

// Grouped by kind, several to a line (rustfmt would give `modal_rate`, longer than its
// short-item threshold, and so every name, a line of its own).
#[rustfmt::skip]
const FUNCTION_NAMES: &[&str] = &[
    // math
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "sqrt", "abs", "sign",
    "min", "max", "step", "if", // kinematics
    "dx", "dy", "dz", "dm", "vx", "vy", "vz", "vm", "vr", "wx", "wy", "wz", "wm", "accx", "accy", "accz", "wdtx",
    "wdty", "wdtz", "ax", "ay", "az", "psi", "theta", "phi", "yaw", "pitch", "roll", // loads
    "fx", "fy", "fz", "tx", "ty", "tz", // differentials, then flexible bodies' modes
    "dif", "dif1", "modal", "modal_rate",
];

/// The keywords `pi` and `time` (not functions, but reserved like them).
pub fn keywords() -> &'static [&'static str] {
    &["pi", "time"]
}

impl MathFn {
    /// Number of arguments the function takes.
    pub fn arity(self) -> usize {
        use MathFn::*;
        match self {
            Atan2 | Min | Max => 2,
            If => 3,
            Step => 5,
            _ => 1,
        }
    }

    /// The function's name in expressions.
    pub fn name(self) -> &'static str {
        use MathFn::*;
        match self {
            Sin => "sin",
            Cos => "cos",
            Tan => "tan",
            Asin => "asin",
            Acos => "acos",
            Atan => "atan",
            Atan2 => "atan2",
            Sinh => "sinh",
            Cosh => "cosh",
            Tanh => "tanh",
            Exp => "exp",
            Log => "log",
            Sqrt => "sqrt",
            Abs => "abs",
            Sign => "sign",
            Min => "min",
            Max => "max",
            Step => "step",
            If => "if",
        }
    }

    fn from_name(s: &str) -> Option<Self> {
        use MathFn::*;
        Some(match s {
            "sin" => Sin,
            "cos" => Cos,
            "tan" => Tan,
            "asin" => Asin,
            "acos" => Acos,
            "atan" => Atan,
            "atan2" => Atan2,
            "sinh" => Sinh,
            "cosh" => Cosh,
            "tanh" => Tanh,
            "exp" => Exp,
            "log" => Log,
            "sqrt" => Sqrt,
            "abs" => Abs,
            "sign" => Sign,
            "min" => Min,
            "max" => Max,
            "step" => Step,
            "if" => If,
            _ => return None,
        })
    }
}

impl ModalFn {
    fn from_name(s: &str) -> Option<Self> {
        match s {
            "modal" => Some(ModalFn::Coordinate),
            "modal_rate" => Some(ModalFn::Rate),
            _ => None,
        }
    }
}

impl KinFn {
    /// Allowed number of marker arguments, `(min, max)`.
    pub fn arity(self) -> (usize, usize) {
        use KinFn::*;
        match self {
            Dm | Vm | Wm | Ax | Ay | Az | Psi | Theta | Phi | Yaw | Pitch | Roll => (1, 2),
            Vr => (2, 2),
            _ => (1, 3),
        }
    }

    /// True for the angle measures (`ax ay az psi theta phi yaw pitch roll`), which the
    /// evaluator passes through [`super::ExprEnv::unwrap_angle`].
    pub fn is_angle(self) -> bool {
        use KinFn::*;
        matches!(self, Ax | Ay | Az | Psi | Theta | Phi | Yaw | Pitch | Roll)
    }

    /// The function's name in expressions.
    pub fn name(self) -> &'static str {
        use KinFn::*;
        match self {
            Dx => "dx",
            Dy => "dy",
            Dz => "dz",
            Dm => "dm",
            Vx => "vx",
            Vy => "vy",
            Vz => "vz",
            Vm => "vm",
            Vr => "vr",
            Wx => "wx",
            Wy => "wy",
            Wz => "wz",
            Wm => "wm",
            Accx => "accx",
            Accy => "accy",
            Accz => "accz",
            Wdtx => "wdtx",
            Wdty => "wdty",
            Wdtz => "wdtz",
            Ax => "ax",
            Ay => "ay",
            Az => "az",
            Psi => "psi",
            Theta => "theta",
            Phi => "phi",
            Yaw => "yaw",
            Pitch => "pitch",
            Roll => "roll",
        }
    }

    fn from_name(s: &str) -> Option<Self> {
        use KinFn::*;
        Some(match s {
            "dx" => Dx,
            "dy" => Dy,
            "dz" => Dz,
            "dm" => Dm,
            "vx" => Vx,
            "vy" => Vy,
            "vz" => Vz,
            "vm" => Vm,
            "vr" => Vr,
            "wx" => Wx,
            "wy" => Wy,
            "wz" => Wz,
            "wm" => Wm,
            "accx" => Accx,
            "accy" => Accy,
            "accz" => Accz,
            "wdtx" => Wdtx,
            "wdty" => Wdty,
            "wdtz" => Wdtz,
            "ax" => Ax,
            "ay" => Ay,
            "az" => Az,
            "psi" => Psi,
            "theta" => Theta,
            "phi" => Phi,
            "yaw" => Yaw,
            "pitch" => Pitch,
            "roll" => Roll,
            _ => return None,
        })
    }
}

impl LoadFn {
    /// The function's name in expressions.
    pub fn name(self) -> &'static str {
        match self {
            LoadFn::Fx => "fx",
            LoadFn::Fy => "fy",
            LoadFn::Fz => "fz",
            LoadFn::Tx => "tx",
            LoadFn::Ty => "ty",
            LoadFn::Tz => "tz",
        }
    }

    fn from_name(s: &str) -> Option<Self> {
        Some(match s {
            "fx" => LoadFn::Fx,
            "fy" => LoadFn::Fy,
            "fz" => LoadFn::Fz,
            "tx" => LoadFn::Tx,
            "ty" => LoadFn::Ty,
            "tz" => LoadFn::Tz,
            _ => return None,
        })
    }
}

/// Parse `src` into an [`Expr`], resolving names through `scope`.
///
/// Never panics. Errors carry the character offset of the offending token and a message
/// such as `unknown name 'x'` or `'atan2' takes 2 arguments, got 3`.
pub fn parse(src: &str, scope: &dyn Scope) -> Result<Expr, ExprError> {
    let mut p = Parser { toks: lex(src), pos: 0, scope };
    let (e, _) = p.sum(0)?;
    match p.peek() {
        Tok::End => Ok(e),
        _ => Err(p.unexpected()),
    }
}

/// A parsed subtree and its depth.
type Node = (Expr, usize);

struct Parser<'a> {
    toks: Vec<Token>,
    pos: usize,
    scope: &'a dyn Scope,
}

fn err(offset: usize, msg: impl Into<String>) -> ExprError {
    ExprError { offset, msg: msg.into() }
}

impl Parser<'_> {
    fn tok(&self) -> &Token {
        // `lex` always ends with `End`, and `bump` never moves past it.
        &self.toks[self.pos.min(self.toks.len() - 1)]
    }
    fn peek(&self) -> &Tok {
        &self.tok().tok
    }
    fn offset(&self) -> usize {
        self.tok().offset
    }
    fn bump(&mut self) {
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
    }
    fn is_sym(&self, c: char) -> bool {
        *self.peek() == Tok::Sym(c)
    }

    /// The error for the current token when it cannot appear here.
    fn unexpected(&self) -> ExprError {
        let t = self.tok();
        match &t.tok {
            Tok::Bad(e) => e.clone(),
            Tok::End => err(t.offset, "unexpected end of expression"),
            Tok::Sym(c) => err(t.offset, format!("unexpected '{c}'")),
            Tok::Ident(s) => err(t.offset, format!("unexpected '{s}'")),
            Tok::Num(_) => err(t.offset, "unexpected number"),
        }
    }

    fn expect(&mut self, c: char) -> Result<(), ExprError> {
        if self.is_sym(c) {
            self.bump();
            Ok(())
        } else {
            Err(match self.peek() {
                Tok::End | Tok::Bad(_) => self.unexpected(),
                _ => {
                    let e = self.unexpected();
                    err(e.offset, format!("{}, expected '{c}'", e.msg))
                }
            })
        }
    }

    /// Check the depth of a node about to be built from children of depth `d`.
    fn deeper(&self, d: usize, offset: usize) -> Result<usize, ExprError> {
        if d + 1 > MAX_DEPTH { Err(err(offset, "expression too deeply nested")) } else { Ok(d + 1) }
    }

    fn sum(&mut self, depth: usize) -> Result<Node, ExprError> {
        let (mut e, mut d) = self.product(depth)?;
        loop {
            let op = match self.peek() {
                Tok::Sym('+') => BinOp::Add,
                Tok::Sym('-') => BinOp::Sub,
                _ => return Ok((e, d)),
            };
            let off = self.offset();
            self.bump();
            let (r, rd) = self.product(depth)?;
            d = self.deeper(d.max(rd), off)?;
            e = Expr::Bin(op, Box::new(e), Box::new(r));
        }
    }

    fn product(&mut self, depth: usize) -> Result<Node, ExprError> {
        let (mut e, mut d) = self.unary(depth)?;
        loop {
            let op = match self.peek() {
                Tok::Sym('*') => BinOp::Mul,
                Tok::Sym('/') => BinOp::Div,
                _ => return Ok((e, d)),
            };
            let off = self.offset();
            self.bump();
            let (r, rd) = self.unary(depth)?;
            d = self.deeper(d.max(rd), off)?;
            e = Expr::Bin(op, Box::new(e), Box::new(r));
        }
    }

    fn unary(&mut self, depth: usize) -> Result<Node, ExprError> {
        let off = self.offset();
        // `depth` counts nesting of recursive calls (parentheses, unary signs, exponents,
        // arguments) so that the parser's own recursion is bounded too.
        if depth > MAX_DEPTH {
            return Err(err(off, "expression too deeply nested"));
        }
        match self.peek() {
            Tok::Sym('-') => {
                self.bump();
                let (e, d) = self.unary(depth + 1)?;
                Ok(match e {
                    Expr::Num(v) => (Expr::Num(-v), d),
                    e => (Expr::Neg(Box::new(e)), self.deeper(d, off)?),
                })
            }
            Tok::Sym('+') => {
                self.bump();
                self.unary(depth + 1)
            }
            _ => self.power(depth),
        }
    }

    fn power(&mut self, depth: usize) -> Result<Node, ExprError> {
        let (b, bd) = self.primary(depth)?;
        if !self.is_sym('^') {
            return Ok((b, bd));
        }
        let off = self.offset();
        self.bump();
        let (x, xd) = self.unary(depth + 1)?;
        let d = self.deeper(bd.max(xd), off)?;
        Ok((Expr::Bin(BinOp::Pow, Box::new(b), Box::new(x)), d))
    }

    fn primary(&mut self, depth: usize) -> Result<Node, ExprError> {
        let off = self.offset();
        match self.peek().clone() {
            Tok::Num(v) => {
                self.bump();
                Ok((Expr::Num(v), 1))
            }
            Tok::Sym('(') => {
                self.bump();
                let e = self.sum(depth + 1)?;
                self.expect(')')?;
                Ok(e)
            }
            Tok::Ident(name) => {
                self.bump();
                if self.is_sym('(') {
                    self.bump();
                    self.call(&name, off, depth)
                } else {
                    self.bare_name(&name, off).map(|e| (e, 1))
                }
            }
            _ => Err(self.unexpected()),
        }
    }

    fn bare_name(&self, name: &str, off: usize) -> Result<Expr, ExprError> {
        match name {
            "pi" => return Ok(Expr::Num(std::f64::consts::PI)),
            "time" => return Ok(Expr::Time),
            _ => {}
        }
        match self.scope.name(name) {
            Some(NameRef::Param(i)) => Ok(Expr::Param(i)),
            Some(NameRef::Input(i)) => Ok(Expr::Input(i)),
            Some(NameRef::Variable(i)) => Ok(Expr::Variable(i)),
            Some(NameRef::Diff(i)) => Ok(Expr::Diff(i)),
            None if FUNCTION_NAMES.contains(&name) => Err(err(off, format!("function '{name}' needs arguments"))),
            None => Err(err(off, format!("unknown name '{name}'"))),
        }
    }

    /// A call `name(` … with the `(` consumed; `off` is the name's offset.
    fn call(&mut self, name: &str, off: usize, depth: usize) -> Result<Node, ExprError> {
        if let Some(f) = MathFn::from_name(name) {
            let mut args = Vec::new();
            let mut d = 0;
            if !self.is_sym(')') {
                loop {
                    let (a, ad) = self.sum(depth + 1)?;
                    args.push(a);
                    d = d.max(ad);
                    if self.is_sym(',') {
                        self.bump();
                    } else {
                        break;
                    }
                }
            }
            self.expect(')')?;
            let n = f.arity();
            if args.len() != n {
                let s = if n == 1 { "" } else { "s" };
                return Err(err(off, format!("'{name}' takes {n} argument{s}, got {}", args.len())));
            }
            let d = self.deeper(d, off)?;
            return Ok((Expr::Math(f, args), d));
        }
        if let Some(f) = ModalFn::from_name(name) {
            return self.modal_args(f, name);
        }
        let kin = KinFn::from_name(name);
        let load = LoadFn::from_name(name);
        let dif = matches!(name, "dif" | "dif1");
        if kin.is_none() && load.is_none() && !dif {
            return Err(err(off, format!("unknown function '{name}'")));
        }
        // The remaining functions take names as arguments.
        let args = self.name_args()?;
        let count = |lo: usize, hi: usize| -> Result<(), ExprError> {
            let n = args.len();
            if n >= lo && n <= hi {
                return Ok(());
            }
            let msg = if lo == hi {
                let s = if lo == 1 { "" } else { "s" };
                format!("'{name}' takes {lo} argument{s}, got {n}")
            } else {
                format!("'{name}' takes {lo} to {hi} arguments, got {n}")
            };
            Err(err(off, msg))
        };
        if let Some(f) = kin {
            let (lo, hi) = f.arity();
            count(lo, hi)?;
            let mut m: [Option<MarkerId>; 3] = [None; 3];
            for (slot, (a, aoff)) in m.iter_mut().zip(&args) {
                *slot = Some(self.scope.marker(a).ok_or_else(|| err(*aoff, format!("unknown marker '{a}'")))?);
            }
            let i = m[0].ok_or_else(|| err(off, "missing marker"))?;
            return Ok((Expr::Kin(f, i, m[1], m[2]), 1));
        }
        count(1, 1)?;
        let (a, aoff) = &args[0];
        if let Some(f) = load {
            let e: ElementRef = self.scope.element(a).ok_or_else(|| err(*aoff, format!("unknown element '{a}'")))?;
            return Ok((Expr::Load(f, e), 1));
        }
        match self.scope.name(a) {
            Some(NameRef::Diff(i)) => Ok((if name == "dif" { Expr::Diff(i) } else { Expr::DiffDot(i) }, 1)),
            Some(_) => Err(err(*aoff, format!("'{a}' is not a differential"))),
            None => Err(err(*aoff, format!("unknown name '{a}'"))),
        }
    }

    /// The arguments of `modal(body, k)` / `modal_rate(body, k)` after the `(`: a flexible
    /// body's name and a mode number from 1 (a whole number literal), then `)`.
    fn modal_args(&mut self, f: ModalFn, name: &str) -> Result<Node, ExprError> {
        let usage = || format!("'{name}' takes a flexible body and a mode number: {name}(body, k)");
        let (body, boff) = match self.peek().clone() {
            Tok::Ident(s) => (s, self.offset()),
            Tok::End | Tok::Bad(_) => return Err(self.unexpected()),
            _ => return Err(err(self.offset(), usage())),
        };
        self.bump();
        if !self.is_sym(',') {
            return Err(err(self.offset(), usage()));
        }
        self.bump();
        let (k, koff) = match *self.peek() {
            Tok::Num(v) => (v, self.offset()),
            Tok::End | Tok::Bad(_) => return Err(self.unexpected()),
            _ => return Err(err(self.offset(), usage())),
        };
        self.bump();
        self.expect(')')?;
        let (cm, modes) = self.scope.flexible(&body).ok_or_else(|| {
            let what = if self.scope.marker(&body).is_some() { "is not a flexible body" } else { "is unknown" };
            err(boff, format!("'{body}' {what}: '{name}' reads a <flexible_body>'s modes"))
        })?;
        if k.fract() != 0.0 || k < 1.0 || k > modes as f64 {
            return Err(err(koff, format!("mode {k} of '{body}': it has modes 1 to {modes}")));
        }
        Ok((Expr::Modal(f, cm, k as usize - 1), 1))
    }

    /// Arguments that are bare names (markers, elements, differentials), up to and
    /// including the closing `)`; each with its offset.
    fn name_args(&mut self) -> Result<Vec<(String, usize)>, ExprError> {
        let mut args = Vec::new();
        if self.is_sym(')') {
            self.bump();
            return Ok(args);
        }
        loop {
            let off = self.offset();
            match self.peek().clone() {
                Tok::Ident(s) => {
                    self.bump();
                    args.push((s, off));
                }
                Tok::Sym(_) | Tok::Num(_) => {
                    let e = self.unexpected();
                    return Err(err(e.offset, format!("{}, expected a name", e.msg)));
                }
                _ => return Err(self.unexpected()),
            }
            match self.peek() {
                Tok::Sym(',') => self.bump(),
                Tok::Sym(')') => {
                    self.bump();
                    return Ok(args);
                }
                Tok::End | Tok::Bad(_) => return Err(self.unexpected()),
                _ => {
                    let e = self.unexpected();
                    return Err(err(e.offset, format!("{}, expected ',' or ')'", e.msg)));
                }
            }
        }
    }
}
