//! Each paper case against its committed reference run in
//! `cases/reference/<case>.csv`; `--bless` rewrites them and says what
//! changed, so a deliberate change of results is a reviewed diff.

use std::fmt::Write as _;
use std::path::Path;

use crate::report::{max_or_nan, num, Report};
use crate::scene::Trace;
use crate::Run;

/// Column names of a reference file.
pub const COLUMNS: [&str; 11] = [
    "t",
    "ux81",
    "ux85",
    "sigma71",
    "sigma81",
    "v81",
    "kinetic",
    "strain",
    "work",
    "dissipated",
    "total",
];

/// Relative tolerance: |run − reference| ≤ TOL · max|reference column|.
/// Round-off only: the same code on the same inputs is deterministic, and
/// reordered floating-point sums stay far below it.
pub const TOL: f64 = 1e-9;

/// The columns of a trace.
pub fn columns(t: &Trace) -> Vec<Vec<f64>> {
    let e = |f: fn(&stickslip_time::Energy) -> f64| t.energy.iter().map(f).collect::<Vec<f64>>();
    vec![
        t.t.clone(),
        t.ux81.clone(),
        t.ux85.clone(),
        t.sigma71.clone(),
        t.sigma81.clone(),
        t.v81.clone(),
        e(|e| e.kinetic),
        e(|e| e.strain),
        e(|e| e.external_work),
        e(|e| e.dissipated),
        e(|e| e.total),
    ]
}

/// The CSV text of a trace.
pub fn to_csv(t: &Trace) -> String {
    let cols = columns(t);
    let mut s = COLUMNS.join(",");
    s.push('\n');
    for k in 0..t.t.len() {
        let row: Vec<String> = cols.iter().map(|c| format!("{:.17e}", c[k])).collect();
        let _ = writeln!(s, "{}", row.join(","));
    }
    s
}

/// Parses a reference file into columns.
///
/// # Errors
/// A header other than [`COLUMNS`], or a field that is not a number (with
/// its line).
pub fn parse(text: &str, file: &Path) -> Result<Vec<Vec<f64>>, String> {
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("");
    if header != COLUMNS.join(",") {
        return Err(format!(
            "{}: line 1: header {header:?}, expected {:?}; rewrite with `cargo xtask verify --bless`",
            file.display(),
            COLUMNS.join(",")
        ));
    }
    let mut cols = vec![Vec::new(); COLUMNS.len()];
    for (i, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != COLUMNS.len() {
            return Err(format!(
                "{}: line {}: {} fields, expected {}",
                file.display(),
                i + 2,
                fields.len(),
                COLUMNS.len()
            ));
        }
        for (c, f) in fields.iter().enumerate() {
            cols[c].push(f.trim().parse::<f64>().map_err(|e| {
                format!(
                    "{}: line {}, column {}: {f:?}: {e}",
                    file.display(),
                    i + 2,
                    COLUMNS[c]
                )
            })?);
        }
    }
    Ok(cols)
}

/// Largest |a − b| / max|b| per column (steps must match); NaN where
/// either side has a NaN.
fn deviations(run: &[Vec<f64>], reference: &[Vec<f64>]) -> Vec<f64> {
    run.iter()
        .zip(reference)
        .map(|(a, b)| {
            let scale = max_or_nan(b.iter().map(|v| v.abs()).chain([1e-300]));
            max_or_nan(a.iter().zip(b).map(|(x, y)| (x - y).abs()).chain([0.0])) / scale
        })
        .collect()
}

/// Runs the suite (or rewrites the references when `bless`).
pub fn run(root: &Path, runs: &[Run], bless: bool, r: &mut Report) {
    r.suite("reference");
    let dir = root.join("cases/reference");
    for run in runs {
        let name = run.case.name.as_str();
        let file = dir.join(format!("{name}.csv"));
        let trace = &run.trace;
        if let Some(e) = &trace.error {
            r.holds(name, "run completes", e.clone(), "completes", false);
            continue;
        }
        let cols = columns(trace);
        let stored = std::fs::read_to_string(&file)
            .map_err(|e| format!("{}: {e}", file.display()))
            .and_then(|t| parse(&t, &file));
        if bless {
            let change = match &stored {
                Ok(old) if old[0].len() == cols[0].len() => {
                    let d = deviations(&cols, old);
                    let changed: Vec<String> = COLUMNS
                        .iter()
                        .zip(&d)
                        .filter(|(_, d)| **d != 0.0)
                        .map(|(c, d)| format!("{c} {}", num(*d)))
                        .collect();
                    if changed.is_empty() {
                        "unchanged".to_string()
                    } else {
                        format!("changed (max rel. change: {})", changed.join(", "))
                    }
                }
                Ok(old) => format!("changed: {} samples, was {}", cols[0].len(), old[0].len()),
                Err(_) => "new file".to_string(),
            };
            let written =
                std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&file, to_csv(trace)));
            match written {
                Ok(()) => println!(
                    "bless: {} {change}",
                    file.strip_prefix(root).unwrap_or(&file).display()
                ),
                Err(e) => r.holds(
                    name,
                    "write reference",
                    format!("{}: {e}", file.display()),
                    "written",
                    false,
                ),
            }
            continue;
        }
        let stored = match stored {
            Ok(s) => s,
            Err(e) => {
                r.holds(
                    name,
                    "reference file",
                    e,
                    "readable; create with --bless",
                    false,
                );
                continue;
            }
        };
        if stored[0].len() != cols[0].len() {
            r.holds(
                name,
                "samples vs reference",
                cols[0].len().to_string(),
                &format!("{} (cases/reference/{name}.csv)", stored[0].len()),
                false,
            );
            continue;
        }
        let d = deviations(&cols, &stored);
        for (c, dev) in COLUMNS.iter().zip(d) {
            r.at_most(
                name,
                &format!("{c}: max |run − ref| / max|ref|"),
                dev,
                TOL,
                &format!("cases/reference/{name}.csv"),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::deviations;

    #[test]
    fn a_nan_in_the_run_or_the_reference_is_a_deviation() {
        let reference = vec![vec![1.0, 2.0, 4.0]];
        assert_eq!(deviations(&reference, &reference), vec![0.0]);
        let run = vec![vec![1.0, f64::NAN, 4.0]];
        assert!(deviations(&run, &reference)[0].is_nan());
        assert!(deviations(&reference, &run)[0].is_nan());
    }
}
