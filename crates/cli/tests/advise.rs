//! `stickslip advise` checked on the paper's slab.
//!
//! For three tolerances on u_x at (8, 1) the configuration advise picks
//! (from estimates measured by its own pilot runs) must meet the tolerance
//! against the chart's converged reference (Q2 64x16, Newmark ¼/½ with
//! step reduction, Δt = 2e-4): the true error is the `err_ux_8_1` column
//! of docs/work-precision.csv for the same configuration (written by
//! `cargo xtask chart`, not by advise), or, when the CSV has no such row,
//! computed here by running it and the reference. What the pick costs
//! against the cheapest configuration that meets the tolerance is a
//! measurement, not a test: `cargo xtask bench advise`.
//!
//! The tolerances are reachable per the CSV: its cheapest configurations
//! meeting them have errors 2.96e-2, 1.67e-2 and 8.7e-3. The first is 1.2%
//! below 3e-2, so that case asks for an estimate sharper than the 1.5× of
//! differences of neighbouring refinements; advise measures each pilot
//! against its finest pilot run instead (see crates/cli/src/advise/mod.rs).

use std::path::Path;

use stickslip::advise::{self, Quantity};
use stickslip_case::pilot::Trace;
use stickslip_case::{self as case, Method};
use stickslip_testkit::{scratch, workspace_root as root};

mod common;
use common::{bin, succeeded};

const TOLS: [f64; 3] = [3e-2, 2e-2, 1e-2];
const AT: [f64; 2] = [8.0, 1.0];

/// One `dt` row of the chart's CSV (step load).
#[derive(Clone, Debug)]
struct Row {
    mesh: String,
    method: Method,
    dt: f64,
    eps: f64,
    err_ux_8_1: f64,
    /// The CSV's median time (only the measurement at the end reads it).
    time_s: f64,
}

fn csv_rows() -> Vec<Row> {
    let path = root().join("docs/work-precision.csv");
    let text = std::fs::read_to_string(&path).expect("docs/work-precision.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let c_time = col("time_s");
    let (c_study, c_load, c_mesh, c_method, c_dt, c_eps, c_err) = (
        col("study"),
        col("load"),
        col("mesh"),
        col("method"),
        col("dt"),
        col("eps"),
        col("err_ux_8_1"),
    );
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[c_study] == "dt" && f[c_load] == "step")
        .map(|f| Row {
            mesh: f[c_mesh].to_string(),
            method: Method::ALL
                .into_iter()
                .find(|m| m.name() == f[c_method])
                .expect("known method"),
            dt: f[c_dt].parse().unwrap(),
            eps: f[c_eps].parse().unwrap(),
            err_ux_8_1: f[c_err].parse().unwrap(),
            time_s: f[c_time].parse().unwrap(),
        })
        .collect()
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs())
}

#[test]
fn advise_picks_meet_the_tolerance() {
    let case_path = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let case = case::load(&case_path, &[]).expect("paper case loads");
    let meshes = root().join("cases/meshes");
    let est = advise::estimate(&case, Quantity::Ux, Some(AT), &mut |l| eprintln!("{l}"))
        .expect("estimates");
    eprintln!("pilots: {} runs, {:.2} s", est.pilots.len(), est.seconds);
    let rows = csv_rows();
    let mut reference: Option<Trace> = None;
    let grid = advise::grid(case.time.t_end);
    let mut failures = Vec::new();
    for tol in TOLS {
        let Some(pick) = advise::pick(&est.candidates, tol) else {
            failures.push(format!("tol {tol:e}: advise found no configuration"));
            continue;
        };
        let name = Path::new(&pick.mesh)
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let row = rows.iter().find(|r| {
            r.mesh == name
                && r.method == pick.method
                && same(r.dt, pick.dt)
                && same(r.eps, pick.eps)
        });
        let truth = match row {
            Some(r) => r.err_ux_8_1,
            None => {
                let reference = reference.get_or_insert_with(|| {
                    let c = Method::TrapezoidalReduced.configure(
                        &case,
                        &meshes.join("slab-q2-64x16.msh"),
                        2e-4,
                        1e-4,
                    );
                    advise::run_traced(&c, Quantity::Ux, Some(AT)).expect("reference")
                });
                let c = pick.method.configure(
                    &case,
                    &est.ladder[pick.mesh_index].path,
                    pick.dt,
                    pick.eps,
                );
                let tr = advise::run_traced(&c, Quantity::Ux, Some(AT)).expect("pick runs");
                advise::distance(Quantity::Ux, &tr, reference, &grid)
            }
        };
        eprintln!(
            "tol {tol:e}: pick Q{} {} {} dt {:.4e} eps {:e}: estimate {:.3e}, true {truth:.3e} ({})",
            pick.order,
            name,
            pick.method.name(),
            pick.dt,
            pick.eps,
            pick.estimate(),
            if row.is_some() { "CSV" } else { "run here" },
        );
        if truth > tol {
            failures.push(format!(
                "tol {tol:e}: the pick {name} {} dt {:.4e} has error {truth:.3e} against the reference",
                pick.method.name(),
                pick.dt
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn advise_command_writes_a_case_that_loads_and_keeps_comments() {
    let dir = scratch("advise");
    let out = dir.join("adjusted.toml");
    std::fs::remove_file(&out).ok();
    let case_path = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let st = bin()
        .args(["advise"])
        .arg(&case_path)
        .args([
            "--tol", "3e-2", "--on", "ux", "--at", "8,1", "--json", "--write",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let j: serde_json::Value = serde_json::from_str(&succeeded(&st, "advise --write")).unwrap();
    assert_eq!(j["found"], true);
    let text = std::fs::read_to_string(&out).unwrap();
    // The paper case's comments survive (toml_edit keeps them).
    assert!(text.contains("# rollers on the top face"), "{text}");
    let c = case::load(&out, &[]).expect("the written case loads");
    let choice = &j["choice"];
    assert_eq!(c.time.dt, choice["dt"].as_f64().unwrap());
    assert!(c.mesh.file.ends_with(
        Path::new(choice["mesh"].as_str().unwrap())
            .file_name()
            .unwrap()
    ));
    assert!(c.mesh.file.is_file(), "{}", c.mesh.file.display());
    // Bad input exits 2 with a message naming what to do.
    let bad = bin()
        .args(["advise"])
        .arg(&case_path)
        .args(["--tol", "1e-2", "--on", "ux"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("needs --at X,Y"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn advise_never_writes_over_a_file() {
    let dir = scratch("advise-over");
    let out = dir.join("mine.toml");
    std::fs::write(&out, "mine").unwrap();
    let st = bin()
        .arg("advise")
        .arg(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .args(["--tol", "3e-2", "--on", "ux", "--at", "8,1", "--write"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(st.status.code(), Some(2), "{err}");
    assert!(err.contains("the file exists"), "{err}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine");
    // Nor through a link to nowhere, nor into a directory it may not
    // write (a read-only mount where one can be made): both said so only
    // after the pilot runs, exit 1.
    let link = dir.join("link.toml");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(dir.join("nowhere/x.toml"), &link).unwrap();
    let mut places = vec![(link, "exists")];
    if let Some(ro) = common::tmpfs(&dir, "ro", "ro,size=1M") {
        places.push((ro.join("advised.toml"), "cannot write in the directory"));
    }
    for (place, says) in &places {
        let st = bin()
            .arg("advise")
            .arg(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
            .args(["--tol", "3e-2", "--on", "ux", "--at", "8,1", "--write"])
            .arg(place)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(2), "{}: {err}", place.display());
        assert!(err.contains(says), "{}: {err}", place.display());
        assert!(!err.contains("pilot"), "refused before the pilots: {err}");
    }
    if places.len() > 1 {
        std::process::Command::new("umount")
            .arg(dir.join("ro"))
            .status()
            .ok();
    }
    // A directory, and a negative tolerance (clap took "-1" for a flag).
    for (args, says) in [
        (
            vec!["--tol", "3e-2", "--write", dir.to_str().unwrap()],
            "is a directory",
        ),
        (vec!["--tol", "-1"], "give a relative error between 0 and 1"),
        (
            vec!["--tol", "1e308"],
            "--tol 1e308: give a relative error between 0 and 1",
        ),
    ] {
        let st = bin()
            .arg("advise")
            .arg(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
            .args(["--on", "ux", "--at", "8,1"])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    // --at with the energy, which has no point, was silently ignored.
    let st = bin()
        .arg("advise")
        .arg(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .args(["--tol", "1e-2", "--on", "energy", "--at", "8,1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(st.status.code(), Some(2), "{err}");
    assert!(err.contains("--at goes with"), "{err}");
}

/// A ladder of two bodies, a probe point off the body, and a friction
/// stress asked at a node that carries none are bad input (before: 21
/// pilots, then "add finer meshes"; and a silent snap to the nearest
/// node).
#[test]
fn advise_refuses_a_ladder_of_two_bodies_and_a_point_off_the_body() {
    let dir = scratch("advise-bodies");
    let meshes = root().join("cases/meshes");
    let text = std::fs::read_to_string(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .unwrap()
        .replace("\"../meshes/", &format!("\"{}/", meshes.display()));
    let case = dir.join("case.toml");
    std::fs::write(&case, &text).unwrap();
    let advise = |case: &Path, at: &str| {
        bin()
            .arg("advise")
            .arg(case)
            .args(["--tol", "2e-2", "--on", "ux", "--at", at])
            .output()
            .unwrap()
    };
    let o = advise(&case, "100,100");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("lies outside the mesh"), "{err}");
    // The friction stress at the corner a support holds, which carries
    // none: it ran the pilots at another node on each mesh and exited 1.
    let o = bin()
        .arg("advise")
        .arg(&case)
        .args(["--tol", "5e-1", "--on", "friction_stress", "--at", "0,0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("carries no friction") && !err.contains("pilot  "),
        "{err}"
    );

    let bodies = dir.join("bodies.toml");
    std::fs::write(&bodies, text.replace("slab-q2-16x4.msh", "hole-q1.msh")).unwrap();
    let o = advise(&bodies, "8,1");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("a ladder is one geometry"), "{err}");
    assert!(!err.contains("pilot"), "refused before any pilot: {err}");
}

/// Surfaces of different ε: advise gives every surface one ε (its pilots
/// and --write), so it advised another problem and --write set the second
/// surface's 1e-2 to the first's 1e-4 without a word. Refused before any
/// pilot, at the differing ε's line.
#[test]
fn advise_refuses_surfaces_of_different_eps() {
    let dir = scratch("advise-two-eps");
    let meshes = root().join("cases/meshes");
    let text = std::fs::read_to_string(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .unwrap()
        .replace("\"../meshes/", &format!("\"{}/", meshes.display()))
        .replace("[contact]", "[[contact]]");
    let text = format!(
        "{text}\n[[contact]]\ngroup = \"support\"\npressure = 10.0\nmu = 0.1\neps = 1e-2\n"
    );
    let case = dir.join("two.toml");
    std::fs::write(&case, &text).unwrap();
    let written = dir.join("w.toml");
    let o = bin()
        .arg("advise")
        .arg(&case)
        .args(["--tol", "8e-1", "--on", "ux", "--at", "8,1", "--write"])
        .arg(&written)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let line = text.lines().position(|l| l == "eps = 1e-2").unwrap() + 1;
    assert!(
        err.contains(&format!("two.toml:{line}:")) && err.contains("contact.1.eps = 1e-2"),
        "{err}"
    );
    assert!(!err.contains("pilot  ") && !written.exists(), "{err}");
}

/// A case without [contact] has no ε: advise printed `eps = NaN` in its
/// choice and in the header it writes, and, NaN being unequal to itself,
/// did not find its own pilot of the chosen configuration (an estimate
/// from the sums). The header left out --at, so it could not be run again
/// as written.
#[test]
fn advise_a_case_without_contact() {
    let dir = scratch("advise-no-contact");
    let meshes = root().join("cases/meshes");
    let text = std::fs::read_to_string(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .unwrap()
        .replace("\"../meshes/", &format!("\"{}/", meshes.display()));
    let contact = text.find("[contact]").unwrap();
    let next = contact + text[contact..].find("\n\n").unwrap();
    let text = format!("{}{}", &text[..contact], &text[next..]);
    let case = dir.join("nc.toml");
    std::fs::write(&case, &text).unwrap();
    let written = dir.join("w.toml");
    let o = bin()
        .arg("advise")
        .arg(&case)
        .args(["--tol", "3e-2", "--on", "ux", "--at", "8,1", "--write"])
        .arg(&written)
        .output()
        .unwrap();
    let out = succeeded(&o, "advise");
    assert!(!out.contains("NaN") && out.contains("was a pilot"), "{out}");
    let w = std::fs::read_to_string(&written).unwrap();
    assert!(
        w.starts_with("# Adjusted by `stickslip advise --tol 3e-2 --on ux --at 8,1`")
            && !w.contains("NaN"),
        "{w}"
    );
    // Without its end load nothing moves: every relative error was NaN,
    // and the advice to add finer meshes (exit 1). Refused after the
    // first pilot.
    let still = dir.join("still.toml");
    std::fs::write(&still, text.replace("t = [-150.0, 0.0]", "t = [0.0, 0.0]")).unwrap();
    let o = bin()
        .arg("advise")
        .arg(&still)
        .args(["--tol", "3e-2", "--on", "ux", "--at", "8,1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("does not change over the run") && !err.contains("NaN"),
        "{err}"
    );
}

/// The README's ranges of advise's estimates over the chart's errors, for
/// the configurations that were pilots and for the others, on the slab
/// case (u_x at (8, 1)), with the five farthest of the others:
///
///     cargo test --release -p stickslip --test advise estimates_against_the_chart -- --ignored --nocapture
#[test]
#[ignore = "a measurement: prints the ranges the README quotes"]
fn estimates_against_the_chart() {
    let case_path = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let case = case::load(&case_path, &[]).expect("paper case loads");
    let est = advise::estimate(&case, Quantity::Ux, Some(AT), &mut |_| {}).expect("estimates");
    let rows = csv_rows();
    let mut ratios: [Vec<(f64, String)>; 2] = [Vec::new(), Vec::new()];
    for c in &est.candidates {
        let name = Path::new(&c.mesh).file_name().unwrap().to_string_lossy();
        let Some(r) = rows.iter().find(|r| {
            r.mesh == name && r.method == c.method && same(r.dt, c.dt) && same(r.eps, c.eps)
        }) else {
            continue;
        };
        let what = format!(
            "{name} {} dt {:.4e}: estimate {:.3e}, chart {:.3e}",
            c.method.name(),
            c.dt,
            c.estimate(),
            r.err_ux_8_1
        );
        ratios[usize::from(!c.run)].push((c.estimate() / r.err_ux_8_1, what));
    }
    for (label, r) in ["pilots", "not run"].iter().zip(&mut ratios) {
        r.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (Some(lo), Some(hi)) = (r.first(), r.last()) else {
            continue;
        };
        println!(
            "{label}: {} configurations of the chart, estimate / chart error {:.2}-{:.2}",
            r.len(),
            lo.0,
            hi.0
        );
    }
    // The picks at five tolerances against the chart's cheapest
    // configuration that meets each (the chart's times).
    for tol in [5e-2, 4e-2, 3e-2, 2e-2, 1e-2] {
        let Some(pick) = advise::pick(&est.candidates, tol) else {
            println!("tol {tol:e}: no pick");
            continue;
        };
        let name = Path::new(&pick.mesh).file_name().unwrap().to_string_lossy();
        let row = rows.iter().find(|r| {
            r.mesh == name
                && r.method == pick.method
                && same(r.dt, pick.dt)
                && same(r.eps, pick.eps)
        });
        let cheapest = rows
            .iter()
            .filter(|r| r.err_ux_8_1 <= tol)
            .min_by(|a, b| a.time_s.total_cmp(&b.time_s));
        match (row, cheapest) {
            (Some(r), Some(c)) => println!(
                "tol {tol:e}: pick {name} {} dt {:.4e} (chart error {:.3e}), {:.2}x the time of the chart's cheapest, {} {} dt {:.4e}",
                pick.method.name(),
                pick.dt,
                r.err_ux_8_1,
                r.time_s / c.time_s,
                c.mesh,
                c.method.name(),
                c.dt
            ),
            _ => println!(
                "tol {tol:e}: pick {name} {} dt {:.4e}, not in the chart",
                pick.method.name(),
                pick.dt
            ),
        }
    }
    let others = &ratios[1];
    let mut far: Vec<&(f64, String)> = others.iter().collect();
    far.sort_by(|a, b| a.0.ln().abs().total_cmp(&b.0.ln().abs()));
    for (ratio, what) in far.iter().rev().take(5) {
        println!("  {ratio:.2}x  {what}");
    }
}
