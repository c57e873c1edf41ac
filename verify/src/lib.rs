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
    Ok(run_selected(select_cases(root, only)?, fault))
}

/// The cases of `cases/martins-oden` whose names contain one of `only`
/// (all when empty), read but not run.
///
/// # Errors
/// An unreadable case directory or case file.
fn select_cases(root: &Path, only: &[String]) -> Result<Vec<PaperCase>, String> {
    let mut cases = PaperCase::read_dir(&cases_dir(root))?;
    cases.retain(|case| only.is_empty() || only.iter().any(|o| case.name.contains(o.as_str())));
    Ok(cases)
}

/// Runs `cases`, with `fault`.
fn run_selected(cases: Vec<PaperCase>, fault: Option<Fault>) -> Vec<Run> {
    cases
        .into_iter()
        .map(|case| {
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
            Run { case, trace }
        })
        .collect()
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
    let reads_cases = opts.bless || wants("paper") || wants("reference");
    if !opts.cases.is_empty() && !reads_cases {
        return Err(format!(
            "--case selects paper cases, which --only {} does not run; drop --case, or choose \
             --only paper or --only reference",
            opts.only.as_deref().unwrap_or_default()
        ));
    }
    // The cases are chosen first and run where a suite reads them: a
    // mistyped --case is refused before any suite runs (it would
    // otherwise pass on the others, or bless nothing).
    let cases = if reads_cases {
        select_cases(root, &opts.cases)?
    } else {
        Vec::new()
    };
    if reads_cases && cases.is_empty() && (opts.bless || !opts.cases.is_empty()) {
        let bless = if opts.bless { "--bless: " } else { "" };
        return Err(format!(
            "{bless}no paper case matched --case {:?}",
            opts.cases
        ));
    }
    if opts.bless {
        let runs = run_selected(cases, opts.fault);
        suites::reference::run(root, &runs, true, report);
        return Ok(());
    }
    if wants("analytic") {
        suites::analytic::run(root, opts, report);
    }
    if wants("rates") {
        suites::rates::run(root, opts, report);
    }
    if reads_cases {
        let runs = run_selected(cases, opts.fault);
        if wants("paper") {
            suites::paper::run(&runs, report);
        }
        if wants("reference") {
            suites::reference::run(root, &runs, false, report);
        }
    }
    Ok(())
}
