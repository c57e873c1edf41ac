//! `cargo xtask chart` and `cargo xtask stability`: run the stickslip-study
//! binary (the integrators in-process, no HDF5) in the dev profile.

use std::path::Path;

/// `cargo xtask chart [--quick] [--out DIR]`: the work-precision study,
/// docs/work-precision.csv, .png and .svg (`--quick`: a smoke test into
/// target/study-quick/).
pub fn chart(root: &Path, args: &[String]) -> Result<(), String> {
    run_study_binary(root, "chart", args)
}

/// `cargo xtask stability [--quick] [--out DIR]`: the stability map,
/// docs/stability-*.csv, .png and .svg.
pub fn stability(root: &Path, args: &[String]) -> Result<(), String> {
    run_study_binary(root, "stability", args)
}

fn run_study_binary(root: &Path, sub: &str, args: &[String]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = std::process::Command::new(cargo);
    cmd.current_dir(root)
        .args(["run", "--quiet", "-p", "stickslip-study", "--"])
        .arg(sub)
        .args(args);
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start cargo run -p stickslip-study: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("stickslip-study {sub} failed ({status})"))
    }
}
