//! The verify tool catches a broken build: each defect it must catch is
//! injected through the library API into the paper cases, and a failing row
//! must name the cause. The clean build must pass the same suites (against the
//! committed references in cases/reference/).

use stickslip_testkit::workspace_root as root;
use stickslip_verify::suites::{paper, reference};
use stickslip_verify::{run_cases, Fault, Report, Row};

fn failures(fault: Option<Fault>) -> Vec<Row> {
    let runs = run_cases(&root(), fault, &[]).expect("the case files read");
    assert_eq!(runs.len(), 8, "cases/martins-oden has the paper's 8 cases");
    let mut r = Report::new(false);
    paper::run(&runs, &mut r);
    reference::run(&root(), &runs, false, &mut r);
    r.rows.into_iter().filter(|x| !x.pass).collect()
}

fn show(rows: &[Row]) -> String {
    rows.iter()
        .map(stickslip_verify::report::format_row)
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_clean_build_passes_paper_and_reference() {
    let f = failures(None);
    assert!(f.is_empty(), "failing rows:\n{}", show(&f));
}

#[test]
fn a_flipped_friction_sign_fails_the_dissipation_check() {
    // Friction pushing along the slip feeds energy in: the dissipation
    // ledger must fall somewhere (METHOD.md §6).
    let f = failures(Some(Fault::FrictionSign));
    assert!(
        f.iter().any(|r| r.suite == "paper"
            && r.case == "cd-step-eps1e-4"
            && r.quantity == "largest decrease of dissipation"),
        "no dissipation row failed:\n{}",
        show(&f)
    );
}

#[test]
fn dropping_remark_4_2_fails_the_newmark_runs_with_the_cure_named() {
    // Paper Remark 4.2: without it the iteration cycles on unloading. The
    // explicit runs solve each node in closed form and do not iterate.
    let f = failures(Some(Fault::NoRemark42));
    for case in [
        "newmark-step",
        "newmark-step-reduced",
        "newmark-damped-step",
    ] {
        assert!(
            f.iter().any(|r| r.case == case
                && r.quantity == "run completes"
                && r.measured.contains("did not converge")
                && r.measured.contains("Remark 4.2")),
            "{case}: no failing run row naming Remark 4.2:\n{}",
            show(&f)
        );
    }
}

#[test]
fn the_wrong_mass_fails_the_mass_row_and_the_references() {
    let f = failures(Some(Fault::WrongMass));
    for case in [
        "newmark-step",
        "newmark-step-reduced",
        "newmark-damped-step",
    ] {
        assert!(
            f.iter()
                .any(|r| r.case == case && r.quantity == "mass matrix the integrator uses"),
            "{case}: no failing mass row:\n{}",
            show(&f)
        );
    }
    // Central difference with a non-HRZ diagonal mass: the displacement of
    // node 81 leaves its committed reference.
    assert!(
        f.iter().any(|r| r.suite == "reference"
            && r.case == "cd-step-eps1e-4"
            && r.quantity.starts_with("ux81")),
        "no failing reference row for u_x(81):\n{}",
        show(&f)
    );
}

/// A mistyped --case is refused before any suite runs (the analytic and
/// rate suites would otherwise pass, and the run prove nothing), with
/// --bless too (which would rewrite nothing).
#[test]
fn a_case_that_matches_nothing_is_refused_before_the_suites_run() {
    for bless in [false, true] {
        let opts = stickslip_verify::Options {
            quick: true,
            bless,
            only: None,
            fault: None,
            cases: vec!["no-such-case".into()],
        };
        let mut report = Report::new(false);
        let e = stickslip_verify::verify(&root(), &opts, &mut report).unwrap_err();
        assert!(e.contains("no paper case matched"), "{e}");
        assert!(report.rows.is_empty(), "{} rows ran", report.rows.len());
    }
    // --case with a suite that reads no paper case would be ignored.
    let opts = stickslip_verify::Options {
        quick: true,
        only: Some("analytic".into()),
        cases: vec!["cd-step".into()],
        ..Default::default()
    };
    let mut report = Report::new(false);
    let e = stickslip_verify::verify(&root(), &opts, &mut report).unwrap_err();
    assert!(e.contains("--only analytic does not run"), "{e}");
    assert!(report.rows.is_empty(), "{} rows ran", report.rows.len());
}
