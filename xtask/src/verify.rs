//! `cargo xtask verify` and `cargo xtask figures`: run the stickslip-verify
//! binary (the integrators in-process, no HDF5) in the dev profile.

use std::path::Path;

/// `cargo xtask verify [--quick] [--bless] [--only SUITE]`: the table of
/// checks; fails when any check fails.
pub fn verify(root: &Path, args: &[String]) -> Result<(), String> {
    run_verify_binary(root, "verify", args)
}

/// `cargo xtask figures [--out DIR]`: docs/figures/*.png and *.svg.
pub fn figures(root: &Path, args: &[String]) -> Result<(), String> {
    run_verify_binary(root, "figures", args)
}

fn run_verify_binary(root: &Path, sub: &str, args: &[String]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = std::process::Command::new(cargo);
    cmd.current_dir(root)
        .args(["run", "--quiet", "-p", "stickslip-verify", "--"])
        .arg(sub)
        .args(args);
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start cargo run -p stickslip-verify: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("stickslip-verify {sub} failed ({status})"))
    }
}
