//! The peers `cargo xtask bench run` times against `stickslip run`: whole
//! Python processes that read the same case file and mesh, run the same
//! scheme for the same steps and write their results (bench/README.md).
//!
//! * `scipy`: bench/scipy_run.py (scikit-fem, numpy, scipy), on this
//!   machine's Python (`$PYTHON`), its modules pip-installed when missing.
//! * `fenicsx`: bench/fenicsx_run.py (DOLFINx 0.11), in a venv of its own,
//!   target/bench/fenicsx, which the bench makes when it is missing: the
//!   `dolfinx-solver-real` wheel needs Python ≥ 3.12, looked for as
//!   `$FENICSX_PYTHON`, `python3.12`, `python3.13`, `python3` and pyenv's
//!   versions.
//!
//! Before a peer is timed on a run, its results must agree with
//! stickslip's (bench/peer_check.py: displacements at every common record
//! to 1e-8 of the largest).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The largest rung (in DOFs) either peer runs: scipy's `splu` and
/// DOLFINx's assembly from 500k DOFs take minutes and gigabytes, which a
/// shared machine does not give.
const PEER_MAX_DOFS: u64 = 260_000;

/// The pip packages of the FEniCSx venv.
const FENICSX_PACKAGES: [&str; 3] = ["dolfinx-solver-real", "meshio", "h5py"];

/// One peer: its name in the table and the CSV, the interpreter and the
/// script that make a run.
pub(crate) struct Peer {
    pub name: &'static str,
    python: PathBuf,
    script: &'static str,
    /// Runs on structured meshes only (rectangular cells).
    structured_only: bool,
}

impl Peer {
    /// Whether the peer runs a rung of `dofs` DOFs (`structured`: all cells
    /// rectangles).
    pub fn fits(&self, dofs: u64, structured: bool) -> bool {
        dofs <= PEER_MAX_DOFS && (structured || !self.structured_only)
    }

    /// The peer's run of `case` with `sets`, writing `out`, as a command to
    /// time (run in `root`).
    pub fn command(&self, root: &Path, out: &Path, case: &str, sets: &[String]) -> Command {
        let mut cmd = Command::new(&self.python);
        cmd.current_dir(root)
            .arg(root.join(self.script))
            .args(["--quiet", "--force", "-o"])
            .arg(out)
            .arg(case)
            .stdin(Stdio::null());
        for kv in sets {
            cmd.arg("--set").arg(kv);
        }
        cmd
    }
}

/// The peers named in `names` (`scipy`, `fenicsx`), installed. A peer that
/// cannot be installed is left out, saying why (the others' figures still
/// stand), unless it is the only one asked for.
///
/// # Errors
/// An unknown name, or the only peer asked for cannot be installed.
pub(crate) fn peers(root: &Path, names: &[String]) -> Result<Vec<Peer>, String> {
    if !names.is_empty() {
        // bench/peer_check.py, on this machine's Python.
        crate::python::ensure_python_modules(&[
            ("numpy", "numpy"),
            ("scipy", "scipy"),
            ("h5py", "h5py"),
        ])?;
    }
    let mut peers = Vec::new();
    for name in names {
        let peer = match name.as_str() {
            "scipy" => scipy(),
            "fenicsx" => fenicsx(root),
            other => return Err(format!("--peers {other}: the peers are scipy and fenicsx")),
        };
        match peer {
            Ok(p) => peers.push(p),
            Err(e) if names.len() > 1 => eprintln!("bench run: the {name} peer is left out: {e}"),
            Err(e) => return Err(format!("the {name} peer: {e}")),
        }
    }
    Ok(peers)
}

fn scipy() -> Result<Peer, String> {
    crate::python::ensure_python_modules(&[
        ("numpy", "numpy"),
        ("scipy", "scipy"),
        ("skfem", "scikit-fem"),
        ("meshio", "meshio"),
        ("h5py", "h5py"),
    ])?;
    Ok(Peer {
        name: "scipy",
        python: PathBuf::from(crate::python::python()),
        script: "bench/scipy_run.py",
        structured_only: false,
    })
}

/// The FEniCSx venv's Python, the venv made and DOLFINx installed into it
/// when it does not import (saying so).
fn fenicsx(root: &Path) -> Result<Peer, String> {
    let venv = root.join("target/bench/fenicsx");
    let python = venv.join("bin/python");
    let imports = |py: &Path| {
        Command::new(py)
            .args(["-c", "import dolfinx_solver, dolfinx, meshio, h5py"])
            .stdin(Stdio::null())
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !imports(&python) {
        let base = python_312()?;
        eprintln!(
            "bench run: installing DOLFINx 0.11 for the FEniCSx peer into {} ({}; about 400 MB)",
            venv.display(),
            base.display()
        );
        let _ = std::fs::remove_dir_all(&venv);
        checked(
            Command::new(&base).arg("-m").arg("venv").arg(&venv),
            "making the venv",
        )?;
        checked(
            Command::new(&python)
                .args(["-m", "pip", "install", "--disable-pip-version-check", "-q"])
                .args(FENICSX_PACKAGES),
            "pip install dolfinx-solver-real meshio h5py",
        )?;
        if !imports(&python) {
            return Err(format!(
                "installed, but `{} -c \"import dolfinx_solver, dolfinx\"` still fails",
                python.display()
            ));
        }
        eprintln!("bench run: DOLFINx installed");
    }
    Ok(Peer {
        name: "fenicsx",
        python,
        script: "bench/fenicsx_run.py",
        structured_only: true,
    })
}

/// Runs `cmd` to its end; its output's tail in the error.
fn checked(cmd: &mut Command, what: &str) -> Result<(), String> {
    let o = cmd
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("{what}: cannot start: {e}"))?;
    if o.status.success() {
        return Ok(());
    }
    let text = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = text.lines().collect();
    Err(format!(
        "{what} failed ({}):\n{}",
        o.status,
        lines[lines.len().saturating_sub(15)..].join("\n")
    ))
}

/// A Python of version 3.12 or later, for the `dolfinx-solver-real` wheel.
fn python_312() -> Result<PathBuf, String> {
    let mut candidates: Vec<PathBuf> = std::env::var_os("FENICSX_PYTHON")
        .map(PathBuf::from)
        .into_iter()
        .chain(["python3.12", "python3.13", "python3"].map(PathBuf::from))
        .collect();
    // pyenv's shims refuse a version not selected; its versions do not.
    if let Some(home) = std::env::var_os("PYENV_ROOT")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".pyenv")))
    {
        if let Ok(dir) = std::fs::read_dir(home.join("versions")) {
            let mut found: Vec<PathBuf> = dir
                .flatten()
                .map(|e| e.path().join("bin/python3"))
                .filter(|p| p.is_file())
                .collect();
            found.sort();
            candidates.extend(found);
        }
    }
    let script = "import sys; sys.exit(0 if sys.version_info >= (3, 12) else 1)";
    candidates
        .into_iter()
        .find(|py| {
            Command::new(py)
                .args(["-c", script])
                .stdin(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        })
        .ok_or_else(|| {
            "no Python 3.12 or later (the dolfinx-solver-real wheel needs one): install it, \
             or set FENICSX_PYTHON to one"
                .to_string()
        })
}

/// How far the peer's results file `theirs` is from stickslip's `ours`
/// (bench/peer_check.py's max |Δu| / max |u|).
///
/// # Errors
/// They differ by more than 1e-8, or cannot be compared: the message says
/// which and by how much.
pub(crate) fn check(root: &Path, ours: &Path, theirs: &Path) -> Result<f64, String> {
    let o = Command::new(crate::python::python())
        .current_dir(root)
        .arg("bench/peer_check.py")
        .arg(ours)
        .arg(theirs)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot start python: {e}"))?;
    let text = String::from_utf8_lossy(&o.stdout);
    let rel = text
        .lines()
        .find_map(|l| l.strip_prefix("PEERCHECK records="))
        .and_then(|l| l.split("max_rel=").nth(1))
        .and_then(|v| v.trim().parse::<f64>().ok());
    match rel {
        Some(rel) if o.status.success() => Ok(rel),
        _ => Err(format!(
            "{}{}",
            text.trim(),
            String::from_utf8_lossy(&o.stderr).trim()
        )),
    }
}

/// A peer as the bench would find it installed, for tests of which runs it
/// makes (`fenicsx`: structured meshes only).
#[cfg(test)]
pub(crate) fn installed(name: &'static str) -> Peer {
    Peer {
        name,
        python: PathBuf::from("python3"),
        script: "",
        structured_only: name == "fenicsx",
    }
}
