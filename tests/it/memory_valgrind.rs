//! valgrind memcheck over a full FMU lifecycle (issue 12 item 6): examples/fmu_lifecycle
//! drives the exported C functions (instantiate, initialize, steps, directional
//! derivatives, get/set/serialize/deserialize FMU states with two left for
//! fmi2FreeInstance, reset, a second run, terminate, free) and must end with 0 errors and
//! 0 bytes definitely (or indirectly) lost, on three models, one of them on a host thread
//! with a 64 KiB stack, and through the FMI 3 exports (`--fmi3`) on one (the exports then run the engine on a stack of their own). A
//! control run that leaks 4096 bytes on purpose must fail, so the check cannot pass blind.
//!
//! Without valgrind the tests say so and pass, except in CI (the `CI` variable set), where
//! they fail: CI installs valgrind (.ci/run).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::Instant;

/// Whether this runs in CI (the `CI` variable set, and not to "false" or "0").
fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// Whether valgrind can run; absent outside CI: say so (on the real stderr, past the test
/// harness's capture) and return false; absent in CI: fail.
fn have_valgrind(test: &str) -> bool {
    let found = Command::new("valgrind").arg("--version").output().is_ok_and(|o| o.status.success());
    if !found {
        assert!(!in_ci(), "valgrind is not installed, and CI must run {test} (Debian: apt-get install -y valgrind)");
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED {test}: valgrind is not installed (Debian: apt-get install -y valgrind); CI fails instead"
        );
    }
    found
}

/// The fmu_lifecycle example, built by cargo in the profile of this test (a no-op when
/// `cargo test` has built it already); its path from cargo's own report.
fn lifecycle_binary() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let mut cmd = Command::new(env!("CARGO"));
        cmd.current_dir(env!("CARGO_MANIFEST_DIR")).args([
            "build",
            "--example",
            "fmu_lifecycle",
            "--message-format=json-render-diagnostics",
        ]);
        if !cfg!(debug_assertions) {
            cmd.arg("--release");
        }
        let out = cmd.output().expect("cargo runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "cargo build --example fmu_lifecycle failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        // The compiler-artifact message of the example: ..."executable":"/path/fmu_lifecycle"...
        let exe = stdout
            .lines()
            .filter(|l| l.contains(r#""reason":"compiler-artifact""#) && l.contains(r#""name":"fmu_lifecycle""#))
            .find_map(|l| l.split(r#""executable":""#).nth(1)?.split('"').next().map(PathBuf::from))
            .unwrap_or_else(|| panic!("no executable for fmu_lifecycle in cargo's report:\n{stdout}"));
        assert!(exe.is_file(), "{} is not a file", exe.display());
        exe
    })
}

/// Bytes that may stay reachable at exit (measured: 648).
const REACHABLE_BOUND: u64 = 4096;

/// What memcheck said of one run.
struct Memcheck {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    secs: f64,
}

impl Memcheck {
    /// The byte count of a LEAK SUMMARY line ("definitely lost: 1,000 bytes in 1 blocks");
    /// 0 when memcheck printed no summary because every block was freed.
    fn bytes(&self, kind: &str) -> u64 {
        let Some(line) = self.stderr.lines().find(|l| l.contains(&format!("{kind}:"))) else {
            assert!(self.stderr.contains("All heap blocks were freed"), "no '{kind}' line:\n{}", self.stderr);
            return 0;
        };
        let after = line.split(&format!("{kind}:")).nth(1).unwrap();
        let n = after.split_whitespace().next().unwrap().replace(',', "");
        n.parse().unwrap_or_else(|_| panic!("cannot read the bytes of '{line}'"))
    }

    /// The error count of "ERROR SUMMARY: N errors from M contexts".
    fn errors(&self) -> u64 {
        let line = self.stderr.lines().find(|l| l.contains("ERROR SUMMARY:")).expect("an ERROR SUMMARY line");
        let after = line.split("ERROR SUMMARY:").nth(1).unwrap();
        after.split_whitespace().next().unwrap().replace(',', "").parse().unwrap()
    }
}

/// Run the lifecycle of `model` (with `args`) under memcheck; definite leaks count as
/// errors and make the exit code 99.
fn memcheck(model: &str, args: &[&str]) -> Memcheck {
    let model_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("models").join(model);
    let t = Instant::now();
    let out = Command::new("valgrind")
        .args(["--tool=memcheck", "--leak-check=full", "--errors-for-leak-kinds=definite", "--error-exitcode=99"])
        .arg(lifecycle_binary())
        .arg(&model_path)
        .args(args)
        .output()
        .expect("valgrind runs");
    let run = Memcheck {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        secs: t.elapsed().as_secs_f64(),
    };
    println!(
        "{model} {args:?} under memcheck: exit {:?}, {} errors, definitely lost {} B, indirectly lost {} B, possibly \
         lost {} B, still reachable {} B, {:.1} s\n{}",
        run.code,
        run.errors(),
        run.bytes("definitely lost"),
        run.bytes("indirectly lost"),
        run.bytes("possibly lost"),
        run.bytes("still reachable"),
        run.secs,
        run.stdout.trim_end(),
    );
    run
}

/// The lifecycle of `model` is clean under memcheck.
fn clean(model: &str, args: &[&str]) {
    let run = memcheck(model, args);
    let all = format!("stdout:\n{}\nstderr:\n{}", run.stdout, run.stderr);
    assert!(run.stdout.contains(": ok on "), "the lifecycle did not finish: {all}");
    assert_eq!(run.errors(), 0, "memcheck errors: {all}");
    assert_eq!(run.bytes("definitely lost"), 0, "{all}");
    assert_eq!(run.bytes("indirectly lost"), 0, "{all}");
    // What stays reachable at exit is the live-instance registry's empty node and the
    // standard library's thread record (648 bytes): an instance that fmi2FreeInstance
    // left in the registry (still reachable, so no leak to memcheck) would be far more.
    let reachable = run.bytes("still reachable");
    assert!(reachable <= REACHABLE_BOUND, "{reachable} bytes still reachable at exit: {all}");
    assert_eq!(run.code, Some(0), "{all}");
}

#[test]
fn pendulum_lifecycle_has_no_memory_errors_and_no_leak() {
    if have_valgrind("pendulum_lifecycle_has_no_memory_errors_and_no_leak") {
        clean("pendulum.xml", &[]);
    }
}

#[test]
fn benchmark_bicycle_lifecycle_has_no_memory_errors_and_no_leak() {
    if have_valgrind("benchmark_bicycle_lifecycle_has_no_memory_errors_and_no_leak") {
        clean("benchmark_bicycle.xml", &[]);
    }
}

#[test]
fn cart_pendulum_pid_lifecycle_on_a_64_kib_host_thread_has_no_memory_errors_and_no_leak() {
    if have_valgrind("cart_pendulum_pid_lifecycle_on_a_64_kib_host_thread_has_no_memory_errors_and_no_leak") {
        clean("cart_pendulum_pid.xml", &["--thread-stack", "65536"]);
    }
}

#[test]
fn fmi3_cart_pendulum_pid_lifecycle_on_a_64_kib_host_thread_has_no_memory_errors_and_no_leak() {
    // The FMI 3 exports (instantiation, steps, directional and adjoint derivatives, FMU
    // states with one left for fmi3FreeInstance, reset, terminate, free).
    if have_valgrind("fmi3_cart_pendulum_pid_lifecycle_on_a_64_kib_host_thread_has_no_memory_errors_and_no_leak") {
        clean("cart_pendulum_pid.xml", &["--fmi3", "--thread-stack", "65536"]);
    }
}

#[test]
fn a_deliberate_leak_fails_the_memcheck_run() {
    if have_valgrind("a_deliberate_leak_fails_the_memcheck_run") {
        let run = memcheck("pendulum.xml", &["--leak", "4096"]);
        assert_eq!(run.code, Some(99), "stderr:\n{}", run.stderr);
        assert_eq!(run.bytes("definitely lost"), 4096, "stderr:\n{}", run.stderr);
        assert_eq!(run.errors(), 1, "the leak is the only error:\n{}", run.stderr);
    }
}
