//! `cargo xtask bench step`: time per step of central difference and of
//! implicit Newmark (Schur path) on the slab ladder (issue 7, deliverable
//! 3), with the hardware figures measured in the same run (STREAM triad
//! bandwidth and the bytes an explicit step moves; one forward+back solve
//! for Newmark).
//!
//! Runs `crates/time/examples/bench_step.rs`, which times each rung in its
//! own process (so its peak RSS is the rung's), prints one `RESULT` line per
//! rung and writes target/bench/step.csv. Figures are printed, not asserted.
//!
//!     cargo xtask bench step [--quick] [--max-dofs N]

use std::path::Path;
use std::process::Command;

/// Builds and runs the bench example, passing `--quick` / `--max-dofs N`.
///
/// # Errors
/// Bad arguments or a failing cargo run.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let mut pass: Vec<String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => pass.push(a.clone()),
            "--max-dofs" => {
                let v = it.next().ok_or("--max-dofs needs a number of DOFs")?;
                v.parse::<u64>()
                    .map_err(|_| format!("--max-dofs {v}: not an integer"))?;
                pass.push(a.clone());
                pass.push(v.clone());
            }
            "-h" | "--help" => {
                println!("cargo xtask bench step [--quick] [--max-dofs N]");
                return Ok(());
            }
            other => {
                return Err(format!(
                    "cargo xtask bench step: unknown argument {other:?}; try --help"
                ))
            }
        }
    }
    let status = Command::new("cargo")
        .current_dir(root)
        .args([
            "run",
            "-q",
            "-p",
            "stickslip-time",
            "--example",
            "bench_step",
            "--",
        ])
        .args(&pass)
        .status()
        .map_err(|e| format!("could not run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("the step bench failed ({status})"));
    }
    println!("table: {}", root.join("target/bench/step.csv").display());
    Ok(())
}
