//! The `stickslip` command's library: the HDF5 results and checkpoints
//! ([`output`]), runs ([`run`]) and checks
//! ([`check_cmd`]), the `mesh` report
//! ([`mesh_cmd`]), the `probe` reader ([`probe`]), the results file's
//! protection ([`results_file`]), the `advise` command ([`advise`]: the
//! cheapest configuration for a tolerance) and the viewers' files
//! ([`views_cmd`]); text on stdout and stderr written without panicking
//! ([`console`]). Case files are read by
//! `stickslip-case`.
//!
//! This crate owns everything that touches the results files and the
//! terminal; the numerics live in the library crates below it. It is a
//! library as well as the binary (`main.rs`, the command line) so that the
//! tests can call its parts directly.
//!
//! Exit codes (used by `main.rs`): 0 success; 2 bad input (case, mesh,
//! arguments: a `stickslip_case::InputError`); 1 a run that failed after it
//! started, or a command's text that could not be written to stdout or
//! stderr ([`console::WriteError`]; not the lines of `say!`, below); 130
//! interrupted.
//!
//! Its system calls (signals, the results file's lock, free disk space)
//! are in [`sys`], the one module allowed `unsafe`.

// Deny, not forbid: `sys` allows it for itself.
#![deny(unsafe_code)]

/// `eprintln!` that does not panic when stderr is closed: a run's
/// messages must not end it (`stickslip run ... 2>&1 | head` closes the
/// pipe while the run goes on, and a panic there lost the steps since the
/// last flush).
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

pub mod advise;
pub mod check_cmd;
pub mod console;
pub mod frames;
pub mod mesh_cmd;
mod normal_stress;
pub mod output;
mod pending;
pub mod probe;
pub mod results_file;
pub mod run;
mod start;
mod stored;
pub mod stress_cmd;
pub mod sys;
pub mod views;
pub mod views_cmd;
pub mod xdmf;
