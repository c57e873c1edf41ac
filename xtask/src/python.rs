//! Python for xtask commands (meshing with Gmsh, benchmarks' peer figures,
//! cross-checks with h5py / numpy / scipy / scikit-fem): which interpreter,
//! and making sure the modules a command needs import, installing the missing
//! ones with pip. Std only, like the rest of xtask.

use std::path::Path;
use std::process::{Command, Output, Stdio};

/// The Python interpreter: `$PYTHON` if set, else `python3`.
pub fn python() -> String {
    std::env::var("PYTHON")
        .ok()
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "python3".to_string())
}

/// Makes sure every module imports; pip-installs the missing ones.
///
/// `modules` pairs the import name with the pip name, e.g.
/// `("gmsh", "gmsh")`, `("skfem", "scikit-fem")`. Plain `pip install` is
/// tried first; if pip refuses because the interpreter is "externally
/// managed" (PEP 668, e.g. Debian's system Python), it is retried with
/// `--break-system-packages`.
///
/// # Errors
/// No interpreter, no pip, pip failing, or a module still not importable
/// after the install; the message says what to run by hand.
pub fn ensure_python_modules(modules: &[(&str, &str)]) -> Result<(), String> {
    let py = python();
    let mut missing = Vec::new();
    for &(import, pip_name) in modules {
        if !importable(&py, import)? {
            missing.push((import, pip_name));
        }
    }
    if missing.is_empty() {
        return Ok(());
    }
    let pip_names: Vec<&str> = missing.iter().map(|m| m.1).collect();
    let what = pip_names.join(", ");
    let line = format!("{py} -m pip install {}", pip_names.join(" "));
    eprintln!("installing {what} with pip ({line})");

    let out = pip_install(&py, &pip_names, false)?;
    if !out.status.success() {
        let text = output_text(&out);
        if text.contains("externally-managed-environment") || text.contains("externally managed") {
            eprintln!("pip refused: this Python is externally managed (PEP 668); retrying with --break-system-packages");
            let out2 = pip_install(&py, &pip_names, true)?;
            if !out2.status.success() {
                return Err(format!(
                    "`{line} --break-system-packages` failed:\n{}\ninstall {what} by hand (or in a venv and set PYTHON=/path/to/venv/bin/python)",
                    tail(&output_text(&out2), 20)
                ));
            }
        } else if text.contains("No module named pip") {
            return Err(format!(
                "{py} has no pip; install it (Debian: `apt-get install -y python3-pip`) and rerun, or install {what} by hand"
            ));
        } else {
            return Err(format!(
                "`{line}` failed:\n{}\ninstall {what} by hand and rerun",
                tail(&text, 20)
            ));
        }
    }
    for (import, pip_name) in missing {
        if !importable(&py, import)? {
            return Err(format!(
                "pip installed {pip_name}, but `{py} -c \"import {import}\"` still fails; \
                 is pip installing for another interpreter? Set PYTHON to the one that has it"
            ));
        }
    }
    eprintln!("installed {what}");
    Ok(())
}

/// Runs `python script args…` in `dir` with the terminal's stdout/stderr.
///
/// # Errors
/// The interpreter cannot be started, or the script exits non-zero.
pub fn run_script(dir: &Path, script: &Path, args: &[String]) -> Result<(), String> {
    let py = python();
    let status = Command::new(&py)
        .arg(script)
        .args(args)
        .current_dir(dir)
        .status()
        .map_err(|e| format!("cannot run {py}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{py} {}` failed ({status})", script.display()))
    }
}

fn importable(py: &str, module: &str) -> Result<bool, String> {
    let out = Command::new(py)
        .args(["-c", &format!("import {module}")])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run `{py}` ({e}); install Python 3 (Debian: `apt-get install -y python3 python3-pip`) or set PYTHON"))?;
    Ok(out.status.success())
}

fn pip_install(py: &str, names: &[&str], break_system: bool) -> Result<Output, String> {
    let mut cmd = Command::new(py);
    cmd.args(["-m", "pip", "install", "--disable-pip-version-check"]);
    if break_system {
        cmd.arg("--break-system-packages");
    }
    cmd.args(names).stdin(Stdio::null());
    cmd.output()
        .map_err(|e| format!("cannot run `{py} -m pip`: {e}"))
}

fn output_text(out: &Output) -> String {
    let mut s = String::from_utf8_lossy(&out.stdout).into_owned();
    s.push_str(&String::from_utf8_lossy(&out.stderr));
    s
}

/// The last `n` lines of `s` (pip's useful message is at the end).
fn tail(s: &str, n: usize) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}
