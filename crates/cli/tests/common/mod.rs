//! What the cli's integration tests share: the binary under test, the
//! repository and the tests' data (the repository's root and scratch
//! directories from the test kit), and the commands as the tests run them.
// Each test file uses a part of this module.
#![allow(dead_code, unused_imports)]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The stickslip binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stickslip"))
}

pub use stickslip_testkit::{scratch, workspace_root as root};

/// A file of crates/cli/tests/data.
pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// What a command wrote to stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `stickslip check CASE --set KV...`.
pub fn check(case: &Path, sets: &[&str]) -> Output {
    let mut cmd = bin();
    cmd.arg("check").arg(case);
    for kv in sets {
        cmd.args(["--set", kv]);
    }
    cmd.output().unwrap()
}

/// `stickslip run CASE -o OUT FLAGS...`.
pub fn run(case: &Path, out: &Path, flags: &[&str]) -> Output {
    bin()
        .arg("run")
        .arg(case)
        .arg("-o")
        .arg(out)
        .args(flags)
        .output()
        .unwrap()
}

/// Whether python3 imports `modules` (as written after `import`). A check
/// that needs them cannot run without them: under CI, where `cargo xtask
/// test` installs them, that is a failure saying `missing`; elsewhere a
/// skip, said on stderr as `skipped`.
pub fn python_has(modules: &str, missing: &str, skipped: &str) -> bool {
    let has = Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .status()
        .is_ok_and(|s| s.success());
    if !has {
        assert!(std::env::var_os("CI").is_none(), "{missing}");
        eprintln!("{skipped}");
    }
    has
}

/// A check that cannot run for want of `what`: under CI (where `cargo
/// xtask test` provides it) a failure saying `remedy`, elsewhere a skip
/// said on stderr. Call it where the test would return.
pub fn skip_without(what: &str, remedy: &str) {
    assert!(
        std::env::var_os("CI").is_none(),
        "{what} is missing here, and CI must run this test: {remedy}"
    );
    eprintln!("skipped: {what} is missing");
}

/// `python3 -c SCRIPT ARGS...`, which must succeed: what it printed.
pub fn python<S: AsRef<OsStr>>(script: &str, args: &[S]) -> String {
    let o = Command::new("python3")
        .arg("-c")
        .arg(script)
        .args(args)
        .output()
        .unwrap();
    succeeded(&o, "python check failed")
}

/// The stdout of a command that must have succeeded; where it did not,
/// the failure says `what` and shows all it printed.
pub fn succeeded(o: &Output, what: &str) -> String {
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{what}:\n{stdout}{}", stderr(o));
    stdout
}

/// `stickslip probe RESULTS ARGS...`.
pub fn probe(results: &Path, args: &[&str]) -> Output {
    bin().arg("probe").arg(results).args(args).output().unwrap()
}

/// Runs `stickslip ARGS…` and returns what it did.
pub fn stickslip<S: AsRef<OsStr>>(args: &[S]) -> Output {
    bin().args(args).output().unwrap()
}

/// [`stickslip`], which must succeed.
pub fn stickslip_ok<S: AsRef<OsStr>>(args: &[S]) {
    let o = stickslip(args);
    assert!(
        o.status.success(),
        "stickslip {:?} failed: {}",
        args.iter().map(|a| a.as_ref()).collect::<Vec<_>>(),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A tmpfs mounted at `dir/name` with the mount `options` (its size;
/// `ro`), or `None` where this process may not mount one (not root, or a
/// container without the capability): then a failure under CI, where the
/// test must run, and a skip elsewhere (the disk-full and read-only
/// tests).
pub fn tmpfs(dir: &Path, name: &str, options: &str) -> Option<PathBuf> {
    let at = dir.join(name);
    std::fs::create_dir_all(&at).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", options, "tmpfs"])
        .arg(&at)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        assert!(
            std::env::var_os("CI").is_none(),
            "cannot mount a tmpfs at {}: run the tests as root, or give the container \
             CAP_SYS_ADMIN (docker run --cap-add SYS_ADMIN)",
            at.display()
        );
        eprintln!("skipped: cannot mount a tmpfs here (needs root or CAP_SYS_ADMIN)");
        return None;
    }
    Some(at)
}
