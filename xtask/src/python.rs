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
/// `--break-system-packages`. A module whose import fails for a missing
/// shared library gets the Debian package that provides it
/// ([`libraries_repaired`]).
///
/// # Errors
/// No interpreter, no pip, pip failing, or a module still not importable
/// after the install; the message says what to run by hand.
pub fn ensure_python_modules(modules: &[(&str, &str)]) -> Result<(), String> {
    let py = python();
    let mut apt = crate::apt::Apt::default();
    let mut missing = Vec::new();
    for &(import, pip_name) in modules {
        // Installed but failing for a shared library (a slim image without
        // X and GL): install the library, not the module again.
        if !importable(&py, import)? && !libraries_repaired(&py, import, &mut apt)? {
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
        if !importable(&py, import)? && !libraries_repaired(&py, import, &mut apt)? {
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
    Ok(import_error(py, module)?.is_none())
}

/// What `import module` prints when it fails, or `None` when it imports.
fn import_error(py: &str, module: &str) -> Result<Option<String>, String> {
    let out = Command::new(py)
        .args(["-c", &format!("import {module}")])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run `{py}` ({e}); install Python 3 (Debian: `apt-get install -y python3 python3-pip`) or set PYTHON"))?;
    Ok((!out.status.success()).then(|| output_text(&out)))
}

/// Debian's packages of the shared libraries that PyPI's wheels of Gmsh
/// (and VTK, under PyVista) load and slim images lack: (file name up to
/// ".so", package).
const LIBRARY_PACKAGES: [(&str, &str); 18] = [
    ("libGLU", "libglu1-mesa"),
    ("libGL", "libgl1"),
    ("libEGL", "libegl1"),
    ("libOSMesa", "libosmesa6"),
    ("libXcursor", "libxcursor1"),
    ("libXft", "libxft2"),
    ("libXinerama", "libxinerama1"),
    ("libXrender", "libxrender1"),
    ("libXext", "libxext6"),
    ("libXfixes", "libxfixes3"),
    ("libXi", "libxi6"),
    ("libXrandr", "libxrandr2"),
    ("libX11", "libx11-6"),
    ("libSM", "libsm6"),
    ("libICE", "libice6"),
    ("libfontconfig", "libfontconfig1"),
    ("libfreetype", "libfreetype6"),
    ("libgomp", "libgomp1"),
];

/// The libraries Gmsh's wheel loads besides the one its import names
/// first: installed together, so that one round of apt-get does.
const GMSH_LIBRARIES: [&str; 4] = ["libglu1-mesa", "libxcursor1", "libxft2", "libxinerama1"];

/// The shared library a failed import names: "libGLU.so.1" in
/// "OSError: libGLU.so.1: cannot open shared object file: No such file or
/// directory".
fn missing_library(error: &str) -> Option<&str> {
    let head = &error[..error.find(": cannot open shared object file")?];
    let start = head
        .rfind(|c: char| c.is_whitespace() || c == ':' || c == '\'' || c == '"')
        .map_or(0, |i| i + 1);
    Some(&head[start..]).filter(|lib| lib.contains(".so"))
}

/// The Debian package of `lib` ("libGLU.so.1" → "libglu1-mesa").
fn library_package(lib: &str) -> Option<&'static str> {
    let stem = &lib[..lib.find(".so")?];
    LIBRARY_PACKAGES
        .iter()
        .find(|(name, _)| *name == stem)
        .map(|(_, package)| *package)
}

/// While `import module` fails for a missing shared library, installs the
/// Debian package that provides it, saying so; whether the module imports
/// at the end (false: it fails for another reason).
///
/// # Errors
/// A library no known package provides, one still missing after its
/// package was installed, or apt-get failing: the message names the
/// library and what to install.
fn libraries_repaired(py: &str, module: &str, apt: &mut crate::apt::Apt) -> Result<bool, String> {
    let mut installed: Vec<&str> = Vec::new();
    while let Some(error) = import_error(py, module)? {
        let Some(lib) = missing_library(&error) else {
            return Ok(false);
        };
        let package = library_package(lib).ok_or_else(|| {
            format!(
                "`{py} -c \"import {module}\"` fails: the shared library {lib} is missing and the set-up \
                 knows no Debian package for it; install the package that provides it \
                 (`apt-file search {lib}`) and rerun"
            )
        })?;
        if installed.contains(&package) {
            return Err(format!(
                "installed Debian's {package}, but `import {module}` still misses {lib}; \
                 install the package that provides it (`apt-file search {lib}`) and rerun"
            ));
        }
        let mut packages = vec![package];
        if module == "gmsh" {
            packages.extend(GMSH_LIBRARIES.iter().filter(|p| **p != package));
        }
        eprintln!(
            "setup: `import {module}` fails: {lib} is missing (a slim image without X or GL); \
             installing Debian's {}",
            packages.join(", ")
        );
        apt.install(&packages)?;
        installed.extend(packages);
    }
    eprintln!("setup: `import {module}` works now");
    Ok(true)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_library_is_named_and_found_a_package() {
        // The form of `import gmsh`'s failure where libGLU is missing.
        let error = "Traceback (most recent call last):\n  File \"<string>\", line 1, in <module>\n  \
                     File \"/usr/lib/python3/site-packages/gmsh.py\", line 86, in <module>\n    \
                     lib = CDLL(libpath)\nOSError: libGLU.so.1: cannot open shared object file: No such file or directory\n";
        assert_eq!(missing_library(error), Some("libGLU.so.1"));
        assert_eq!(library_package("libGLU.so.1"), Some("libglu1-mesa"));
        assert_eq!(
            missing_library("ImportError: libXcursor.so.1: cannot open shared object file"),
            Some("libXcursor.so.1")
        );
        assert_eq!(library_package("libXcursor.so.1"), Some("libxcursor1"));
        assert_eq!(library_package("libXft.so.2"), Some("libxft2"));
        assert_eq!(library_package("libXinerama.so.1"), Some("libxinerama1"));
        // libGL is not libGLU's prefix match.
        assert_eq!(library_package("libGL.so.1"), Some("libgl1"));
        assert_eq!(library_package("libunknown.so.3"), None);
        assert_eq!(
            missing_library("ModuleNotFoundError: No module named 'gmsh'"),
            None
        );
    }
}
