//! End-to-end tests of `stickslip check`, `run` and `probe` on case files:
//! bad input exits 2 with `file:line`, a good case runs and can be probed.

use std::path::PathBuf;

mod common;
use common::scratch;
use common::{check, data, probe, run, stderr};
use stickslip_testkit::meshes_dir;

/// tests/data/slab.toml with the mesh path made absolute, after `edit`,
/// written to a scratch directory. Returns the case path and its text.
fn case_with(name: &str, edit: impl Fn(String) -> String) -> (PathBuf, String) {
    let mesh = meshes_dir().join("slab-q2-8x2.msh");
    let text = std::fs::read_to_string(data("slab.toml")).unwrap().replace(
        "../../../../cases/meshes/slab-q2-8x2.msh",
        &mesh.display().to_string().replace('\\', "/"),
    );
    let text = edit(text);
    let path = scratch(name).join(format!("{name}.toml"));
    std::fs::write(&path, &text).unwrap();
    (path, text)
}

/// 1-based line of the first line containing `needle` (the expected location
/// comes from the test's own text).
/// A needle starting with '\n' must start its line.
fn line_of(text: &str, needle: &str) -> usize {
    match needle.strip_prefix('\n') {
        Some(n) => text.lines().position(|l| l.starts_with(n)),
        None => text.lines().position(|l| l.contains(needle)),
    }
    .expect("needle in text")
        + 1
}

#[test]
fn check_accepts_the_slab_case() {
    let o = check(&data("slab.toml"), &[]);
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        stderr(&o)
    );
}

#[test]
fn case_errors_exit_2_with_file_and_line() {
    // (case name, edit of slab.toml, text on the line to blame, message)
    type BadCase = (
        &'static str,
        fn(String) -> String,
        &'static str,
        &'static str,
    );
    let cases: [BadCase; 10] = [
        (
            "unknown-key",
            |t| t.replace("eps = 1e-4", "eps = 1e-4\nepsilon = 1"),
            "epsilon",
            "unknown field `epsilon`",
        ),
        (
            "eps-zero",
            |t| t.replace("eps = 1e-4", "eps = 0"),
            "eps = 0",
            "contact.eps = 0 must be > 0",
        ),
        (
            "mu-negative",
            |t| t.replace("\nmu = 0.3", "\nmu = -0.3"),
            "\nmu = -0.3",
            "contact.mu = -0.3 must be >= 0",
        ),
        (
            "dt-negative",
            |t| t.replace("dt = 1e-3", "dt = -1e-3"),
            "dt = -1e-3",
            "time.dt = -0.001 must be a finite number > 0",
        ),
        (
            "t-end-zero",
            |t| t.replace("t_end = 0.05", "t_end = 0.0"),
            "t_end = 0.0",
            "time.t_end = 0 must be a finite number > 0",
        ),
        (
            "newmark-unstable",
            |t| {
                t.replace(
                    "scheme = \"central_difference\"",
                    "scheme = \"newmark\"\nbeta = 0.1\ngamma = 0.5",
                )
            },
            "gamma = 0.5",
            "not unconditionally stable",
        ),
        (
            "bad-scheme",
            |t| t.replace("\"central_difference\"", "\"leapfrog\""),
            "leapfrog",
            "unknown variant `leapfrog`",
        ),
        (
            "mu-speed-zero",
            |t| {
                t.replace(
                    "\nmu = 0.3",
                    "\nmu = { static = 0.3, kinetic = 0.2, speed = 0 }",
                )
            },
            "speed = 0 }",
            "speed = 0 must be > 0",
        ),
        (
            "mu-kinetic-above",
            |t| {
                t.replace(
                    "\nmu = 0.3",
                    "\nmu = { static = 0.3, kinetic = 0.4, speed = 1e-2 }",
                )
            },
            "kinetic = 0.4",
            "must be >= 0 and at most static = 0.3",
        ),
        (
            "foundation-string",
            |t| t.replace("eps = 1e-4", "eps = 1e-4\nfoundation_velocity = \"fast\""),
            "foundation_velocity",
            "expected a number",
        ),
    ];
    for (name, edit, needle, what) in cases {
        let (path, text) = case_with(name, edit);
        let o = check(&path, &[]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {e}");
        let at = format!("{name}.toml:{}:", line_of(&text, needle));
        assert!(
            e.starts_with("error: ") && e.contains(&at) && e.contains(what),
            "{name}: expected '{at}' and '{what}' in: {e}"
        );
        // run refuses it the same way, before creating any output.
        let out = path.with_extension("h5");
        let o = run(&path, &out, &[]);
        assert_eq!(o.status.code(), Some(2), "{name} run: {}", stderr(&o));
        assert!(!out.exists(), "{name}: no results file for bad input");
    }
}

#[test]
fn several_problems_are_reported_together() {
    let (path, text) = case_with("several", |t| {
        t.replace("eps = 1e-4", "eps = -1")
            .replace("\nmu = 0.3", "\nmu = -1")
    });
    let o = check(&path, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2));
    // (The slab's [contact] comment also says "mu = 0.3": only the key line is edited.)
    for needle in ["eps = -1", "mu = -1"] {
        assert!(
            e.contains(&format!("several.toml:{}:", line_of(&text, needle))),
            "{needle}: {e}"
        );
    }
    assert_eq!(
        e.lines().filter(|l| l.starts_with("error: ")).count(),
        2,
        "{e}"
    );
}

#[test]
fn set_overrides_and_names_itself_in_errors() {
    let slab = data("slab.toml");
    let o = check(&slab, &["contact.eps=-1e-2"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--set contact.eps=-1e-2") && e.contains("must be > 0"),
        "{e}"
    );
    let o = check(&slab, &["time.scheme=newmark", "time.dt=5e-3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = check(&slab, &["time.dtt=5e-3"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("unknown field `dtt`"), "{}", stderr(&o));
}

#[test]
fn missing_group_lists_the_mesh_groups() {
    let o = check(&data("slab.toml"), &["contact.group=bottom"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("bottom") && e.contains("support") && e.contains("left"),
        "{e}"
    );
}

#[test]
fn run_refuses_to_overwrite_without_force() {
    let dir = scratch("overwrite");
    let out = dir.join("exists.h5");
    std::fs::write(&out, b"precious").unwrap();
    let o = run(&data("slab.toml"), &out, &["--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("use --force"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
    let o = run(&data("slab.toml"), &out, &["--quiet", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(std::fs::read(&out).unwrap(), b"precious");
}

#[test]
fn run_into_a_missing_directory_is_bad_input() {
    let out = scratch("nodir").join("no/such/dir/out.h5");
    let o = run(&data("slab.toml"), &out, &["--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
}

#[test]
fn run_then_probe_node_81() {
    let out = scratch("probe").join("slab.h5");
    let o = run(&data("slab.toml"), &out, &["--quiet", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));

    // Node 81 of the paper = (8, 0). BENCHMARK.md: the initial static state is
    // u_x = 0.117 x, so u_x(8, 0) = 0.936 at t = 0, and it decreases under
    // the compressive end load.
    let o = probe(&out, &["--at", "8,0", "--field", "ux", "--csv"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("at (8, 0)"),
        "node info on stderr with --csv: {}",
        stderr(&o)
    );
    let csv = String::from_utf8(o.stdout).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,ux"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let (t, v) = l.split_once(',').unwrap();
            (t.parse().unwrap(), v.parse().unwrap())
        })
        .collect();
    assert_eq!(rows.len(), 51, "t = 0, 0.001, ..., 0.05 with every = 1");
    assert_eq!(rows[0].0, 0.0);
    assert!(
        // The closed form, exact but for the static solve's round-off
        // (measured 6.8e-15 relative; `--csv` prints full precision).
        (rows[0].1 - 0.936).abs() <= 1e-9 * 0.936,
        "u_x(8,0) at t = 0: {}",
        rows[0].1
    );
    assert!(rows.last().unwrap().1 < rows[0].1, "the end moves in -x");

    // |σ_T| <= g = μ F_n = 90 (the regularized law never exceeds the bound).
    let o = probe(&out, &["--at", "8,0", "--field", "friction_stress"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let vals: Vec<f64> = text
        .lines()
        .skip(2)
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect();
    assert_eq!(vals.len(), 51, "{text}");
    assert!(
        vals.iter().all(|v| v.abs() <= 90.0 * (1.0 + 1e-12)),
        "{vals:?}"
    );

    // The top-right corner (8, 1) is not on the contact surface.
    let o = probe(&out, &["--at", "8,1", "--field", "friction_stress"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a contact node"), "{}", stderr(&o));
}

/// `check` of an explicit case with a preload (the contact pressure, a
/// constant traction) names the factorization of K its initial state
/// takes, and its ordering; with no preload there is none.
#[test]
fn check_names_the_explicit_preloads_factorization() {
    let (path, _) = case_with("check-preload", |t| {
        t.replace("history = \"step\"", "history = \"constant\"")
    });
    let o = check(&path, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let solver = out
        .lines()
        .find(|l| l.starts_with("solver"))
        .expect("a solver line");
    assert!(
        solver.contains("sparse Cholesky (faer, AMD) of K"),
        "{solver}"
    );
    // No contact (its pressure is a constant load) and a step: r₀ = 0.
    let (path, _) = case_with("check-no-preload", |t| {
        let (head, rest) = t.split_once("[contact]").unwrap();
        format!("{head}{}", &rest[rest.find("[time]").unwrap()..])
    });
    let o = check(&path, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let solver = out.lines().find(|l| l.starts_with("solver")).unwrap();
    assert!(
        solver.contains("explicit: no linear system;") && !solver.contains("Cholesky"),
        "{solver}"
    );
}

#[test]
fn check_refuses_the_output_file_run_refuses_at_its_line() {
    for (name, file, words) in [
        ("out-nodir", "nodir/x.h5", "does not exist"),
        ("out-empty", "", "directory"),
    ] {
        let (case, text) = case_with(name, |t| {
            t.replace("file = \"slab.h5\"", &format!("file = \"{file}\""))
        });
        let line = line_of(&text, &format!("file = \"{file}\""));
        let at = format!("{}:{line}:", case.display());
        let o = check(&case, &[]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{file:?}: {e}");
        assert!(
            e.contains(&at) && e.contains("output.file") && e.contains(words),
            "{e}"
        );
        // `run` without -o refuses it the same way, at the same line.
        let o = common::bin().arg("run").arg(&case).output().unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{file:?}: {e}");
        assert!(e.contains(&at) && e.contains(words), "{e}");
        // `run -o` names its own file: the case's is not used.
        let o = run(&case, &case.with_extension("h5"), &["--quiet"]);
        assert!(o.status.success(), "{file:?}: {}", stderr(&o));
    }
}

/// tests/data/slab.toml on a copy of the committed quad9 slab (MSH 2.2)
/// whose group `emptied` has lost its elements, as Gmsh writes a
/// `Physical Curve` whose curves are missing: the name alone.
fn case_on_emptied_mesh(emptied: &str) -> (PathBuf, String) {
    let text = std::fs::read_to_string(meshes_dir().join("slab-q2-8x2-v22.msh")).unwrap();
    let tag = text
        .lines()
        .find_map(|l| {
            let l = l.strip_suffix(&format!(" \"{emptied}\""))?;
            l.strip_prefix("1 ")
        })
        .expect("the group in $PhysicalNames")
        .to_string();
    // Element lines `id type 2 PHYS GEOM nodes..`: drop the group's.
    let mut dropped = 0;
    let mut lines: Vec<String> = Vec::new();
    for l in text.lines() {
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() > 4 && f[1] == "8" && f[3] == tag {
            dropped += 1;
            continue;
        }
        lines.push(l.to_string());
    }
    assert!(dropped > 0);
    let at = lines.iter().position(|l| l == "$Elements").unwrap() + 1;
    let n: usize = lines[at].parse().unwrap();
    lines[at] = (n - dropped).to_string();
    let dir = scratch(&format!("empty-{emptied}"));
    let mesh = dir.join("slab.msh");
    std::fs::write(&mesh, lines.join("\n") + "\n").unwrap();
    let case_text = std::fs::read_to_string(data("slab.toml"))
        .unwrap()
        .replace("../../../../cases/meshes/slab-q2-8x2.msh", "slab.msh");
    let case = dir.join("case.toml");
    std::fs::write(&case, &case_text).unwrap();
    (case, case_text)
}

#[test]
fn an_empty_group_is_refused_at_the_line_naming_it() {
    for (group, key, needle) in [
        ("load", "traction.0.group", "group = \"load\""),
        ("support", "dirichlet.0.group", "group = \"support\""),
        ("contact", "contact.group", "group = \"contact\""),
    ] {
        let (case, text) = case_on_emptied_mesh(group);
        let o = check(&case, &[]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{group}: {e}");
        let line = line_of(&text, needle);
        assert!(
            e.lines().any(|m| m.contains(&format!("case.toml:{line}:"))
                && m.contains(&format!("{key} = \"{group}\""))
                && m.contains("has no elements")
                && m.contains("Physical Curve")),
            "{group}: {e}"
        );
    }
}

#[test]
fn a_contact_field_of_a_run_without_contact_says_there_was_none() {
    // The slab held on its bottom in y in place of the friction surface.
    let (case, _) = case_with("no-contact", |t| {
        let start = t.find("[contact]").unwrap();
        let end = t.find("[time]").unwrap();
        format!(
            "{}[[dirichlet]]\ngroup = \"contact\"\nuy = 0.0\n\n{}",
            &t[..start],
            &t[end..]
        )
    });
    let h5 = case.with_extension("h5");
    let o = run(&case, &h5, &["--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for args in [
        &["--at", "8,0", "--field", "friction_stress"][..],
        &[
            "--along",
            "contact",
            "--times",
            "0.01",
            "--field",
            "slip_velocity",
        ][..],
    ] {
        let o = probe(&h5, args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(
            e.contains("its run had no contact surface") && !e.contains("give a results file"),
            "{args:?}: {e}"
        );
    }
}
