//! The structure ARCHITECTURE.md promises, checked on the text of `src/`: every reference
//! from one file of the library to another (`crate::a::b`, `super::x`, `use` trees) points
//! down the layers (ad, geom → modal → model → mechanics → dae → linearize → fmi → pack → cli), the files
//! form no cycle, and the FMI shell reaches the engine only through the faces that
//! ARCHITECTURE.md names. Re-exports (`pub use`) and module declarations are not
//! references; `#[cfg(test)]` modules are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first: a file may refer to its own layer and those below.
/// `pack` (the build-time packer) sits above `fmi` (what runs inside a host): the packer
/// writes what the shell reads, never the other way.
const LAYERS: [&str; 10] = ["ad", "geom", "modal", "model", "mechanics", "dae", "linearize", "fmi", "pack", "cli"];

/// What the FMI shell may use of the layers below it: the model, and the faces of the
/// engine (what `dae` and `linearize` export from their mod.rs; the byte codec of saved
/// states).
const FMI_MAY_USE: [&str; 4] = ["model", "dae/mod.rs", "dae/bytes.rs", "linearize/mod.rs"];

/// A source file: its module path and the text that counts (comments and test modules
/// removed).
struct Source {
    file: String,
    module: Vec<String>,
    code: String,
}

fn sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&root, &mut files);
    files
        .into_iter()
        .filter_map(|p| {
            let rel = p.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
            if rel == "main.rs" {
                return None; // the binary: it uses the library by name
            }
            let text = std::fs::read_to_string(&p).unwrap();
            let text = match text.find("#[cfg(test)]") {
                Some(i) => &text[..i],
                None => &text[..],
            };
            let code: String = text.lines().map(|l| format!("{}\n", l.split("//").next().unwrap())).collect();
            let mut module: Vec<String> = rel.trim_end_matches(".rs").split('/').map(String::from).collect();
            if module.last().is_some_and(|m| m == "mod" || m == "lib") {
                module.pop();
            }
            Some(Source { file: rel, module, code })
        })
        .collect()
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Expand a `use` tree (`a::{b, c::{d, e}}`) into its paths.
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        return vec![tree.split(" as ").next().unwrap().trim().to_string()];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap()];
    let (mut depth, mut start, mut parts) = (0, 0, Vec::new());
    for (i, ch) in inner.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(|p| expand(p).into_iter().map(move |x| format!("{prefix}{x}")))
        .collect()
}

/// Every path to another module of the crate that `code` mentions, from `use` trees
/// (re-exports left out) and from paths written in the code.
fn paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = String::new();
    for stmt in code.split_inclusive(';') {
        let s = stmt.trim_start();
        let body = s.strip_prefix("pub(crate) use ").or_else(|| s.strip_prefix("use "));
        if s.starts_with("pub use ") {
            continue;
        }
        match body {
            Some(b) => out.extend(expand(b.trim_end_matches(';'))),
            None => rest.push_str(stmt),
        }
    }
    let bytes = rest.as_bytes();
    for start in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(i) = rest[from..].find(start) {
            let i = from + i;
            from = i + start.len();
            if i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_') {
                continue;
            }
            let end = rest[i..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .map_or(rest.len(), |e| i + e);
            out.push(rest[i..end].trim_end_matches(':').to_string());
        }
    }
    out
}

/// The file a path leads to: the deepest module on it.
fn resolve(path: &str, from: &[String], modules: &BTreeMap<Vec<String>, String>) -> Option<String> {
    let mut segs: Vec<&str> = path.split("::").collect();
    let mut base: Vec<String> = match segs.first() {
        Some(&"crate") => {
            segs.remove(0);
            Vec::new()
        }
        Some(&"super") => {
            let mut b = from.to_vec();
            while segs.first() == Some(&"super") {
                segs.remove(0);
                b.pop();
            }
            b
        }
        _ => return None,
    };
    let mut found = modules.get(&base).cloned();
    for s in segs {
        base.push(s.to_string());
        match modules.get(&base) {
            Some(f) => found = Some(f.clone()),
            None => break,
        }
    }
    found
}

/// The edges file → file of the library.
fn edges() -> BTreeMap<String, BTreeSet<String>> {
    let srcs = sources();
    let modules: BTreeMap<Vec<String>, String> = srcs.iter().map(|s| (s.module.clone(), s.file.clone())).collect();
    let mut g = BTreeMap::new();
    for s in &srcs {
        let to: BTreeSet<String> = paths(&s.code)
            .iter()
            .filter_map(|p| resolve(p, &s.module, &modules))
            .filter(|t| *t != s.file && t != "lib.rs")
            .collect();
        g.insert(s.file.clone(), to);
    }
    g
}

fn layer(file: &str) -> Option<usize> {
    LAYERS.iter().position(|l| file.split('/').next() == Some(l))
}

#[test]
fn the_use_tree_reader_finds_every_path() {
    let code = "use super::{a, b::{C, d as e}};\nuse crate::x::Y;\npub use z::W;\nfn f() { crate::p::q(); }";
    let mut p = paths(code);
    p.sort();
    assert_eq!(p, ["crate::p::q", "crate::x::Y", "super::a", "super::b::C", "super::b::d"]);
}

#[test]
fn layers_point_one_way() {
    let mut wrong = Vec::new();
    for (from, tos) in edges() {
        let Some(lf) = layer(&from) else { continue };
        for to in tos {
            if layer(&to).is_some_and(|lt| lt > lf) {
                wrong.push(format!("{from} -> {to}"));
            }
        }
    }
    assert!(wrong.is_empty(), "references up the layers:\n{}", wrong.join("\n"));
}

#[test]
fn files_form_no_cycle() {
    let g = edges();
    // Depth-first search with colours: grey = on the current path.
    fn visit<'a>(
        f: &'a str,
        g: &'a BTreeMap<String, BTreeSet<String>>,
        colour: &mut BTreeMap<&'a str, u8>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        match colour.get(f) {
            Some(2) => return None,
            Some(1) => {
                let i = path.iter().position(|p| *p == f).unwrap();
                return Some(path[i..].iter().map(|s| s.to_string()).chain([f.to_string()]).collect());
            }
            _ => {}
        }
        colour.insert(f, 1);
        path.push(f);
        for t in g.get(f).into_iter().flatten() {
            if let Some(c) = visit(t, g, colour, path) {
                return Some(c);
            }
        }
        path.pop();
        colour.insert(f, 2);
        None
    }
    let mut colour = BTreeMap::new();
    for f in g.keys() {
        if let Some(cycle) = visit(f, &g, &mut colour, &mut Vec::new()) {
            panic!("file cycle: {}", cycle.join(" -> "));
        }
    }
}

#[test]
fn the_fmi_shell_uses_only_the_engines_faces() {
    let mut wrong = Vec::new();
    for (from, tos) in edges().into_iter().filter(|(f, _)| f.starts_with("fmi/")) {
        for to in tos {
            let allowed =
                to.starts_with("fmi/") || FMI_MAY_USE.iter().any(|a| to == *a || to.starts_with(&format!("{a}/")));
            if !allowed {
                wrong.push(format!("{from} -> {to}"));
            }
        }
    }
    assert!(wrong.is_empty(), "the FMI shell reaches into the engine:\n{}", wrong.join("\n"));
}
