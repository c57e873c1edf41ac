//! `cargo xtask bench mesh`: the .msh reader's speed and memory on a ~1M-node
//! Q1 slab, with Gmsh's own load time of the same files (`gmsh.open` from
//! Python) as the peer figure.
//!
//! Steps: make sure `gmsh` imports (pip-install it if not); write the slab
//! (default 1000 x 999 cells = 1,001,000 nodes) to `target/bench-meshes/` in
//! MSH 4.1 ASCII and binary with `cases/meshes/generate.py --bench-out`
//! (reused when present, `--regenerate` to rewrite); time
//! `Mesh::from_file` with `crates/mesh/examples/bench_read.rs` (dev profile,
//! median of 5) and `gmsh.open` (median of 3); print a table with the
//! targets: >= 100 MB/s ASCII, >= 500 MB/s binary, peak memory < 2x the Mesh.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::python;

const RUST_RUNS: usize = 5;
const GMSH_RUNS: usize = 3;
const TARGET_ASCII_MBPS: f64 = 100.0;
const TARGET_BINARY_MBPS: f64 = 500.0;
const TARGET_PEAK_RATIO: f64 = 2.0;

/// Times `gmsh.open(FILE)` RUNS times, a fresh Gmsh state each time.
const GMSH_TIMER: &str = r#"
import resource, sys, time
import gmsh
path, runs = sys.argv[1], int(sys.argv[2])
times = []
for _ in range(runs):
    gmsh.initialize(["gmsh", "-nopopup"], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    t = time.perf_counter()
    gmsh.open(path)
    times.append(time.perf_counter() - t)
    gmsh.finalize()
times.sort()
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(f"RESULT median_s={times[len(times) // 2]:.6f} min_s={times[0]:.6f} max_s={times[-1]:.6f} peak_rss_bytes={rss}")
"#;

struct Options {
    nx: usize,
    ny: usize,
    regenerate: bool,
}

fn parse_args(args: &[String]) -> Result<Options, String> {
    let mut o = Options {
        nx: 1000,
        ny: 999,
        regenerate: false,
    };
    let usage = format!(
        "[--nx N] [--ny M] [--regenerate]\n\n\
         Reads a Q1 slab of N x M cells (default 1000 x 999, ~1M nodes) in MSH 4.1 ASCII and binary\n\
         with stickslip-mesh (median of {RUST_RUNS}) and with gmsh.open (median of {GMSH_RUNS}).\n\
         Meshes go to target/bench-meshes/ and are reused unless --regenerate."
    );
    crate::bench::args("bench mesh", &usage, args, |a, it| {
        match a {
            "--regenerate" => o.regenerate = true,
            "--nx" | "--ny" => {
                let v = it.next().ok_or_else(|| format!("{a} needs a number"))?;
                let n: usize = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or_else(|| format!("{a} {v}: not a positive integer"))?;
                if a == "--nx" {
                    o.nx = n;
                } else {
                    o.ny = n;
                }
            }
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    Ok(o)
}

/// Key/value pairs of the `RESULT k=v …` line a timing program prints last.
fn parse_result(stdout: &str, who: &str) -> Result<Vec<(String, String)>, String> {
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("RESULT "))
        .ok_or_else(|| format!("{who} printed no RESULT line; its output was:\n{stdout}"))?;
    Ok(line
        .split_whitespace()
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect())
}

fn get(kv: &[(String, String)], key: &str, who: &str) -> Result<f64, String> {
    kv.iter()
        .find(|(k, _)| k == key)
        .and_then(|(_, v)| v.parse::<f64>().ok())
        .ok_or_else(|| format!("{who}: no numeric {key} in its RESULT line"))
}

struct Row {
    label: &'static str,
    file_mb: f64,
    rust_s: f64,
    rust_mbps: f64,
    read_s: f64,
    parse_s: f64,
    target_mbps: f64,
    mesh_mb: f64,
    peak_mb: f64,
    peak_ratio: f64,
    gmsh_s: f64,
    gmsh_rss_mb: f64,
}

/// Runs the benchmark and prints the table.
///
/// # Errors
/// gmsh missing and not installable, mesh generation failing, the reader
/// failing on the file, or a timing program not printing its result.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let opt = parse_args(args)?;
    python::ensure_python_modules(&[("gmsh", "gmsh")])?;

    let target_dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let dir = target_dir.join("bench-meshes");
    let stem = format!("slab-q1-{}x{}", opt.nx, opt.ny);
    let files = [
        (
            "ASCII",
            dir.join(format!("{stem}-ascii.msh")),
            TARGET_ASCII_MBPS,
        ),
        (
            "binary",
            dir.join(format!("{stem}-bin.msh")),
            TARGET_BINARY_MBPS,
        ),
    ];
    if opt.regenerate || files.iter().any(|f| !f.1.is_file()) {
        println!(
            "writing the benchmark meshes ({} x {} Q1 cells, {} nodes) to {}",
            opt.nx,
            opt.ny,
            (opt.nx + 1) * (opt.ny + 1),
            dir.display()
        );
        let script = root.join("cases/meshes/generate.py");
        let gen_args = vec![
            "--bench-out".to_string(),
            dir.display().to_string(),
            "--nx".to_string(),
            opt.nx.to_string(),
            "--ny".to_string(),
            opt.ny.to_string(),
        ];
        python::run_script(root, &script, &gen_args)?;
    } else {
        println!(
            "reusing {} and {} (--regenerate to rewrite)",
            files[0].1.display(),
            files[1].1.display()
        );
    }

    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut rows = Vec::new();
    for (label, path, target_mbps) in &files {
        println!("\n== {label}: {}", path.display());
        println!(
            "-- stickslip-mesh (cargo run -p stickslip-mesh --example bench_read, dev profile)"
        );
        let out = Command::new(&cargo)
            .args([
                "run",
                "--quiet",
                "-p",
                "stickslip-mesh",
                "--example",
                "bench_read",
                "--",
            ])
            .arg(path)
            .arg(RUST_RUNS.to_string())
            .current_dir(root)
            .output()
            .map_err(|e| format!("cannot run {cargo}: {e}"))?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        print!("{stdout}");
        if !out.status.success() {
            return Err(format!(
                "bench_read failed on {} ({}):\n{}",
                path.display(),
                out.status,
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let r = parse_result(&stdout, "bench_read")?;

        println!(
            "-- Gmsh {} (gmsh.open from Python, median of {GMSH_RUNS})",
            gmsh_version()
        );
        let py = python::python();
        let out = Command::new(&py)
            .args(["-c", GMSH_TIMER])
            .arg(path)
            .arg(GMSH_RUNS.to_string())
            .current_dir(root)
            .output()
            .map_err(|e| format!("cannot run {py}: {e}"))?;
        let gstdout = String::from_utf8_lossy(&out.stdout);
        if !out.status.success() {
            return Err(format!(
                "gmsh.open failed on {} ({}):\n{}",
                path.display(),
                out.status,
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let g = parse_result(&gstdout, "the gmsh.open timer")?;
        let gmsh_s = get(&g, "median_s", "gmsh timer")?;
        println!("gmsh.open median {gmsh_s:.3} s");

        rows.push(Row {
            label,
            file_mb: get(&r, "file_bytes", "bench_read")? / 1e6,
            rust_s: get(&r, "median_s", "bench_read")?,
            rust_mbps: get(&r, "mb_per_s", "bench_read")?,
            read_s: get(&r, "read_s", "bench_read")?,
            parse_s: get(&r, "parse_s", "bench_read")?,
            target_mbps: *target_mbps,
            mesh_mb: get(&r, "mesh_bytes", "bench_read")? / 1e6,
            peak_mb: get(&r, "peak_bytes", "bench_read").unwrap_or(f64::NAN) / 1e6,
            peak_ratio: get(&r, "peak_ratio", "bench_read").unwrap_or(f64::NAN),
            gmsh_s,
            gmsh_rss_mb: get(&g, "peak_rss_bytes", "gmsh timer")? / 1e6,
        });
    }

    println!(
        "\nMesh read, {} x {} Q1 slab ({} nodes), MSH 4.1; times are medians",
        opt.nx,
        opt.ny,
        (opt.nx + 1) * (opt.ny + 1)
    );
    println!(
        "{:<7} {:>8} {:>10} {:>8} {:>13} {:>10} {:>11} {:>8} {:>9} {:>10} {:>13}",
        "format",
        "file MB",
        "ours s",
        "MB/s",
        "target MB/s",
        "gmsh s",
        "gmsh/ours",
        "Mesh MB",
        "peak MB",
        "peak/Mesh",
        "gmsh RSS MB"
    );
    let mut all_met = true;
    for r in &rows {
        let speed_ok = r.rust_mbps >= r.target_mbps;
        let mem_ok = r.peak_ratio < TARGET_PEAK_RATIO;
        all_met &= speed_ok && mem_ok;
        println!(
            "{:<7} {:>8.1} {:>10.3} {:>8.1} {:>8.0} {:<4} {:>10.3} {:>11.2} {:>8.1} {:>9.1} {:>5.2} {:<4} {:>13.0}",
            r.label,
            r.file_mb,
            r.rust_s,
            r.rust_mbps,
            r.target_mbps,
            if speed_ok { "ok" } else { "MISS" },
            r.gmsh_s,
            r.gmsh_s / r.rust_s,
            r.mesh_mb,
            r.peak_mb,
            r.peak_ratio,
            if mem_ok { "ok" } else { "MISS" },
            r.gmsh_rss_mb
        );
    }
    for r in &rows {
        println!(
            "{}: std::fs::read {:.3} s + Mesh::from_bytes {:.3} s ({:.0} MB/s on bytes in memory)",
            r.label,
            r.read_s,
            r.parse_s,
            r.file_mb / r.parse_s
        );
    }
    println!(
        "\npeak MB = growth of the resident set (VmHWM) during one Mesh::from_file, which streams regular files through a 1 MiB buffer;\n\
         target peak/Mesh < {TARGET_PEAK_RATIO}. gmsh RSS = peak resident set of the whole Python process (interpreter + libgmsh + model).\n\
         {}",
        if all_met { "All targets met." } else { "Some targets are MISSED (see MISS above)." }
    );
    Ok(())
}

fn gmsh_version() -> String {
    Command::new(python::python())
        .args(["-c", "import gmsh; print(gmsh.__version__)"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "?".into())
}
