//! `cargo xtask bench advise`: what the configuration `stickslip advise`
//! picks costs against the cheapest one that meets the same tolerance. On
//! the paper's slab, u_x at (8, 1) (the picks whose errors
//! crates/cli/tests/advise.rs checks), for each tolerance: the release
//! `stickslip advise --json` gives the pick; docs/work-precision.csv
//! (`cargo xtask chart`) gives the configuration with the lowest time among
//! those whose error meets the tolerance. Both are timed here side by side,
//! interleaved: `stickslip run` with the configuration set by `--set` and
//! only the last step written (advise's pilots time runs without their
//! output), the process's wall time and the run's own (setup and steps,
//! as its `done:` line reports it), medians of the rounds. Advise aims at
//! no more than twice the cheapest; figures are printed, not asserted.
//!
//!     cargo xtask bench advise [--rounds N] [--tol T]...

use std::path::Path;
use std::process::Command;

/// The case and the point of the advise tests and of the chart's errors.
const CASE: &str = "cases/martins-oden/cd-step-eps1e-4.toml";
const AT: &str = "8,1";
/// The tolerances crates/cli/tests/advise.rs checks.
const TOLS: [f64; 3] = [3e-2, 2e-2, 1e-2];

/// A configuration as advise and the chart's CSV name it.
struct Config {
    /// Mesh file relative to the case's directory.
    mesh: String,
    /// The CSV's method name (`cd`, `nm-0.25-0.5`, ...).
    method: String,
    dt: f64,
    eps: f64,
}

impl Config {
    fn describe(&self) -> String {
        let mesh = self.mesh.rsplit('/').next().unwrap_or(&self.mesh);
        format!(
            "{mesh} {} dt {:.4e} eps {:e}",
            self.method, self.dt, self.eps
        )
    }

    /// The same configuration: Δt and ε to 1e-6 (the pilots' Δt_crit and
    /// the chart's differ in their last bits).
    fn is(&self, other: &Config) -> bool {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
        self.mesh == other.mesh
            && self.method == other.method
            && close(self.dt, other.dt)
            && close(self.eps, other.eps)
    }

    /// The `--set`s that turn the paper case into this configuration, as
    /// advise configures its runs.
    fn sets(&self) -> Result<Vec<String>, String> {
        let mut s = vec![
            format!("mesh.file={}", self.mesh),
            format!("time.dt={:e}", self.dt),
            format!("contact.eps={:e}", self.eps),
        ];
        let newmark = |beta: &str, gamma: &str| {
            [
                "time.scheme=newmark".to_string(),
                format!("time.beta={beta}"),
                format!("time.gamma={gamma}"),
            ]
        };
        match self.method.as_str() {
            "cd" => s.push("time.scheme=central_difference".into()),
            "nm-0.25-0.5" => s.extend(newmark("0.25", "0.5")),
            "nm-0.3025-0.6" => s.extend(newmark("0.3025", "0.6")),
            "nm-0.25-0.5-reduced" => {
                s.extend(newmark("0.25", "0.5"));
                // The paper's step reduction (METHOD.md §5, Remark 4.3),
                // advise's for a case without its own.
                s.push("time.stick_reduction={ dt = 1e-7, steps = 10 }".into());
            }
            other => return Err(format!("unknown method {other:?}")),
        }
        Ok(s)
    }
}

/// Runs the rounds and prints the table.
///
/// # Errors
/// Bad arguments, a failing build, advise or run, an unreadable CSV.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let mut rounds = 7usize;
    let mut tols = Vec::new();
    crate::bench::args(
        "bench advise",
        "[--rounds N] [--tol T]...",
        args,
        |a, it| {
            match a {
                "--rounds" => {
                    rounds = crate::bench::integer_arg::<usize>(a, "a number", it)?.max(1)
                }
                "--tol" => {
                    let v = it.next().ok_or("--tol needs a relative error, e.g. 2e-2")?;
                    tols.push(
                        v.parse::<f64>()
                            .map_err(|_| format!("--tol {v}: not a number"))?,
                    );
                }
                _ => return Ok(false),
            }
            Ok(true)
        },
    )?;
    if tols.is_empty() {
        tols = TOLS.to_vec();
    }
    let (exe, dir) = crate::bench::release_stickslip(root, "advise")?;
    let csv = root.join("docs/work-precision.csv");
    let rows = std::fs::read_to_string(&csv)
        .map_err(|e| format!("{}: {e}", csv.display()))
        .and_then(|t| csv_rows(&t).map_err(|e| format!("{}: {e}", csv.display())))?;

    println!(
        "advise's pick against the cheapest configuration of docs/work-precision.csv that meets \
         the tolerance (u_x at ({AT}), {CASE}); `stickslip run` (release), last step written, \
         median of {rounds} interleaved rounds:\n"
    );
    println!(
        "{:<8} {:<9} {:<52} {:>8} {:>8}",
        "tol", "", "configuration", "wall s", "run s"
    );
    for tol in tols {
        let pick = advise_pick(root, &exe, tol)?;
        let cheapest = rows
            .iter()
            .filter(|(_, err, _)| *err <= tol)
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .map(|(c, _, _)| c)
            .ok_or_else(|| format!("the CSV has no configuration with an error <= {tol:e}"))?;
        let configs = [&pick, cheapest];
        // times[config] = (wall, run) per round, the two interleaved.
        let mut times: [Vec<(f64, Option<f64>)>; 2] = [Vec::new(), Vec::new()];
        for _ in 0..rounds {
            for (k, c) in configs.iter().enumerate() {
                times[k].push(time_run(root, &exe, &dir.join(format!("{k}.h5")), c)?);
            }
        }
        let medians: Vec<(f64, Option<f64>)> = times
            .iter()
            .map(|t| {
                let wall = median(t.iter().map(|x| x.0).collect());
                let own: Option<Vec<f64>> = t.iter().map(|x| x.1).collect();
                (wall, own.map(median))
            })
            .collect();
        let fmt =
            |x: Option<f64>, digits: usize| x.map_or("-".to_string(), |x| format!("{x:.digits$}"));
        for (label, c, (wall, own)) in [
            ("pick", &pick, medians[0]),
            ("cheapest", cheapest, medians[1]),
        ] {
            let tol_col = if label == "pick" {
                format!("{tol:e}")
            } else {
                String::new()
            };
            println!(
                "{tol_col:<8} {label:<9} {:<52} {wall:>8.4} {:>8}",
                c.describe(),
                fmt(own, 4)
            );
        }
        let ratio_own = medians[0].1.zip(medians[1].1).map(|(a, b)| a / b);
        // The same configuration twice: its ratio is the noise of the timing.
        let same = pick.is(cheapest);
        println!(
            "{:<8} {:<9} {:<52} {:>8.2} {:>8}",
            "",
            "ratio",
            if same {
                "pick / cheapest (the same configuration)"
            } else {
                "pick / cheapest"
            },
            medians[0].0 / medians[1].0,
            fmt(ratio_own, 2)
        );
    }
    Ok(())
}

/// The configuration `stickslip advise --tol TOL --json` chooses.
fn advise_pick(root: &Path, exe: &Path, tol: f64) -> Result<Config, String> {
    let o = Command::new(exe)
        .current_dir(root)
        .arg("advise")
        .arg(CASE)
        .args([
            "--tol",
            &format!("{tol:e}"),
            "--on",
            "ux",
            "--at",
            AT,
            "--json",
        ])
        .output()
        .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
    let out = String::from_utf8_lossy(&o.stdout);
    if !o.status.success() {
        return Err(format!(
            "advise --tol {tol:e} failed ({}): {}{}",
            o.status,
            out,
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    // The choice is a flat object of numbers and strings.
    let choice = out
        .split_once("\"choice\":{")
        .and_then(|(_, rest)| rest.split_once('}'))
        .map(|(obj, _)| obj)
        .ok_or_else(|| format!("advise --tol {tol:e} --json gave no choice: {out}"))?;
    let field = |key: &str| -> Result<&str, String> {
        let pat = format!("\"{key}\":");
        let start = choice
            .find(&pat)
            .ok_or_else(|| format!("advise's choice has no {key}: {choice}"))?
            + pat.len();
        let rest = &choice[start..];
        Ok(match rest.strip_prefix('"') {
            Some(s) => s.split('"').next().unwrap_or(""),
            None => rest.split(',').next().unwrap_or(""),
        })
    };
    let number = |key: &str| -> Result<f64, String> {
        let v = field(key)?;
        v.parse()
            .map_err(|_| format!("advise's choice: {key} = {v:?} is not a number"))
    };
    Ok(Config {
        mesh: field("mesh")?.to_string(),
        method: field("method")?.to_string(),
        dt: number("dt")?,
        eps: number("eps")?,
    })
}

/// The step-load rows of the chart's Δt study: configuration, error of
/// u_x at (8, 1), median time.
fn csv_rows(text: &str) -> Result<Vec<(Config, f64, f64)>, String> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty")?.split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| format!("no column {name}"))
    };
    let [study, load, mesh, method, dt, eps, err, time] = [
        "study",
        "load",
        "mesh",
        "method",
        "dt",
        "eps",
        "err_ux_8_1",
        "time_s",
    ]
    .map(col);
    let (study, load, mesh, method) = (study?, load?, mesh?, method?);
    let (dt, eps, err, time) = (dt?, eps?, err?, time?);
    let number = |f: &[&str], k: usize| -> Result<f64, String> {
        f[k].parse()
            .map_err(|_| format!("{:?} is not a number ({})", f[k], header[k]))
    };
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f.len() == header.len() && f[study] == "dt" && f[load] == "step")
        .map(|f| {
            Ok((
                Config {
                    mesh: format!("../meshes/{}", f[mesh]),
                    method: f[method].to_string(),
                    dt: number(&f, dt)?,
                    eps: number(&f, eps)?,
                },
                number(&f, err)?,
                number(&f, time)?,
            ))
        })
        .collect()
}

/// One `stickslip run` of the paper case in configuration `c`: the
/// process's wall time, and the run's own from its `done:` line.
fn time_run(root: &Path, exe: &Path, out: &Path, c: &Config) -> Result<(f64, Option<f64>), String> {
    let mut sets = vec!["output.every=1000000000".to_string()];
    sets.extend(c.sets()?);
    let (o, wall) =
        crate::bench::timed_run(Command::new(exe), root, &["--force"], out, CASE, &sets)?;
    let err = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() {
        return Err(format!("run of {} failed: {err}", c.describe()));
    }
    // "done: 500 steps to t = 0.5 (...) in 0.041 s (setup 0.022 s, ...)"
    let own = err
        .lines()
        .find(|l| l.starts_with("done: "))
        .and_then(|l| l.split(") in ").nth(1))
        .and_then(|r| r.split(" s").next())
        .and_then(|s| s.parse().ok());
    Ok((wall, own))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
