//! The whole-run targets `cargo xtask bench run` checks its medians
//! against, each with a verdict, so that a bench says which still stand
//! open (docs/performance.md keeps what was tried against them).
//!
//! The targets: on the paper's mesh ≥ 40× FEniCSx and ≥ 20× the scipy
//! peer, both schemes; on Q2 64×16 ≥ 20× FEniCSx with central difference
//! and ≥ 60× with Newmark; explicit runs from 500k DOFs spend at most a
//! quarter of the run in the setup; the 1M-DOF unstructured explicit run
//! takes under 15 s. A target whose figure the bench did not measure (a
//! rung or a peer left out) is not printed.

/// One run of the bench as the targets read it.
#[derive(Debug)]
pub struct Measured<'a> {
    /// The rung's name ("q2-64x16", "paper q2-8x2", ...).
    pub rung: &'a str,
    /// "cd" or "newmark".
    pub scheme: &'a str,
    pub dofs: u64,
    /// Our median whole run and its setup's median, s.
    pub median: f64,
    pub setup: f64,
    /// Each peer that ran it: (name, its median / ours).
    pub ratios: Vec<(&'a str, f64)>,
}

/// A figure against its bound.
enum Bound {
    AtLeast(f64),
    AtMost(f64),
    Under(f64),
}

/// The verdict lines for the targets `runs` measure, in the order of
/// `runs`.
pub fn verdicts(runs: &[Measured]) -> Vec<String> {
    let mut lines = Vec::new();
    let mut check = |run: &Measured, what: String, value: f64, bound: Bound| {
        let (met, text) = match bound {
            Bound::AtLeast(b) => (value >= b, format!("≥ {b}")),
            Bound::AtMost(b) => (value <= b, format!("≤ {b}")),
            Bound::Under(b) => (value < b, format!("< {b}")),
        };
        let verdict = if met { "met" } else { "NOT met" };
        lines.push(format!(
            "{} {}: {what} {value:.3} (target {text}): {verdict}",
            run.rung, run.scheme
        ));
    };
    for run in runs {
        let ratio = |peer: &str| run.ratios.iter().find(|(p, _)| *p == peer).map(|r| r.1);
        let mut peer_target = |peer: &str, label: &str, at_least: f64| {
            if let Some(r) = ratio(peer) {
                check(run, format!("{label} / ours"), r, Bound::AtLeast(at_least));
            }
        };
        if run.rung.starts_with("paper") {
            peer_target("fenicsx", "FEniCSx", 40.0);
            peer_target("scipy", "scipy", 20.0);
        }
        match (run.rung, run.scheme) {
            ("q2-64x16", "cd") => peer_target("fenicsx", "FEniCSx", 20.0),
            ("q2-64x16", "newmark") => peer_target("fenicsx", "FEniCSx", 60.0),
            _ => {}
        }
        if run.scheme == "cd" && run.dofs >= 500_000 && run.setup.is_finite() {
            let share = run.setup / run.median;
            check(run, "setup / whole run".into(), share, Bound::AtMost(0.25));
        }
        if (run.rung, run.scheme) == ("q1-unstructured-1m", "cd") {
            check(run, "whole run, s".into(), run.median, Bound::Under(15.0));
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run<'a>(rung: &'a str, scheme: &'a str, dofs: u64, median: f64, setup: f64) -> Measured<'a> {
        Measured {
            rung,
            scheme,
            dofs,
            median,
            setup,
            ratios: Vec::new(),
        }
    }

    #[test]
    fn each_target_reads_its_figure_and_its_bound() {
        let mut paper = run("paper q2-8x2", "cd", 148, 0.014, 0.004);
        paper.ratios = vec![("scipy", 58.2), ("fenicsx", 39.9)];
        let mut q2 = run("q2-64x16", "newmark", 8_352, 0.15, 0.045);
        q2.ratios = vec![("fenicsx", 60.0)];
        let lines = verdicts(&[
            paper,
            q2,
            run("q1-unstructured-500k", "cd", 500_000, 5.653, 1.648),
            run("q1-unstructured-1m", "cd", 1_000_000, 12.136, 3.0),
        ]);
        assert_eq!(
            lines,
            [
                "paper q2-8x2 cd: FEniCSx / ours 39.900 (target ≥ 40): NOT met",
                "paper q2-8x2 cd: scipy / ours 58.200 (target ≥ 20): met",
                "q2-64x16 newmark: FEniCSx / ours 60.000 (target ≥ 60): met",
                "q1-unstructured-500k cd: setup / whole run 0.292 (target ≤ 0.25): NOT met",
                "q1-unstructured-1m cd: setup / whole run 0.247 (target ≤ 0.25): met",
                "q1-unstructured-1m cd: whole run, s 12.136 (target < 15): met",
            ]
        );
    }

    #[test]
    fn a_figure_the_bench_did_not_measure_prints_no_target() {
        // No peers (--peers none), a rung without targets, a failed setup.
        let lines = verdicts(&[
            run("q2-64x16", "cd", 8_352, 0.08, 0.03),
            run("q1-128x32", "cd", 8_352, 0.07, 0.03),
            run("q1-1416x354", "cd", 1_004_298, 9.0, f64::NAN),
        ]);
        assert!(lines.is_empty(), "{lines:?}");
    }
}
