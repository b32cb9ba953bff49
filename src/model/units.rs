//! Unit strings in the FMI/Modelica syntax: factors joined by `.`, at most one `/`, each
//! factor a symbol with an optional integer exponent — `kg.m2`, `N.m.s/rad`, `m/s2`,
//! `1/s`. Symbols: the SI base units, the derived N J W Pa Hz V C, optionally with an SI
//! prefix (`mm`, `kN`, `ms`), and g, deg, rpm, min, h, bar, 1. `Ns/m` is not a unit
//! (`N.s/m` is); neither is `m^2` (`m2` is).
//!
//! Also the units of kinematic measures and of time derivatives, for the FMU's states.

use super::expr::{Expr, KinFn};

/// SI base units in the order of FMI's `<BaseUnit>` attributes.
pub const BASE_NAMES: [&str; 8] = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];

/// A parsed unit: exponents of [`BASE_NAMES`] and the factor to SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    /// Exponent of each base unit, in [`BASE_NAMES`] order (kg m s A K mol cd rad).
    pub exps: [i32; 8],
    /// SI value of one of this unit (1e-3 for `mm` or `g`, π/180 for `deg`).
    pub factor: f64,
}

fn symbol(s: &str) -> Option<([i32; 8], f64)> {
    let pi = std::f64::consts::PI;
    Some(match s {
        "kg" => ([1, 0, 0, 0, 0, 0, 0, 0], 1.0),
        "g" => ([1, 0, 0, 0, 0, 0, 0, 0], 1e-3),
        "m" => ([0, 1, 0, 0, 0, 0, 0, 0], 1.0),
        "s" => ([0, 0, 1, 0, 0, 0, 0, 0], 1.0),
        "min" => ([0, 0, 1, 0, 0, 0, 0, 0], 60.0),
        "h" => ([0, 0, 1, 0, 0, 0, 0, 0], 3600.0),
        "A" => ([0, 0, 0, 1, 0, 0, 0, 0], 1.0),
        "K" => ([0, 0, 0, 0, 1, 0, 0, 0], 1.0),
        "mol" => ([0, 0, 0, 0, 0, 1, 0, 0], 1.0),
        "cd" => ([0, 0, 0, 0, 0, 0, 1, 0], 1.0),
        "rad" => ([0, 0, 0, 0, 0, 0, 0, 1], 1.0),
        "deg" => ([0, 0, 0, 0, 0, 0, 0, 1], pi / 180.0),
        "rpm" => ([0, 0, -1, 0, 0, 0, 0, 1], 2.0 * pi / 60.0),
        "N" => ([1, 1, -2, 0, 0, 0, 0, 0], 1.0),
        "J" => ([1, 2, -2, 0, 0, 0, 0, 0], 1.0),
        "W" => ([1, 2, -3, 0, 0, 0, 0, 0], 1.0),
        "Pa" => ([1, -1, -2, 0, 0, 0, 0, 0], 1.0),
        "bar" => ([1, -1, -2, 0, 0, 0, 0, 0], 1e5),
        "Hz" => ([0, 0, -1, 0, 0, 0, 0, 0], 1.0),
        "V" => ([1, 2, -3, -1, 0, 0, 0, 0], 1.0),
        "C" => ([0, 0, 1, 1, 0, 0, 0, 0], 1.0),
        "1" => ([0; 8], 1.0),
        _ => return None,
    })
}

/// SI prefixes that may stand before a base or derived SI symbol (not before kg, the
/// non-SI units or 1).
fn prefix(c: char) -> Option<f64> {
    Some(match c {
        'G' => 1e9,
        'M' => 1e6,
        'k' => 1e3,
        'd' => 1e-1,
        'c' => 1e-2,
        'm' => 1e-3,
        'u' => 1e-6,
        'n' => 1e-9,
        'p' => 1e-12,
        _ => return None,
    })
}

fn prefixed(sym: &str) -> Option<([i32; 8], f64)> {
    if let Some(s) = symbol(sym) {
        return Some(s);
    }
    let mut chars = sym.chars();
    let p = prefix(chars.next()?)?;
    let rest = chars.as_str();
    if matches!(rest, "kg" | "min" | "h" | "deg" | "rpm" | "bar" | "1" | "") {
        return None;
    }
    symbol(rest).map(|(e, f)| (e, f * p))
}

/// Parse a unit string; the error says what is wrong with it.
pub fn parse(unit: &str) -> Result<Unit, String> {
    let bad = |why: String| {
        Err(format!("'{unit}' is not a unit: {why} (write factors joined by '.', e.g. 'N.s/m', 'kg.m2', 'm/s2')"))
    };
    if unit.is_empty() {
        return bad("it is empty".into());
    }
    let (num, den) = match unit.split_once('/') {
        Some((n, d)) => (n, Some(d)),
        None => (unit, None),
    };
    if den.is_some_and(|d| d.contains('/')) {
        return bad("more than one '/'".into());
    }
    let mut u = Unit { exps: [0; 8], factor: 1.0 };
    for (part, sign) in [(Some(num), 1), (den, -1)] {
        let Some(part) = part else { continue };
        for factor in part.split('.') {
            let split = factor.find(|c: char| c.is_ascii_digit() || c == '-').unwrap_or(factor.len());
            let (sym, pow) = factor.split_at(split);
            let (sym, pow) = if sym.is_empty() && pow == "1" { ("1", "") } else { (sym, pow) };
            let pow: i32 = if pow.is_empty() {
                1
            } else {
                match pow.parse() {
                    Ok(p) => p,
                    Err(_) => return bad(format!("'{factor}' has no integer exponent")),
                }
            };
            let Some((e, f)) = prefixed(sym) else {
                return bad(if factor.is_empty() {
                    "an empty factor".into()
                } else {
                    format!("'{sym}' is not a unit symbol")
                });
            };
            for (acc, b) in u.exps.iter_mut().zip(e) {
                *acc += sign * pow * b;
            }
            u.factor *= f.powi(sign * pow);
        }
    }
    Ok(u)
}

/// The unit of a kinematic measure, when an expression is one (positions, velocities,
/// accelerations of markers; angles).
pub fn of_expr(e: &Expr) -> Option<&'static str> {
    use KinFn::*;
    match e {
        Expr::Kin(k, ..) => Some(match k {
            Dx | Dy | Dz | Dm => "m",
            Vx | Vy | Vz | Vm | Vr => "m/s",
            Accx | Accy | Accz => "m/s2",
            Wx | Wy | Wz | Wm => "rad/s",
            Wdtx | Wdty | Wdtz => "rad/s2",
            Ax | Ay | Az | Psi | Theta | Phi | Yaw | Pitch | Roll => "rad",
        }),
        Expr::Neg(inner) => of_expr(inner),
        _ => None,
    }
}

/// The unit of the time derivative of a quantity in `unit` (m → m/s → m/s2).
pub fn per_second(unit: &str) -> Option<String> {
    Some(match unit {
        "m" | "rad" => format!("{unit}/s"),
        "m/s" | "rad/s" => format!("{unit}2"),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_of_the_fmi_syntax_parse_with_their_si_exponents_and_factor() {
        let p = |s: &str| parse(s).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p("N.s/m").exps, [1, 0, -1, 0, 0, 0, 0, 0]);
        assert_eq!(p("kg.m2").exps, [1, 2, 0, 0, 0, 0, 0, 0]);
        assert_eq!(p("m/s2").exps, [0, 1, -2, 0, 0, 0, 0, 0]);
        assert_eq!(p("1/s").exps, [0, 0, -1, 0, 0, 0, 0, 0]);
        assert_eq!(p("s-1").exps, p("1/s").exps);
        assert_eq!((p("mm").exps, p("mm").factor), (p("m").exps, 1e-3));
        assert_eq!(p("kN.m").factor, 1e3);
        assert!((p("deg").factor - std::f64::consts::PI / 180.0).abs() < 1e-18);
        assert!((p("rpm").factor - std::f64::consts::PI / 30.0).abs() < 1e-16);
        assert_eq!(p("mol").factor, 1.0); // mol, not milli-ol
        assert_eq!(p("min").factor, 60.0);
    }

    #[test]
    fn strings_outside_the_grammar_are_refused_with_the_reason() {
        for (s, why) in [
            ("Ns/m", "'Ns' is not a unit symbol"),
            ("N m", "'N m' is not a unit symbol"),
            ("m/s/s", "more than one '/'"),
            ("", "it is empty"),
            ("m..s", "an empty factor"),
            ("mkg", "'mkg' is not a unit symbol"),
        ] {
            let e = parse(s).unwrap_err();
            assert!(e.contains(why), "{s}: {e}");
        }
    }

    #[test]
    fn kinematic_measures_and_derivatives_have_units() {
        assert_eq!(per_second("m").as_deref(), Some("m/s"));
        assert_eq!(per_second("rad/s").as_deref(), Some("rad/s2"));
        assert_eq!(per_second("N"), None);
    }
}
