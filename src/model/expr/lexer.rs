//! Tokenizer for expressions. Offsets are 0-based character (not byte) offsets.

use super::scope::ExprError;

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    /// A number literal.
    Num(f64),
    /// An identifier; may contain dots (`body.marker`).
    Ident(String),
    /// One of `+ - * / ^ ( ) ,`.
    Sym(char),
    /// A lexical error (bad number, stray character), reported when the parser reaches it.
    Bad(ExprError),
    /// End of the text.
    End,
}

/// A token and the character offset where it starts.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Token {
    /// The token's kind and value.
    pub tok: Tok,
    /// 0-based character offset of its first character in the expression text.
    pub offset: usize,
}

/// Split `src` into tokens; the last token is always [`Tok::End`]. Never fails: lexical
/// errors become [`Tok::Bad`] tokens so that the first error in reading order is reported.
pub(super) fn lex(src: &str) -> Vec<Token> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        let tok = if c.is_ascii_digit() || c == '.' {
            // Take the maximal run that could belong to a number (so `1e`, `2x`, `1.2.3`
            // are reported whole), then validate it.
            i += 1;
            while i < chars.len() {
                let d = chars[i];
                let sign_after_exp = (d == '+' || d == '-')
                    && matches!(chars[i - 1], 'e' | 'E')
                    && chars[start..i - 1].iter().all(|x| x.is_ascii_digit() || *x == '.');
                if d.is_ascii_alphanumeric() || d == '_' || d == '.' || sign_after_exp {
                    i += 1;
                } else {
                    break;
                }
            }
            let text: String = chars[start..i].iter().collect();
            match parse_number(&text) {
                Some(v) => Tok::Num(v),
                None => Tok::Bad(ExprError { offset: start, msg: format!("bad number '{text}'") }),
            }
        } else if c.is_ascii_alphabetic() || c == '_' {
            i += 1;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_' || chars[i] == '.') {
                i += 1;
            }
            Tok::Ident(chars[start..i].iter().collect())
        } else if "+-*/^(),".contains(c) {
            i += 1;
            Tok::Sym(c)
        } else {
            i += 1;
            Tok::Bad(ExprError { offset: start, msg: format!("unexpected character '{c}'") })
        };
        out.push(Token { tok, offset: start });
    }
    out.push(Token { tok: Tok::End, offset: chars.len() });
    out
}

/// Strict number syntax: `digits[.digits][e[+-]digits]` or `.digits[e[+-]digits]`
/// (`1.` is allowed). Returns `None` for anything else.
fn parse_number(text: &str) -> Option<f64> {
    let b = text.as_bytes();
    let mut i = 0;
    let int_digits = count_digits(&b[i..]);
    i += int_digits;
    let mut frac_digits = 0;
    if i < b.len() && b[i] == b'.' {
        i += 1;
        frac_digits = count_digits(&b[i..]);
        i += frac_digits;
    }
    if int_digits + frac_digits == 0 {
        return None;
    }
    let mantissa_end = i;
    let mut exp: i64 = 0;
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        i += 1;
        let neg = match b.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let n = count_digits(&b[i..]);
        if n == 0 {
            return None;
        }
        // Clamp huge exponents: the value is inf or 0 anyway.
        let e: i64 = text[i..i + n].parse::<i64>().unwrap_or(100_000).min(100_000);
        exp = if neg { -e } else { e };
        i += n;
    }
    if i != b.len() {
        return None;
    }
    // Rebuild a form Rust's parser always accepts ("1." -> "1.0", ".5" -> "0.5").
    let mant = &text[..mantissa_end];
    let int_part = if int_digits == 0 { "0" } else { &mant[..int_digits] };
    let frac_part = if frac_digits == 0 { "0" } else { &mant[int_digits + 1..] };
    format!("{int_part}.{frac_part}e{exp}").parse::<f64>().ok()
}

fn count_digits(b: &[u8]) -> usize {
    b.iter().take_while(|c| c.is_ascii_digit()).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_all_accepted_forms() {
        for (s, v) in [("1", 1.0), ("1e-3", 1e-3), (".5", 0.5), ("2.", 2.0), ("1.5E+2", 150.0), ("0.25e1", 2.5)] {
            assert_eq!(parse_number(s), Some(v), "{s}");
        }
        for s in ["1e", "1e+", ".", "1.2.3", "2x", "1e3.5", ".e1"] {
            assert_eq!(parse_number(s), None, "{s}");
        }
        assert_eq!(parse_number("1e999999999999999999999"), Some(f64::INFINITY));
    }

    #[test]
    fn offsets_count_characters_not_bytes() {
        let t = lex("é + x");
        assert_eq!(t[0].tok, Tok::Bad(ExprError { offset: 0, msg: "unexpected character 'é'".into() }));
        assert_eq!(t[1], Token { tok: Tok::Sym('+'), offset: 2 });
        assert_eq!(t[2], Token { tok: Tok::Ident("x".into()), offset: 4 });
        assert_eq!(t[3], Token { tok: Tok::End, offset: 5 });
    }

    #[test]
    fn exponent_sign_belongs_to_the_number_only_after_e() {
        let t = lex("2e-3-b.m");
        assert_eq!(t[0].tok, Tok::Num(2e-3));
        assert_eq!(t[1].tok, Tok::Sym('-'));
        assert_eq!(t[2].tok, Tok::Ident("b.m".into()));
    }
}
