//! The solver's proof of itself (`cargo xtask verify`) and the paper's
//! figures redrawn from our runs (`cargo xtask figures`).
//!
//! This crate owns the verification suites — closed-form problems
//! (`analytic`), measured convergence orders against the theory's
//! (`rates`), the properties Martins & Oden report for their experiments
//! (`paper`), and committed reference runs of every paper case
//! (`reference`) — the table they print, and the plots. It runs the
//! integrators in-process through the library crates (no HDF5, no CLI);
//! the paper's cases are read and built by stickslip-case, the reader and
//! builder of `stickslip run`, so the checks see what users run, and a
//! defect can be injected into what it built ([`Fault`]) to show that a
//! check catches it.

pub mod figures;
pub mod plotting;
pub mod report;
pub mod scene;
pub mod suites;

use std::path::{Path, PathBuf};

pub use report::{Report, Row};
pub use scene::{Fault, PaperCase, Trace};
use stickslip_time::Scheme;

/// Newmark ¼, ½ (average acceleration).
pub const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

/// What `verify` runs.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The CI subset.
    pub quick: bool,
    /// Rewrite the reference runs instead of comparing.
    pub bless: bool,
    /// Only this suite (analytic, rates, paper, reference).
    pub only: Option<String>,
    /// A defect to inject into the paper cases.
    pub fault: Option<Fault>,
    /// Only the cases whose name contains one of these (all when empty).
    pub cases: Vec<String>,
}

/// The suites by name, in the order they run.
pub const SUITES: [&str; 4] = ["analytic", "rates", "paper", "reference"];

/// One paper case and its run.
#[derive(Debug)]
pub struct Run {
    /// The case.
    pub case: PaperCase,
    /// Its time histories (with the error that stopped it early, if any).
    pub trace: Trace,
}

/// The directory of the paper's cases.
pub fn cases_dir(root: &Path) -> PathBuf {
    root.join("cases/martins-oden")
}

/// Runs every case of `cases/martins-oden` (those selected), with `fault`.
///
/// # Errors
/// An unreadable case directory or case file.
pub fn run_cases(root: &Path, fault: Option<Fault>, only: &[String]) -> Result<Vec<Run>, String> {
    let cases = PaperCase::read_dir(&cases_dir(root))?;
    let mut runs = Vec::new();
    for case in cases {
        if !only.is_empty() && !only.iter().any(|o| case.name.contains(o.as_str())) {
            continue;
        }
        let trace = match case.scene() {
            Ok(mut s) => {
                if let Some(f) = fault {
                    f.inject(&mut s);
                }
                scene::run(&s)
            }
            Err(e) => Trace {
                error: Some(e),
                ..Trace::default()
            },
        };
        runs.push(Run { case, trace });
    }
    Ok(runs)
}

/// Runs the selected suites, adding rows to `report`.
///
/// # Errors
/// `--only` naming no suite, or unreadable case files.
pub fn verify(root: &Path, opts: &Options, report: &mut Report) -> Result<(), String> {
    if let Some(o) = &opts.only {
        if !SUITES.contains(&o.as_str()) {
            return Err(format!(
                "--only {o:?}: the suites are {}",
                SUITES.join(", ")
            ));
        }
    }
    let wants = |s: &str| opts.only.as_deref().is_none_or(|o| o == s);
    // The paper cases first: a mistyped --case is refused before the
    // other suites run (it would otherwise pass on them).
    let runs = if opts.bless || wants("paper") || wants("reference") {
        let runs = run_cases(root, opts.fault, &opts.cases)?;
        if runs.is_empty() && (opts.bless || !opts.cases.is_empty()) {
            let bless = if opts.bless { "--bless: " } else { "" };
            return Err(format!(
                "{bless}no paper case matched --case {:?}",
                opts.cases
            ));
        }
        runs
    } else {
        Vec::new()
    };
    if opts.bless {
        suites::reference::run(root, &runs, true, report);
        return Ok(());
    }
    if wants("analytic") {
        suites::analytic::run(root, opts, report);
    }
    if wants("rates") {
        suites::rates::run(root, opts, report);
    }
    if wants("paper") || wants("reference") {
        if wants("paper") {
            suites::paper::run(&runs, report);
        }
        if wants("reference") {
            suites::reference::run(root, &runs, false, report);
        }
    }
    Ok(())
}
