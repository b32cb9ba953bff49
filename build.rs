//! Build script: fingerprint the engine sources so that an FMU's GUID (a hash of the model
//! text and the engine version) changes whenever the engine that will run it changes.

use std::path::Path;

fn fnv1a64(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

fn visit(dir: &Path, files: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            visit(&p, files);
        } else if p.extension().is_some_and(|x| x == "rs") {
            files.push(p);
        }
    }
}

fn main() {
    let mut files = Vec::new();
    visit(Path::new("src"), &mut files);
    files.sort();
    let mut h = 0xcbf29ce484222325u64;
    for f in &files {
        h = fnv1a64(f.to_string_lossy().as_bytes(), h);
        h = fnv1a64(&std::fs::read(f).unwrap_or_default(), h);
    }
    println!("cargo:rustc-env=MBFMU_ENGINE_FINGERPRINT={h:016x}");
    println!("cargo:rerun-if-changed=src");
}
