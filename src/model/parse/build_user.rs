//! Building the user elements (the seed paper's Eq. 7: variables, differentials, inputs,
//! outputs) and the linearization states.

use super::build::LoadReader;
use super::load::Loader;
use super::validate::{Allowed, check_body_count, check_deps};
use super::xml::XElem;
use crate::model::expr;
use crate::model::*;

impl<'a> Loader<'a> {
    /// The `function` of a `<variable>` or `<differential>`: it may read what a force
    /// reads, touches at most the element body count, and its loads go to `load_readers`.
    fn user_function(&self, x: &'a XElem, load_readers: &mut Vec<LoadReader<'a>>) -> Result<expr::Expr, ModelError> {
        let el = self.el(x);
        let function = el.expr_req("function")?;
        check_deps(&el, "function", &function, Allowed::Force)?;
        check_body_count(&el, &self.scope, &[], &[("function", &function)], true)?;
        load_readers.push((x, "function", expr::deps(&function).loads));
        Ok(function)
    }

    /// `<variable>`: a user variable V = `function`; the loads it reads go to
    /// `load_readers`.
    pub(super) fn build_variable(
        &mut self,
        x: &'a XElem,
        load_readers: &mut Vec<LoadReader<'a>>,
    ) -> Result<(), ModelError> {
        let function = self.user_function(x, load_readers)?;
        self.model.variables.push(Variable { name: x.label().into(), function, pos: x.pos });
        Ok(())
    }

    /// `<differential>`: a user state X, explicit (dX/dt = `function`) or implicit
    /// (`function` = 0, using `dif1` of itself); the loads it reads go to `load_readers`.
    pub(super) fn build_differential(
        &mut self,
        x: &'a XElem,
        load_readers: &mut Vec<LoadReader<'a>>,
    ) -> Result<(), ModelError> {
        let function = self.user_function(x, load_readers)?;
        let el = self.el(x);
        let implicit = el.keyword("implicit", &[("true", true), ("false", false)])?.unwrap_or(false);
        let me = self.model.differentials.len();
        if implicit && !expr::deps(&function).diff_dots.contains(&me) {
            let at = el.get("function").map_or(x.pos, |a| a.pos);
            return Err(el.err_at(at, format!("implicit: 'function' must use dif1({})", x.label())));
        }
        self.model.differentials.push(Differential {
            name: x.label().into(),
            start: el.num_or("start", 0.0)?,
            function,
            implicit,
            pos: x.pos,
        });
        Ok(())
    }

    /// `<input>`: an FMI input, with its start value and unit.
    pub(super) fn build_input(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let input = Input { name: x.label().into(), start: el.num_or("start", 0.0)?, unit: el.unit()?, pos: x.pos };
        self.model.inputs.push(input);
        Ok(())
    }

    /// `<output>`: an FMI output = `function` (which may read anything), with its unit.
    pub(super) fn build_output(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        let el = self.el(x);
        let function = el.expr_req("function")?;
        check_deps(&el, "function", &function, Allowed::Any)?;
        self.model.outputs.push(Output { name: x.label().into(), function, unit: el.unit()?, pos: x.pos });
        Ok(())
    }

    /// `<linearization>`: its `<state>`s (functions of positions) and `<velocity>`s
    /// (functions of velocities), whose names must not clash with other named quantities.
    pub(super) fn build_linearization(&mut self, x: &'a XElem) -> Result<(), ModelError> {
        for c in &x.children {
            let el = self.el(c);
            let function = el.expr_req("function")?;
            let (name, pos) = (c.label().to_string(), c.pos);
            // A linearization state is a named quantity of the model, like parameters,
            // inputs, outputs, differentials and variables: its name is theirs to share.
            let clash = match self.scope.names.get(&name) {
                Some(&(r, line)) => Some((r.kind(), line)),
                None => self.ns_outputs.line(&name).map(|line| ("output", line)),
            };
            if let Some((kind, line)) = clash {
                let at = el.get("name").map_or(c.pos, |a| a.pos);
                return Err(el.err_at(at, format!("name '{name}' is already used by {kind} at line {line}")));
            }
            check_body_count(&el, &self.scope, &[], &[("function", &function)], false)?;
            if c.tag == "state" {
                check_deps(&el, "function", &function, Allowed::Positions)?;
                self.model.lin_states.push(LinState { name, function, pos });
            } else {
                check_deps(&el, "function", &function, Allowed::Velocities)?;
                self.model.lin_velocities.push(LinVelocity { name, function, pos });
            }
        }
        Ok(())
    }
}
