//! Parameter values: each `value` may use other parameters, in any order; they are
//! evaluated in dependency order and a cycle is an error naming it.

use crate::model::expr::{self, Expr};

/// Evaluate parameter expressions in dependency order. On a cycle, returns the index of
/// the parameter where it was found and the cycle's names (`a -> b -> a`).
pub(crate) fn evaluate(exprs: &[Expr], names: &[String]) -> Result<Vec<f64>, (usize, String)> {
    let n = exprs.len();
    let deps: Vec<Vec<usize>> =
        exprs.iter().map(|e| expr::deps(e).params.iter().copied().filter(|&p| p < n).collect()).collect();
    let mut state = vec![0u8; n]; // 0 new, 1 on stack, 2 done
    let mut order = Vec::with_capacity(n);
    for start in 0..n {
        if state[start] != 0 {
            continue;
        }
        // Iterative DFS: (node, next dependency to visit).
        let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
        state[start] = 1;
        while let Some(top) = stack.last_mut() {
            let (node, k) = *top;
            if let Some(&d) = deps[node].get(k) {
                top.1 += 1;
                match state[d] {
                    0 => {
                        state[d] = 1;
                        stack.push((d, 0));
                    }
                    1 => {
                        let from = stack.iter().position(|&(s, _)| s == d).unwrap_or(0);
                        let mut cyc: Vec<&str> = stack[from..].iter().map(|&(s, _)| names[s].as_str()).collect();
                        cyc.push(&names[d]);
                        return Err((d, format!("dependency cycle {}", cyc.join(" -> "))));
                    }
                    _ => {}
                }
            } else {
                state[node] = 2;
                order.push(node);
                stack.pop();
            }
        }
    }
    let mut values = vec![f64::NAN; n];
    for i in order {
        values[i] = expr::const_value(&exprs[i], &values);
    }
    Ok(values)
}
