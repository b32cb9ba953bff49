//! TEMPORARY (branch `parse` only): stand-ins for the expression API that the real parser
//! (branch `expr`) provides, so the model reader compiles and its tests run before the
//! merge. Delete this file and its two lines in `expr/mod.rs` when merging; the model
//! reader uses exactly these signatures: [`parse`], [`deps`], [`Deps`], [`is_constant`],
//! [`const_value`], [`function_names`].
//!
//! The stub `parse` understands only numbers, `pi`, `time`, bare names (through the
//! [`Scope`]), `+ - * / ^`, unary minus and parentheses.

use super::ast::{BinOp, ElementRef, Expr, MarkerId};
use super::scope::{ExprError, NameRef, Scope};

/// What an expression depends on (stub of the real `deps` result).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Deps {
    pub markers: Vec<MarkerId>,
    /// 0 positions, 1 velocities, 2 accelerations.
    pub level: u8,
    pub time: bool,
    pub params: Vec<usize>,
    pub inputs: Vec<usize>,
    pub variables: Vec<usize>,
    pub diffs: Vec<usize>,
    pub diff_dots: Vec<usize>,
    pub loads: Vec<ElementRef>,
}

/// Names of the functions of the expression language (not usable as element names).
pub fn function_names() -> &'static [&'static str] {
    &[
        "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log",
        "sqrt", "abs", "sign", "min", "max", "step", "if", "dx", "dy", "dz", "dm", "vx", "vy",
        "vz", "vm", "vr", "wx", "wy", "wz", "wm", "accx", "accy", "accz", "wdtx", "wdty", "wdtz",
        "ax", "ay", "az", "psi", "theta", "phi", "yaw", "pitch", "roll", "fx", "fy", "fz", "tx",
        "ty", "tz", "dif", "dif1",
    ]
}

/// Dependencies of `e` (stub: covers every node kind).
pub fn deps(e: &Expr) -> Deps {
    let mut d = Deps::default();
    collect(e, &mut d);
    d
}

fn collect(e: &Expr, d: &mut Deps) {
    fn add(v: &mut Vec<usize>, i: usize) {
        if !v.contains(&i) {
            v.push(i);
        }
    }
    match e {
        Expr::Num(_) => {}
        Expr::Time => d.time = true,
        Expr::Param(i) => add(&mut d.params, *i),
        Expr::Input(i) => add(&mut d.inputs, *i),
        Expr::Variable(i) => add(&mut d.variables, *i),
        Expr::Diff(i) => add(&mut d.diffs, *i),
        Expr::DiffDot(i) => add(&mut d.diff_dots, *i),
        Expr::Neg(a) => collect(a, d),
        Expr::Bin(_, a, b) => {
            collect(a, d);
            collect(b, d);
        }
        Expr::Math(_, args) => args.iter().for_each(|a| collect(a, d)),
        Expr::Kin(f, i, j, k) => {
            d.level = d.level.max(f.level());
            for m in [Some(*i), *j, *k].into_iter().flatten() {
                add(&mut d.markers, m);
            }
        }
        Expr::Load(_, r) => {
            if !d.loads.contains(r) {
                d.loads.push(*r);
            }
        }
    }
}

/// True when `e` uses only numbers, `pi` and parameters.
pub fn is_constant(e: &Expr) -> bool {
    let d = deps(e);
    !d.time
        && d.markers.is_empty()
        && d.inputs.is_empty()
        && d.variables.is_empty()
        && d.diffs.is_empty()
        && d.diff_dots.is_empty()
        && d.loads.is_empty()
}

/// Value of a constant expression for the given parameter values (stub: arithmetic only;
/// anything else evaluates to NaN).
pub fn const_value(e: &Expr, params: &[f64]) -> f64 {
    match e {
        Expr::Num(v) => *v,
        Expr::Param(i) => params.get(*i).copied().unwrap_or(f64::NAN),
        Expr::Neg(a) => -const_value(a, params),
        Expr::Bin(op, a, b) => {
            let (a, b) = (const_value(a, params), const_value(b, params));
            match op {
                BinOp::Add => a + b,
                BinOp::Sub => a - b,
                BinOp::Mul => a * b,
                BinOp::Div => a / b,
                BinOp::Pow => a.powf(b),
            }
        }
        _ => f64::NAN,
    }
}

/// Stub parser: numbers, `pi`, `time`, names, `+ - * / ^`, unary minus, parentheses.
pub fn parse(src: &str, scope: &dyn Scope) -> Result<Expr, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let mut p = P {
        c: &chars,
        i: 0,
        scope,
    };
    let e = p.sum()?;
    p.ws();
    if p.i < chars.len() {
        return Err(p.err(format!("unexpected '{}'", chars[p.i])));
    }
    Ok(e)
}

struct P<'a> {
    c: &'a [char],
    i: usize,
    scope: &'a dyn Scope,
}

impl P<'_> {
    fn err(&self, msg: String) -> ExprError {
        ExprError {
            offset: self.i,
            msg,
        }
    }
    fn ws(&mut self) {
        while self.i < self.c.len() && self.c[self.i].is_whitespace() {
            self.i += 1;
        }
    }
    fn peek(&mut self) -> Option<char> {
        self.ws();
        self.c.get(self.i).copied()
    }
    fn sum(&mut self) -> Result<Expr, ExprError> {
        let mut a = self.product()?;
        while let Some(op @ ('+' | '-')) = self.peek() {
            self.i += 1;
            let b = self.product()?;
            let op = if op == '+' { BinOp::Add } else { BinOp::Sub };
            a = Expr::Bin(op, Box::new(a), Box::new(b));
        }
        Ok(a)
    }
    fn product(&mut self) -> Result<Expr, ExprError> {
        let mut a = self.unary()?;
        while let Some(op @ ('*' | '/')) = self.peek() {
            self.i += 1;
            let b = self.unary()?;
            let op = if op == '*' { BinOp::Mul } else { BinOp::Div };
            a = Expr::Bin(op, Box::new(a), Box::new(b));
        }
        Ok(a)
    }
    fn unary(&mut self) -> Result<Expr, ExprError> {
        if self.peek() == Some('-') {
            self.i += 1;
            return Ok(Expr::Neg(Box::new(self.unary()?)));
        }
        let a = self.atom()?;
        if self.peek() == Some('^') {
            self.i += 1;
            let b = self.unary()?;
            return Ok(Expr::Bin(BinOp::Pow, Box::new(a), Box::new(b)));
        }
        Ok(a)
    }
    fn atom(&mut self) -> Result<Expr, ExprError> {
        let start = self.i;
        match self.peek() {
            None => Err(self.err("unexpected end of expression".into())),
            Some('(') => {
                self.i += 1;
                let e = self.sum()?;
                if self.peek() != Some(')') {
                    return Err(self.err("expected ')'".into()));
                }
                self.i += 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => {
                let s = self.i;
                while self.i < self.c.len()
                    && (self.c[self.i].is_ascii_alphanumeric()
                        || self.c[self.i] == '.'
                        || ((self.c[self.i] == '+' || self.c[self.i] == '-')
                            && matches!(self.c[self.i - 1], 'e' | 'E')))
                {
                    self.i += 1;
                }
                let t: String = self.c[s..self.i].iter().collect();
                t.parse::<f64>().map(Expr::Num).map_err(|_| ExprError {
                    offset: s,
                    msg: format!("bad number '{t}'"),
                })
            }
            Some(c) if c.is_alphabetic() || c == '_' => {
                let s = self.i;
                while self.i < self.c.len()
                    && (self.c[self.i].is_alphanumeric() || self.c[self.i] == '_')
                {
                    self.i += 1;
                }
                let t: String = self.c[s..self.i].iter().collect();
                if self.peek() == Some('(') {
                    return Err(ExprError {
                        offset: s,
                        msg: format!("function '{t}' needs the real expression parser"),
                    });
                }
                match t.as_str() {
                    "pi" => Ok(Expr::Num(std::f64::consts::PI)),
                    "time" => Ok(Expr::Time),
                    _ => match self.scope.name(&t) {
                        Some(NameRef::Param(i)) => Ok(Expr::Param(i)),
                        Some(NameRef::Input(i)) => Ok(Expr::Input(i)),
                        Some(NameRef::Variable(i)) => Ok(Expr::Variable(i)),
                        Some(NameRef::Diff(i)) => Ok(Expr::Diff(i)),
                        None => Err(ExprError {
                            offset: s,
                            msg: format!("unknown name '{t}'"),
                        }),
                    },
                }
            }
            Some(c) => {
                let _ = start;
                Err(self.err(format!("unexpected '{c}'")))
            }
        }
    }
}
