//! `cargo xtask bench step`: time per step of central difference and of
//! implicit Newmark (Schur path) on the slab ladder, with the figures it is
//! compared with measured in the same run: STREAM triad bandwidth and the
//! bytes an explicit step moves; one forward+back solve for Newmark; the scipy
//! peer (bench/peer.py, numpy + scipy, its K and M assembled by scikit-fem,
//! installed with pip if missing) on the paper's 85-node mesh and the rungs of
//! ≥ 100k DOFs, its matrices checked against ours (1e-10) and its state
//! against ours (1e-8) before it is timed; peak memory against what the run
//! must hold.
//!
//! Runs `crates/time/examples/bench_step.rs` in the release profile (what
//! `cargo install` builds; the dev profile keeps debug assertions and overflow
//! checks, which slow the small rungs' steps: docs/performance.md), which
//! times each rung in its own process (so its peak RSS is the rung's), prints
//! one row per rung and writes target/bench/step.csv; a full run (no --quick,
//! no --max-dofs) with the peer also copies it to docs/bench-step.csv, the
//! table the README quotes. Figures are printed, not asserted.
//!
//!     cargo xtask bench step [--quick] [--max-dofs N] [--no-peer]

use std::path::Path;
use std::process::Command;

use crate::python;

/// Builds and runs the bench example, passing `--quick` / `--max-dofs N`.
///
/// # Errors
/// Bad arguments or a failing cargo run.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let mut pass: Vec<String> = Vec::new();
    let mut peer = true;
    let usage = "[--quick] [--max-dofs N] [--no-peer]";
    crate::bench::args("bench step", usage, args, |a, it| {
        match a {
            "--quick" => pass.push(a.to_string()),
            "--no-peer" => peer = false,
            "--max-dofs" => {
                let v: u64 = crate::bench::integer_arg(a, "a number of DOFs", it)?;
                pass.extend([a.to_string(), v.to_string()]);
            }
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    if peer {
        python::ensure_python_modules(&[
            ("numpy", "numpy"),
            ("scipy", "scipy"),
            ("skfem", "scikit-fem"),
        ])?;
        pass.push("--peer".into());
    }
    gmsh_slab(root);
    let status = Command::new("cargo")
        .current_dir(root)
        .args([
            "run",
            "-q",
            "--release",
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
    let table = root.join("target/bench/step.csv");
    println!("table: {}", table.display());
    let full = peer && !pass.iter().any(|a| a == "--quick" || a == "--max-dofs");
    if full {
        let docs = root.join("docs/bench-step.csv");
        std::fs::copy(&table, &docs)
            .map_err(|e| format!("cannot copy {} to {}: {e}", table.display(), docs.display()))?;
        println!("copied to {} (quoted by the README)", docs.display());
    }
    Ok(())
}

/// Writes Gmsh's own Q2 352x88 slab (its numbering and coordinates, not
/// snapped) into target/bench/gmsh for the bench's "gmsh-" rungs, unless it
/// is there. Failing (no gmsh to be had) leaves those rungs out, with a
/// message.
fn gmsh_slab(root: &Path) {
    let dir = root.join("target/bench/gmsh");
    if dir.join("slab-q2-352x88-bin.msh").exists() {
        return;
    }
    if let Err(e) = python::ensure_python_modules(&[("gmsh", "gmsh")]) {
        eprintln!("bench step: no Gmsh slab ({e}); its rungs are left out");
        return;
    }
    let status = Command::new(python::python())
        .arg(root.join("cases/meshes/generate.py"))
        .arg("--bench-out")
        .arg(&dir)
        .args(["--order", "2", "--nx", "352", "--ny", "88"])
        .status();
    if !matches!(status, Ok(s) if s.success()) {
        eprintln!("bench step: generate.py did not write the Gmsh slab; its rungs are left out");
    }
}
