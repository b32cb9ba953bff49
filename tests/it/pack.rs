//! `mbfmu pack`: the FMU's files, its GUID, and the command's exit codes.
//!
//! The packer embeds the crate's cdylib, which cargo builds with the tests because the
//! library's crate types include `cdylib` (`target/<profile>/deps/libmbfmu.so`; `cargo
//! build` also puts it next to the `mbfmu` binary).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use crate::common::root;

fn mbfmu(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("MBFMU_LIB")
        .stdin(Stdio::null())
        .output()
        .expect("the mbfmu binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A fresh empty directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mbfmu-pack-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create temp dir");
    d
}

/// The cdylib the packer embeds: this test executable runs from `target/<profile>/deps/`
/// and the binary from `target/<profile>/`, and both search the same three places.
fn library() -> PathBuf {
    mbfmu::pack::find_library().unwrap_or_else(|e| panic!("{e}"))
}

/// Entries of a zip archive, name -> bytes, in archive order.
fn unzip(path: &Path) -> Vec<(String, Vec<u8>)> {
    let f = std::fs::File::open(path).expect("the FMU exists");
    let mut z = zip::ZipArchive::new(f).expect("the FMU is a zip archive");
    (0..z.len())
        .map(|i| {
            let mut e = z.by_index(i).expect("entry");
            let mut data = Vec::new();
            e.read_to_end(&mut data).expect("entry readable");
            (e.name().expect("entry name").to_string(), data)
        })
        .collect()
}

/// The `guid="..."` of a modelDescription.xml.
fn guid_of(xml: &str) -> String {
    let start = xml.find(" guid=\"").expect("a guid attribute") + 7;
    xml[start..start + xml[start..].find('"').expect("closing quote")].to_string()
}

#[test]
fn cargo_builds_the_cdylib_for_the_tests() {
    // crate-type includes cdylib, so `cargo test` builds it (in target/<profile>/deps/).
    assert!(library().is_file(), "{}", library().display());
}

#[test]
fn pack_writes_the_fmu_zip_and_directory() {
    let dir = temp_dir("zip");
    let fmu = dir.join("pendulum.fmu");
    let unzipped = dir.join("pendulum");
    let model = root().join("models/pendulum.xml");
    let o = mbfmu(&[
        "pack".as_ref(),
        model.as_os_str(),
        "-o".as_ref(),
        fmu.as_os_str(),
        "--out-dir".as_ref(),
        unzipped.as_os_str(),
    ]);
    assert!(o.status.success(), "pack failed: {}", text(&o.stderr));
    let stdout = text(&o.stdout);
    assert_eq!(stdout.lines().count(), 1, "one summary line: {stdout}");
    assert!(stdout.contains("'pendulum'") && stdout.contains(&fmu.display().to_string()), "{stdout}");

    let entries = unzip(&fmu);
    let names: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "modelDescription.xml",
            "binaries/linux64/pendulum.so",
            "resources/model.xml",
            "resources/states.txt",
            "resources/interfaces.txt"
        ]
    );
    let model_bytes = std::fs::read(&model).expect("model readable");
    assert_eq!(entries[2].1, model_bytes, "resources/model.xml is the model file, byte for byte");
    assert_eq!(entries[1].1, std::fs::read(library()).expect("cdylib readable"), "the .so is the crate's cdylib");
    let xml = text(&entries[0].1);
    assert!(xml.contains("modelIdentifier=\"pendulum\""));
    let guid = guid_of(&xml);
    assert!(stdout.contains(&guid), "the summary names the GUID: {stdout}");
    assert_eq!(guid, crate::common::guid(&text(&model_bytes)));

    // The unzipped tree holds the same files.
    for (name, data) in &entries {
        assert_eq!(&std::fs::read(unzipped.join(name)).expect("file in --out-dir"), data, "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_changed_model_text_gives_a_new_guid() {
    let dir = temp_dir("guid");
    let original = std::fs::read_to_string(root().join("models/pendulum.xml")).expect("readable");
    let changed_model = dir.join("changed.xml");
    // Same model, one more comment: the text changes, the meaning does not.
    std::fs::write(&changed_model, format!("{original}\n<!-- changed -->\n")).expect("write");
    let mut guids = Vec::new();
    for (i, model) in [root().join("models/pendulum.xml"), changed_model].iter().enumerate() {
        let out = dir.join(format!("{i}"));
        let o = mbfmu(&["pack".as_ref(), model.as_os_str(), "--out-dir".as_ref(), out.as_os_str()]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        guids.push(guid_of(&std::fs::read_to_string(out.join("modelDescription.xml")).expect("written")));
    }
    assert_ne!(guids[0], guids[1]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_malformed_model_exits_2_with_a_located_message_and_writes_nothing() {
    let dir = temp_dir("malformed");
    let fmu = dir.join("bad.fmu");
    let o = mbfmu(&["pack".as_ref(), "tests/malformed/05_bad_expression.xml".as_ref(), "-o".as_ref(), fmu.as_os_str()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.starts_with("tests/malformed/05_bad_expression.xml:2:"), "located message: {err}");
    assert!(err.contains("body 'b'"), "names the element: {err}");
    assert!(!fmu.exists(), "no FMU for a bad model");

    let o = mbfmu(&["pack".as_ref(), "models/no_such_model.xml".as_ref(), "-o".as_ref(), fmu.as_os_str()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).starts_with("models/no_such_model.xml:1:1:"), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pack_without_a_destination_is_a_usage_error() {
    let o = mbfmu(&["pack".as_ref(), "models/pendulum.xml".as_ref()]);
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    assert!(err.contains("--out") && err.contains("--out-dir"), "names the missing options: {err}");
}

#[test]
fn an_unwritable_destination_exits_1() {
    let dir = temp_dir("unwritable");
    let fmu = dir.join("no/such/dir/p.fmu");
    let o = mbfmu(&["pack".as_ref(), "models/pendulum.xml".as_ref(), "-o".as_ref(), fmu.as_os_str()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).starts_with("error: writing "), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_library_is_a_clear_error() {
    let dir = temp_dir("nolib");
    let o = Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(["pack", "models/pendulum.xml", "--out-dir"])
        .arg(&dir)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("MBFMU_LIB", dir.join("missing.so"))
        .stdin(Stdio::null())
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("MBFMU_LIB="), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn installed_mbfmu_packs_from_any_directory_with_no_environment() {
    // `mbfmu install --prefix P` writes P/bin/mbfmu with the FMU library embedded; run from
    // an empty directory without MBFMU_LIB, it packs an FMU whose binary is that library.
    let root = std::env::temp_dir().join(format!("mbfmu-install-{}", std::process::id()));
    let (prefix, empty) = (root.join("prefix"), root.join("empty"));
    std::fs::create_dir_all(&empty).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(["install", "--prefix", prefix.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let installed = prefix.join("bin").join("mbfmu");
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/pendulum.xml");
    std::fs::copy(&model, empty.join("pendulum.xml")).unwrap();
    let pack = |exe: &Path| {
        let o = std::process::Command::new(exe)
            .args(["pack", "pendulum.xml", "-o", "p.fmu", "--out-dir", "p"])
            .current_dir(&empty)
            .env_remove("MBFMU_LIB")
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(empty.join("p/binaries").join(mbfmu::pack::PLATFORM).join("pendulum.so")).unwrap()
    };
    let lib = mbfmu::pack::library().unwrap();
    assert_eq!(pack(&installed), lib);
    // Installing from the installed copy embeds the library once, not twice.
    let again = root.join("again");
    let o =
        std::process::Command::new(&installed).args(["install", "--prefix", again.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (a, b) =
        (std::fs::metadata(&installed).unwrap().len(), std::fs::metadata(again.join("bin/mbfmu")).unwrap().len());
    assert_eq!(a, b);
    assert_eq!(pack(&again.join("bin/mbfmu")), lib);
    std::fs::remove_dir_all(&root).ok();
}
