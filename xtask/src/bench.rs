//! What the bench commands share: their arguments, the release binary and
//! its scratch directory, and timed `stickslip run`s.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

/// Reads a bench command's arguments: `flag` is given each one, with the
/// iterator over the rest for its value, and says whether it knows it.
/// `-h` or `--help` prints `cargo xtask {command} {usage}` and ends xtask
/// (a help asks for nothing more). An unknown argument is an error that
/// names the command.
pub fn args(
    command: &str,
    usage: &str,
    args: &[String],
    mut flag: impl FnMut(&str, &mut std::slice::Iter<String>) -> Result<bool, String>,
) -> Result<(), String> {
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "-h" || a == "--help" {
            println!("cargo xtask {command} {usage}");
            std::process::exit(0);
        }
        if !flag(a, &mut it)? {
            return Err(format!(
                "cargo xtask {command}: unknown argument {a:?}; try --help"
            ));
        }
    }
    Ok(())
}

/// The integer after the flag `flag` of a bench command: "{flag} needs
/// {what}" when it is missing, "{flag} {v}: not an integer" when it is not
/// one.
pub fn integer_arg<T: std::str::FromStr>(
    flag: &str,
    what: &str,
    it: &mut std::slice::Iter<String>,
) -> Result<T, String> {
    let v = it.next().ok_or_else(|| format!("{flag} needs {what}"))?;
    v.parse().map_err(|_| format!("{flag} {v}: not an integer"))
}

/// The release `stickslip` (HDF5 installed and the binary built first, if
/// need be) and a bench's scratch directory target/bench/NAME.
pub(crate) fn release_stickslip(root: &Path, name: &str) -> Result<(PathBuf, PathBuf), String> {
    crate::setup(false)?;
    crate::run(crate::cargo().current_dir(root).args([
        "build",
        "--release",
        "-q",
        "-p",
        "stickslip",
    ]))?;
    let dir = root.join("target/bench").join(name);
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    Ok((root.join("target/release/stickslip"), dir))
}

/// `cmd` (a stickslip binary, with any environment of its own) as
/// `run FLAGS -o OUT CASE --set KV...` in `root`, timed: its output and
/// wall seconds; an error only when it does not start.
pub(crate) fn timed_run<S: AsRef<OsStr>>(
    mut cmd: Command,
    root: &Path,
    flags: &[&str],
    out: &Path,
    case: &str,
    sets: &[S],
) -> Result<(Output, f64), String> {
    cmd.current_dir(root)
        .arg("run")
        .args(flags)
        .arg("-o")
        .arg(out)
        .arg(case);
    for kv in sets {
        cmd.arg("--set").arg(kv);
    }
    timed(cmd)
}

/// `cmd` run to its end, timed: its output and wall seconds; an error only
/// when it does not start.
pub(crate) fn timed(mut cmd: Command) -> Result<(Output, f64), String> {
    let t = Instant::now();
    let o = cmd.output().map_err(|e| {
        format!(
            "cannot start {}: {e}",
            Path::new(cmd.get_program()).display()
        )
    })?;
    Ok((o, t.elapsed().as_secs_f64()))
}
