//! Model loader: any bytes, read as (lossy) UTF-8 text, through XML reading, validation
//! and system building (`System::from_model`, what `Simulator::new` does first; not
//! assembly or integration, which are too slow per input).
//!
//! Properties (a violation panics, so libFuzzer reports the input):
//! - no panic, hang or stack overflow;
//! - a rejected model is answered `fuzz.xml:<line>:<col>: ...`, and the position lies in
//!   the text (line ≤ number of lines, column ≤ characters in that line + 1);
//! - a model that loads builds its system: every model error is found by the loader,
//!   with a location, not later by the mechanics layer (whose errors have none);
//! - re-evaluating a loaded model with its own parameter values (what the FMU does when
//!   parameters are set) succeeds and changes nothing;
//! - a UTF-8 byte order mark in front changes nothing, positions included; CRLF line
//!   ends instead of LF change neither whether it loads nor where an error is.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mbfmu::mechanics::System;
use mbfmu::model::{ModelError, load_str};

const FILE: &str = "fuzz.xml";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let result = load_str(&text, FILE);
    if !text.starts_with('\u{feff}') {
        let with_bom = load_str(&format!("\u{feff}{text}"), FILE);
        assert!(with_bom == result, "a byte order mark changes the result:\n{with_bom:?}\nwithout:\n{result:?}");
    }
    if !text.contains('\r') {
        // CRLF line ends: the same lines, so the same outcome at the same position (the
        // message may differ where it quotes the text).
        let crlf = load_str(&text.replace('\n', "\r\n"), FILE);
        let at = |r: &Result<_, ModelError>| r.as_ref().err().map(|e| (e.pos, e.element.clone()));
        assert!(at(&crlf) == at(&result), "CRLF line ends change the result:\n{crlf:?}\nwith LF:\n{result:?}");
    }
    match result {
        Err(e) => {
            let msg = e.to_string();
            check_location(&text, &msg, e.pos.line, e.pos.col);
        }
        Ok(model) => {
            if let Err(e) = System::from_model(&model) {
                panic!("model loaded, but System::from_model refused it without a location: {e}");
            }
            match model.with_params(&model.param_values()) {
                Ok(again) => assert!(again == model, "re-evaluating with the same parameter values changed the model"),
                Err(e) => panic!("model loaded, but re-evaluating it with its own parameter values failed: {e}"),
            }
            let _ = model.summary();
        }
    }
});

/// The message starts `fuzz.xml:line:col: ` and the position is inside the text.
fn check_location(text: &str, msg: &str, line: usize, col: usize) {
    let prefix = format!("{FILE}:{line}:{col}: ");
    assert!(msg.starts_with(&prefix), "error without file:line:col: {msg}");
    let lines: Vec<&str> = text.split('\n').collect();
    assert!(line >= 1 && line <= lines.len(), "line {line} outside the text ({} lines): {msg}", lines.len());
    let width = lines[line - 1].chars().count();
    assert!(col >= 1 && col <= width + 1, "column {col} outside line {line} ({width} characters): {msg}");
}
