//! What the cli's integration tests share: the binary under test, the
//! repository and the tests' data, and the commands as the tests run them.
// Each test file uses a part of this module.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The stickslip binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stickslip"))
}

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

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

/// `stickslip probe RESULTS ARGS...`.
pub fn probe(results: &Path, args: &[&str]) -> Output {
    bin().arg("probe").arg(results).args(args).output().unwrap()
}
