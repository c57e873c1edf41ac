//! `cargo xtask bench fem`: assembly and Cholesky on the Q2 slab ladder, with
//! scikit-fem's assembly of the same K and scipy's SuperLU on the very matrix
//! stickslip assembled as peer figures.
//!
//! Each rung runs `crates/fem/examples/bench_assembly.rs` in its own process
//! (so its peak RSS is the rung's), dumping K and the load to
//! `target/bench-fem/rR/`, then `bench/fem_peer.py` on the same mesh and
//! matrix. Figures are printed, not asserted: targets are assembly >= 10x
//! faster than scikit-fem and factorization faster than SuperLU.
//!
//!     cargo xtask bench fem [--refine 8,16,32,64] [--q1] [--no-peer] [--splu-max-dofs N]

use std::path::Path;
use std::process::Command;

use crate::python;

fn kv(line: &str) -> Vec<(String, String)> {
    line.trim_start_matches("RESULT ")
        .split_whitespace()
        .filter_map(|s| s.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn num(kv: &[(String, String)], key: &str) -> f64 {
    kv.iter()
        .find(|(k, _)| k == key)
        .and_then(|(_, v)| v.parse().ok())
        .unwrap_or(f64::NAN)
}

/// Runs the ladder and prints the table.
///
/// # Errors
/// Bad arguments, a failing cargo or Python run.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let mut refines = vec![8usize, 16, 32, 64];
    let (mut q1, mut peer) = (false, true);
    let mut splu_max = 600_000usize;
    let usage = "[--refine 8,16,32,64] [--q1] [--no-peer] [--splu-max-dofs N]";
    crate::bench::args("bench fem", usage, args, |a, it| {
        match a {
            "--refine" => {
                let v = it.next().ok_or("--refine needs a list like 8,16,32")?;
                refines = v
                    .split(',')
                    .map(|s| {
                        s.parse()
                            .map_err(|_| format!("--refine {v}: not a list of integers"))
                    })
                    .collect::<Result<_, _>>()?;
            }
            "--splu-max-dofs" => splu_max = crate::bench::integer_arg(a, "a number", it)?,
            "--q1" => q1 = true,
            "--no-peer" => peer = false,
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    if peer {
        python::ensure_python_modules(&[("skfem", "scikit-fem"), ("scipy", "scipy")])?;
    }
    let status = Command::new("cargo")
        .current_dir(root)
        .args([
            "build",
            "-q",
            "-p",
            "stickslip-fem",
            "--example",
            "bench_assembly",
        ])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("building the bench_assembly example failed".into());
    }
    println!(
        "{:>7} {:>9} {:>10} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>9} | {:>9} {:>7} {:>9} {:>7}",
        "refine",
        "free_dofs",
        "nnz",
        "pattern_s",
        "K+M_s",
        "symbolic",
        "numeric",
        "solve_s",
        "peak_MB",
        "factor",
        "skfem_s",
        "x_asm",
        "splu_s",
        "x_fact"
    );
    for r in refines {
        let dump = root.join("target/bench-fem").join(format!("r{r}"));
        let mut cmd = Command::new("cargo");
        cmd.current_dir(root).args([
            "run",
            "-q",
            "-p",
            "stickslip-fem",
            "--example",
            "bench_assembly",
            "--",
            "--refine",
            &r.to_string(),
        ]);
        if q1 {
            cmd.arg("--q1");
        }
        if peer {
            cmd.arg("--dump").arg(&dump);
        }
        let out = cmd.output().map_err(|e| format!("cannot run cargo: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "bench_assembly --refine {r} failed:\n{}",
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let ours = kv(String::from_utf8_lossy(&out.stdout)
            .lines()
            .last()
            .unwrap_or(""));
        let dofs = num(&ours, "free_dofs");
        let asm = num(&ours, "assembly_s") + num(&ours, "pattern_s");
        let fact = num(&ours, "symbolic_s") + num(&ours, "numeric_s");
        let (mut sk, mut splu) = (f64::NAN, f64::NAN);
        if peer {
            let mut pcmd = Command::new(python::python());
            pcmd.current_dir(root)
                .arg("bench/fem_peer.py")
                .args(["--refine", &r.to_string(), "--dump"])
                .arg(&dump);
            if q1 {
                pcmd.arg("--q1");
            }
            if dofs > splu_max as f64 {
                pcmd.arg("--no-splu");
            }
            let po = pcmd
                .output()
                .map_err(|e| format!("cannot run python: {e}"))?;
            if !po.status.success() {
                return Err(format!(
                    "fem_peer.py --refine {r} failed:\n{}",
                    String::from_utf8_lossy(&po.stderr)
                ));
            }
            let stdout = String::from_utf8_lossy(&po.stdout);
            let theirs = kv(stdout
                .lines()
                .rev()
                .find(|l| l.starts_with("RESULT "))
                .unwrap_or(""));
            sk = num(&theirs, "skfem_assembly_s");
            splu = num(&theirs, "splu_factor_s");
            let _ = std::fs::remove_dir_all(&dump);
        }
        println!(
            "{:>7} {:>9} {:>10} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8.0} {:>9.3} | {:>9.3} {:>7.1} {:>9.3} {:>7.1}",
            r,
            dofs,
            num(&ours, "nnz"),
            num(&ours, "pattern_s"),
            num(&ours, "assembly_s"),
            num(&ours, "symbolic_s"),
            num(&ours, "numeric_s"),
            num(&ours, "solve_s"),
            num(&ours, "peak_rss_mb"),
            fact,
            sk,
            sk / asm,
            splu,
            splu / fact
        );
    }
    println!("K+M_s: K, consistent M and lumped M in one pass (pattern excluded); x_asm = scikit-fem K assembly / (pattern + K+M);");
    println!("factor = ordering + symbolic + numeric Cholesky (faer; AMD, from 500 free DOFs a nested dissection of the cells unless AMD's factor is 10% smaller); x_fact = scipy splu (SuperLU, COLAMD) factor time / factor.");
    Ok(())
}
