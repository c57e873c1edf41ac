//! Helpers shared by the end-to-end test files that include this module
//! (`mod common;`): the repository root, a fresh scratch directory, and
//! the `stickslip` binary.

// Each test file that includes this module uses only part of it.
#![allow(dead_code)]

use std::ffi::OsStr;

use std::process::{Command, Output};

pub use stickslip_testkit::{scratch, workspace_root as root};

/// Runs `stickslip ARGS…` and returns what it did.
pub fn stickslip<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args(args)
        .output()
        .unwrap()
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
