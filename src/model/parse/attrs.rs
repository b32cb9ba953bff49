//! Attribute access for one element: allowed/required checks, vector splitting, constant
//! numbers and expressions, each error located at the attribute (or the offending char).

use super::names::ModelScope;
use super::source::Source;
use super::xml::{XAttr, XElem};
use crate::model::expr::{self, Expr};
use crate::model::{ModelError, Num, NumVec, SrcPos};

/// One element being read, with what its constant attributes may use.
pub(crate) struct El<'a> {
    /// The XML element being read.
    pub x: &'a XElem,
    /// The model text, for positions and messages.
    pub src: &'a Source<'a>,
    /// Names its expressions may use.
    pub scope: &'a ModelScope,
    /// Evaluated parameter values (empty while parameters themselves are read).
    pub params: &'a [f64],
}

/// Split a vector attribute: on commas if there is any, else on white space. Each item
/// comes with the character offset of its first character.
pub(crate) fn split_items(s: &str) -> Vec<(usize, &str)> {
    // Separators count only outside parentheses, so function arguments stay together.
    let depth_at: Vec<i32> = s
        .chars()
        .scan(0i32, |d, c| {
            let here = *d;
            match c {
                '(' => *d += 1,
                ')' => *d -= 1,
                _ => {}
            }
            Some(if c == ')' { here - 1 } else { here })
        })
        .collect();
    let top_comma = s.chars().zip(&depth_at).any(|(c, &d)| c == ',' && d == 0);
    let is_sep = |c: char, d: i32| d == 0 && if top_comma { c == ',' } else { c.is_whitespace() };
    let mut out = Vec::new();
    let mut item: Option<(usize, usize)> = None; // (char index, byte index) of the item start
    let mut last_end = 0usize; // byte index after the last non-space char of the item
    fn push<'s>(out: &mut Vec<(usize, &'s str)>, item: Option<(usize, usize)>, end: usize, s: &'s str) {
        if let Some((ci, bi)) = item {
            out.push((ci, s[bi..end].trim()));
        }
    }
    for (ci, ((b, c), &d)) in s.char_indices().zip(&depth_at).enumerate() {
        if is_sep(c, d) {
            if top_comma {
                push(&mut out, item.take().or(Some((ci, b))), b, s);
            } else {
                push(&mut out, item.take(), last_end, s);
            }
        } else if !c.is_whitespace() {
            if item.is_none() {
                item = Some((ci, b));
            }
            last_end = b + c.len_utf8();
        }
    }
    if top_comma {
        let n = s.chars().count();
        push(&mut out, item.take().or(Some((n, s.len()))), s.len(), s);
    } else {
        push(&mut out, item.take(), last_end, s);
    }
    out
}

impl<'a> El<'a> {
    /// An error on this element at `pos`.
    pub fn err_at(&self, pos: SrcPos, msg: impl Into<String>) -> ModelError {
        self.src.error(pos, &self.x.tag, self.x.label(), msg)
    }
    /// An error on this element at its `<`.
    pub fn err(&self, msg: impl Into<String>) -> ModelError {
        self.err_at(self.x.pos, msg)
    }

    /// Reject attributes not in `allowed`, and require those in `required`.
    pub fn check_attrs(&self, allowed: &[&str], required: &[&str]) -> Result<(), ModelError> {
        for a in &self.x.attrs {
            if !allowed.contains(&a.name.as_str()) {
                return Err(self.err_at(a.pos, format!("unknown attribute '{}'", a.name)));
            }
        }
        for r in required {
            self.req(r)?;
        }
        Ok(())
    }

    /// Attribute `name`, if present.
    pub fn get(&self, name: &str) -> Option<&'a XAttr> {
        self.x.attr(name)
    }
    /// The optional `unit` attribute, checked against the unit grammar
    /// ([`crate::model::units`]); an error points at the attribute.
    pub fn unit(&self) -> Result<Option<String>, ModelError> {
        let Some(a) = self.get("unit") else { return Ok(None) };
        crate::model::units::parse(&a.value).map_err(|e| self.err_at(a.pos, format!("attribute 'unit': {e}")))?;
        Ok(Some(a.value.clone()))
    }
    /// Attribute `name`, required.
    pub fn req(&self, name: &str) -> Result<&'a XAttr, ModelError> {
        self.get(name).ok_or_else(|| self.err(format!("missing required attribute '{name}'")))
    }

    /// Position of character `char_off` of attribute `a`'s value (as read: entities
    /// replaced, line ends normalized), found by walking the value as written: an entity
    /// (`&lt;`, `&#43;`, ...) and a `\r\n` line end are one character of the value.
    pub fn value_pos(&self, a: &XAttr, char_off: usize) -> SrcPos {
        let Some(start) = a.value_off else {
            return a.pos;
        };
        let rest = self.src.text.get(start..).unwrap_or("");
        let mut byte = 0;
        for _ in 0..char_off {
            let r = &rest[byte..];
            byte += if r.starts_with("\r\n") {
                2
            } else if r.starts_with('&') {
                // The value was unescaped without error: every `&` starts an entity.
                r.find(';').map_or(1, |i| i + 1)
            } else {
                match r.chars().next() {
                    Some(c) => c.len_utf8(),
                    None => break,
                }
            };
        }
        self.src.pos(start + byte)
    }

    /// Parse `text` (item at char offset `off` of attribute `a`) as an expression.
    pub fn parse_expr(&self, a: &XAttr, off: usize, text: &str) -> Result<Expr, ModelError> {
        expr::parse(text, self.scope).map_err(|e| {
            self.err_at(self.value_pos(a, off + e.offset), format!("bad expression in '{}': {}", a.name, e.msg))
        })
    }

    /// Parse a constant expression (numbers, `pi`, parameters) without evaluating it.
    pub fn const_expr(&self, a: &XAttr, off: usize, text: &str) -> Result<Expr, ModelError> {
        let e = self.parse_expr(a, off, text)?;
        if !expr::is_constant(&e) {
            return Err(self.err_at(
                self.value_pos(a, off),
                format!("'{}' must be a constant expression (numbers, pi, parameters)", a.name),
            ));
        }
        Ok(e)
    }

    /// Parse and evaluate one constant item.
    fn num_item(&self, a: &XAttr, off: usize, text: &str) -> Result<Num, ModelError> {
        let e = self.const_expr(a, off, text)?;
        let value = expr::const_value(&e, self.params);
        if !value.is_finite() {
            return Err(self.err_at(self.value_pos(a, off), format!("'{}' evaluates to {value}", a.name)));
        }
        Ok(Num { expr: e, value })
    }

    /// Optional constant attribute.
    pub fn num(&self, name: &str) -> Result<Option<Num>, ModelError> {
        let Some(a) = self.get(name) else {
            return Ok(None);
        };
        let off = a.value.len() - a.value.trim_start().len();
        self.num_item(a, a.value[..off].chars().count(), a.value.trim()).map(Some)
    }
    /// Constant attribute with a default value.
    pub fn num_or(&self, name: &str, default: f64) -> Result<Num, ModelError> {
        Ok(self.num(name)?.unwrap_or_else(|| constant(default)))
    }
    /// Required constant attribute.
    pub fn num_req(&self, name: &str) -> Result<Num, ModelError> {
        self.req(name)?;
        self.num(name)?.ok_or_else(|| self.err(format!("missing required attribute '{name}'")))
    }

    /// Split attribute `a` into items, checking the count is one of `counts`.
    fn items(&self, a: &'a XAttr, counts: &[usize]) -> Result<Vec<(usize, &'a str)>, ModelError> {
        let items = split_items(&a.value);
        if !counts.contains(&items.len()) {
            let want = counts.iter().map(|c| c.to_string()).collect::<Vec<_>>().join(" or ");
            return Err(self.err_at(a.pos, format!("attribute '{}' needs {want} items, found {}", a.name, items.len())));
        }
        Ok(items)
    }

    /// Optional constant vector attribute with one of the item counts `counts`.
    pub fn num_vec(&self, name: &str, counts: &[usize]) -> Result<Option<NumVec>, ModelError> {
        let Some(a) = self.get(name) else {
            return Ok(None);
        };
        let items = self
            .items(a, counts)?
            .into_iter()
            .map(|(off, t)| self.num_item(a, off, t))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Some(NumVec { items }))
    }
    /// Required constant 3-vector.
    pub fn vec3_req(&self, name: &str) -> Result<NumVec, ModelError> {
        self.req(name)?;
        self.num_vec(name, &[3])?.ok_or_else(|| self.err(format!("missing required attribute '{name}'")))
    }

    /// Required expression attribute.
    pub fn expr_req(&self, name: &str) -> Result<Expr, ModelError> {
        let a = self.req(name)?;
        let off = a.value.len() - a.value.trim_start().len();
        self.parse_expr(a, a.value[..off].chars().count(), a.value.trim())
    }

    /// Optional vector of three expressions (default zeros).
    pub fn expr_vec3(&self, name: &str) -> Result<[Expr; 3], ModelError> {
        let Some(a) = self.get(name) else {
            return Ok([Expr::Num(0.0), Expr::Num(0.0), Expr::Num(0.0)]);
        };
        let items = self.items(a, &[3])?;
        let mut out = Vec::with_capacity(3);
        for (off, t) in items {
            out.push(self.parse_expr(a, off, t)?);
        }
        out.try_into().map_err(|_| self.err_at(a.pos, format!("attribute '{name}' needs 3 items")))
    }

    /// Optional keyword attribute among `choices`.
    pub fn keyword<T: Copy>(&self, name: &str, choices: &[(&str, T)]) -> Result<Option<T>, ModelError> {
        let Some(a) = self.get(name) else {
            return Ok(None);
        };
        let v = a.value.trim();
        match choices.iter().find(|(k, _)| *k == v) {
            Some(&(_, t)) => Ok(Some(t)),
            None => {
                let list = choices.iter().map(|(k, _)| *k).collect::<Vec<_>>().join(", ");
                Err(self.err_at(a.pos, format!("bad value '{v}' for '{name}' (expected {list})")))
            }
        }
    }
    /// Required keyword attribute.
    pub fn keyword_req<T: Copy>(&self, name: &str, choices: &[(&str, T)]) -> Result<T, ModelError> {
        self.req(name)?;
        self.keyword(name, choices)?.ok_or_else(|| self.err(format!("missing required attribute '{name}'")))
    }
}

/// A literal constant.
pub(crate) fn constant(v: f64) -> Num {
    Num { expr: Expr::Num(v), value: v }
}
