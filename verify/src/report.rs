//! The table `verify` prints: one row per check, and the closing count.

use std::io::Write as _;

/// One check: what was measured, what was expected and why, the verdict.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// analytic, rates, paper, reference.
    pub suite: String,
    /// The problem or case file.
    pub case: String,
    /// What is measured.
    pub quantity: String,
    /// The measured value, formatted.
    pub measured: String,
    /// The expected value and where it comes from.
    pub expected: String,
    /// The tolerance or the kind of bound.
    pub tolerance: String,
    /// True when the check holds.
    pub pass: bool,
    /// A figure shown for the table only ([`Report::reported`]): it fails
    /// where it is not a number, and otherwise counts as reported, not as
    /// a check passed.
    pub reported: bool,
}

/// Collects rows, printing each as it comes (a long run shows progress).
#[derive(Debug, Default)]
pub struct Report {
    /// Every row so far.
    pub rows: Vec<Row>,
    /// Print rows as they are added.
    pub echo: bool,
    suite: String,
}

/// A number in a short, readable form.
pub fn num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if !x.is_finite() {
        format!("{x}")
    } else if (1e-3..1e5).contains(&x.abs()) {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.4e}")
    }
}

/// The NaN-keeping worst of a suite's values (every "worst of" in the
/// suites and the test kit's helpers goes through them).
pub use stickslip_testkit::{max_or_nan, min_or_nan};

impl Report {
    /// A report that prints its rows as they come when `echo`.
    pub fn new(echo: bool) -> Report {
        Report {
            echo,
            ..Report::default()
        }
    }

    /// Sets the suite name of the rows that follow.
    pub fn suite(&mut self, name: &str) {
        self.suite = name.to_string();
    }

    /// Adds a row.
    pub fn row(
        &mut self,
        case: &str,
        quantity: &str,
        measured: String,
        expected: String,
        tolerance: String,
        pass: bool,
    ) {
        self.push(Row {
            suite: self.suite.clone(),
            case: case.to_string(),
            quantity: quantity.to_string(),
            measured,
            expected,
            tolerance,
            pass,
            reported: false,
        });
    }

    fn push(&mut self, row: Row) {
        if self.echo {
            println!("{}", format_row(&row));
            let _ = std::io::stdout().flush();
        }
        self.rows.push(row);
    }

    /// |measured − expected| ≤ tol.
    pub fn close(
        &mut self,
        case: &str,
        quantity: &str,
        measured: f64,
        expected: f64,
        source: &str,
        tol: f64,
    ) {
        let pass = (measured - expected).abs() <= tol;
        self.row(
            case,
            quantity,
            num(measured),
            format!("{} ({source})", num(expected)),
            format!("±{}", num(tol)),
            pass,
        );
    }

    /// A figure shown for the table only (`why`: what it is read for); it
    /// fails only where it is not a number.
    pub fn reported(&mut self, case: &str, quantity: &str, measured: f64, why: &str) {
        self.push(Row {
            suite: self.suite.clone(),
            case: case.to_string(),
            quantity: quantity.to_string(),
            measured: num(measured),
            expected: why.to_string(),
            tolerance: "reported".into(),
            pass: measured.is_finite(),
            reported: true,
        });
    }

    /// measured ≤ bound.
    pub fn at_most(&mut self, case: &str, quantity: &str, measured: f64, bound: f64, source: &str) {
        let pass = measured <= bound;
        self.row(
            case,
            quantity,
            num(measured),
            format!("≤ {} ({source})", num(bound)),
            "bound".into(),
            pass,
        );
    }

    /// measured ≥ bound.
    pub fn at_least(
        &mut self,
        case: &str,
        quantity: &str,
        measured: f64,
        bound: f64,
        source: &str,
    ) {
        let pass = measured >= bound;
        self.row(
            case,
            quantity,
            num(measured),
            format!("≥ {} ({source})", num(bound)),
            "bound".into(),
            pass,
        );
    }

    /// A yes/no property.
    pub fn holds(
        &mut self,
        case: &str,
        quantity: &str,
        measured: String,
        expected: &str,
        pass: bool,
    ) {
        self.row(
            case,
            quantity,
            measured,
            expected.to_string(),
            "exact".into(),
            pass,
        );
    }

    /// Rows that failed.
    pub fn failed(&self) -> usize {
        self.rows.iter().filter(|r| !r.pass).count()
    }

    /// Checks that passed (reported figures not counted).
    pub fn passed(&self) -> usize {
        self.rows.iter().filter(|r| r.pass && !r.reported).count()
    }

    /// Figures reported for the table only that are numbers (a reported
    /// NaN counts among the failed).
    pub fn reported_count(&self) -> usize {
        self.rows.iter().filter(|r| r.pass && r.reported).count()
    }

    /// The closing line: `N passed, M failed, K reported`.
    pub fn summary(&self) -> String {
        format!(
            "{} passed, {} failed, {} reported",
            self.passed(),
            self.failed(),
            self.reported_count()
        )
    }
}

/// The column headings, aligned like [`format_row`].
pub fn header() -> String {
    format!(
        "{:<9} | {:<26} | {:<44} | {:<14} | {:<52} | {:<10} | verdict",
        "suite", "case", "quantity", "measured", "expected (source)", "tolerance"
    )
}

/// One row of the table.
pub fn format_row(r: &Row) -> String {
    format!(
        "{:<9} | {:<26} | {:<44} | {:<14} | {:<52} | {:<10} | {}",
        r.suite,
        r.case,
        r.quantity,
        r.measured,
        r.expected,
        r.tolerance,
        if r.pass { "PASS" } else { "FAIL" }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nan_anywhere_makes_the_worst_nan() {
        assert_eq!(max_or_nan([1.0, 3.0, 2.0]), 3.0);
        assert_eq!(min_or_nan([1.0, 3.0, -2.0]), -2.0);
        assert_eq!(max_or_nan([]), f64::NEG_INFINITY);
        // Where f64::max would drop it: first, middle, last, alone.
        for v in [
            vec![f64::NAN, 1.0, 2.0],
            vec![1.0, f64::NAN, 2.0],
            vec![1.0, 2.0, f64::NAN],
            vec![f64::NAN],
        ] {
            assert!(v.iter().copied().fold(0.0, f64::max).is_finite());
            assert!(max_or_nan(v.iter().copied()).is_nan(), "{v:?}");
            assert!(min_or_nan(v.iter().copied()).is_nan(), "{v:?}");
        }
    }

    #[test]
    fn a_nan_fails_every_kind_of_check() {
        let mut r = Report::new(false);
        let worst = max_or_nan([1e-14, f64::NAN, 2e-14]);
        r.at_most("c", "worst", worst, 1e-12, "round-off");
        r.at_least("c", "order", -worst.log2(), 0.9, "first order");
        r.close("c", "E(0)", worst, 0.0, "closed form", 1.0);
        r.reported("c", "figure", worst, "table");
        assert_eq!(r.failed(), 4, "{:?}", r.rows);
        assert_eq!(r.summary(), "0 passed, 4 failed, 0 reported");
        // An all-NaN energy: every step-to-step rise is NaN, not −∞.
        let energy = [f64::NAN; 4];
        let rise = max_or_nan(energy.windows(2).map(|w| w[1] - w[0]));
        r.at_most("c", "largest rise", rise, 0.05, "band");
        assert_eq!(r.failed(), 5);
    }

    #[test]
    fn reported_figures_are_counted_apart_from_checks() {
        let mut r = Report::new(false);
        r.at_most("c", "q", 1.0, 2.0, "bound");
        r.at_most("c", "q", 3.0, 2.0, "bound");
        r.reported("c", "figure", 0.5, "table");
        r.reported("c", "figure", 0.7, "table");
        r.reported("c", "figure", f64::INFINITY, "table");
        assert_eq!((r.passed(), r.failed(), r.reported_count()), (1, 2, 2));
        assert_eq!(r.summary(), "1 passed, 2 failed, 2 reported");
    }
}
