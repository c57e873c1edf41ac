//! `cargo xtask`: the project's own commands (rust-analyzer's convention).
//!
//! This crate has no dependencies on purpose: it must build on a fresh
//! machine without HDF5 so that it can install HDF5 before anything that
//! links it is compiled (the set-up promise: README.md, "The two commands").

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

mod apt;
mod bench;
mod bench_advise;
mod bench_fem;
mod bench_mesh;
mod bench_output;
mod bench_peers;
mod bench_run;
mod bench_step;
mod bench_targets;
mod meshes;
mod python;
mod study;
mod verify;

const USAGE: &str = "\
usage: cargo xtask <command> [args]

  demo              install what is missing (HDF5), build, and run the paper's
                    slab (central difference, eps = 1e-4) into target/demo/slab.h5;
                    more arguments go to `stickslip run` (-o OUT.h5, --set K=V)
  test              install what is missing (HDF5, Python modules, ParaView), then run
                    the whole test suite (what .ci/run and CI run)
  setup             only install what is missing: libhdf5-dev, and h5py, numpy,
                    gmsh, matplotlib, meshio, pyvista, scipy, scikit-fem and
                    Debian's paraview for the tests (and the X/GL libraries
                    gmsh's wheel loads)
  verify            the proof of correctness: closed forms, convergence rates,
                    the paper's experiments, committed reference runs
                    [--quick] [--bless] [--only SUITE]
  figures           redraw the paper's figures from our runs into docs/figures
                    [--out DIR]
  chart             work-precision study on the slab: error against wall time
                    for each order, mesh, scheme and step into docs/ [--quick]
  stability         where methods fail: central difference around its critical
                    step, ringing after sticking, the iteration without
                    Remark 4.2, into docs/ [--quick]
  meshes            regenerate cases/meshes/*.msh with Gmsh (installs gmsh from PyPI)
  bench mesh        .msh read throughput on a 1M-node mesh against gmsh.open
  bench step        time per step of both schemes on the slab ladders, against
                    the STREAM bandwidth and one forward+back solve
  bench fem         assembly and Cholesky on the Q2 slab ladder against
                    scikit-fem and scipy's splu (--refine 8,16,32,64 --no-peer)
  bench run         whole `stickslip run` processes on the slab ladder, both
                    schemes, against a numpy/scipy and a FEniCSx peer
                    [--rounds N] [--max-dofs N] [--against EXE] [--peers LIST]
  bench output      wall time of whole runs (paper slab, a 4k-node slab) with
                    their results written uncompressed, deflated, or not at all
  bench advise      wall time of advise's pick against the cheapest configuration of
                    the chart meeting the same tolerance [--rounds N] [--tol T]...
";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = project_root();
    let (cmd, rest) = match args.split_first() {
        Some((c, r)) => (c.as_str(), r),
        None => {
            eprint!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    let result = match cmd {
        "demo" => demo(&root, rest),
        "test" | "ci" => test(&root, rest),
        "setup" if !rest.is_empty() => Err(format!(
            "setup takes no arguments (got {})\n{USAGE}",
            rest.join(" ")
        )),
        "setup" => setup(true),
        "meshes" => meshes::run(&root, rest),
        "verify" => verify::verify(&root, rest),
        "figures" => verify::figures(&root, rest),
        "chart" => study::chart(&root, rest),
        "stability" => study::stability(&root, rest),
        "bench" => match rest.split_first() {
            Some((what, more)) if what == "mesh" => bench_mesh::run(&root, more),
            Some((what, more)) if what == "fem" => bench_fem::run(&root, more),
            Some((what, more)) if what == "step" => bench_step::run(&root, more),
            Some((what, more)) if what == "output" => bench_output::run(&root, more),
            Some((what, more)) if what == "run" => bench_run::run(&root, more),
            Some((what, more)) if what == "advise" => bench_advise::run(&root, more),
            _ => Err(format!(
                "cargo xtask bench: say what to benchmark (mesh, fem, step, output, run, advise)\n{USAGE}"
            )),
        },
        "help" | "--help" | "-h" => {
            print!("{USAGE}");
            Ok(())
        }
        other => {
            eprintln!("xtask: unknown command {other:?}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The workspace root: xtask/ sits directly inside it.
fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask/ has a parent")
        .to_path_buf()
}

/// `cargo run -p PACKAGE -- SUB ARGS` (dev profile) in `root`: a binary of
/// the workspace that runs the integrators in-process, without HDF5.
pub(crate) fn cargo_run(
    root: &Path,
    package: &str,
    sub: &str,
    args: &[String],
) -> Result<(), String> {
    let status = cargo()
        .current_dir(root)
        .args(["run", "--quiet", "-p", package, "--"])
        .arg(sub)
        .args(args)
        .status();
    match status {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(format!("{package} {sub} failed ({s})")),
        Err(e) => Err(format!("cannot start cargo run -p {package}: {e}")),
    }
}

/// Runs a command, echoing it, and fails with its exit status.
pub fn run(cmd: &mut Command) -> Result<(), String> {
    eprintln!("$ {}", describe(cmd));
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start {}: {e}", describe(cmd)))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{} failed ({status})", describe(cmd)))
    }
}

fn describe(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

pub(crate) fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// HDF5's C library and headers, found the way hdf5-metno-sys finds them
/// (pkg-config), or Debian's serial header path.
fn hdf5_present() -> bool {
    let pkg = Command::new("pkg-config")
        .args(["--exists", "hdf5"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    pkg || Path::new("/usr/include/hdf5/serial/hdf5.h").exists()
}

/// Installs libhdf5-dev when missing, and for the tests (`for_tests`)
/// the Python modules and ParaView's pvpython they read results with,
/// saying so.
pub(crate) fn setup(for_tests: bool) -> Result<(), String> {
    let mut apt = apt::Apt::default();
    if hdf5_present() {
        eprintln!("setup: HDF5 development files found");
    } else {
        eprintln!(
            "setup: HDF5 is missing; installing Debian's libhdf5-dev and hdf5-tools (about 20 s)"
        );
        apt.install(&["libhdf5-dev", "hdf5-tools", "pkg-config"])?;
        if !hdf5_present() {
            return Err(
                "libhdf5-dev was installed but HDF5 is still not found by pkg-config".into(),
            );
        }
    }
    if for_tests {
        // What the end-to-end tests and examples read results and make
        // meshes and pictures with, as users do; scipy and scikit-fem for
        // the independent numpy/scipy peer (bench/scipy_run.py) that
        // crates/cli/tests/peer_agreement.rs checks the paper's cases with.
        python::ensure_python_modules(&[
            ("h5py", "h5py"),
            ("numpy", "numpy"),
            ("gmsh", "gmsh"),
            ("matplotlib", "matplotlib"),
            ("meshio", "meshio"),
            ("pyvista", "pyvista"),
            ("scipy", "scipy"),
            ("skfem", "scikit-fem"),
        ])?;
        // The XDMF tests open the results in ParaView, as users do; under
        // CI they fail without it.
        if pvpython_present() {
            eprintln!("setup: ParaView's pvpython found");
        } else {
            eprintln!(
                "setup: pvpython is missing; installing Debian's paraview for the XDMF test \
                 (about 250 MB to download, 1.4 GB on disk; a few minutes)"
            );
            apt.install(&["paraview"])?;
            if !pvpython_present() {
                return Err("paraview was installed but `pvpython --version` still fails".into());
            }
        }
    }
    Ok(())
}

fn pvpython_present() -> bool {
    Command::new("pvpython")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The main job: the paper's slab under a step load, central difference.
fn demo(root: &Path, rest: &[String]) -> Result<(), String> {
    if rest.iter().any(|a| a == "-h" || a == "--help") {
        print!("{USAGE}");
        return Ok(());
    }
    setup(false)?;
    let case = root.join("cases/martins-oden/cd-step-eps1e-4.toml");
    // `-o OUT.h5` (or --output) among the arguments replaces the default.
    let given = rest
        .iter()
        .position(|a| a == "-o" || a == "--output")
        .and_then(|i| rest.get(i + 1))
        .map(|o| root.join(o));
    // Into the target directory cargo builds in (CARGO_TARGET_DIR moves it).
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(|d| root.join(d))
        .unwrap_or_else(|| root.join("target"));
    let out = given.clone().unwrap_or_else(|| target.join("demo/slab.h5"));
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let mut cmd = cargo();
    cmd.current_dir(root)
        .args(["run", "--quiet", "-p", "stickslip", "--", "run"]);
    cmd.arg(&case);
    if given.is_none() {
        cmd.arg("-o").arg(&out).arg("--force");
    }
    cmd.args(rest);
    run(&mut cmd)?;
    eprintln!("demo: results in {}", out.display());
    eprintln!(
        "demo: read them with `python3 examples/slab_node81.py {}` (h5py)",
        out.display()
    );
    Ok(())
}

/// The whole test suite: every crate's tests in the (optimized) dev
/// profile, built once. Ends with one plain line `tests: N passed, M failed,
/// K skipped` summed over every test binary, so the total is not lost among
/// the per-binary lines (the last of which is often an empty doc-test run).
fn test(root: &Path, rest: &[String]) -> Result<(), String> {
    setup(true)?;
    let mut cmd = cargo();
    cmd.current_dir(root)
        .args(["test", "--workspace"])
        .args(rest);
    let totals = run_counting(&mut cmd)?;
    println!(
        "tests: {} passed, {} failed, {} skipped",
        totals.passed, totals.failed, totals.ignored
    );
    if totals.failed > 0 {
        return Err(format!("{} test(s) failed", totals.failed));
    }
    if !totals.ok {
        return Err("cargo test failed (see its messages above)".into());
    }
    if totals.passed == 0 {
        return Err("no test ran".into());
    }
    // The quick verification table (closed forms, rates, the paper, the
    // references): the README's promise of what the test command checks.
    println!("$ cargo xtask verify --quick");
    verify::verify(root, &["--quick".to_string()]).map_err(|e| format!("verify --quick: {e}"))?;
    Ok(())
}

#[derive(Default)]
struct Totals {
    passed: u64,
    failed: u64,
    ignored: u64,
    ok: bool,
}

/// Runs a test command, echoing its output, and sums its `test result:` lines.
fn run_counting(cmd: &mut Command) -> Result<Totals, String> {
    use std::io::{BufRead, BufReader};
    eprintln!("$ {}", describe(cmd));
    let mut child = cmd
        .stdout(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start {}: {e}", describe(cmd)))?;
    let mut totals = Totals::default();
    let stdout = child.stdout.take().expect("piped stdout");
    for line in BufReader::new(stdout).lines() {
        let line = line.map_err(|e| e.to_string())?;
        println!("{line}");
        if let Some(rest) = line.strip_prefix("test result: ") {
            // "ok. 3 passed; 0 failed; 1 ignored; 0 measured; ..."
            for part in rest.split(['.', ';']) {
                let mut words = part.split_whitespace();
                if let (Some(n), Some(what)) = (words.next(), words.next()) {
                    if let Ok(n) = n.parse::<u64>() {
                        match what {
                            "passed" => totals.passed += n,
                            "failed" => totals.failed += n,
                            "ignored" => totals.ignored += n,
                            _ => {}
                        }
                    }
                }
            }
        }
    }
    let status = child.wait().map_err(|e| e.to_string())?;
    totals.ok = status.success();
    Ok(totals)
}
