//! The build-time packer (`mbfmu pack`): a model file into an FMI Co-Simulation FMU:
//!
//! ```text
//! modelDescription.xml
//! binaries/<platform>/<modelIdentifier>.<ext>   a copy of this crate's cdylib
//! resources/model.xml                           the model file, byte for byte
//! resources/states.txt                          the linearization states (StateLayout)
//! resources/start_values.txt                    with `--set`: the start values, `name=value`
//! ```
//!
//! Start values (`mbfmu pack --set NAME=VALUE`, [`crate::model::overrides`]) replace the
//! model file's parameter values as the FMU's defaults: modelDescription.xml's `start`,
//! the state selection and the values of an instance not told otherwise all come from the
//! model with them applied, while `resources/model.xml` stays the user's file byte for
//! byte; an instance applies `resources/start_values.txt` at fmi2Instantiate
//! ([`crate::fmi::resources::read_start_values`]), and the GUID covers it ([`guid_with`]).
//!
//! The linearization states are selected once, here (an engine run,
//! [`crate::linearize::for_fmu`]); an instance reads them back with [`crate::fmi::resources::read_layout`]
//! instead of selecting them again. When they cannot be selected the FMU is still packed,
//! without states, and [`Packed::warnings`] says why (the engine's error then shows again,
//! located, at fmi2EnterInitializationMode).
//!
//! The cdylib is found through the environment variable `MBFMU_LIB` (a file path), else
//! inside the running executable (an installed `mbfmu`, see [`bundle`]), else next
//! to it (a cargo build, see [`find_library`]).

pub mod bundle;
pub mod fmi2_description;
pub mod fmi3_description;
mod structure;
mod xml;

use std::io::Write;
use std::path::{Path, PathBuf};

use zip::CompressionMethod;
use zip::write::SimpleFileOptions;

use crate::dae::StartValues;
use crate::fmi::guid::{guid, guid_with, model_identifier};
use crate::fmi::resources::{INTERFACES_FILE, Interfaces, LAYOUT_FILE, START_VALUES_FILE};
use crate::fmi::variables::Standard;
use crate::linearize::{FmuLinearization, StateLayout, for_fmu};
use crate::model::overrides::start_values_text;
use crate::model::{ModelError, load_str};

/// FMI 3 platform tuple under `binaries/` (`<arch>-<os>`: `x86_64-linux`, `aarch64-darwin`, …).
pub fn platform_tuple() -> String {
    let os = match std::env::consts::OS {
        "macos" => "darwin",
        os => os,
    };
    format!("{}-{os}", std::env::consts::ARCH)
}

/// FMI 2 platform folder under `binaries/`.
#[cfg(target_os = "macos")]
pub const PLATFORM: &str = "darwin64";
/// FMI 2 platform folder under `binaries/`.
#[cfg(target_os = "windows")]
pub const PLATFORM: &str = "win64";
/// FMI 2 platform folder under `binaries/`.
#[cfg(not(any(target_os = "macos", target_os = "windows")))]
pub const PLATFORM: &str = "linux64";

/// Extension of a shared library on this platform (`so`, `dylib`, `dll`).
pub const LIB_EXT: &str = std::env::consts::DLL_EXTENSION;

/// What packing can fail with.
#[derive(Debug, thiserror::Error)]
pub enum PackError {
    /// The model file does not load (bad input).
    #[error("{0}")]
    Model(#[from] ModelError),
    /// A start value is unusable: unknown name, set twice, or rejected by the model (bad
    /// input).
    #[error("{0}")]
    StartValue(String),
    /// The FMU's shared library was not found.
    #[error("{0}")]
    LibraryNotFound(String),
    /// The FMU asked for cannot be made of this model (bad request).
    #[error("{0}")]
    Unsupported(String),
    /// Reading or writing a file failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being read or written.
        context: String,
        /// The I/O error.
        source: std::io::Error,
    },
}

fn io_err(context: impl Into<String>) -> impl FnOnce(std::io::Error) -> PackError {
    let context = context.into();
    move |source| PackError::Io { context, source }
}

/// Co-Simulation only (an FMU that cannot offer Model Exchange).
pub const CO_SIMULATION: Interfaces = Interfaces { model_exchange: false, co_simulation: true };

/// Which interfaces `mbfmu pack --kind` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Model Exchange only.
    ModelExchange,
    /// Co-Simulation only.
    CoSimulation,
    /// Both, in one FMU (the default).
    Both,
}

impl Kind {
    /// The interfaces an FMU with the linearization states `layout` offers for this kind
    /// (either FMI version), and a warning when `Both` has to drop Model Exchange; an
    /// error when the kind cannot be had (Model Exchange needs the linearization states
    /// as its continuous states).
    pub fn interfaces(self, layout: &StateLayout) -> Result<(Interfaces, Option<String>), PackError> {
        let me = matches!(self, Kind::ModelExchange | Kind::Both);
        let cs = matches!(self, Kind::CoSimulation | Kind::Both);
        let why_not = layout
            .missing
            .as_ref()
            .map(|why| format!("the model has no linearization states to be its continuous states: {why}"));
        match (me, why_not) {
            (true, Some(why)) if !cs => Err(PackError::Unsupported(format!("--kind me: {why}"))),
            (true, Some(why)) => Ok((CO_SIMULATION, Some(format!("Co-Simulation only: {why}")))),
            _ => Ok((Interfaces { model_exchange: me, co_simulation: cs }, None)),
        }
    }
}

/// What was packed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Packed {
    /// The FMU's modelIdentifier (also the shared library's base name).
    pub model_identifier: String,
    /// The FMU's GUID.
    pub guid: String,
    /// What the FMU lacks and why (no linearization states: the selection's error).
    pub warnings: Vec<String>,
}

/// The files of an FMU, relative path and contents, in archive order.
struct Contents {
    packed: Packed,
    files: Vec<(String, Vec<u8>)>,
}

/// Name of this crate's cdylib as cargo writes it (`libmbfmu.so` on Linux).
pub fn library_file_name() -> String {
    format!("{}mbfmu{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX)
}

/// Locate the cdylib to embed: `MBFMU_LIB`, else the newest of `libmbfmu.so` next to the
/// running executable, in its `deps/` subdirectory, or in its parent directory. (`cargo
/// build` puts the cdylib next to the binary; `cargo test` only updates `deps/`, and runs
/// test executables from `deps/`.)
pub fn find_library() -> Result<PathBuf, PackError> {
    if let Some(p) = std::env::var_os("MBFMU_LIB") {
        let p = PathBuf::from(p);
        return if p.is_file() {
            Ok(p)
        } else {
            Err(PackError::LibraryNotFound(format!("MBFMU_LIB={} is not a file", p.display())))
        };
    }
    let name = library_file_name();
    let exe = std::env::current_exe().map_err(io_err("locating the running executable"))?;
    let dir = exe.parent().unwrap_or(Path::new("."));
    let mut candidates = vec![dir.join(&name), dir.join("deps").join(&name)];
    if let Some(parent) = dir.parent() {
        candidates.push(parent.join(&name));
    }
    let newest = candidates
        .iter()
        .filter_map(|p| {
            let meta = std::fs::metadata(p).ok().filter(|m| m.is_file())?;
            Some((meta.modified().ok(), p))
        })
        .max_by_key(|(modified, _)| *modified);
    match newest {
        Some((_, p)) => Ok(p.clone()),
        None => Err(PackError::LibraryNotFound(format!(
            "the FMU library {name} was not found (tried {}); build it with `cargo build --release` \
             and install mbfmu with `target/release/mbfmu install` (README), or set MBFMU_LIB",
            candidates.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
        ))),
    }
}

/// The FMU library's bytes: `MBFMU_LIB` if set, else the copy embedded in the running
/// executable by `mbfmu install` ([`bundle`]), else the cdylib of the build the
/// executable comes from ([`find_library`]).
pub fn library() -> Result<Vec<u8>, PackError> {
    if std::env::var_os("MBFMU_LIB").is_none()
        && let Some(lib) = bundle::embedded_library()
    {
        return Ok(lib);
    }
    let path = find_library()?;
    std::fs::read(&path).map_err(io_err(format!("reading {}", path.display())))
}

/// Load the model and gather every file of its FMU, with the start values `set`.
fn contents(model_path: &Path, set: &[(String, f64)], standard: Standard, kind: Kind) -> Result<Contents, PackError> {
    let label = model_path.display().to_string();
    let bytes = std::fs::read(model_path).map_err(|e| ModelError {
        file: label.clone(),
        pos: crate::model::SrcPos { line: 1, col: 1 },
        element: "file".into(),
        name: label.clone(),
        msg: format!("cannot read: {e}"),
    })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| ModelError {
        file: label.clone(),
        pos: crate::model::SrcPos { line: 1, col: 1 },
        element: "file".into(),
        name: label.clone(),
        msg: format!("not UTF-8: {e}"),
    })?;
    let base = load_str(text, &label)?;
    let overrides = base.resolve_overrides(set).map_err(PackError::StartValue)?;
    let model = base.with_overrides(&overrides).map_err(PackError::StartValue)?;
    StartValues::check_names(&model).map_err(PackError::StartValue)?;
    let start_values = start_values_text(&overrides);
    let id = model_identifier(&model.name);
    let lib = library()?;
    let FmuLinearization { layout, structure, starts } = for_fmu(&model);
    let guid = guid_with(&base, text, &start_values);
    let (interfaces, dropped) = kind.interfaces(&layout)?;
    let (xml, platform) = match standard {
        Standard::Fmi2 => {
            (fmi2_description::describe(&model, &guid, &layout, &structure, &starts, interfaces), PLATFORM.to_string())
        }
        Standard::Fmi3 => {
            (fmi3_description::describe(&model, &guid, &layout, &structure, &starts, interfaces), platform_tuple())
        }
    };
    let warnings = layout
        .missing
        .iter()
        .map(|why| format!("the FMU has no linearization states (fmi2GetDirectionalDerivative will fail): {why}"))
        .chain(dropped)
        .collect();
    let mut files = vec![
        ("modelDescription.xml".to_string(), xml.into_bytes()),
        (format!("binaries/{platform}/{id}.{LIB_EXT}"), lib),
        ("resources/model.xml".to_string(), bytes.clone()),
        (format!("resources/{LAYOUT_FILE}"), layout.to_text(&guid).into_bytes()),
        (format!("resources/{INTERFACES_FILE}"), interfaces.to_text().into_bytes()),
    ];
    if !start_values.is_empty() {
        files.push((format!("resources/{START_VALUES_FILE}"), start_values.into_bytes()));
    }
    files.extend(modal_files(&model)?);
    Ok(Contents { packed: Packed { guid, model_identifier: id, warnings }, files })
}

/// The modal data files of the model's flexible bodies, as `resources/<path as written>`
/// (the FMU reads `resources/model.xml`, whose relative paths then point there). A path
/// that is absolute or leaves the model's directory cannot be packed.
fn modal_files(model: &crate::model::Model) -> Result<Vec<(String, Vec<u8>)>, PackError> {
    let mut out: Vec<(String, Vec<u8>)> = Vec::new();
    for b in &model.bodies {
        let Some(f) = &b.flex else { continue };
        let err = |msg: String| ModelError {
            file: model.file.clone(),
            pos: b.pos,
            element: "flexible_body".into(),
            name: b.name.clone(),
            msg,
        };
        let rel = Path::new(&f.file);
        let inside =
            rel.components().all(|c| matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir));
        if !inside {
            return Err(err(format!(
                "modal data '{}': to be packed into the FMU it must be a relative path inside the model file's directory",
                f.file
            ))
            .into());
        }
        let data = std::fs::read(&f.path).map_err(|e| err(format!("modal data '{}': cannot read: {e}", f.path)))?;
        let name = format!(
            "resources/{}",
            rel.components().filter_map(|c| c.as_os_str().to_str()).filter(|c| *c != ".").collect::<Vec<_>>().join("/")
        );
        if !out.iter().any(|(n, _)| *n == name) {
            out.push((name, data));
        }
    }
    Ok(out)
}

/// The state layout file of the model text `model_text` (as [`pack`] writes it into
/// `resources/`), and the warning when the states cannot be selected. For hosts that
/// build a resources directory themselves (tests); the engine runs on a stack of its own
/// when the caller's is small (as in the exports).
pub fn layout_file(model_text: &str, label: &str) -> Result<(Vec<u8>, Option<String>), ModelError> {
    crate::fmi::guard::with_stack(|| {
        let model = load_str(model_text, label)?;
        let layout = StateLayout::at_start(&model);
        Ok((layout.to_text(&guid(&model, model_text)).into_bytes(), layout.missing))
    })
}

/// Write the FMU of the model file `model_path` as the zip archive `out` (replacing it).
pub fn pack_fmu(model_path: &Path, out: &Path) -> Result<Packed, PackError> {
    let c = contents(model_path, &[], Standard::Fmi2, Kind::Both)?;
    write_zip(&c, out)?;
    Ok(c.packed)
}

/// Write the FMU of the model file `model_path` unzipped into the directory `dir`
/// (created if needed; files of the same names are replaced).
pub fn pack_dir(model_path: &Path, dir: &Path) -> Result<Packed, PackError> {
    let c = contents(model_path, &[], Standard::Fmi2, Kind::Both)?;
    write_dir(&c, dir)?;
    Ok(c.packed)
}

/// Pack both ways at once (either may be `None`); the model is loaded once.
pub fn pack(model_path: &Path, fmu: Option<&Path>, dir: Option<&Path>) -> Result<Packed, PackError> {
    pack_with(model_path, &[], Standard::Fmi2, Kind::Both, fmu, dir)
}

/// [`pack`] with the start values `set` (`NAME=VALUE` pairs, [`crate::model::overrides`])
/// instead of the model file's values, as an FMU of FMI version `standard` offering the
/// interfaces of `kind`.
pub fn pack_with(
    model_path: &Path,
    set: &[(String, f64)],
    standard: Standard,
    kind: Kind,
    fmu: Option<&Path>,
    dir: Option<&Path>,
) -> Result<Packed, PackError> {
    let c = contents(model_path, set, standard, kind)?;
    if let Some(out) = fmu {
        write_zip(&c, out)?;
    }
    if let Some(dir) = dir {
        write_dir(&c, dir)?;
    }
    Ok(c.packed)
}

fn write_dir(c: &Contents, dir: &Path) -> Result<(), PackError> {
    for (name, data) in &c.files {
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(io_err(format!("creating {}", parent.display())))?;
        }
        std::fs::write(&path, data).map_err(io_err(format!("writing {}", path.display())))?;
    }
    Ok(())
}

/// Write the archive to a sibling temporary file, then rename it over `out`, so that a
/// failure never leaves a truncated FMU behind.
fn write_zip(c: &Contents, out: &Path) -> Result<(), PackError> {
    let mut tmp_name = out.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    tmp_name.push(".partial");
    let tmp = out.with_file_name(tmp_name);
    let result = write_zip_to(c, &tmp, out);
    match result {
        Ok(()) => std::fs::rename(&tmp, out).map_err(io_err(format!("writing {}", out.display()))),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

fn write_zip_to(c: &Contents, tmp: &Path, out: &Path) -> Result<(), PackError> {
    let ctx = || format!("writing {}", out.display());
    let file = std::fs::File::create(tmp).map_err(io_err(ctx()))?;
    let mut zip = zip::ZipWriter::new(std::io::BufWriter::new(file));
    for (name, data) in &c.files {
        let mode = if name.starts_with("binaries/") { 0o755 } else { 0o644 };
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .unix_permissions(mode)
            .large_file(data.len() >= u32::MAX as usize);
        zip.start_file(name.as_str(), options).map_err(|e| PackError::Io { context: ctx(), source: e.into() })?;
        zip.write_all(data).map_err(io_err(ctx()))?;
    }
    let mut w = zip.finish().map_err(|e| PackError::Io { context: ctx(), source: e.into() })?;
    w.flush().map_err(io_err(ctx()))?;
    Ok(())
}
