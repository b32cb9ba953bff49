//! What a test host of the FMU's C API needs: callbacks without a logger, and a resources
//! directory for a model text. Included with `#[path]` by the tests and examples that call
//! the exports directly (`tests/common/mod.rs` is the engine-side helpers).

#![allow(dead_code)]

use mbfmu::fmi::types::CallbackFunctions;
use std::ffi::CString;
use std::path::PathBuf;

/// Callbacks without a logger: its C type is variadic, which stable Rust cannot define.
/// The instance still keeps its recent messages (`last_messages`).
pub const CALLBACKS: CallbackFunctions = CallbackFunctions {
    logger: None,
    allocate_memory: None,
    free_memory: None,
    step_finished: None,
    component_environment: std::ptr::null_mut(),
};

/// `<tmp>/mbfmu <tag> 100% <pid> <guid>/resources/model.xml` holding `text`: the directory
/// (remove it when done, if wanted) and the resource location's `file://` URI, with the
/// space and the `%` of the path escaped as a host must.
pub fn resources(text: &str, tag: &str) -> (PathBuf, CString) {
    let id: String = mbfmu::fmi::guid::guid(text).chars().filter(char::is_ascii_hexdigit).collect();
    let top = std::env::temp_dir().join(format!("mbfmu {tag} 100% {} {id}", std::process::id()));
    let dir = top.join("resources");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let file = dir.join("model.xml");
    if !file.exists() {
        // Write then rename: tests running in parallel never read a half-written file.
        let tmp = dir.join(format!("model.{:?}.tmp", std::thread::current().id()));
        std::fs::write(&tmp, text).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
        std::fs::rename(&tmp, &file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    }
    let path = dir.to_str().expect("UTF-8 temporary directory").replace('%', "%25").replace(' ', "%20");
    (top, CString::new(format!("file://{path}")).expect("no NUL in the path"))
}
