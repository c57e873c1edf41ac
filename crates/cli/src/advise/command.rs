//! The command: its options, checked before any pilot runs, then the
//! estimates, the pick, the report and `--write`.

use std::path::PathBuf;

use anyhow::Context;

use stickslip_case::{Case, InputError};

use crate::console::WriteError;

use super::adjusted::adjusted_case;
use super::candidates::pick;
use super::estimate::estimate;
use super::input;
use super::quantity::Quantity;
use super::report;

/// Parses `--at X,Y`.
///
/// # Errors
/// Not two finite numbers.
pub fn parse_point(s: &str) -> Result<[f64; 2], InputError> {
    let bad = || {
        InputError(format!(
            "--at {s:?}: expected two numbers X,Y, e.g. --at 8,1"
        ))
    };
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if x.is_finite() && y.is_finite() {
        Ok([x, y])
    } else {
        Err(bad())
    }
}

/// The command's options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Tolerance on the relative error.
    pub tol: f64,
    /// The output.
    pub quantity: Quantity,
    /// The point (ux, uy, friction_stress).
    pub at: Option<[f64; 2]>,
    /// Write the adjusted case here.
    pub write: Option<PathBuf>,
    /// One JSON object on stdout instead of the report.
    pub json: bool,
}

/// How `advise` ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// A configuration meets the tolerance (estimated).
    Found,
    /// None of the ladder's does.
    NotReachable,
}

/// The options' own errors, found before any pilot runs.
fn check(o: &Options) -> anyhow::Result<()> {
    // A relative error of 1 or more is no accuracy (the coarsest pilot
    // meets it whatever it computes).
    if !(o.tol > 0.0 && o.tol < 1.0) {
        let tol = o.tol.to_string();
        let tol = if tol.len() > 12 {
            format!("{:e}", o.tol)
        } else {
            tol
        };
        return Err(input(format!(
            "--tol {tol}: give a relative error between 0 and 1, e.g. --tol 1e-2"
        )));
    }
    if o.quantity == Quantity::Energy && o.at.is_some() {
        return Err(input(
            "--at goes with --on ux, uy or friction_stress; --on energy is the body's total energy \
             at t_end, at no point: leave --at out"
                .to_string(),
        ));
    }
    if let Some(w) = &o.write {
        if w.is_dir() {
            return Err(input(format!(
                "--write {}: it is a directory; give a file name in it, e.g. --write {}",
                w.display(),
                w.join("advised.toml").display()
            )));
        }
        // Never over a file: it may be the case being advised, or another
        // (nor through a link, even one to nowhere).
        if std::fs::symlink_metadata(w).is_ok() {
            return Err(input(format!(
                "--write {}: the file exists; give a new name (advise never overwrites a file)",
                w.display()
            )));
        }
        if let Some(dir) = w
            .parent()
            .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
        {
            return Err(input(format!(
                "--write {}: the directory {} does not exist; create it or write elsewhere",
                w.display(),
                dir.display()
            )));
        }
        // Said before the pilot runs, not after them.
        let dir = crate::results_file::dir_of(w);
        if !crate::sys::can_write_in(dir) {
            return Err(input(format!(
                "--write {}: cannot write in the directory {} (read-only, or not yours); write \
                 elsewhere",
                w.display(),
                dir.display()
            )));
        }
    }
    Ok(())
}

/// `stickslip advise`: pilots, choice, report, `--write`.
///
/// # Errors
/// Input problems as [`InputError`]; pilot runs that fail; an unwritable output.
pub fn command(case: &Case, o: &Options) -> anyhow::Result<Verdict> {
    check(o)?;
    if case.time.scheme == stickslip_case::Scheme::QuasiStatic {
        return Err(input(format!(
            "{}time.scheme = \"quasi_static\": advise picks among the dynamic schemes (central \
             difference, Newmark), Δt and ε by pilot runs; a quasi-static case has no such choice. \
             Advise a dynamic copy of the case instead: in a copy of the case file, set time.scheme = \
             \"central_difference\" (or \"newmark\") at that line, and give the copy to advise",
            case.at("time.scheme")
        )));
    }
    // The pilots and --write give every surface one ε: surfaces of
    // different ε would be advised as another problem, their ε lost.
    if let Some((i, c)) = case
        .contact
        .iter()
        .enumerate()
        .find(|(_, c)| c.eps != case.contact[0].eps)
    {
        return Err(input(format!(
            "{}contact.{i}.eps = {:e} differs from contact.0.eps = {:e}: advise chooses one ε \
             for every surface (its pilots run with it, and --write gives it to each), so it \
             would advise another problem and drop that ε; give every [[contact]] one eps to \
             advise the case, or advise each ε's surfaces in a case of their own",
            case.at(&case.contact_key(i, "eps")),
            c.eps,
            case.contact[0].eps
        )));
    }
    let json = o.json;
    // A pilot's line that stderr refuses does not stop the pilots: the
    // report and --write follow, and the loss exits 1 at the end.
    let mut lost: Option<WriteError> = None;
    let mut log = |l: &str| {
        if !json {
            if let Err(e) = crate::console::err(&format!("{l}\n")) {
                lost.get_or_insert(e);
            }
        }
    };
    let est = estimate(case, o.quantity, o.at, &mut log)?;
    let what = report::measure(o.quantity, est.ladder[0].node_at);
    let choice = pick(&est.candidates, o.tol);
    let best = est
        .candidates
        .iter()
        .filter(|c| c.estimate().is_finite())
        .min_by(|a, b| a.estimate().total_cmp(&b.estimate()));
    if json {
        report::json(case, o, &est, &what, choice, best)?;
    } else {
        // The report up to the choice: where no configuration qualifies,
        // the errors per mesh are what tells how much finer the ladder
        // must go.
        report::measured(case, o, &est, &what)?;
    }
    let Some(c) = choice else {
        report::not_reachable(case, o, &est, &what, best)?;
        return lost.map_or(Ok(Verdict::NotReachable), |e| Err(e.into()));
    };
    if !json {
        report::choice(c, &est.ladder)?;
    }
    if let Some(w) = &o.write {
        let header = report::write_header(o, c, &est.ladder);
        let text = adjusted_case(case, c, &est.ladder, w, &header)?;
        // A new file only, even if one appeared while the pilots ran.
        let written = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(w)
            .and_then(|mut f| std::io::Write::write_all(&mut f, text.as_bytes()));
        match written {
            // The place (a read-only file system, a link or directory put
            // there since): the user's to change, exit 2.
            Err(e) if crate::sys::place_error(&e) => {
                return Err(input(format!(
                    "--write {}: cannot write it: {e}; write elsewhere",
                    w.display()
                )))
            }
            r => r.with_context(|| format!("cannot write {}", w.display()))?,
        }
        if !json {
            crate::console::out(&format!("written     {}\n", w.display()))?;
        }
    }
    lost.map_or(Ok(Verdict::Found), |e| Err(e.into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points() {
        assert_eq!(parse_point("8, -1").unwrap(), [8.0, -1.0]);
        assert!(parse_point("8").is_err());
        assert!(parse_point("8,nan").is_err());
    }
}
