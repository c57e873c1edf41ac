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
        let row = Row {
            suite: self.suite.clone(),
            case: case.to_string(),
            quantity: quantity.to_string(),
            measured,
            expected,
            tolerance,
            pass,
        };
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
        self.row(
            case,
            quantity,
            num(measured),
            why.to_string(),
            "reported".into(),
            measured.is_finite(),
        );
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

    /// Rows that passed.
    pub fn passed(&self) -> usize {
        self.rows.len() - self.failed()
    }

    /// The closing line: `N passed, M failed`.
    pub fn summary(&self) -> String {
        format!("{} passed, {} failed", self.passed(), self.failed())
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
