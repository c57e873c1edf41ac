//! Issue 8 end to end: every class of bad input exits 2 with a message that
//! names the place and what to do; a run that blows up exits 1 and keeps its
//! steps; SIGINT/SIGTERM stop cleanly (exit 130) with a valid file; a
//! `kill -9` leaves a file h5py opens; `--restart` continues a file and is
//! bit-identical to a run that never stopped; `--json` prints one object.
//!
//! Expected values come from the case text (lines, keys), the slab's mesh
//! (its physical groups, shared/BENCHMARK.md) and the theory of the
//! central-difference scheme (Δt_crit); bit-identity is checked against an
//! uninterrupted run of the same binary, dataset by dataset, row by row.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use hdf5::types::{FloatSize, IntSize, TypeDescriptor, VarLenUnicode};
use stickslip_testkit::{scratch, workspace_root as root};

mod common;
use common::{bin, check, probe, python, python_has, stderr, tmpfs};

/// tests/data/slab.toml (t_end = 0.05, dt = 1e-3, central difference) with
/// an absolute mesh path, after `edit`, written into `dir`.
fn slab_case(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> (PathBuf, String) {
    let mesh = root().join("cases/meshes/slab-q2-8x2.msh");
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/slab.toml"))
            .unwrap()
            .replace(
                "../../../../cases/meshes/slab-q2-8x2.msh",
                &mesh.display().to_string(),
            );
    let text = edit(text);
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, &text).unwrap();
    (path, text)
}

/// A paper case (cases/martins-oden) with an absolute mesh path, in `dir`.
fn paper_case(dir: &Path, case: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join("cases/martins-oden").join(case))
        .unwrap()
        .replace(
            "\"../meshes/",
            &format!("\"{}/", root().join("cases/meshes").display()),
        );
    let path = dir.join(case);
    std::fs::write(&path, text).unwrap();
    path
}

/// 1-based line of the first line containing `needle` (from the test's text).
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle in text")
        + 1
}

/// `stickslip run CASE -o OUT --quiet --force ARGS...`.
fn run(case: &Path, out: &Path, args: &[&str]) -> Output {
    common::run(case, out, &[&["--quiet", "--force"], args].concat())
}

fn restart(case: &Path, out: &Path, args: &[&str]) -> Output {
    bin()
        .arg("run")
        .arg(case)
        .arg("--restart")
        .arg(out)
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

/// A restart of `out` that must be refused (exit 2) leaving the file's
/// bytes as they were: its stderr.
fn refused_restart(case: &Path, out: &Path, args: &[&str]) -> String {
    let before = std::fs::read(out).unwrap();
    let o = restart(case, out, args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(std::fs::read(out).unwrap() == before, "the file changed");
    e
}

/// Asserts exit 2 from both `check` and `run` (which must not create the
/// results file), and that the message has each of `words`; returns it.
fn refused(case: &Path, sets: &[&str], words: &[&str]) -> String {
    let o = check(case, sets);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "check: {e}");
    for w in words {
        assert!(e.contains(w), "expected {w:?} in:\n{e}");
    }
    assert!(e.lines().all(|l| l.starts_with("error: ")), "{e}");
    let out = case.with_extension("refused.h5");
    std::fs::remove_file(&out).ok();
    let mut c = bin();
    c.arg("run").arg(case).arg("-o").arg(&out).arg("--quiet");
    for s in sets {
        c.args(["--set", s]);
    }
    let o = c.output().unwrap();
    assert_eq!(o.status.code(), Some(2), "run: {}", stderr(&o));
    assert!(!out.exists(), "no results file for bad input");
    e
}

// ---------------------------------------------------------------------------
// 1. Bad input: one test per class, exit 2.

#[test]
fn unknown_keys_are_all_reported_with_the_nearest_key() {
    let dir = scratch("unknown");
    let (case, text) = slab_case(&dir, "unknown", |t| {
        t.replace("eps = 1e-4", "eps = 1e-4\nepsilon = 1")
            .replace("every = 1", "every = 1\nevry = 2")
            .replace("t_end = 0.05", "t_end = 0.05\nmu = 0.3")
    });
    let e = refused(&case, &[], &["did you mean `eps`", "did you mean `every`"]);
    for (needle, what) in [
        ("epsilon", "unknown field `epsilon` in [contact]"),
        ("evry", "unknown field `evry` in [output]"),
        ("\nmu = 0.3", "`mu` belongs in [contact]"),
    ] {
        // The misplaced `mu` is the line after t_end (the first "mu = 0.3"
        // is the one in [contact]).
        let l = if needle.starts_with('\n') {
            line_of(&text, "t_end = 0.05") + 1
        } else {
            line_of(&text, needle)
        };
        assert!(
            e.lines()
                .any(|m| m.contains(&format!("unknown.toml:{l}:")) && m.contains(what)),
            "{what} at line {l}:\n{e}"
        );
    }
    assert_eq!(e.lines().count(), 3, "one line per problem:\n{e}");
}

/// A whole number beyond i64 given by --set is too large, not text to
/// unquote: `--set` keeps what TOML cannot read as a string, and the
/// message said "write it without quotes"; a quoted one still is text.
#[test]
fn a_set_whole_number_too_large_is_called_so() {
    let dir = scratch("set-huge");
    let (case, _) = slab_case(&dir, "huge", |t| t);
    let e = refused(
        &case,
        &["output.every=18446744073709551615"],
        &["output.every"],
    );
    assert!(
        e.contains("beyond the largest") && !e.contains("without quotes"),
        "{e}"
    );
    let e = refused(&case, &["output.every=\"12\""], &["output.every"]);
    assert!(e.contains("without quotes") && !e.contains("beyond"), "{e}");
}

#[test]
fn wrong_types_name_the_key_and_the_type() {
    let dir = scratch("types");
    let (case, text) = slab_case(&dir, "types", |t| {
        t.replace("E = 1000.0", "E = \"1000\"")
            .replace("every = 1", "every = 1.5")
            .replace("t = [-150.0, 0.0]", "t = -150.0")
    });
    let e = refused(&case, &[], &[]);
    for (needle, what) in [
        (
            "E = \"1000\"",
            "material.E: expected a number, found the string \"1000\"",
        ),
        ("every = 1.5", "output.every: expected a whole number"),
        (
            "t = -150.0",
            "traction.0.t: expected a vector of two numbers",
        ),
    ] {
        let l = line_of(&text, needle);
        assert!(
            e.lines()
                .any(|m| m.contains(&format!("types.toml:{l}:")) && m.contains(what)),
            "{what} at line {l}:\n{e}"
        );
    }
    assert_eq!(e.lines().count(), 3, "{e}");
}

#[test]
fn out_of_range_values_and_other_problems_come_together() {
    let dir = scratch("range");
    let (case, text) = slab_case(&dir, "range", |t| {
        t.replace("eps = 1e-4", "eps = 0")
            .replace(
                "every = 1",
                "every = 1\ncompression = 12\nflush_seconds = 0\nflush_every = 0",
            )
            .replace("rho = 1.0", "rho = \"heavy\"")
            .replace("eps = 0", "eps = 0\nmux = 1")
    });
    let e = refused(&case, &[], &[]);
    let expect = [
        ("eps = 0", "contact.eps = 0 must be > 0"),
        (
            "compression = 12",
            "output.compression = 12 must be 0 (none) to 9",
        ),
        ("flush_seconds = 0", "output.flush_seconds = 0 must be > 0"),
        ("flush_every = 0", "output.flush_every must be >= 1"),
        ("rho = \"heavy\"", "material.rho: expected a number"),
        ("mux = 1", "did you mean `mu`"),
    ];
    for (needle, what) in expect {
        let l = line_of(&text, needle);
        assert!(
            e.lines()
                .any(|m| m.contains(&format!("range.toml:{l}:")) && m.contains(what)),
            "{what} at line {l}:\n{e}"
        );
    }
    assert_eq!(e.lines().count(), expect.len(), "{e}");
}

#[test]
fn a_component_fixed_twice_is_refused() {
    let dir = scratch("twice");
    let (case, text) = slab_case(&dir, "twice", |t| {
        t + "\n[[dirichlet]]\ngroup = \"support\"\nuy = 0.0\n"
    });
    let e = refused(
        &case,
        &[],
        &[
            "sets uy again",
            "already set by dirichlet.0",
            "give each component of a group once",
        ],
    );
    let last = text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "group = \"support\"")
        .last()
        .unwrap()
        .0
        + 1;
    assert!(e.contains(&format!("twice.toml:{last}:")), "{e}");
}

#[test]
fn mesh_problems_are_gathered_and_list_the_groups() {
    // The slab mesh has contact, load, support, left (lines) and body (cells).
    let dir = scratch("groups");
    let (case, text) = slab_case(&dir, "groups", |t| {
        t.replace("group = \"contact\"", "group = \"body\"")
            .replace("group = \"load\"", "group = \"right\"")
    });
    let e = refused(
        &case,
        &[],
        &[
            "has no physical group \"right\"",
            "\"support\" (dim 1)",
            "\"body\" (dim 2)",
            "contact.group = \"body\"",
            "has dimension 2",
        ],
    );
    assert!(
        e.contains(&format!("groups.toml:{}:", line_of(&text, "\"right\""))),
        "{e}"
    );
    assert!(
        e.contains(&format!("groups.toml:{}:", line_of(&text, "\"body\""))),
        "{e}"
    );
    assert_eq!(e.lines().count(), 2, "{e}");
}

#[test]
fn a_contact_surface_held_in_its_tangent_is_refused() {
    // ux = 0 on the whole (horizontal) contact line: friction could act
    // nowhere; before, it was dropped silently and the file had no /contact.
    let dir = scratch("held-contact");
    let (case, _) = slab_case(&dir, "held", |t| {
        t.replace(
            "[contact]",
            "[[dirichlet]]\ngroup = \"contact\"\nux = 0.0\n\n[contact]",
        )
    });
    let e = refused(&case, &[], &["can slide", "friction would act nowhere"]);
    assert!(e.contains("held.toml:"), "{e}");
}

#[test]
fn a_floating_part_under_unbalanced_preloads_is_refused() {
    // Without the left end's ux = 0 nothing holds the slab in x. With the
    // end load H(t) the loads before t = 0 (the contact pressure, reacted
    // by the top's rollers) are in equilibrium and the case runs; with the
    // end load "constant" they push the slab in x (net force −150 per unit
    // height on the end of height 1) and the static preload does not exist.
    let dir = scratch("rigid");
    let floating = |t: String| {
        t.replace(
            "[[dirichlet]]        # the left end is held in x\ngroup = \"left\"\nux = 0.0\n",
            "",
        )
    };
    let (case, _) = slab_case(&dir, "balanced", floating);
    let o = run(&case, &dir.join("balanced.h5"), &[]);
    assert!(
        o.status.success() && !stderr(&o).contains("no friction acts"),
        "{}",
        stderr(&o)
    );
    // `check` says which motions are free, and that friction holds them
    // (the slab's contact has mu = 0.3).
    let o = check(&case, &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success()
            && out.contains(
                "floating    the supports leave free: translation in x (held by friction alone);"
            )
            && !out.contains("nothing holds"),
        "{out}{}",
        stderr(&o)
    );
    // With mu = 0 no friction acts: nothing holds the part in x, which
    // `check` says and warns of, and a run warns of before its first step.
    let o = check(&case, &["contact.mu=0.0"]);
    let out = String::from_utf8_lossy(&o.stdout);
    let warning = "the supports leave free translation in x and no friction acts along it: nothing holds the part there";
    assert!(
        o.status.success()
            && out.contains(
                "floating    the supports leave free: translation in x (nothing holds it: no friction acts along it);"
            )
            && !out.contains("held by friction")
            && out.contains(&format!("warning     {warning}")),
        "{out}{}",
        stderr(&o)
    );
    let mut c = bin();
    c.arg("run")
        .arg(&case)
        .arg("-o")
        .arg(dir.join("frictionless.h5"))
        .args([
            "--quiet",
            "--force",
            "--set",
            "contact.mu=0.0",
            "--set",
            "time.t_end=2e-3",
        ]);
    let o = c.output().unwrap();
    let e = stderr(&o);
    assert!(
        e.contains(&format!("balanced.toml: warning: {warning}")),
        "{e}"
    );
    let (case, text) = slab_case(&dir, "unbalanced", |t| {
        floating(t).replace("history = \"step\"", "history = \"constant\"")
    });
    refused(
        &case,
        &[],
        &[
            &format!("unbalanced.toml:{}:", line_of(&text, "group = \"support\"")),
            "not in equilibrium",
            "translation in x: net force F_x = -1.5",
            "state = \"rest\"",
        ],
    );
    // Started at rest, the same case needs no static state and runs.
    let (case, _) = slab_case(&dir, "rest", |t| {
        floating(t).replace("history = \"step\"", "history = \"constant\"")
            + "\n[initial]\nstate = \"rest\"\n"
    });
    let o = run(&case, &dir.join("rest.h5"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A part with no [[dirichlet]] at all whose preload (the contact
/// pressure, present before t = 0) is not in equilibrium: the refusal
/// named a [[dirichlet]] table the case does not have, at no line; it is
/// now at the pressure's line, under [contact].
#[test]
fn an_unbalanced_preload_without_supports_is_placed_at_the_pressure() {
    let dir = scratch("unbalanced-free");
    let (case, text) = slab_case(&dir, "free", |t| {
        t.replace(
            "[[dirichlet]]        # rollers on the top face\ngroup = \"support\"\nuy = 0.0\n",
            "",
        )
        .replace(
            "[[dirichlet]]        # the left end is held in x\ngroup = \"left\"\nux = 0.0\n",
            "",
        )
    });
    assert!(!text.contains("[[dirichlet]]"), "{text}");
    let e = refused(&case, &[], &["not in equilibrium", "F_y"]);
    let at = format!("free.toml:{}:", line_of(&text, "pressure = 300.0"));
    assert!(e.contains(&at) && e.contains("[contact]: "), "{e}");
    assert!(!e.contains("[[dirichlet]]:"), "{e}");
}

/// Friction holds a free motion only where it acts along it: the slab
/// without its top's rollers is free in y, which the friction of its
/// bottom face (along x) cannot hold, and a compliant floor with μ = 0
/// holds y but not x. `check` said "held there by friction alone" of
/// every free motion wherever a contact surface was, and neither it nor
/// the run warned; the slab then left along y (u_y = ½·300·t²).
#[test]
fn a_motion_friction_cannot_hold_is_named_and_warned_of() {
    let dir = scratch("unheld-y");
    let (case, _) = slab_case(&dir, "free-y", |t| {
        t.replace(
            "[[dirichlet]]        # rollers on the top face\ngroup = \"support\"\nuy = 0.0\n",
            "",
        )
        .replace(
            "pressure = 300.0",
            "pressure = 300.0\npressure_history = \"step\"",
        )
    });
    let o = check(&case, &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    let warning = "the supports leave free translation in y and no friction acts along it";
    assert!(
        o.status.success()
            && out.contains(
                "floating    the supports leave free: translation in y (nothing holds it: no friction acts along it);"
            )
            && out.contains(&format!("warning     {warning}")),
        "{out}{}",
        stderr(&o)
    );
    let o = run(&case, &dir.join("free-y.h5"), &["--set", "time.t_end=2e-3"]);
    assert!(
        o.status.success() && stderr(&o).contains(warning),
        "{}",
        stderr(&o)
    );
    // Held in y at its left end only: friction holds the x translation and
    // the rotation about the end's middle each, but not their sum, a
    // rotation about the bottom corner that moves the bottom along its
    // normal (the slab left by 39.7 without a word).
    let (case, _) = slab_case(&dir, "corner", |t| {
        t.replace(
            "[[dirichlet]]        # rollers on the top face\ngroup = \"support\"\nuy = 0.0\n",
            "",
        )
        .replace("group = \"left\"\nux = 0.0", "group = \"left\"\nuy = 0.0")
        .replace(
            "pressure = 300.0",
            "pressure = 300.0\npressure_history = \"step\"",
        )
    });
    let o = check(&case, &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success()
            && out.contains(
                "warning     the supports leave free a combination of translation in x and rotation about"
            ),
        "{out}{}",
        stderr(&o)
    );
}
#[test]
fn bad_damping_and_initial_velocities_are_refused_at_their_lines() {
    let dir = scratch("damping-input");
    let with_damping = |d: &'static str| {
        move |t: String| t.replace("rho = 1.0", &format!("rho = 1.0\ndamping = {d}"))
    };
    let (case, text) = slab_case(&dir, "negative", with_damping("{ alpha = -1.0 }"));
    refused(
        &case,
        &[],
        &[
            &format!("negative.toml:{}:", line_of(&text, "alpha = -1.0")),
            "material.damping.alpha = -1 must be a finite number >= 0",
        ],
    );
    // β = 1: at the slab's ω_max (about 1.1e3, Δt_crit = 5.6e-3 undamped)
    // ξ ≈ 560 and Δt_crit ≈ 1.6e-6, far below time.dt = 1e-3.
    let (case, text) = slab_case(&dir, "too-damped", with_damping("{ beta = 1.0 }"));
    refused(
        &case,
        &[],
        &[
            &format!("too-damped.toml:{}:", line_of(&text, "beta = 1.0")),
            "Rayleigh damping beta = 1e0",
            "lower material.damping.beta",
            "newmark",
        ],
    );
    // β = 1e10: ξ ≈ 1.8e12 and Δt_crit ≈ 1.6e-15, 3e13 steps to t_end.
    let (case, text) = slab_case(&dir, "no-step", with_damping("{ beta = 1e10 }"));
    refused(
        &case,
        &[],
        &[
            &format!("no-step.toml:{}:", line_of(&text, "beta = 1e10")),
            "no usable stable step",
        ],
    );
    let (case, text) = slab_case(&dir, "velocity-group", |t| {
        t + "\n[[initial.velocities]]\ngroup = \"nowhere\"\nvelocity = [1.0, 0.0]\n"
    });
    refused(
        &case,
        &[],
        &[
            &format!("velocity-group.toml:{}:", line_of(&text, "\"nowhere\"")),
            "no physical group \"nowhere\"",
        ],
    );
    let (case, text) = slab_case(&dir, "velocity-length", |t| {
        t + "\n[initial]\nvelocity = [1.0]\n"
    });
    refused(
        &case,
        &[],
        &[
            &format!(
                "velocity-length.toml:{}:",
                line_of(&text, "velocity = [1.0]")
            ),
            "a vector of two numbers",
        ],
    );
}

/// A damped run books the damping's dissipation in /energy/damped: 0 at
/// the start, never decreasing, positive at the end; an undamped run's
/// series is all zeros.
#[test]
fn a_damped_run_writes_its_damped_energy() {
    let dir = scratch("damped-energy");
    for (name, damping, positive) in [
        ("damped", "\ndamping = { alpha = 5.0, beta = 1e-4 }", true),
        ("undamped", "", false),
    ] {
        let (case, _) = slab_case(&dir, name, |t| {
            t.replace("rho = 1.0", &format!("rho = 1.0{damping}"))
        });
        let out = dir.join(format!("{name}.h5"));
        let o = run(&case, &out, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        let f = hdf5::File::open(&out).unwrap();
        let d: Vec<f64> = f.dataset("energy/damped").unwrap().read_raw().unwrap();
        assert_eq!(d[0], 0.0);
        assert!(d.windows(2).all(|w| w[1] >= w[0]), "{name}: {d:?}");
        assert_eq!(*d.last().unwrap() > 0.0, positive, "{name}: {d:?}");
    }
}

#[test]
fn quasi_static_with_a_motion_only_friction_would_hold_is_refused() {
    // The slab pressed on its rough base without the left end's ux = 0:
    // friction (g = 90 over Γ_C) would hold it in x, but quasi-static
    // increments factorize Δt K, so the supports must hold every motion;
    // refused before any work, the motion named, at the [[dirichlet]].
    let dir = scratch("rigid-qs");
    let (case, text) = slab_case(&dir, "rigid", |t| {
        t.replace(
            "[[dirichlet]]        # the left end is held in x\ngroup = \"left\"\nux = 0.0\n",
            "",
        )
        .replace(
            "scheme = \"central_difference\"",
            "scheme = \"quasi_static\"",
        )
    });
    assert!(
        text.contains("quasi_static"),
        "the template's scheme changed"
    );
    let e = refused(
        &case,
        &[],
        &[
            "rigid-body motion free",
            "quasi-static increments",
            "translation in x",
        ],
    );
    // At the first [[dirichlet]]'s group.
    let line = line_of(&text, "[[dirichlet]]") + 1;
    assert!(e.contains(&format!("rigid.toml:{line}:")), "{e}");
}

#[test]
fn a_missing_mesh_file_is_refused() {
    let dir = scratch("nomesh");
    let (case, text) = slab_case(&dir, "nomesh", |t| {
        t.replace("slab-q2-8x2.msh", "no-such-mesh.msh")
    });
    refused(
        &case,
        &[],
        &[
            &format!("nomesh.toml:{}:", line_of(&text, "no-such-mesh")),
            "does not exist",
        ],
    );
}

#[test]
fn dt_above_the_critical_step_is_refused_with_dt_crit() {
    let dir = scratch("dtcrit");
    let (case, text) = slab_case(&dir, "dtcrit", |t| t.replace("dt = 1e-3", "dt = 6e-3"));
    refused(
        &case,
        &[],
        &[
            &format!("dtcrit.toml:{}:", line_of(&text, "dt = 6e-3")),
            "Δt_crit = 5.59",
            "allow_unstable",
        ],
    );
}

// ---------------------------------------------------------------------------
// 2. A run that fails: exit 1, every step kept, reason in the file.

/// A foundation stiffening with the approach (m_n = 2, c_n = 1e10) run
/// past its bound by time.allow_unstable blows up at a Δt below Δt_crit:
/// the message says so, not that Δt is above Δt_crit (which it is not).
#[test]
fn a_stiffening_foundation_blow_up_says_what_made_it() {
    let dir = scratch("stiffening-blowup");
    let mesh = root().join("cases/meshes/slab-q1-16x4.msh");
    let text = format!(
        "[mesh]\nfile = \"{}\"\n[material]\nE = 1000.0\nnu = 0.3\nrho = 1.0\n\
         [[dirichlet]]\ngroup = \"left\"\nux = 0.0\n\
         [[traction]]\ngroup = \"support\"\npressure = 300.0\nhistory = \"step\"\n\
         [contact]\ngroup = \"contact\"\nlaw = \"compliance\"\n\
         foundation = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\ncn = 1e10\nmn = 2.0\nmu = 0.0\neps = 1e-3\n\
         [initial]\nstate = \"rest\"\n\
         [time]\nscheme = \"central_difference\"\ndt = 1e-3\nt_end = 0.2\nallow_unstable = true\n",
        mesh.display()
    );
    let case = dir.join("stiff.toml");
    std::fs::write(&case, text).unwrap();
    let o = run(&case, &dir.join("stiff.h5"), &[]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("energy blow-up"), "{e}");
    assert!(
        e.contains("below its critical step") && !e.contains("above its critical step"),
        "{e}"
    );
}

#[test]
fn an_unstable_explicit_run_stops_at_the_blow_up_and_keeps_its_steps() {
    // dt = 6e-3 > Δt_crit = 5.6e-3 (printed by `check`): with
    // allow_unstable the highest mode grows by |λ|² ≈ 4.5 per step
    // (ωΔt ≈ 2.14), so the energy leaves the physical bound within a few steps.
    let dir = scratch("blowup");
    let (case, _) = slab_case(&dir, "blowup", |t| {
        t.replace("dt = 1e-3", "dt = 6e-3\nallow_unstable = true")
            .replace("t_end = 0.05", "t_end = 20.0")
    });
    let out = dir.join("blowup.h5");
    let o = run(&case, &out, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    for w in [
        "energy blow-up",
        "dt_crit = 5.59",
        "use time.dt < 5.59",
        "complete = false",
    ] {
        assert!(e.contains(w), "{w:?} in {e}");
    }
    let f = hdf5::File::open(&out).unwrap();
    assert!(!f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
    let why = f
        .attr("failure")
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap();
    assert!(why.as_str().contains("energy blow-up"), "{}", why.as_str());
    let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    let steps = f
        .group("solver")
        .unwrap()
        .attr("steps")
        .unwrap()
        .read_scalar::<u64>()
        .unwrap();
    assert_eq!(
        t.len() as u64,
        steps + 1,
        "every = 1: every step kept, t = 0 included"
    );
    assert!(t.len() < 20.0f64.div_euclid(6e-3) as usize, "stopped early");
    let k = f
        .dataset("energy/kinetic")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    let s = f
        .dataset("energy/strain")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    let w = f
        .dataset("energy/external_work")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    let d = f
        .dataset("energy/dissipated")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    assert!(
        k.iter().chain(&s).all(|x| x.is_finite()),
        "stopped before overflow"
    );
    // Detection delay: rows from the first one above the physical bound
    // K + U <= E0 + |W| + D (METHOD.md §6) to the stop.
    let e0 = k[0] + s[0];
    let first = (0..t.len())
        .find(|&i| k[i] + s[i] > e0 + w[i].abs() + d[i])
        .expect("the energy left the physical bound");
    assert!(
        t.len() - 1 - first <= 5,
        "detected {} steps after the energy left its bound",
        t.len() - 1 - first
    );
}

// ---------------------------------------------------------------------------
// 3. Interruption.

/// Starts a long run (t_end = 200: 200,000 steps; t_end = 50 took 0.84 s
/// with every step written uncompressed on this machine, 2026-11-24, so
/// about 3 s) in the background, waits `secs` after its results file
/// appears.
fn start_long(case: &Path, out: &Path, extra: &[&str], secs: f64) -> Child {
    let child = bin()
        .arg("run")
        .arg(case)
        .arg("-o")
        .arg(out)
        .args(["--force", "--set", "time.t_end=200"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !out.exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_secs_f64(secs));
    child
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

/// Runs a Python snippet with h5py on `path` (skipped when h5py is missing,
/// except under CI).
fn h5py(script: &str, path: &Path) -> Option<String> {
    let has = python_has(
        "h5py",
        "h5py is missing",
        "skipping the h5py check: h5py is not installed",
    );
    let script = script.replace("PY_SLOT", PY_SLOT);
    has.then(|| python(&script, &[path]).trim().to_string())
}

const H5PY_INTERRUPTED: &str = r#"
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
n = f["time"].shape[0]
assert not f.attrs["complete"]
assert "interrupted by" in f.attrs["failure"]
for name in ("displacement", "velocity", "acceleration"):
    assert f[name].shape[0] == n and np.isfinite(f[name][-1]).all(), name
for name in ("kinetic", "strain", "external_work", "dissipated", "total", "balance"):
    assert f["energy/" + name].shape == (n,), name
assert f["contact/state"].shape[0] == n
PY_SLOT
assert c.attrs["rows"] == n and c.attrs["t"] == f["time"][-1], (c.attrs["rows"], n)
assert np.all(np.diff(f["time"][:]) > 0)
print(n)
"#;

#[test]
fn sigint_and_sigterm_stop_cleanly_with_a_valid_file() {
    let dir = scratch("sigint");
    let (case, _) = slab_case(&dir, "sigint", |t| t);
    // SIGHUP: a closed terminal or a dropped ssh session (it ended the run
    // between flushes, with no message and no checkpoint of its last steps).
    for sig in ["SIGINT", "SIGTERM", "SIGHUP"] {
        let out = dir.join(format!("{sig}.h5"));
        let child = start_long(&case, &out, &[], 1.0);
        signal(&child, &format!("-{}", &sig[3..]));
        let o = child.wait_with_output().unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(130), "{sig}: {e}");
        assert!(
            e.contains(&format!("interrupted by {sig}: stopped after step"))
                && e.contains("--restart"),
            "{e}"
        );
        // The command it suggests repeats the run's --set overrides (a
        // restart without them was refused).
        assert!(
            e.contains(&format!("--restart {} --set time.t_end=200", out.display())),
            "{e}"
        );
        // Through the hdf5 crate: a valid, incomplete file whose last row is
        // the step it stopped at (every = 1) and whose checkpoint is that step.
        let f = hdf5::File::open(&out).unwrap();
        assert!(!f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
        let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
        let n = t.len();
        assert!(n > 10, "{sig}: ran a while before the signal: {n} rows");
        assert!(t[n - 1] < 200.0, "stopped mid-run");
        let cp = slot(&f);
        let rows = cp.attr("rows").unwrap().read_scalar::<u64>().unwrap();
        let steps = cp.attr("steps").unwrap().read_scalar::<u64>().unwrap();
        let tc = cp.attr("t").unwrap().read_scalar::<f64>().unwrap();
        assert_eq!((rows as usize, steps as usize, tc), (n, n - 1, t[n - 1]));
        for name in ["displacement", "velocity", "acceleration"] {
            assert_eq!(f.dataset(name).unwrap().shape()[0], n, "{name}");
        }
        let u = f
            .dataset("displacement")
            .unwrap()
            .read_raw::<f64>()
            .unwrap();
        assert!(u.iter().all(|x| x.is_finite()));
        assert!(e.contains(&format!("holds {n} records")), "{e}");
        drop(f);
        if let Some(p) = h5py(H5PY_INTERRUPTED, &out) {
            assert_eq!(p, n.to_string());
        }
    }
}

/// The same signal sent twice at once (GNU `timeout -s INT` signals the
/// process and then its group) is one Ctrl-C: the run stops cleanly with
/// its checkpoint. It was taken for a second Ctrl-C and exited at once,
/// leaving a new file with no checkpoint to continue from.
#[test]
fn a_signal_sent_twice_at_once_stops_the_run_cleanly() {
    let dir = scratch("sigint-twice");
    let (case, _) = slab_case(&dir, "twice", |t| t);
    let out = dir.join("twice.h5");
    let child = start_long(&case, &out, &[], 0.3);
    // Two kills a process start apart (one kill of the pid twice is one
    // signal: the second finds the first pending). The run may be gone
    // before the second.
    signal(&child, "-INT");
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(
        e.contains("interrupted by SIGINT") && !e.contains("second signal"),
        "{e}"
    );
}

/// An interrupted run's last step is a frame, as a completed run's is,
/// so that probe and the viewers show the state it stopped at
/// (with output.frames it was not: the frames ended before it); the
/// checkpoint leaves that frame out, so the continued run is still bit
/// for bit the run that never stopped.
#[test]
fn an_interrupted_run_ends_on_a_frame_and_restarts_as_if_never_stopped() {
    let dir = scratch("sigterm-frame");
    let (case, _) = slab_case(&dir, "frames", |t| t);
    let frames = ["--set", "output.frames=20"];
    let out = dir.join("part.h5");
    let child = start_long(&case, &out, &frames, 0.5);
    signal(&child, "-TERM");
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let f = hdf5::File::open(&out).unwrap();
    let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    let ft = f.dataset("frames/time").unwrap().read_raw::<f64>().unwrap();
    assert!(
        t.len() > 10 && *t.last().unwrap() < 200.0,
        "{} rows",
        t.len()
    );
    assert_eq!(
        ft.last().map(|x| x.to_bits()),
        t.last().map(|x| x.to_bits())
    );
    drop(f);
    let sets = ["--set", "time.t_end=200", "--set", "output.frames=20"];
    ok(&restart(&case, &out, &sets));
    let full = dir.join("full.h5");
    ok(&run(&case, &full, &sets));
    assert_same_datasets(&full, &out);
}

// ---------------------------------------------------------------------------
// 5. Restart: bit-identical to a run that never stopped.

/// The current checkpoint slot of a results file (output.rs: two slots,
/// `/checkpoint.slot` names the current one).
fn slot(f: &hdf5::File) -> hdf5::Group {
    let c = f.group("checkpoint").unwrap();
    let k = c.attr("slot").unwrap().read_scalar::<u8>().unwrap();
    c.group(["a", "b"][k as usize]).unwrap()
}

fn checkpoint_attr<T: hdf5::H5Type>(path: &Path, name: &str) -> T {
    let f = hdf5::File::open(path).unwrap();
    let g = slot(&f);
    g.attr(name).unwrap().read_scalar::<T>().unwrap()
}

/// Python: `c` = the current checkpoint slot of file `f`.
const PY_SLOT: &str = r#"c = f["checkpoint"][("a", "b")[int(f["checkpoint"].attrs["slot"])]]"#;

/// Every dataset of `a` equals the one of `b` (same shape, same bits, row
/// by row; the first differing row is reported), the current checkpoint
/// slots included. The other slot holds an older checkpoint whose step
/// depends on when time-based flushes fell, so it is not compared.
fn assert_same_datasets(a: &Path, b: &Path) {
    fn walk(g: &hdf5::Group, prefix: &str, out: &mut Vec<String>) {
        for name in g.member_names().unwrap() {
            let path = format!("{prefix}/{name}");
            if let Ok(sub) = g.group(&name) {
                walk(&sub, &path, out);
            } else {
                out.push(path);
            }
        }
    }
    let (fa, fb) = (hdf5::File::open(a).unwrap(), hdf5::File::open(b).unwrap());
    let (mut na, mut nb) = (Vec::new(), Vec::new());
    walk(&fa, "", &mut na);
    walk(&fb, "", &mut nb);
    na.retain(|n| !n.starts_with("/checkpoint/"));
    nb.retain(|n| !n.starts_with("/checkpoint/"));
    assert_eq!(na, nb, "same datasets");
    let (sa, sb) = (slot(&fa), slot(&fb));
    let mut pairs: Vec<(String, hdf5::Dataset, hdf5::Dataset)> = na
        .iter()
        .map(|n| (n.clone(), fa.dataset(n).unwrap(), fb.dataset(n).unwrap()))
        .collect();
    for n in sa.member_names().unwrap() {
        pairs.push((
            format!("checkpoint slot/{n}"),
            sa.dataset(&n).unwrap(),
            sb.dataset(&n).unwrap(),
        ));
    }
    // Not `factorizations`: it counts work done, and a restarted run must
    // factorize again (the factors are not saved), so it is larger by design.
    for attr in [
        "t",
        "steps",
        "rows",
        "reduced_remaining",
        "total_iterations",
        "normal_iterations",
    ] {
        let (x, y) = (sa.attr(attr).unwrap(), sb.attr(attr).unwrap());
        let bits = |a: &hdf5::Attribute| match a.dtype().unwrap().to_descriptor().unwrap() {
            TypeDescriptor::Float(_) => a.read_scalar::<f64>().unwrap().to_bits(),
            _ => a.read_scalar::<u64>().unwrap(),
        };
        assert_eq!(bits(&x), bits(&y), "checkpoint {attr}");
    }
    for (name, da, db) in &pairs {
        let (da, db) = (da.clone(), db.clone());
        assert_eq!(da.shape(), db.shape(), "{name}: shape");
        let row = da.shape().iter().skip(1).product::<usize>().max(1);
        let bits: fn(&hdf5::Dataset) -> Vec<u64> =
            match da.dtype().unwrap().to_descriptor().unwrap() {
                TypeDescriptor::Float(FloatSize::U8) => |d| {
                    d.read_raw::<f64>()
                        .unwrap()
                        .iter()
                        .map(|x| x.to_bits())
                        .collect()
                },
                TypeDescriptor::Integer(IntSize::U8) => |d| {
                    d.read_raw::<i64>()
                        .unwrap()
                        .iter()
                        .map(|&x| x as u64)
                        .collect()
                },
                TypeDescriptor::Integer(IntSize::U1) => |d| {
                    d.read_raw::<i8>()
                        .unwrap()
                        .iter()
                        .map(|&x| x as u64)
                        .collect()
                },
                TypeDescriptor::Unsigned(IntSize::U4) => |d| {
                    d.read_raw::<u32>()
                        .unwrap()
                        .iter()
                        .map(|&x| x as u64)
                        .collect()
                },
                TypeDescriptor::Unsigned(IntSize::U8) => |d| d.read_raw::<u64>().unwrap(),
                other => panic!("{name}: unexpected type {other:?}"),
            };
        let (va, vb) = if da.size() == 0 {
            (Vec::new(), Vec::new())
        } else {
            (bits(&da), bits(&db))
        };
        if let Some(i) = (0..va.len()).find(|&i| va[i] != vb[i]) {
            panic!("{name}: first difference in row {} (entry {i})", i / row);
        }
    }
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        stderr(o)
    );
}

/// Checkpoints go by wall time: a run of milliseconds (tests/data/slab.toml,
/// 50 steps) writes one, its last, where `flush_every = 100` wrote one
/// before the first step and one at the end. Each checkpoint goes into the
/// slot the one before did not use, the first into a (0), so the current
/// slot counts them: one checkpoint leaves slot a; with `flush_every = 25`
/// a flush after step 25 and the last make two, slot b; with
/// `flush_seconds` below any setup's time, the initial state's checkpoint
/// and one after each step (the last step's flush is the last
/// checkpoint) make 1 + 49 + 1 = 51, slot a.
#[test]
fn a_short_run_checkpoints_by_wall_time() {
    let dir = scratch("flush-by-time");
    let (case, _) = slab_case(&dir, "flush", |t| t);
    let slot_of = |o: &Path| {
        let f = hdf5::File::open(o).unwrap();
        let c = f.group("checkpoint").unwrap();
        c.attr("slot").unwrap().read_scalar::<u8>().unwrap()
    };
    for (sets, slot) in [
        (vec![], 0),
        (vec!["--set", "output.flush_every=25"], 1),
        (vec!["--set", "output.flush_seconds=1e-9"], 0),
    ] {
        let out = dir.join("f.h5");
        ok(&run(&case, &out, &sets));
        assert_eq!(slot_of(&out), slot, "{sets:?}");
        // Whatever the checkpoints, the restart to a later t_end starts
        // from the last (the state before the last step) and the file holds
        // every record.
        assert_eq!(checkpoint_attr::<u64>(&out, "steps"), 49, "{sets:?}");
        let f = hdf5::File::open(&out).unwrap();
        assert_eq!(f.dataset("time").unwrap().size(), 51, "{sets:?}");
    }
}

#[test]
fn restart_after_an_earlier_t_end_is_bit_identical_central_difference() {
    // t_end = 0.1374 is not on the Δt grid: the short run's last step is
    // shortened to land on it, and the restart must redo that step at full
    // length. every = 3 checks the output grid across the restart.
    let dir = scratch("restart-cd");
    let (case, _) = slab_case(&dir, "cd", |t| t);
    for every in ["1", "3"] {
        let set_every = format!("output.every={every}");
        let full = dir.join(format!("full-{every}.h5"));
        ok(&run(
            &case,
            &full,
            &["--set", "time.t_end=0.3", "--set", &set_every],
        ));
        let part = dir.join(format!("part-{every}.h5"));
        ok(&run(
            &case,
            &part,
            &["--set", "time.t_end=0.1374", "--set", &set_every],
        ));
        ok(&restart(
            &case,
            &part,
            &["--set", "time.t_end=0.3", "--set", &set_every],
        ));
        assert_same_datasets(&full, &part);
        let f = hdf5::File::open(&part).unwrap();
        assert!(f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
        assert!(f.attr("failure").is_err());
    }
}

#[test]
fn restart_after_sigint_is_bit_identical_central_difference() {
    let dir = scratch("restart-int");
    let (case, _) = slab_case(&dir, "int", |t| t);
    let part = dir.join("part.h5");
    let child = start_long(&case, &part, &["--quiet"], 0.5);
    signal(&child, "-INT");
    assert_eq!(child.wait_with_output().unwrap().status.code(), Some(130));
    let t = checkpoint_attr::<f64>(&part, "t");
    let t_end = format!("time.t_end={}", (t + 0.25).ceil());
    ok(&restart(&case, &part, &["--set", &t_end]));
    let full = dir.join("full.h5");
    ok(&run(&case, &full, &["--set", &t_end]));
    assert_same_datasets(&full, &part);
}

#[test]
fn restart_after_kill_9_reads_in_h5py_and_is_bit_identical() {
    // kill -9 gives no chance to clean up: the file holds what the last
    // flush wrote (flush_seconds = 0.1 here), h5py opens it, and --restart
    // drops any row written after the checkpoint. Deflated: a compressed
    // chunk rewritten after a flush moves in the file (output.rs), the
    // case this guards.
    let dir = scratch("restart-kill");
    let (case, _) = slab_case(&dir, "kill", |t| t);
    let part = dir.join("part.h5");
    let mut child = start_long(
        &case,
        &part,
        &[
            "--quiet",
            "--set",
            "output.flush_seconds=0.1",
            "--set",
            "output.compression=4",
        ],
        1.0,
    );
    child.kill().unwrap();
    child.wait().unwrap();
    let py = h5py(
        r#"
import sys, h5py
f = h5py.File(sys.argv[1], "r")
PY_SLOT
assert not f.attrs["complete"]
n = int(c.attrs["rows"])
assert f["time"].shape[0] >= n >= 2, (f["time"].shape, n)
# Every flushed row reads back (decompresses) and is finite.
import numpy as np
for name in ("time", "displacement", "velocity", "acceleration", "contact/friction_stress",
             "contact/state", "energy/total", "solver/dt"):
    assert np.isfinite(f[name][:n]).all(), name
assert f["time"][n - 1] == c.attrs["t"]
print(c.attrs["t"])
"#,
        &part,
    );
    let t: f64 = match py {
        Some(s) => s.parse().unwrap(),
        None => checkpoint_attr::<f64>(&part, "t"),
    };
    let t_end = format!("time.t_end={}", (t + 0.25).ceil());
    ok(&restart(&case, &part, &["--set", &t_end]));
    let full = dir.join("full.h5");
    ok(&run(&case, &full, &["--set", &t_end]));
    assert_same_datasets(&full, &part);
}

/// The bits of the last record's time and displacement in `path`.
fn last_record(path: &Path) -> (u64, Vec<u64>) {
    let f = hdf5::File::open(path).unwrap();
    let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    let r = f
        .dataset("displacement")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    let row = r.len() / t.len();
    let last = t.len() - 1;
    (
        t[last].to_bits(),
        r[last * row..].iter().map(|x| x.to_bits()).collect(),
    )
}

#[test]
fn restart_in_a_step_reduction_is_bit_identical_newmark() {
    // Newmark 1/4, 1/2 with Remark 4.3's reduction (dt 5e-3 cut to 1e-7 for
    // 10 steps after sticking). The short run ends half a reduced step
    // after a reduced step, so its checkpoint (taken before its shortened
    // last step) has the reduction counter running; written every step and
    // every second step.
    for (every, product) in [("1", "paired node blocks"), ("2", "paired node blocks")] {
        let dir = scratch(&format!("restart-nm-{every}"));
        let case = paper_case(&dir, "newmark-step-reduced.toml");
        let every = format!("output.every={every}");
        let full = dir.join("full.h5");
        ok(&run(
            &case,
            &full,
            &["--set", "time.t_end=0.3", "--set", &every],
        ));
        let f = hdf5::File::open(&full).unwrap();
        let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
        let dt = f.dataset("solver/dt").unwrap().read_raw::<f64>().unwrap();
        let used: String = f
            .group("solver")
            .unwrap()
            .attr("stiffness_product")
            .unwrap()
            .read_scalar::<hdf5::types::VarLenUnicode>()
            .unwrap()
            .as_str()
            .to_string();
        assert_eq!(used, product, "{every}");
        drop(f);
        let k = (1..dt.len() - 3)
            .find(|&k| dt[k] == 1e-7 && dt[k + 1] == 1e-7 && dt[k + 2] == 1e-7)
            .expect("a stick event with reduced steps before t = 0.3");
        let t1 = t[k] + 0.5e-7;
        let part = dir.join("part.h5");
        ok(&run(
            &case,
            &part,
            &["--set", &format!("time.t_end={t1:e}"), "--set", &every],
        ));
        let remaining = checkpoint_attr::<u64>(&part, "reduced_remaining");
        assert!(remaining > 0, "{every}: checkpoint inside a reduction");
        ok(&restart(
            &case,
            &part,
            &["--set", "time.t_end=0.3", "--set", &every],
        ));
        assert_same_datasets(&full, &part);
        // And across a plain restart point (no reduction running), with
        // the output cadence changed: the stored run's solver continues.
        let part2 = dir.join("part2.h5");
        ok(&run(
            &case,
            &part2,
            &["--set", "time.t_end=0.1", "--set", &every],
        ));
        let other = if every.ends_with('1') {
            "output.every=2"
        } else {
            "output.every=1"
        };
        ok(&restart(
            &case,
            &part2,
            &["--set", "time.t_end=0.3", "--set", other],
        ));
        assert_eq!(
            last_record(&part2),
            last_record(&full),
            "{every}: the last state, bit for bit, after a restart with {other}"
        );
    }
}

#[test]
fn restart_refuses_changed_physics_and_an_earlier_t_end() {
    let dir = scratch("restart-refuse");
    let (case, _) = slab_case(&dir, "refuse", |t| t);
    let out = dir.join("r.h5");
    ok(&run(&case, &out, &[]));
    let before = std::fs::read(&out).unwrap();
    for (set, words) in [
        (
            "contact.mu=0.2",
            vec![
                "contact.mu: 0.3 in the stored run, 0.2 now",
                "only time.t_end, output.*, title, mesh.ladder and contact.max_iterations",
            ],
        ),
        (
            "time.dt=5e-4",
            vec!["time.dt: 0.001 in the stored run, 0.0005 now"],
        ),
        (
            "time.t_end=0.01",
            vec!["time.t_end = 0.01 is before the checkpoint's t"],
        ),
    ] {
        let o = restart(&case, &out, &["--set", set]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {e}");
        for w in words {
            assert!(e.contains(w), "{set}: {w:?} in {e}");
        }
        assert_eq!(
            std::fs::read(&out).unwrap(),
            before,
            "{set}: the file is untouched"
        );
    }
    // A missing file is bad input too.
    let o = restart(&case, &dir.join("none.h5"), &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("none.h5"), "{}", stderr(&o));
    // Output settings may change.
    ok(&restart(
        &case,
        &out,
        &["--set", "time.t_end=0.08", "--set", "output.every=2"],
    ));
}

/// A restart refused (exit 2) changes nothing on disk: beside the results
/// file, the viewers' files and the stresses stay byte for byte. A
/// restart accepted removes the XML and the stresses, which list the
/// earlier run's records.
#[test]
fn a_refused_restart_keeps_the_viewers_files_and_the_stresses() {
    let dir = scratch("restart-refused-companions");
    let (case, _) = slab_case(&dir, "companions", |t| t);
    let out = dir.join("c.h5");
    ok(&run(&case, &out, &[]));
    for command in ["views", "stress"] {
        ok(&bin()
            .arg(command)
            .arg(&out)
            .arg("--quiet")
            .output()
            .unwrap());
    }
    let files = [
        "c.h5",
        "c.xdmf",
        "c.contact.xdmf",
        "c.views.h5",
        "c.stress.h5",
    ]
    .map(|name| dir.join(name));
    let before: Vec<Vec<u8>> = files.iter().map(|p| std::fs::read(p).unwrap()).collect();
    for set in ["time.t_end=0.01", "time.dt=5e-4"] {
        let o = restart(&case, &out, &["--set", set]);
        assert_eq!(o.status.code(), Some(2), "{set}: {}", stderr(&o));
        for (path, was) in files.iter().zip(&before) {
            assert!(
                std::fs::read(path).is_ok_and(|now| now == *was),
                "{set}: {} changed",
                path.display()
            );
        }
    }
    ok(&restart(&case, &out, &["--set", "time.t_end=0.08"]));
    for gone in &files[1..3] {
        assert!(!gone.exists(), "{}", gone.display());
    }
    assert!(!files[4].exists());
    assert!(files[3].exists(), "the views file is kept");
}

/// A restart to its checkpoint's own time takes no step: the run's last
/// step is the checkpoint's state, the row it continues after, which need
/// not be a frame (7 frames of 0.1 / 7 over 3e-3 steps: rows 29 and 34
/// are, row 33 is not). It ends complete with that row a frame, whose
/// fields are those of a run that ends there, and a later restart from it
/// continues as one from the file before.
#[test]
fn a_restart_at_the_checkpoint_time_ends_on_a_frame() {
    let (dir, case, part, sets) = run_to_a_tenth("restart-at-checkpoint", "output.frames=7");
    let other = dir.join("other.h5");
    std::fs::copy(&part, &other).unwrap();
    let rows = |p: &Path| {
        let f = hdf5::File::open(p).unwrap();
        f.dataset("frames/row").unwrap().read_raw::<u64>().unwrap()
    };
    assert_eq!(rows(&part), [0, 5, 10, 15, 20, 24, 29, 34]);
    ok(&restart(&case, &part, &sets("time.t_end=0.099")));
    let direct = dir.join("direct.h5");
    ok(&run(&case, &direct, &sets("time.t_end=0.099")));
    let (f, g) = (
        hdf5::File::open(&part).unwrap(),
        hdf5::File::open(&direct).unwrap(),
    );
    assert!(f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
    let read = |f: &hdf5::File, name: &str| f.dataset(name).unwrap().read_raw::<f64>().unwrap();
    let time = read(&f, "time");
    assert_eq!(time, read(&g, "time"));
    assert_eq!(time.len(), 34);
    assert_eq!(rows(&part).last(), Some(&33));
    assert_eq!(read(&f, "frames/time").last(), Some(&0.099));
    for name in ["displacement", "velocity", "acceleration"] {
        let (a, b) = (read(&f, name), read(&g, name));
        let n = 85 * 2;
        let last = |v: &[f64]| {
            v[v.len() - n..]
                .iter()
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(last(&a), last(&b), "{name} at the last step");
    }
    drop((f, g));
    ok(&restart(&case, &part, &sets("time.t_end=0.2")));
    ok(&restart(&case, &other, &sets("time.t_end=0.2")));
    assert_same_datasets(&other, &part);
}

/// The paper's explicit case with `output` (a `--set`) in a scratch
/// directory `name`, run to t_end = 0.1 by Δt = 3e-3 (33 steps and a
/// shortened one: the checkpoint, the state before the last step, at t =
/// 0.099) into `part.h5`: (the directory, the case, the file, the sets
/// for another t_end).
fn run_to_a_tenth(
    name: &str,
    output: &'static str,
) -> (
    PathBuf,
    PathBuf,
    PathBuf,
    impl Fn(&'static str) -> [&'static str; 6],
) {
    let dir = scratch(name);
    let case = paper_case(&dir, "cd-step-eps1e-4.toml");
    let sets =
        move |t_end: &'static str| ["--set", output, "--set", "time.dt=3e-3", "--set", t_end];
    let part = dir.join("part.h5");
    ok(&run(&case, &part, &sets("time.t_end=0.1")));
    assert_eq!(checkpoint_attr::<f64>(&part, "t"), 0.099);
    (dir, case, part, sets)
}

/// With output.every = 4 the checkpoint's step (33, before the last) has
/// no row: a restart to its time would end complete without fields for
/// its last step, so it is refused (exit 2, the file as it was).
#[test]
fn a_restart_at_a_checkpoint_without_its_row_is_refused() {
    let (_, case, part, sets) = run_to_a_tenth("restart-at-checkpoint-every", "output.every=4");
    let e = refused_restart(&case, &part, &sets("time.t_end=0.099"));
    assert!(
        e.contains("time.t_end") && e.contains("give a t_end > 0.099"),
        "{e}"
    );
    // A later t_end continues it.
    ok(&restart(&case, &part, &sets("time.t_end=0.2")));
}

// ---------------------------------------------------------------------------
// --json

#[test]
fn json_summary_is_one_object_on_stdout() {
    let dir = scratch("json");
    let (case, _) = slab_case(&dir, "json", |t| t);
    let out = dir.join("j.h5");
    let o = run(&case, &out, &["--json"]);
    ok(&o);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    // tests/data/slab.toml: t_end = 0.05, dt = 1e-3, every = 1.
    assert_eq!(j["status"], "complete");
    assert_eq!(j["steps"], 50);
    assert_eq!(j["records"], 51);
    assert_eq!(j["t"], 0.05);
    assert_eq!(j["output"], out.display().to_string());
    // The run writes no viewers' files; it gives the command that does.
    assert_eq!(
        j["view_command"],
        format!("stickslip views {}", out.display())
    );
    assert!(!out.with_extension("xdmf").exists());
    assert!(j["energy"]["total"].is_f64() && j["dt_crit"].is_f64());
    // The compliance Newton count of the text summary: none on the
    // paper's prescribed pressure.
    assert_eq!(j["normal_iterations"], 0);
    // The setup's parts: the slab is preloaded (the contact pressure acts
    // before t = 0), so the preload's factor is among them; they and the
    // rest ("other") add up to setup_s, to the printed rounding.
    let parts = j["setup_parts"].as_object().expect("setup_parts");
    for part in [
        "mesh_read",
        "assembly",
        "critical_step",
        "preload_factor",
        "operators",
        "other",
    ] {
        assert!(
            parts[part].as_f64().is_some_and(|s| s >= 0.0),
            "{part}: {parts:?}"
        );
    }
    let sum: f64 = parts.values().map(|v| v.as_f64().unwrap()).sum();
    let setup = j["setup_s"].as_f64().unwrap();
    assert!(
        (sum - setup).abs() <= 1e-9 * setup.max(1.0),
        "{sum} against {setup}"
    );
}

/// A run stored in one node order continues in another
/// (`STICKSLIP_DOF_ORDER=mesh` keeps the file's; a file of a version
/// before the node orders reads as the file's): the restart reads the
/// state into its own numbering, and the run ends where one run in that
/// order ends, to rounding (the sums run in another order, so not bit for
/// bit), with `node_order` in the checkpoint saying which numbering it
/// holds: the paper's mesh is a grid (1), the unstructured slab is
/// numbered by reverse Cuthill–McKee (2).
#[test]
fn restart_across_node_orders_continues_the_run() {
    let dir = scratch("restart-order");
    for (mesh, own) in [("slab-q2-8x2.msh", 1u8), ("slab-unstructured-q1.msh", 2)] {
        let (case, _) = slab_case(&dir, "order", |t| t.replace("slab-q2-8x2.msh", mesh));
        let run_in = |order: &str, out: &Path, t_end: &str, again: bool| {
            let mut c = bin();
            c.env("STICKSLIP_DOF_ORDER", order).arg("run").arg(&case);
            if again {
                c.arg("--restart").arg(out);
            } else {
                c.arg("-o").arg(out).arg("--force");
            }
            c.args(["--quiet", "--set", &format!("time.t_end={t_end}")]);
            c.output().unwrap()
        };
        let stored_order = |path: &Path| -> u8 {
            let f = hdf5::File::open(path).unwrap();
            let cp = f.group("checkpoint").unwrap();
            let slot: u8 = cp.attr("slot").unwrap().read_scalar().unwrap();
            let g = cp.group(["a", "b"][usize::from(slot)]).unwrap();
            g.attr("node_order").unwrap().read_scalar().unwrap()
        };
        for (first, then) in [("mesh", "own"), ("own", "mesh")] {
            let code = |o: &str| if o == "mesh" { 0 } else { own };
            let full = dir.join(format!("full-{then}.h5"));
            ok(&run_in(then, &full, "0.3", false));
            let part = dir.join(format!("{first}-then-{then}.h5"));
            ok(&run_in(first, &part, "0.1374", false));
            assert_eq!(stored_order(&part), code(first), "{mesh}: {first}");
            ok(&run_in(then, &part, "0.3", true));
            assert_eq!(
                stored_order(&part),
                code(then),
                "{mesh}: {first} then {then}"
            );
            let (ta, ra) = last_record(&full);
            let (tb, rb) = last_record(&part);
            assert_eq!(ta, tb, "{mesh}: {first} then {then}: the same last time");
            let max = ra
                .iter()
                .map(|&x| f64::from_bits(x).abs())
                .fold(0.0, f64::max);
            let diff = ra
                .iter()
                .zip(&rb)
                .map(|(&x, &y)| (f64::from_bits(x) - f64::from_bits(y)).abs())
                .fold(0.0, f64::max);
            assert!(
                diff <= 1e-10 * max,
                "{mesh}: {first} then {then}: last displacement differs by {diff:e} (max {max:e})"
            );
            assert!(max > 0.0);
        }
    }
}

/// The results file is protected: `--force` does not touch a file another
/// run is writing (before, HDF5 truncated it and then failed on its lock,
/// leaving both runs without results), an OUT.xdmf is not overwritten
/// without `--force`, the case file cannot be the output, and a place that
/// cannot be written is bad input (2), not a failed run (1).
#[test]
fn the_results_file_is_never_clobbered() {
    let dir = scratch("clobber");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let out = dir.join("live.h5");
    let mut first = start_long(&case, &out, &["--quiet"], 0.5);
    let second = run(&case, &out, &[]);
    // Under cargo test HDF5's locking is off (.cargo/config.toml), so
    // only the run's own lock tells probe to wait.
    let probe = bin()
        .arg("probe")
        .arg(&out)
        .args(["--at", "8,0"])
        .output()
        .unwrap();
    let still_running = first.try_wait().unwrap().is_none();
    signal(&first, "-INT");
    let status = first.wait().unwrap();
    assert!(
        still_running,
        "the first run lasts past the second's attempt"
    );
    assert_eq!(second.status.code(), Some(2), "{}", stderr(&second));
    assert!(
        stderr(&second).contains("open in another process"),
        "{}",
        stderr(&second)
    );
    assert_eq!(probe.status.code(), Some(2), "{}", stderr(&probe));
    assert!(
        stderr(&probe).contains("still writing it"),
        "{}",
        stderr(&probe)
    );
    assert_eq!(status.code(), Some(130), "the first run ends by its SIGINT");
    let f = hdf5::File::open(&out).expect("the first run's file is intact");
    assert!(
        f.dataset("time").unwrap().size() > 1,
        "its records are there"
    );
    drop(f);

    let lone = dir.join("lone.h5");
    std::fs::write(dir.join("lone.xdmf"), "mine").unwrap();
    let o = bin()
        .arg("run")
        .arg(&case)
        .arg("-o")
        .arg(&lone)
        .arg("--quiet")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("lone.xdmf already exists"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("lone.xdmf")).unwrap(),
        "mine"
    );

    let o = run(&case, &case, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("is the case file itself"),
        "{}",
        stderr(&o)
    );
    assert!(std::fs::read_to_string(&case).unwrap().contains("[time]"));

    for bad in [dir.clone(), case.join("x.h5")] {
        let o = run(&case, &bad, &[]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}: {}",
            bad.display(),
            stderr(&o)
        );
    }
}

/// `-o` and `--times` belong to `--along`: with `--at` they were silently
/// ignored (the history went to stdout and no file was written).
#[test]
fn probe_refuses_along_options_with_at() {
    let dir = scratch("probe-o");
    for extra in [["-o", "x.csv"], ["--times", "0.1"]] {
        let o = bin()
            .arg("probe")
            .arg(dir.join("any.h5"))
            .args(["--at", "8,0"])
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("go with --along"), "{}", stderr(&o));
    }
}

/// A load or friction on a line inside the body (Gmsh's embedded curve)
/// and a group name two groups share are refused with the group named
/// (before: accepted, and the first of the two groups taken).
#[test]
fn interior_lines_and_shared_group_names_are_refused() {
    let dir = scratch("interior");
    let msh = std::fs::read_to_string(
        root().join("crates/mesh/tests/data/slab_q4_embedded_v41_ascii.msh"),
    )
    .unwrap();
    let embedded = dir.join("embedded.msh");
    std::fs::write(&embedded, &msh).unwrap();
    let on = |mesh: &Path, t: String| {
        t.replace(
            &root()
                .join("cases/meshes/slab-q2-8x2.msh")
                .display()
                .to_string(),
            &mesh.display().to_string(),
        )
    };
    let (case, _) = slab_case(&dir, "crack", |t| {
        on(&embedded, t).replace("group = \"load\"", "group = \"crack\"")
    });
    refused(
        &case,
        &[],
        &["traction.0.group = \"crack\"", "must be on the boundary"],
    );

    let shared = dir.join("shared.msh");
    std::fs::write(&shared, msh.replace("1 5 \"crack\"", "1 5 \"support\"")).unwrap();
    let (case, _) = slab_case(&dir, "shared", |t| on(&shared, t));
    refused(&case, &[], &["several physical groups called \"support\""]);
}

/// `-o` never writes over an input of the case, a device or a FIFO, nor
/// names the .xdmf (which is written beside the .h5 under its name): with
/// --force a run as root replaced /dev/null with a results file, wrote
/// over the case's mesh, hung on a FIFO, and `-o out.xdmf` wrote the XDMF
/// over the HDF5 file. Without --force, only an HDF5 file is offered
/// --restart.
#[test]
fn inputs_devices_fifos_and_the_xdmf_are_never_the_output() {
    let dir = scratch("not-output");
    let mesh = dir.join("m.msh");
    std::fs::copy(root().join("cases/meshes/slab-q2-8x2.msh"), &mesh).unwrap();
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let set = format!("mesh.file={}", toml_str(&mesh));
    let before = std::fs::read(&mesh).unwrap();
    let o = run(&case, &mesh, &["--set", &set]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("is an input of the case"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        before,
        "the mesh is untouched"
    );

    let fifo = dir.join("fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let o = run(&case, &fifo, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("is not a regular file"),
        "{}",
        stderr(&o)
    );
    let o = run(&case, Path::new("/dev/null"), &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(std::fs::metadata("/dev/null").is_ok_and(|m| !m.is_file()));

    // A symbolic link, dangling or not (a dangling one read as "created by
    // another process just now").
    for target in [dir.join("nowhere/x.h5"), dir.join("real.h5")] {
        let link = dir.join("link.h5");
        std::fs::remove_file(&link).ok();
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let o = run(&case, &link, &[]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("is a symbolic link"), "{}", stderr(&o));
    }

    let o = run(&case, &dir.join("out.xdmf"), &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("give -o"), "{}", stderr(&o));
    assert!(!dir.join("out.xdmf").exists());

    let text = dir.join("notes.h5");
    std::fs::write(&text, "my notes").unwrap();
    let o = bin()
        .arg("run")
        .arg(&case)
        .arg("-o")
        .arg(&text)
        .arg("--quiet")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("already exists") && !stderr(&o).contains("--restart"),
        "{}",
        stderr(&o)
    );
}

/// A TOML basic string of a path.
fn toml_str(p: &Path) -> String {
    format!("{:?}", p.display().to_string())
}

/// Of two runs started on one file at once, one writes it and the other
/// is refused: fresh runs with --force (the second removed the first's new
/// file and both reported success, one result lost) and restarts (both
/// appended, and the file claimed to be complete with wrong rows). HDF5's
/// locking is off under cargo test, as when a user's environment turns it
/// off; the run's own lock decides.
#[test]
fn of_two_runs_on_one_file_one_writes_it() {
    let dir = scratch("two-runs");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let out = dir.join("two.h5");
    let spawn = |args: &[&str]| {
        bin()
            .arg("run")
            .arg(&case)
            .args(args)
            .args(["--quiet", "--set", "time.t_end=200"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let o = out.to_str().unwrap();
    for args in [vec!["-o", o, "--force"], vec!["--restart", o]] {
        if args[0] == "--restart" {
            // A checkpoint to restart from.
            let c = start_long(&case, &out, &["--quiet"], 0.5);
            signal(&c, "-INT");
            let o = c.wait_with_output().unwrap();
            assert_eq!(o.status.code(), Some(130), "{:?}: {}", o.status, stderr(&o));
        }
        let mut runs = [spawn(&args), spawn(&args)];
        let t0 = Instant::now();
        let mut refused = None;
        while refused.is_none() && t0.elapsed() < Duration::from_secs(60) {
            for (k, r) in runs.iter_mut().enumerate() {
                if r.try_wait().unwrap().is_some() {
                    refused = Some(k);
                }
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let k = refused.expect("one of the two ends at once");
        let [a, b] = runs;
        let (loser, winner) = if k == 0 { (a, b) } else { (b, a) };
        let still = std::process::Command::new("kill")
            .args(["-0", &winner.id().to_string()])
            .status()
            .unwrap()
            .success();
        signal(&winner, "-INT");
        let lost = loser.wait_with_output().unwrap();
        let won = winner.wait_with_output().unwrap();
        assert!(still, "{args:?}: the other run goes on");
        assert_eq!(lost.status.code(), Some(2), "{args:?}: {}", stderr(&lost));
        assert!(
            stderr(&lost).contains("another"),
            "{args:?}: {}",
            stderr(&lost)
        );
        assert_eq!(won.status.code(), Some(130), "{args:?}: {}", stderr(&won));
        // The winner's file: records and checkpoint agree.
        let f = hdf5::File::open(&out).unwrap();
        let n = f.dataset("time").unwrap().size();
        let rows = slot(&f).attr("rows").unwrap().read_scalar::<u64>().unwrap();
        assert_eq!(rows as usize, n, "{args:?}");
    }
}

/// A restart continues on the mesh its run began on: a mesh file changed
/// since (here Q1 16x4 written over Q2 8x2, both 85 nodes) was continued
/// silently with the other mesh.
#[test]
fn restart_refuses_a_changed_mesh() {
    let dir = scratch("changed-mesh");
    let mesh = dir.join("m.msh");
    std::fs::copy(root().join("cases/meshes/slab-q2-8x2.msh"), &mesh).unwrap();
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let set = format!("mesh.file={}", toml_str(&mesh));
    let out = dir.join("r.h5");
    ok(&run(&case, &out, &["--set", &set]));
    ok(&restart(
        &case,
        &out,
        &["--set", &set, "--set", "time.t_end=0.06"],
    ));
    std::fs::copy(root().join("cases/meshes/slab-q1-16x4.msh"), &mesh).unwrap();
    let before = std::fs::read(&out).unwrap();
    let o = restart(&case, &out, &["--set", &set, "--set", "time.t_end=0.07"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("has changed since the run began"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read(&out).unwrap(),
        before,
        "the file is untouched"
    );
}

/// Damaged results files are refused, not read: a stored case that is
/// not UTF-8 (probe and --restart panicked: exit 101), and a /time that
/// claims 1e11 rows (probe aborted on an 800 GB allocation; a restart
/// continued with zeros for the times).
#[test]
fn damaged_results_files_are_refused() {
    let dir = scratch("damaged");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let good = dir.join("good.h5");
    ok(&run(&case, &good, &[]));

    let utf8 = dir.join("utf8.h5");
    let mut bytes = std::fs::read(&good).unwrap();
    let at = bytes
        .windows(8)
        .position(|w| w == b"\n\n[time]")
        .expect("the case text in the file");
    bytes[at + 2] = 0xbf;
    std::fs::write(&utf8, bytes).unwrap();
    let probe = bin()
        .arg("probe")
        .arg(&utf8)
        .args(["--along", "contact", "--times", "0"])
        .output()
        .unwrap();
    assert_ne!(probe.status.code(), Some(101), "{}", stderr(&probe));
    let o = restart(&case, &utf8, &["--set", "time.t_end=0.1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not UTF-8"), "{}", stderr(&o));

    // A copy of the good file whose dataset `name` claims 1e11 rows.
    let claims_huge = |file: &str, name: &str| {
        let path = dir.join(file);
        std::fs::copy(&good, &path).unwrap();
        let f = hdf5::File::open_rw(&path).unwrap();
        f.unlink(name).unwrap();
        let (group, leaf) = name.rsplit_once('/').unwrap_or((".", name));
        f.group(group)
            .unwrap()
            .new_dataset::<f64>()
            .chunk(1024)
            .shape(100_000_000_000usize)
            .create(leaf)
            .unwrap();
        path
    };
    let huge = claims_huge("huge.h5", "time");
    let huge_frames = claims_huge("huge-frames.h5", "frames/time");
    // /time is what the contact's histories are read against, /frames/time
    // what the fields are.
    for (file, field) in [(&huge, "friction_stress"), (&huge_frames, "ux")] {
        let probe = bin()
            .arg("probe")
            .arg(file)
            .args(["--at", "8,0", "--field", field])
            .output()
            .unwrap();
        assert_eq!(probe.status.code(), Some(2), "{}", stderr(&probe));
        assert!(stderr(&probe).contains("damaged"), "{}", stderr(&probe));
    }
    let o = restart(&case, &huge, &["--set", "time.t_end=0.1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("damaged"), "{}", stderr(&o));
}

/// A closed pipe: `check | head` ends quietly (it panicked, exit 101), and
/// a run whose stderr is closed still completes its file (it panicked at
/// its first message and lost the steps since the last flush).
#[test]
fn closed_pipes_neither_panic_nor_end_a_run() {
    let dir = scratch("pipes");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let mut c = bin()
        .arg("check")
        .arg(&case)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(c.stdout.take());
    let o = c.wait_with_output().unwrap();
    assert_ne!(o.status.code(), Some(101), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));

    let out = dir.join("run.h5");
    let mut c = bin()
        .arg("run")
        .arg(&case)
        .arg("-o")
        .arg(&out)
        .args(["--set", "time.t_end=2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(c.stderr.take());
    let o = c.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    let f = hdf5::File::open(&out).unwrap();
    assert!(f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
}

/// A disk that fills up mid-run: the run stops before HDF5's flush fails
/// half way (which left rows of fill values, and turned rows flushed
/// before, in the chunk it rewrote, into zeros that probe printed as
/// u = 0), says so and what to do; the file reads to its last record, and
/// a restart with room continues it. Runs and restarts are sized against
/// their disk before they start, so the disk is filled by another file
/// once the restart has begun (stopped with SIGSTOP meanwhile). Needs a
/// tmpfs: where this process may not mount one (not root, or a container
/// without the capability) the test fails under CI and is skipped
/// elsewhere.
#[test]
fn a_disk_that_fills_up_stops_the_run_with_its_records() {
    use std::io::{BufRead, BufReader, Read};
    let dir = scratch("disk-full");
    let Some(disk) = tmpfs(&dir, "disk", "size=200M") else {
        return;
    };
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let out = disk.join("full.h5");
    let first = run(&case, &out, &[]);
    // 20,000 records of 4.6 kB (92 MB): the disk holds them, the filler
    // leaves 6 MB of it. No flush in a run this short (they come by wall
    // time): the stop's own flush writes again what was appended since
    // the restart began, which the room it keeps must count (without it
    // the file was left unreadable, every record lost).
    let mut child = bin()
        .arg("run")
        .arg(&case)
        .arg("--restart")
        .arg(&out)
        .args(["--set", "time.t_end=20"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut said = String::new();
    loop {
        let mut line = String::new();
        if err.read_line(&mut line).unwrap() == 0 {
            break;
        }
        said.push_str(&line);
        if line.contains("restart: continuing") {
            break;
        }
    }
    signal(&child, "-STOP");
    let filler = fill_leaving(&disk, 6 << 20);
    signal(&child, "-CONT");
    err.read_to_string(&mut said).unwrap();
    let status = child.wait().unwrap();
    let read = hdf5::File::open(&out).map(|f| {
        let u = f
            .dataset("displacement")
            .unwrap()
            .read_raw::<f64>()
            .unwrap();
        let t = f.dataset("time").unwrap().size();
        (u, t)
    });
    std::fs::remove_file(&filler).unwrap();
    let again = restart(&case, &out, &["--set", "time.t_end=21"]);
    Command::new("umount").arg(&disk).status().ok();
    ok(&first);
    assert!(said.contains("restart: continuing"), "{said}");
    assert_eq!(status.code(), Some(1), "{said}");
    assert!(
        said.contains("is nearly full") && said.contains("--restart"),
        "{said}"
    );
    let (u, rows) = read.expect("the file opens");
    assert!(rows > 100, "it ran a while: {rows} records");
    assert!(rows < 20_000, "it stopped before t_end: {rows} records");
    let per_row = u.len() / rows;
    // Every record after the first (the slab at rest) moves.
    let zero = (1..rows)
        .filter(|&k| u[k * per_row..(k + 1) * per_row].iter().all(|&x| x == 0.0))
        .count();
    assert_eq!(zero, 0, "records of zeros among {rows}");
    assert_eq!(again.status.code(), Some(0), "{}", stderr(&again));
}

/// A file `filler` on `disk` that leaves about `left` bytes of it free
/// (`df`'s count, in whole MiB).
fn fill_leaving(disk: &Path, left: u64) -> PathBuf {
    use std::io::Write;
    let avail = Command::new("df")
        .args(["--output=avail", "-B1"])
        .arg(disk)
        .output()
        .unwrap();
    let avail: u64 = String::from_utf8_lossy(&avail.stdout)
        .lines()
        .nth(1)
        .and_then(|l| l.trim().parse().ok())
        .unwrap_or(0);
    let filler = disk.join("filler");
    let mut f = std::fs::File::create(&filler).unwrap();
    let block = vec![1u8; 1 << 20];
    for _ in 0..avail.saturating_sub(left) >> 20 {
        f.write_all(&block).unwrap();
    }
    filler
}

/// The slab's case in the scratch directory `name` and a 6 MB tmpfs
/// beside it for its results ([`tmpfs`]; `None`: skipped).
fn slab_on_a_small_disk(name: &str) -> Option<(PathBuf, PathBuf)> {
    let dir = scratch(name);
    let small = tmpfs(&dir, "small", "size=6M")?;
    let (case, _) = slab_case(&dir, "slab", |t| t);
    Some((case, small))
}

/// Numbers so large or small that the computation overflows are refused
/// by name (E = 1e308 was reported as "a rigid-body motion left free", ρ =
/// 1e-300 as "use time.dt < 0"), and so are case and mesh files that are
/// no regular files or no UTF-8 text (`check /dev/zero` hung; /dev/null as
/// the mesh "did not exist"; a Latin-1 case file got "check the path").
#[test]
fn extreme_values_and_odd_files_are_refused_by_name() {
    let dir = scratch("extreme");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    for set in [
        "material.E=1e308",
        "material.rho=1e-300",
        "contact.eps=1e-320",
        "body_force=[1e308, 0]",
    ] {
        let key = set.split('=').next().unwrap();
        refused(&case, &[set], &[&format!("{key} = "), "moderate"]);
    }
    // A run that would not end passed check and ran on.
    refused(
        &case,
        &["time.dt=1e-90"],
        &["time.t_end / time.dt", "steps"],
    );
    let o = Command::new("timeout")
        .arg("20")
        .arg(env!("CARGO_BIN_EXE_stickslip"))
        .args(["check", "/dev/zero"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a regular file"), "{}", stderr(&o));
    let (null_mesh, _) = slab_case(&dir, "null", |t| {
        let start = t.find("file = ").unwrap();
        let end = start + t[start..].find('\n').unwrap();
        format!("{}file = \"/dev/null\"{}", &t[..start], &t[end..])
    });
    refused(&null_mesh, &[], &["/dev/null is not a regular file"]);
    let utf16 = dir.join("utf16.toml");
    let mut bytes = vec![0xff, 0xfe];
    bytes.extend(
        "title = \"x\"\n"
            .encode_utf16()
            .flat_map(|u| u.to_le_bytes()),
    );
    std::fs::write(&utf16, bytes).unwrap();
    let o = check(&utf16, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("UTF-16"), "{}", stderr(&o));
    let latin1 = dir.join("latin1.toml");
    let mut bytes = b"title = \"caf".to_vec();
    bytes.extend([0xe9, b'"', b'\n']);
    std::fs::write(&latin1, bytes).unwrap();
    let o = check(&latin1, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("latin1.toml:1:13: not UTF-8"),
        "{}",
        stderr(&o)
    );
}

/// docs/case-file.md promises every number of a case finite and, unless
/// 0, of magnitude 1e-100 to 1e100: for every key, a history's numbers
/// included (`output.flush_seconds = inf`, a sin history's omega = 1e200
/// and a table's time 1e-200 were accepted; beta = gamma = inf was called
/// unstable), each value one problem, named by key and line.
#[test]
fn every_number_is_finite_and_moderate_or_refused() {
    let dir = scratch("every-number");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let infinite = "is not a finite number";
    let huge = "beyond what the computation can carry";
    for (set, words) in [
        (
            "output.flush_seconds=inf",
            ["output.flush_seconds = inf", infinite],
        ),
        (
            "output.flush_seconds=nan",
            ["output.flush_seconds = NaN", infinite],
        ),
        (
            "output.flush_seconds=1e200",
            ["output.flush_seconds = 1e200", huge],
        ),
        ("material.E=-inf", ["material.E = -inf", infinite]),
        ("dirichlet.0.uy=nan", ["dirichlet.0.uy = NaN", infinite]),
        (
            "traction.0.history={ sin = { omega = 1e200 } }",
            ["traction.0.history holds 1e200", huge],
        ),
        (
            "traction.0.history={ sin = { omega = inf } }",
            ["traction.0.history holds inf", infinite],
        ),
        (
            "traction.0.history={ table = [[0, 0], [1e-200, 1]] }",
            ["traction.0.history holds 1e-200", huge],
        ),
    ] {
        let e = refused(&case, &[set], &words);
        assert_eq!(e.lines().count(), 1, "{set}: {e}");
    }
    // In the file, each on its line.
    let (newmark, text) = slab_case(&dir, "newmark", |t| {
        t.replace(
            "scheme = \"central_difference\"",
            "scheme = \"newmark\"\nbeta = inf\ngamma = inf",
        )
    });
    let e = refused(&newmark, &[], &[]);
    for key in ["beta", "gamma"] {
        let l = line_of(&text, &format!("{key} = inf"));
        assert!(
            e.lines().any(|m| m.contains(&format!("newmark.toml:{l}:"))
                && m.contains(&format!("time.{key} = inf {infinite}"))),
            "time.{key} at line {l}:\n{e}"
        );
    }
    assert_eq!(e.lines().count(), 2, "{e}");
}

/// A value of the wrong type is one problem: the placeholder that keeps
/// the other checks going was reported too when the value came from --set
/// ("material.nu = 1 must lie in (-1, 0.5)", "placeholder does not exist").
#[test]
fn a_wrong_type_is_reported_once() {
    let dir = scratch("wrong-type");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    for set in ["material.nu=\"abc\"", "mesh.file=0", "mesh.ladder=0"] {
        let e = refused(&case, &[set], &["expected"]);
        assert_eq!(e.lines().count(), 1, "{set}: {e}");
    }
}

/// A history of the wrong form is named as one (serde said only "wanted
/// string or table"), and thousands of problems are listed fifty at a
/// time (20,000 were printed).
#[test]
fn history_forms_are_named_and_long_lists_are_cut() {
    let dir = scratch("history");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    for set in ["traction.0.history=0", "traction.0.history={}"] {
        refused(
            &case,
            &[set],
            &["a traction's history", "history = \"step\""],
        );
    }
    let (many, _) = slab_case(&dir, "many", |t| {
        let extra: String = (0..200)
            .map(|i| format!("\n[[dirichlet]]\ngroup = \"nosuch{i}\"\nuy = 0.0\n"))
            .collect();
        t + &extra
    });
    let o = check(&many, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.lines().count(), 51, "{e}");
    assert!(e.contains("and 150 more problems"), "{e}");
}

/// A run whose records cannot fit on the disk is refused before it starts
/// (t_end = 10 with every step written filled 14 GB in 75 s on its way to
/// 950 GB); `check` says so as a warning.
#[test]
fn a_run_that_cannot_fit_on_its_disk_is_refused() {
    let dir = scratch("no-room");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    // 1e10 records of 4.4 kB: 44 TB.
    let c = check(&case, &["time.t_end=1e7"]);
    let out = String::from_utf8_lossy(&c.stdout).into_owned();
    assert_eq!(c.status.code(), Some(0), "{}", stderr(&c));
    assert!(
        out.contains("warning") && out.contains("free on its disk"),
        "{out}"
    );
    let o = run(&case, &dir.join("big.h5"), &["--set", "time.t_end=1e7"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("output.every"), "{}", stderr(&o));
    assert!(!dir.join("big.h5").exists());
}

/// Units mixed up (E a millionth of what the loads assume) move the part
/// by more than its size: the run and `check` say so (it went without a
/// word); the paper's case, whose slab moves 12% of its length, gets no
/// warning.
#[test]
fn a_static_displacement_beyond_the_part_size_is_reported() {
    let dir = scratch("units");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let checked = check(&case, &["material.E=1e-3"]);
    let said = String::from_utf8_lossy(&checked.stdout).into_owned();
    assert_eq!(checked.status.code(), Some(0), "{}", stderr(&checked));
    assert!(
        said.contains(
            "warning     the initial static displacement, less its mean translation, reaches"
        ),
        "{said}"
    );
    let calm = check(&case, &[]);
    assert!(
        !String::from_utf8_lossy(&calm.stdout).contains("warning"),
        "{}",
        String::from_utf8_lossy(&calm.stdout)
    );
    let loud = bin()
        .arg("run")
        .arg(&case)
        .arg("-o")
        .arg(dir.join("a.h5"))
        .args(["--set", "material.E=1e-3"])
        .output()
        .unwrap();
    assert_eq!(loud.status.code(), Some(0), "{}", stderr(&loud));
    assert!(
        stderr(&loud).contains(
            "warning: the initial static displacement, less its mean translation, reaches"
        ),
        "{}",
        stderr(&loud)
    );
    let calm = bin()
        .arg("run")
        .arg(&case)
        .arg("-o")
        .arg(dir.join("b.h5"))
        .output()
        .unwrap();
    assert_eq!(calm.status.code(), Some(0), "{}", stderr(&calm));
    assert!(!stderr(&calm).contains("warning"), "{}", stderr(&calm));
}

/// `check` of a Newmark case says what its Δt resolves (it printed only
/// central difference's critical step, which does not bound Newmark).
#[test]
fn check_says_what_a_newmark_step_resolves() {
    let dir = scratch("nm-resolves");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let o = check(&case, &["time.scheme=\"newmark\"", "time.dt=5e-3"]);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        out.contains("accuracy") && out.contains("periods above 5.000e-2"),
        "{out}"
    );
    let o = check(&case, &[]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("accuracy    "));
}

/// A support along y on a curved contact face (the hole of
/// cases/meshes/hole-q1.msh) holds most of its nodes off their tangent:
/// `check` and `run` say so (it went without a word); the same support on
/// the straight bottom face, along its normal, gets no warning.
#[test]
fn a_support_oblique_to_a_curved_contact_face_is_reported() {
    let dir = scratch("oblique");
    let held = |group: &'static str| {
        move |t: String| {
            t.replace("slab-q2-8x2.msh", "hole-q1.msh")
                .replace(
                    "[contact]",
                    &format!("[[dirichlet]]\ngroup = \"{group}\"\nuy = 0.0\n\n[contact]"),
                )
                .replace(
                    "group = \"contact\"\npressure",
                    &format!("group = \"{group}\"\npressure"),
                )
        }
    };
    let (oblique, text) = slab_case(&dir, "oblique", held("hole"));
    assert!(text.contains("group = \"hole\"\npressure"), "{text}");
    let said = check(&oblique, &[]);
    let out = String::from_utf8_lossy(&said.stdout).into_owned();
    assert_eq!(said.status.code(), Some(0), "{}", stderr(&said));
    assert!(
        out.contains("warning     ") && out.contains("have uy fixed by a [[dirichlet]] condition"),
        "{out}"
    );
    let o = bin()
        .arg("run")
        .arg(&oblique)
        .arg("-o")
        .arg(dir.join("a.h5"))
        .args(["--set", "time.t_end=0.002"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: ") && stderr(&o).contains("uy fixed"),
        "{}",
        stderr(&o)
    );
    let (normal, _) = slab_case(&dir, "normal", held("contact"));
    let calm = check(&normal, &[]);
    assert_eq!(calm.status.code(), Some(0), "{}", stderr(&calm));
    assert!(
        !String::from_utf8_lossy(&calm.stdout).contains("warning"),
        "{}",
        String::from_utf8_lossy(&calm.stdout)
    );
}

/// A run the disk can hold, but not with the room a run keeps free while
/// it writes (the stop at a nearly full disk), is refused before it
/// starts, and `check` warns of it: both counted the records alone, so
/// the run started and stopped part way (exit 1). Needs a small tmpfs, as
/// the disk-full test.
#[test]
fn a_run_its_disk_holds_only_without_the_room_it_keeps_is_refused() {
    let Some((case, small)) = slab_on_a_small_disk("disk-reserve") else {
        return;
    };
    let out = small.join("x.h5");
    // 801 records of 4.6 kB (3.8 MB) on a 6 MB disk, with 4.4 MB kept.
    let file = format!("output.file={}", toml_str(&out));
    let checked = check(&case, &["time.t_end=0.8", &file]);
    let o = run(&case, &out, &["--set", "time.t_end=0.8"]);
    let left = out.exists();
    Command::new("umount").arg(&small).status().ok();
    let said = String::from_utf8_lossy(&checked.stdout).into_owned();
    assert_eq!(checked.status.code(), Some(0), "{}", stderr(&checked));
    assert!(
        said.contains("warning")
            && said.contains("keeps free")
            && said.contains("`run` refuses it"),
        "{said}"
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("keeps") && e.contains("output.every"), "{e}");
    assert!(!left, "no results file for a run refused");
}

/// A restart whose rest of the run the disk cannot hold is refused before
/// it changes the file, as a new run is: it ran on to a full disk, where
/// HDF5 failed mid-write and left the file unreadable, every record lost.
/// Needs a small tmpfs, as the disk-full test.
#[test]
fn a_restart_its_disk_cannot_hold_is_refused_and_the_file_kept() {
    let Some((case, small)) = slab_on_a_small_disk("restart-disk") else {
        return;
    };
    let out = small.join("r.h5");
    let first = run(&case, &out, &["--set", "time.t_end=0.1"]);
    let before = std::fs::read(&out).ok();
    // 2,000 more records of 4.6 kB (9 MB) on a 6 MB disk.
    let refused = restart(&case, &out, &["--set", "time.t_end=2"]);
    let after = std::fs::read(&out).ok();
    let fits = restart(&case, &out, &["--set", "time.t_end=0.2"]);
    // A restart to its checkpoint's own time adds no step: it needs none
    // of the room a run keeps (it was refused on a nearly full disk).
    let filler = fill_leaving(&small, 2 << 20);
    let no_step = restart(&case, &out, &["--set", "time.t_end=0.199"]);
    std::fs::remove_file(filler).ok();
    Command::new("umount").arg(&small).status().ok();
    assert_eq!(first.status.code(), Some(0), "{}", stderr(&first));
    let e = stderr(&refused);
    assert_eq!(refused.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--restart") && e.contains("the rest of the run") && e.contains("time.t_end"),
        "{e}"
    );
    assert!(
        before.is_some() && before == after,
        "the refused restart changed the file"
    );
    assert_eq!(fits.status.code(), Some(0), "{}", stderr(&fits));
    assert_eq!(no_step.status.code(), Some(0), "{}", stderr(&no_step));
}

/// Physical group names HDF5 cannot take as link names ("" and "."), a
/// '/' that would nest, and two names that meet once '/' is '_' are
/// stored under names it takes, each dataset with its group's own name as
/// the attribute `name`, which `probe --along` finds it by. The run
/// failed with "unknown library error" (exit 1) and left a broken file.
#[test]
fn group_names_hdf5_cannot_take_are_stored_under_others() {
    let dir = scratch("group-names");
    let shipped = root().join("cases/meshes/slab-q2-8x2.msh");
    let text = std::fs::read_to_string(&shipped).unwrap();
    for (body, load, stored) in [
        ("", "load", "_"),
        (".", "load", "_"),
        ("a/b", "a_b", "a_b#10"),
    ] {
        let mesh = dir.join("named.msh");
        let named = text
            .replace("\"body\"", &format!("{body:?}"))
            .replace("\"load\"", &format!("{load:?}"));
        std::fs::write(&mesh, named).unwrap();
        let (case, _) = slab_case(&dir, "slab", |t| {
            t.replace(&shipped.display().to_string(), &mesh.display().to_string())
                .replace("group = \"load\"", &format!("group = {load:?}"))
        });
        let out = dir.join("r.h5");
        ok(&run(&case, &out, &["--set", "time.t_end=0.01"]));
        let f = hdf5::File::open(&out).unwrap();
        let ds = f.dataset(&format!("mesh/groups/{stored}")).unwrap();
        let name = ds.attr("name").unwrap();
        let name = name.read_scalar::<hdf5::types::VarLenUnicode>().unwrap();
        assert_eq!(name.as_str(), body, "{stored}");
        assert_eq!(ds.attr("dim").unwrap().read_scalar::<i64>().unwrap(), 2);
        let o = bin()
            .arg("probe")
            .arg(&out)
            .args(["--along", load, "--field", "ux", "--times", "0"])
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&o.stdout).into_owned() + &stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{said}");
        assert!(said.contains("5 nodes"), "{said}");
    }
    // Two datasets that name one group (a file another program added
    // to): --along refuses the name, as the case refuses a mesh's.
    let out = dir.join("r.h5");
    {
        let f = hdf5::File::open_rw(&out).unwrap();
        let g = f.group("mesh/groups").unwrap();
        let nodes = g.dataset("contact").unwrap().read_raw::<i64>().unwrap();
        let ds = g
            .new_dataset_builder()
            .with_data(&nodes)
            .create("other")
            .unwrap();
        ds.new_attr::<hdf5::types::VarLenUnicode>()
            .create("name")
            .unwrap()
            .write_scalar(&"contact".parse::<hdf5::types::VarLenUnicode>().unwrap())
            .unwrap();
    }
    let o = bin()
        .arg("probe")
        .arg(&out)
        .args(["--along", "contact", "--field", "ux", "--times", "0"])
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("several groups are called \"contact\""), "{e}");
}

/// A copy `to` of the results file `from`, changed by `edit` as another
/// program would change it.
fn edited_copy(from: &Path, to: &Path, edit: impl FnOnce(&hdf5::File)) {
    std::fs::copy(from, to).unwrap();
    edit(&hdf5::File::open_rw(to).unwrap());
}

/// A results file whose /contact/lines or /mesh/nodes is damaged (another
/// shape) is named by `views` and `stress` with the dataset, exit 2: for
/// /contact/lines they printed HDF5's "ndim mismatch" alone and exited 1.
#[test]
fn views_and_stress_name_a_damaged_dataset_of_the_file() {
    let dir = scratch("damaged-dataset");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let r = dir.join("r.h5");
    ok(&run(&case, &r, &["--set", "time.t_end=0.01"]));
    for dataset in ["contact/lines", "mesh/nodes"] {
        let damaged = dir.join("damaged.h5");
        edited_copy(&r, &damaged, |f| {
            let flat = f.dataset(dataset).unwrap().read_raw::<f64>().unwrap();
            f.unlink(dataset).unwrap();
            f.new_dataset_builder()
                .with_data(&flat)
                .create(dataset)
                .unwrap();
        });
        for command in ["views", "stress"] {
            let o = bin().arg(command).arg(&damaged).output().unwrap();
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{command} {dataset}: {e}");
            assert!(
                e.contains(&format!("{}: ", damaged.display())) && e.contains(dataset),
                "{command} {dataset}: {e}"
            );
        }
    }
}

/// A restart of a file whose series another program rewrote (a contiguous
/// dataset, which cannot grow) or removed is refused before it changes
/// the file, exit 2: the first cut every other series back to the
/// checkpoint and then failed (exit 1, the last records lost), the second
/// exited 1 with nothing to do.
#[test]
fn a_restart_of_a_damaged_file_is_refused_before_it_changes_it() {
    let dir = scratch("restart-damaged");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let r = dir.join("r.h5");
    ok(&run(&case, &r, &["--set", "time.t_end=0.02"]));
    for (removed, says) in [(false, "cannot grow"), (true, "is missing")] {
        let damaged = dir.join("damaged.h5");
        edited_copy(&r, &damaged, |f| {
            let a = f
                .dataset("acceleration")
                .unwrap()
                .read_dyn::<f64>()
                .unwrap();
            f.unlink("acceleration").unwrap();
            if !removed {
                f.new_dataset_builder()
                    .with_data(&a)
                    .create("acceleration")
                    .unwrap();
            }
        });
        let e = refused_restart(&case, &damaged, &["--set", "time.t_end=0.04"]);
        assert!(
            e.contains(&format!(
                "--restart {}: /acceleration {says}",
                damaged.display()
            )) && e.contains("damaged"),
            "{e}"
        );
    }
}

/// A checkpoint whose clock another program changed is refused as damaged
/// (exit 2, the file unchanged): the restart ran at the times it gave and
/// blew up, blaming Δt. A summary attribute of another type (`dt_crit` as
/// text) is written anew: the restart failed there after its steps, exit 1.
#[test]
fn a_restart_reads_its_clock_and_rewrites_a_foreign_attribute() {
    use hdf5::types::VarLenUnicode;
    let dir = scratch("restart-clock");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let r = dir.join("r.h5");
    ok(&run(&case, &r, &["--set", "time.t_end=0.02"]));
    let clock = dir.join("clock.h5");
    edited_copy(&r, &clock, |f| {
        let cg = f.group("checkpoint").unwrap();
        for slot in cg.member_names().unwrap() {
            let g = cg.group(&slot).unwrap();
            if let Ok(a) = g.attr("clock_steps") {
                a.write_scalar(&(1u64 << 63)).unwrap();
            }
        }
    });
    let e = refused_restart(&case, &clock, &["--set", "time.t_end=0.04"]);
    assert!(e.contains("its clock") && e.contains("damaged"), "{e}");
    let text = dir.join("text.h5");
    edited_copy(&r, &text, |f| {
        let solver = f.group("solver").unwrap();
        solver.delete_attr("dt_crit").unwrap();
        solver
            .new_attr::<VarLenUnicode>()
            .create("dt_crit")
            .unwrap()
            .write_scalar(&"zz".parse::<VarLenUnicode>().unwrap())
            .unwrap();
    });
    ok(&restart(&case, &text, &["--set", "time.t_end=0.04"]));
    let f = hdf5::File::open(&text).unwrap();
    let dt_crit = f.group("solver").unwrap().attr("dt_crit").unwrap();
    assert!(dt_crit.read_scalar::<f64>().unwrap() > 0.0);
}

/// A part a belt carries along stores the belt's work as strain energy:
/// the blow-up test of central difference counts that work (it stopped a
/// stable run at t = 0.89 as "unstable", exit 1, blaming a foundation
/// stiffness the case does not have). Newmark completes the same run.
#[test]
fn a_belt_that_strains_a_held_part_is_no_blow_up() {
    let dir = scratch("belt-blow-up");
    let mesh = root().join("cases/meshes/slab-q2-8x2.msh");
    let case = dir.join("belt.toml");
    std::fs::write(
        &case,
        format!(
            "[mesh]\nfile = {mesh:?}\n[material]\nE = 1000.0\nnu = 0.3\nrho = 1.0\n\
             [[dirichlet]]\ngroup = \"support\"\nux = 0.0\nuy = 0.0\n\
             [contact]\ngroup = \"contact\"\npressure = 10.0\nmu = 5.0\neps = 1e-4\n\
             foundation_velocity = 0.05\n\
             [time]\nscheme = \"central_difference\"\ndt = 1e-3\nt_end = 1.0\n",
            mesh = mesh.display().to_string()
        ),
    )
    .unwrap();
    ok(&run(&case, &dir.join("r.h5"), &[]));
}

/// Mass-proportional damping the step cannot resolve (alpha·dt > 2) is
/// warned of by `check` and `run`: a floating slab at alpha = 1e7 kept
/// 67% of its kinetic energy, its velocity changing sign every step,
/// without a word. Below, no warning.
#[test]
fn damping_the_step_cannot_resolve_is_warned_of() {
    let dir = scratch("overdamped");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let said = |alpha: &str| {
        let o = check(&case, &[&format!("material.damping={{ alpha = {alpha} }}")]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let over = said("1e7");
    assert!(
        over.contains("warning") && over.contains("alpha·dt = 1.000e4 > 2"),
        "{over}"
    );
    assert!(
        !said("1e3").contains("alpha·dt"),
        "no warning at alpha·dt = 1"
    );
    let o = run(
        &case,
        &dir.join("r.h5"),
        &["--set", "material.damping={ alpha = 1e7 }"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("alpha·dt"), "{}", stderr(&o));
}

/// Files that only bear the names of a results file's companions and hold
/// what replacing them would lose (another run's results written as
/// r.views.h5 or r.stress.h5, a file in use, another program's HDF5 file)
/// are neither replaced by `views` and `stress` nor removed by a run, a
/// `--force` or a restart of r.h5: all exit 2 naming the file (before,
/// each went ahead and the other runs were lost). Views and stresses,
/// whoever's (a copied or renamed results file's), and a damaged one are
/// replaced and removed as before.
#[test]
fn files_named_like_companions_are_not_taken_for_them() {
    let dir = scratch("foreign-companions");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let r = dir.join("r.h5");
    let views = dir.join("r.views.h5");
    let stress = dir.join("r.stress.h5");
    ok(&run(&case, &r, &["--set", "time.t_end=0.02"]));
    ok(&run(&case, &views, &["--set", "material.E=2000"]));
    ok(&run(&case, &stress, &["--set", "material.E=3000"]));
    let bytes = |p: &Path| std::fs::read(p).unwrap();
    let (views_were, stress_was) = (bytes(&views), bytes(&stress));
    // The other runs' files, wherever the test has moved them.
    let kept = |at: [&Path; 2], what: &str| {
        assert!(bytes(at[0]) == views_were, "{what}: run 2's file changed");
        assert!(bytes(at[1]) == stress_was, "{what}: run 3's file changed");
    };
    let refused = |o: &Output, named: &Path, what: &str| {
        let e = stderr(o);
        assert_eq!(o.status.code(), Some(2), "{what}: {e}");
        assert!(
            e.contains(&format!(
                "{} is the results file of another run",
                named.display()
            )),
            "{what}: {e}"
        );
        if named == views {
            assert!(bytes(named) == views_were, "{what}: {e}");
        } else {
            assert!(bytes(named) == stress_was, "{what}: {e}");
        }
    };
    let command = |c: &str, file: &Path| bin().arg(c).arg(file).arg("--quiet").output().unwrap();
    for c in ["views", "stress"] {
        refused(&command(c, &r), &views, c);
    }
    refused(&run(&case, &r, &[]), &views, "run --force");
    // A restart forgets r.h5's own stresses only.
    ok(&restart(&case, &r, &["--set", "time.t_end=0.04"]));
    kept([&views, &stress], "restart");

    // With the views' name free, `views` writes r.h5's own, and its XML
    // lists no stresses of another run.
    let other = dir.join("other.h5");
    std::fs::rename(&views, &other).unwrap();
    ok(&command("views", &r));
    let xml = std::fs::read_to_string(dir.join("r.xdmf")).unwrap();
    assert!(!xml.contains("r.stress.h5"), "{xml}");
    std::fs::rename(&other, &views).unwrap();
    for gone in ["r.h5", "r.views.h5", "r.xdmf", "r.contact.xdmf"] {
        std::fs::rename(dir.join(gone), dir.join(format!("moved-{gone}"))).unwrap();
    }
    // r.h5 absent and no --force: the stresses' name alone stops the run.
    let o = common::run(&case, &r, &["--quiet"]);
    refused(&o, &stress, "a new run");
    assert!(!r.exists());
    std::fs::rename(dir.join("moved-r.h5"), &r).unwrap();
    refused(&command("stress", &r), &stress, "stress");

    // A results file copied with its views and stresses (or renamed):
    // theirs name the old file, but they hold nothing a command cannot
    // make again, so the copy's commands replace them, as a damaged one.
    std::fs::rename(&stress, dir.join("moved-r.stress.h5")).unwrap();
    ok(&command("views", &r));
    ok(&command("stress", &r));
    let s = dir.join("s.h5");
    for (from, to) in [
        ("r.h5", "s.h5"),
        ("r.views.h5", "s.views.h5"),
        ("r.stress.h5", "s.stress.h5"),
    ] {
        std::fs::copy(dir.join(from), dir.join(to)).unwrap();
    }
    let source = |p: &str| {
        let f = hdf5::File::open(dir.join(p)).unwrap();
        f.attr("source")
            .unwrap()
            .read_scalar::<hdf5::types::VarLenUnicode>()
            .unwrap()
            .to_string()
    };
    assert_eq!(source("s.views.h5"), "r.h5");
    ok(&command("views", &s));
    ok(&command("stress", &s));
    assert_eq!(source("s.views.h5"), "s.h5");
    assert_eq!(source("s.stress.h5"), "s.h5");
    // A viewer reading the stresses (HDF5's shared lock of a read-only
    // open, as ParaView holds it) does not make them another's: `views`
    // still lists them in s.xdmf.
    let reader = std::fs::File::open(dir.join("s.stress.h5")).unwrap();
    reader.lock_shared().unwrap();
    ok(&command("views", &s));
    let xdmf = std::fs::read_to_string(dir.join("s.xdmf")).unwrap();
    assert!(xdmf.contains("s.stress.h5"), "{xdmf}");
    drop(reader);
    std::fs::write(
        dir.join("s.views.h5"),
        &bytes(&dir.join("s.views.h5"))[..3000],
    )
    .unwrap();
    ok(&command("views", &s));
    // But not one held open (a run writing its results under that name),
    // nor another program's HDF5 file.
    let held = std::fs::File::open(dir.join("s.views.h5")).unwrap();
    held.lock().unwrap();
    let o = command("views", &s);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("is in use"), "{}", stderr(&o));
    drop(held);
    let theirs = hdf5::File::create(dir.join("s.stress.h5")).unwrap();
    theirs
        .new_dataset::<f64>()
        .shape(3)
        .create("mydata")
        .unwrap();
    drop(theirs);
    let o = command("stress", &s);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("is an HDF5 file of another program"),
        "{}",
        stderr(&o)
    );
    assert!(hdf5::File::open(dir.join("s.stress.h5"))
        .unwrap()
        .link_exists("mydata"));
    std::fs::remove_file(dir.join("s.stress.h5")).unwrap();
    ok(&command("stress", &s));
    ok(&run(&case, &s, &["--set", "time.t_end=0.02"]));
    assert!(!dir.join("s.views.h5").exists() && !dir.join("s.stress.h5").exists());
    std::fs::remove_file(&stress).unwrap();
    // r.h5's own companions: replaced by the commands, removed by --force.
    ok(&command("stress", &r));
    ok(&command("stress", &r));
    ok(&run(&case, &r, &["--set", "time.t_end=0.02"]));
    assert!(!views.exists() && !stress.exists());
    // Nor is a results file named as the files those commands write
    // beside r.h5 and then rename or remove.
    let part = dir.join("r.stress.h5.part");
    let o = run(&case, &part, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(".part names"), "{}", stderr(&o));
    assert!(!part.exists());
    // The other runs' files are whole.
    let moved = ["moved-r.views.h5", "moved-r.stress.h5"].map(|m| dir.join(m));
    kept([&moved[0], &moved[1]], "at the end");
    for file in &moved {
        ok(&probe_at(file));
    }
}

/// `stickslip probe FILE --at 8,0`.
fn probe_at(file: &Path) -> Output {
    bin()
        .arg("probe")
        .arg(file)
        .args(["--at", "8,0"])
        .output()
        .unwrap()
}

/// `probe` given a FIFO named like a results file exits 2 naming it (it
/// waited for a writer before: HDF5's open blocks on a FIFO), as do
/// `views` and `stress`; given the XDMF, it names the results file.
#[test]
fn probe_refuses_a_fifo_and_an_xdmf_for_a_results_file() {
    let dir = scratch("probe-fifo");
    let fifo = dir.join("f.h5");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    for command in ["probe", "views", "stress"] {
        let mut c = bin();
        c.arg(command).arg(&fifo);
        if command == "probe" {
            c.args(["--at", "8,0"]);
        }
        // Bounded: the fault this guards against is a wait without end.
        let mut child = c
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let started = Instant::now();
        while child.try_wait().unwrap().is_none() {
            if started.elapsed() > Duration::from_secs(30) {
                child.kill().unwrap();
                panic!("{command} on a FIFO still waits after 30 s");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let o = child.wait_with_output().unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{command}: {e}");
        assert!(e.contains("is not a regular file"), "{command}: {e}");
    }
    for xdmf in ["r.xdmf", "r.contact.xdmf"] {
        let o = probe_at(&dir.join(xdmf));
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        let named = format!(
            "give the results file the XDMF is written for, {}",
            dir.join("r.h5").display()
        );
        assert!(e.contains(&named), "{xdmf}: {e}");
    }
}

/// A mesh of mesh.ladder is an input of the case like mesh.file: `run -o`
/// (even with --force) and `check`'s output.file refuse it (a run wrote
/// its results over it). A ladder mesh that does not read is placed at
/// mesh.ladder by `advise`, not also at mesh.file's line.
#[test]
fn a_mesh_of_the_ladder_is_never_the_output() {
    let dir = scratch("ladder-output");
    let fine = dir.join("fine.msh");
    std::fs::copy(root().join("cases/meshes/slab-q2-16x4.msh"), &fine).unwrap();
    let ladder = |second: &Path| {
        let entries = format!(
            "ladder = [{}, {}]\n\n[material]",
            toml_str(&root().join("cases/meshes/slab-q2-8x2.msh")),
            toml_str(second)
        );
        move |t: String| t.replace("[material]", &entries)
    };
    let (case, text) = slab_case(&dir, "ladder", ladder(&fine));
    let before = std::fs::read(&fine).unwrap();
    let o = run(&case, &fine, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("a mesh of its mesh.ladder"), "{e}");
    let c = check(&case, &[&format!("output.file={}", toml_str(&fine))]);
    let e = stderr(&c);
    assert_eq!(c.status.code(), Some(2), "{e}");
    assert!(
        e.contains("output.file") && e.contains("a mesh of its mesh.ladder"),
        "{e}"
    );
    assert_eq!(
        std::fs::read(&fine).unwrap(),
        before,
        "the mesh is untouched"
    );

    let bad = dir.join("bad.msh");
    std::fs::write(&bad, "not a mesh\n").unwrap();
    let (case, text_bad) = slab_case(&dir, "bad-ladder", ladder(&bad));
    assert_eq!(line_of(&text, "file ="), line_of(&text_bad, "file ="));
    let o = bin()
        .arg("advise")
        .arg(&case)
        .args(["--tol", "0.1", "--on", "ux", "--at", "8,0"])
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    let at = |needle: &str| format!("bad-ladder.toml:{}:", line_of(&text_bad, needle));
    assert!(e.contains(&at("ladder =")) && e.contains("bad.msh"), "{e}");
    assert!(!e.contains(&at("file =")), "{e}");
}

/// Results files whose datasets disagree in shape (/mesh/nodes of one
/// column, /displacement of fewer nodes than the mesh) are refused with
/// exit 2 naming the dataset by `views`, `stress` and `probe --along`
/// (they panicked, exit 101, and `stress` left its .part behind).
#[test]
fn results_whose_shapes_disagree_are_refused_not_panicked_on() {
    let dir = scratch("bad-shapes");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let good = dir.join("good.h5");
    ok(&run(&case, &good, &[]));
    // A copy of the good file with the dataset `name` replaced by `data`.
    let replaced = |file: &str, name: &str, data: ndarray::ArrayD<f64>| {
        let path = dir.join(file);
        std::fs::copy(&good, &path).unwrap();
        let f = hdf5::File::open_rw(&path).unwrap();
        f.unlink(name).unwrap();
        f.new_dataset_builder()
            .with_data(&data)
            .create(name)
            .unwrap();
        path
    };
    let f = hdf5::File::open(&good).unwrap();
    let n = f.dataset("mesh/nodes").unwrap().shape()[0];
    let k = f.dataset("displacement").unwrap().shape()[0];
    drop(f);
    let nodes = replaced(
        "bad-nodes.h5",
        "mesh/nodes",
        ndarray::ArrayD::zeros(vec![n, 1]),
    );
    let disp = replaced(
        "bad-disp.h5",
        "displacement",
        ndarray::ArrayD::zeros(vec![k, 10, 2]),
    );
    assert_eq!((n, k), (85, 51));
    let along = ["--along", "contact", "--times", "0.01", "--field"];
    let cases: [(&Path, Vec<&str>, &str); 7] = [
        (&nodes, vec!["views"], "/mesh/nodes has shape [85, 1]"),
        (&nodes, vec!["stress"], "/mesh/nodes has shape [85, 1]"),
        (&disp, vec!["views"], "/displacement has shape [51, 10, 2]"),
        (&disp, vec!["stress"], "/displacement has shape [51, 10, 2]"),
        (
            &disp,
            [&["probe"][..], &along, &["sxx"]].concat(),
            "/displacement has shape [51, 10, 2]",
        ),
        (
            &disp,
            [&["probe"][..], &along, &["ux"]].concat(),
            "/displacement has shape [51, 10, 2]",
        ),
        (
            &disp,
            vec!["probe", "--at", "8,0", "--field", "ux"],
            "/displacement has shape [51, 10, 2]",
        ),
    ];
    for (file, args, want) in cases {
        let o = bin()
            .arg(args[0])
            .arg(file)
            .args(&args[1..])
            .output()
            .unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?} {}: {e}", file.display());
        assert!(e.contains(want) && !e.contains("panicked"), "{args:?}: {e}");
    }
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("bad-") && !["bad-nodes.h5", "bad-disp.h5"].contains(&n.as_str()))
        .collect();
    left.sort();
    assert_eq!(left, Vec::<String>::new(), "nothing written beside them");
}

/// A ':' in the results file's name: its XDMF files name it as
/// `NAME:/dataset`, which ParaView, VTK and meshio split at the first ':'
/// (an empty mesh, or no file at all); `run -o`, `check` (output.file),
/// `views` and `stress` refuse it with exit 2, saying what to do.
#[test]
fn a_colon_in_the_results_name_is_refused() {
    let dir = scratch("colon");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let colon = dir.join("case:1.h5");
    let o = run(&case, &colon, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("':'") && e.contains("-o") && e.contains("case_1.h5"),
        "{e}"
    );
    assert!(!colon.exists());
    let c = check(&case, &[&format!("output.file={}", toml_str(&colon))]);
    let e = stderr(&c);
    assert_eq!(c.status.code(), Some(2), "{e}");
    assert!(e.contains("output.file") && e.contains("':'"), "{e}");
    // A file renamed so after its run.
    let good = dir.join("good.h5");
    ok(&run(&case, &good, &[]));
    std::fs::copy(&good, &colon).unwrap();
    for command in ["views", "stress"] {
        let o = bin().arg(command).arg(&colon).output().unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{command}: {e}");
        assert!(
            e.contains("rename it") && e.contains("case_1.h5"),
            "{command}: {e}"
        );
    }
    for beside in ["case:1.xdmf", "case:1.views.h5", "case:1.stress.h5"] {
        assert!(!dir.join(beside).exists(), "{beside}");
    }
}

/// An output.file in a directory the run cannot write: `check` accepted
/// it and `run` refused it with "cannot create ..." alone; both now refuse
/// it at output.file's line of the case. A directory of mode 555 (as root,
/// which writes anyway, a read-only tmpfs; where none can be mounted the
/// test fails under CI and is skipped elsewhere).
#[test]
fn an_output_directory_the_run_cannot_write_is_refused_by_check_and_run() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("unwritable-output");
    let ro = dir.join("ro");
    std::fs::create_dir_all(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    let root_writes = std::fs::File::create(ro.join("probe")).is_ok();
    let mut mounted = None;
    if root_writes {
        std::fs::remove_file(ro.join("probe")).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
        mounted = tmpfs(&dir, "ro", "ro,size=1M");
        if mounted.is_none() {
            return;
        }
    }
    let out = ro.join("x.h5");
    let (case, text) = slab_case(&dir, "slab", |t| {
        t.replace("file = \"slab.h5\"", &format!("file = {}", toml_str(&out)))
    });
    let checked = check(&case, &[]);
    let o = bin().arg("run").arg(&case).arg("--quiet").output().unwrap();
    let created = out.exists();
    match mounted {
        Some(at) => {
            Command::new("umount").arg(&at).status().ok();
        }
        None => std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap(),
    }
    let line = format!("slab.toml:{}:", line_of(&text, "x.h5"));
    for (what, o) in [("check", &checked), ("run", &o)] {
        let e = stderr(o);
        assert_eq!(o.status.code(), Some(2), "{what}: {e}");
        assert!(
            e.contains(&line)
                && e.contains("output.file")
                && e.contains("cannot write in the directory"),
            "{what}: {e}"
        );
    }
    assert!(!created);
}

/// A run stopped by contact.max_iterations continues with a larger
/// budget, as the README says: its state is the last completed step's,
/// now checkpointed (a run that failed before its first flush held no
/// checkpoint, and the restart was refused), and the continued run is
/// bit for bit the one that never stopped.
#[test]
fn a_run_stopped_by_the_iteration_cap_continues_with_a_larger_one() {
    let dir = scratch("cap-restart");
    let case = paper_case(&dir, "newmark-step.toml");
    // Every step a frame (the case's), and 7 frames: the step it stopped
    // at is made a frame, which the checkpoint leaves out.
    for frames in ["output.every=1", "output.frames=7"] {
        let part = dir.join("part.h5");
        let o = run(
            &case,
            &part,
            &["--set", frames, "--set", "contact.max_iterations=2"],
        );
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(
            e.contains("did not converge in 2 iterations")
                && e.contains("a checkpoint at its last step")
                && e.contains("--restart"),
            "{e}"
        );
        let f = hdf5::File::open(&part).unwrap();
        let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
        let ft = f.dataset("frames/time").unwrap().read_raw::<f64>().unwrap();
        let last = |v: &[f64]| v.last().map(|x| x.to_bits());
        assert_eq!(last(&ft), last(&t), "{frames}");
        drop(f);
        let more = ["--set", frames, "--set", "contact.max_iterations=50"];
        ok(&restart(&case, &part, &more));
        let full = dir.join("full.h5");
        ok(&run(&case, &full, &more));
        assert_same_datasets(&full, &part);
    }
}

/// A normal-compliance Newton solve that fails is no budget a restart may
/// raise (its cap is fixed, and time.dt may not change on a restart): the
/// run is not offered a restart, and keeps its last flush's checkpoint.
#[test]
fn a_failed_newton_solve_offers_no_restart() {
    let dir = scratch("newton-no-restart");
    let case = paper_case(&dir, "newmark-step.toml");
    let text = std::fs::read_to_string(&case).unwrap().replace(
        "pressure = 300.0",
        "law = \"compliance\"\nfoundation = { point = [0.0, 0.0], normal = [0.0, 1.0] }\ncn = 1e12\nmn = 3.0",
    );
    let text = text.replace("t = [-150.0, 0.0]", "t = [-150.0, -3e6]");
    std::fs::write(&case, text).unwrap();
    let o = run(&case, &dir.join("n.h5"), &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("Newton solve did not converge"), "{e}");
    assert!(!e.contains("a checkpoint at its last step"), "{e}");
}

/// probe's table gives each row a time of its own: Remark 4.3's reduced
/// steps (1e-7 of a 5e-3 step) printed at 7 digits read as one time over
/// five and six rows.
#[test]
fn probe_tells_the_reduced_steps_times_apart() {
    let dir = scratch("probe-digits");
    let case = paper_case(&dir, "newmark-step-reduced.toml");
    let out = dir.join("r.h5");
    ok(&run(&case, &out, &["--set", "time.t_end=1.1"]));
    let o = probe(&out, &["--at", "8,0", "--field", "friction_stress"]);
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    let times: Vec<&str> = table
        .lines()
        .skip(2)
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    let distinct: std::collections::HashSet<&&str> = times.iter().collect();
    assert!(times.len() > 200, "{table}");
    assert_eq!(distinct.len(), times.len(), "{table}");
}

/// views and stress replace the viewers' XML files beside OUT.h5, but
/// not a file of those names that is no XDMF (notes, another program's
/// HDF5): it went without a word. Refused with exit 2, the file kept; an
/// empty one is replaced.
#[test]
fn views_keep_a_file_named_as_their_xml_that_is_no_xdmf() {
    let dir = scratch("foreign-xdmf");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    let out = dir.join("a.h5");
    ok(&run(&case, &out, &[]));
    for (name, command) in [("a.xdmf", "views"), ("a.contact.xdmf", "stress")] {
        let xml = dir.join(name);
        std::fs::write(&xml, "my notes\n").unwrap();
        let o = bin()
            .arg(command)
            .arg(&out)
            .arg("--quiet")
            .output()
            .unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{command}: {e}");
        assert!(e.contains(name) && e.contains("not an XDMF file"), "{e}");
        assert_eq!(std::fs::read_to_string(&xml).unwrap(), "my notes\n");
        std::fs::write(&xml, "").unwrap();
        let o = bin()
            .arg(command)
            .arg(&out)
            .arg("--quiet")
            .output()
            .unwrap();
        assert!(o.status.success(), "{command}: {}", stderr(&o));
        assert!(std::fs::read_to_string(&xml).unwrap().contains("<Xdmf"));
    }
}

/// A results file on a file system without a size (proc, sysfs report 0
/// blocks, 0 free) is refused as a place it cannot create, not as a disk
/// too full for the run (which told the user to write fewer frames).
#[test]
fn a_file_system_without_a_size_is_not_called_full() {
    let dir = scratch("sizeless-fs");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    for out in ["/proc/stickslip-x.h5", "/sys/stickslip-x.h5"] {
        let o = run(&case, Path::new(out), &[]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{out}: {e}");
        assert!(
            e.contains("cannot create") && e.contains("-o"),
            "{out}: {e}"
        );
        assert!(!e.contains("free"), "{out}: {e}");
    }
}

/// Messages that said the wrong thing, or nothing to do: `views` on a
/// directory ("no such results file"), `probe` and `mesh` on a directory
/// (HDF5's text, the OS error alone), `run --restart` given the case file
/// (HDF5's H5Fopen text).
#[test]
fn directories_and_a_case_given_as_results_are_named_for_what_they_are() {
    let dir = scratch("named-for-what");
    let (case, _) = slab_case(&dir, "slab", |t| t);
    for command in ["views", "stress"] {
        let o = bin().arg(command).arg(&dir).output().unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{command}: {e}");
        assert!(
            e.contains("is a directory; give a results file"),
            "{command}: {e}"
        );
    }
    let o = probe_at(&dir);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("is a directory; give a results file"), "{e}");
    let o = bin().arg("mesh").arg(&dir).output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains(&dir.display().to_string()) && e.contains("is a directory, not a mesh file"),
        "{e}"
    );
    let before = std::fs::read(&case).unwrap();
    let o = restart(&case, &case, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("is not a results file of `stickslip run`")
            && e.contains("--restart OUT.h5")
            && !e.contains("H5Fopen"),
        "{e}"
    );
    assert_eq!(std::fs::read(&case).unwrap(), before);
}

/// `advise` on a quasi-static case says what to do without the `--set`
/// it suggested, which `advise` does not take.
#[test]
fn advise_on_a_quasi_static_case_suggests_only_what_it_takes() {
    let dir = scratch("advise-quasi-static");
    let (case, _) = slab_case(&dir, "qs", |t| {
        t.replace(
            "scheme = \"central_difference\"",
            "scheme = \"quasi_static\"",
        )
    });
    let o = bin()
        .arg("advise")
        .arg(&case)
        .args(["--tol", "0.1", "--on", "ux", "--at", "8,0"])
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("quasi-static case has no such choice"), "{e}");
    assert!(
        !e.contains("--set") && e.contains("copy of the case"),
        "{e}"
    );
}
