//! The compliance law's keys from the case file (docs/case-file.md, "A
//! compliant foundation"): a good surface builds its foundation's nodes,
//! and every bad input is named at its line with what to do.

use std::path::Path;

use stickslip_case::{assemble, load_str, Case};
use stickslip_testkit::case_text::paper_slab_head;

/// The paper's slab (8 × 1, "contact" the bottom y = 0) with `contact`
/// as its surfaces, started at rest.
fn slab(contact: &str, initial: &str) -> String {
    format!(
        r#"{head}{contact}
{initial}
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.01
"#,
        head = paper_slab_head()
    )
}

const REST: &str = "[initial]\nstate = \"rest\"\n";

const FLOOR: &str = r#"[contact]
group = "contact"
law = "compliance"
foundation = { point = [0.0, -0.01], normal = [0.0, 2.0] }
cn = 1e4
mu = 0.3
eps = 1e-3
"#;

fn load(text: &str) -> Result<Case, String> {
    load_str(Path::new("case.toml"), text, &[]).map_err(|e| e.to_string())
}

/// The 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle in text")
        + 1
}

fn assert_at(e: &str, text: &str, needle: &str, what: &str) {
    let at = format!("case.toml:{}:", line_of(text, needle));
    assert!(
        e.lines().any(|l| l.contains(&at) && l.contains(what)),
        "no {what:?} at {at} in:\n{e}"
    );
}

/// The floor below the slab's bottom: every bottom node 0.01 off it (the
/// normal's length does not matter), friction c_T = μ c_n with m_T = m_n
/// = 1, friction along +x (the bottom's tangent), no pressure load.
#[test]
fn a_floor_builds_its_nodes_gaps_and_law() {
    let case = load(&slab(FLOOR, REST)).unwrap();
    let scene = assemble(&case).unwrap();
    let c = scene.contact.as_ref().unwrap();
    // Q2 8 × 2 slab: 17 nodes on the bottom, all free.
    assert_eq!(c.compliance.len(), 17);
    for k in &c.compliance {
        assert!((k.gap - 0.01).abs() < 1e-15, "{k:?}");
        assert_eq!(k.normal, [0.0, 1.0]);
        assert_eq!(
            (k.law.cn, k.law.mn, k.law.ct, k.law.mt),
            (1e4, 1.0, 0.3 * 1e4, 1.0)
        );
        assert_eq!(c.nodes[k.index].tangent, [1.0, 0.0]);
        assert_eq!(c.nodes[k.index].bound, 0.0);
    }
    assert!(scene
        .loads
        .iter()
        .all(|l| l.vector.iter().all(|&x| x == 0.0)));
}

#[test]
fn bad_compliance_input_is_named_at_its_line() {
    let bad = FLOOR
        .replace("normal = [0.0, 2.0]", "normal = [0.0, 0.0]")
        .replace("cn = 1e4", "cn = 0.0\nmn = 0.5\nct = 1.0\npressure = 3.0");
    let text = slab(&bad, REST);
    let e = load(&text).unwrap_err();
    for (needle, what) in [
        ("foundation =", "has no direction"),
        ("cn = 0.0", "contact.cn = 0 must be > 0"),
        ("mn = 0.5", "contact.mn = 0.5 must be >= 1"),
        ("ct = 1.0", "give mu (c_T = mu cn, mt = mn) or ct"),
        (
            "pressure = 3.0",
            "contact.pressure belongs to a prescribed pressure",
        ),
    ] {
        assert_at(&e, &text, needle, what);
    }
    // Compliance keys on a prescribed-pressure surface.
    let text = slab(
        "[contact]\ngroup = \"contact\"\npressure = 300.0\nmu = 0.3\neps = 1e-2\ncn = 1e4\n",
        "",
    );
    let e = load(&text).unwrap_err();
    assert_at(
        &e,
        &text,
        "cn = 1e4",
        "contact.cn belongs to law = \"compliance\"",
    );
    // A compliance surface with neither cn nor a foundation nor friction.
    let text = slab(
        "[contact]\ngroup = \"contact\"\nlaw = \"compliance\"\neps = 1e-2\n",
        REST,
    );
    let e = load(&text).unwrap_err();
    for what in ["needs foundation", "needs cn", "needs mu"] {
        assert_at(&e, &text, "law = \"compliance\"", what);
    }
}

/// The quasi-static increments take the law: the slab of
/// `a_static_start_settles_a_node_inside_the_foundation` (rollers on its
/// top, left end held in x, its bottom 0.02 inside the floor, no load)
/// stays at the preload's closed form σ = c_n d / (1 + c_n (1 − ν²) H / E)
/// through increments that add nothing (each ends in equilibrium with the
/// foundation's end-point force), to 1e-9 of σ.
#[test]
fn the_law_runs_with_quasi_static_increments() {
    let (cn, d, compliance) = (1e4, 0.02, (1.0 - 0.3 * 0.3) * 1.0 / 1000.0);
    let sigma = cn * d / (1.0 + cn * compliance);
    let floor = FLOOR.replace("point = [0.0, -0.01]", "point = [0.0, 0.02]");
    let text = slab(
        &format!(
            "[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n[[dirichlet]]\ngroup = \"support\"\n\
             uy = 0.0\n{floor}"
        ),
        "[initial]\nstate = \"static\"\n",
    )
    .replace("\"central_difference\"", "\"quasi_static\"");
    let case = load(&text).unwrap();
    let mut running = assemble(&case).unwrap().running(&case).unwrap();
    let run = &mut running.integrator;
    for _ in 0..3 {
        run.step().unwrap();
    }
    let mut traction = vec![0.0; run.contact().unwrap().len()];
    run.normal_traction(&mut traction);
    for t in &traction {
        assert!((t - sigma).abs() < 1e-9 * sigma, "{t} ≠ {sigma}");
    }
}

/// A part the foundation alone holds (the slab's left end held in x, free
/// in y) is refused for the quasi-static increments, at the supports,
/// with the motion named and why: each increment factorizes dt K, which
/// the foundation's springs do not join.
#[test]
fn quasi_static_refuses_a_part_held_only_by_the_foundation() {
    let text = slab(
        &format!("[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n{FLOOR}"),
        "[initial]\nstate = \"static\"\n",
    )
    .replace("\"central_difference\"", "\"quasi_static\"");
    let e = assemble(&load(&text).unwrap()).unwrap_err().to_string();
    assert_at(&e, &text, "group = \"left\"", "translation in y");
    assert!(e.contains("compliant foundation"), "{e}");
}

/// `state = "static"` on a floor: the slab (rollers on its top taken off,
/// its left end held in x) pressed by p = 300 on its top (the group
/// "support", constant: present before t = 0) onto a floor of c_n = 1e4
/// touching its bottom starts at the
/// approach p/c_n = 0.03 at every bottom node (uniform compression passes p
/// to the floor; the Q2 cells hold that field exactly) to 1e-9.
#[test]
fn a_static_start_presses_the_slab_into_the_floor() {
    let floor = FLOOR.replace("point = [0.0, -0.01]", "point = [0.0, 0.0]");
    let text = slab(
        &format!(
            "[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n[[traction]]\ngroup = \"support\"\n\
             pressure = 300.0\nhistory = \"constant\"\n{floor}"
        ),
        "[initial]\nstate = \"static\"\n",
    );
    let case = load(&text).unwrap();
    let scene = assemble(&case).unwrap();
    let running = scene.running(&case).unwrap();
    let run = &running.integrator;
    let contact = run.contact().unwrap();
    assert_eq!(contact.nodes.len(), 17);
    for n in &contact.nodes {
        let uy = run.displacement()[n.dofs[1].unwrap()];
        assert!((uy + 0.03).abs() < 1e-9, "node {}: {uy}", n.node);
    }
}

/// Newmark takes the law from rest.
#[test]
fn the_law_runs_with_newmark() {
    let text = slab(FLOOR, REST).replace(
        "\"central_difference\"",
        "\"newmark\"\nmass = \"consistent\"",
    );
    assemble(&load(&text).unwrap()).unwrap();
}

/// A node that starts inside the foundation is refused, for a start at
/// rest, with its place and the number of others that do.
#[test]
fn a_node_inside_the_foundation_is_refused() {
    let text = slab(
        &FLOOR.replace("point = [0.0, -0.01]", "point = [0.0, 0.02]"),
        REST,
    );
    let e = assemble(&load(&text).unwrap()).unwrap_err().to_string();
    assert_at(
        &e,
        &text,
        "foundation =",
        "starts 2e-2 inside the foundation",
    );
    assert!(e.contains("node 1 at (0, 0)"), "{e}");
    // One message for the face, not one a node (17 lines before).
    assert_eq!(e.matches("inside the foundation").count(), 1, "{e}");
    assert!(e.contains("(and 16 other nodes of it)"), "{e}");
}

/// With `state = "static"` a node inside the foundation is an
/// interference the preload settles. The slab (rollers on its top y = H
/// = 1, its left end held in x, no load at all) starts with its bottom
/// d = 0.02 inside a floor of c_n = 1e4. Closed form: the preloaded state
/// is uniform uniaxial stress σ_yy = −σ (σ_xx = 0: the right end is free;
/// the Q2 cells hold the field exactly), the bottom moves up by u =
/// σ (1 − ν²) H / E (plane strain) and the floor's traction is
/// σ = c_n (d − u), so σ = c_n d / (1 + c_n (1 − ν²) H / E) = 200 / 10.1.
/// Every bottom node's traction to 1e-9 of σ, its uy to 1e-9 of u.
#[test]
fn a_static_start_settles_a_node_inside_the_foundation() {
    let (cn, d, compliance) = (1e4, 0.02, (1.0 - 0.3 * 0.3) * 1.0 / 1000.0);
    let sigma = cn * d / (1.0 + cn * compliance);
    let floor = FLOOR.replace("point = [0.0, -0.01]", "point = [0.0, 0.02]");
    let text = slab(
        &format!(
            "[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n[[dirichlet]]\ngroup = \"support\"\n\
             uy = 0.0\n{floor}"
        ),
        "[initial]\nstate = \"static\"\n",
    );
    let case = load(&text).unwrap();
    let scene = assemble(&case).unwrap();
    let c = scene.contact.as_ref().unwrap();
    assert!(c.compliance.iter().all(|k| (k.gap + d).abs() < 1e-15));
    let running = scene.running(&case).unwrap();
    let run = &running.integrator;
    let contact = run.contact().unwrap();
    let mut traction = vec![0.0; contact.len()];
    run.normal_traction(&mut traction);
    assert_eq!(contact.nodes.len(), 17);
    for (n, t) in contact.nodes.iter().zip(&traction) {
        assert!(
            (t - sigma).abs() < 1e-9 * sigma,
            "node {}: {t} ≠ {sigma}",
            n.node
        );
        let uy = run.displacement()[n.dofs[1].unwrap()];
        let u = sigma * compliance;
        assert!((uy - u).abs() < 1e-9 * u, "node {}: {uy} ≠ {u}", n.node);
    }
}

/// An interference with nothing holding the part against the foundation:
/// the slab, its left end held in x only (free to translate in y), starts
/// with its bottom 0.02 inside the floor and no load; the only static
/// state is the slab lifted rigidly until it just touches (closed form:
/// u_y = 0.02 everywhere, no traction). To 1e-9 of 0.02 and of c_n·0.02.
#[test]
fn a_static_start_lifts_a_free_part_out_of_the_foundation() {
    let d = 0.02;
    let floor = FLOOR.replace("point = [0.0, -0.01]", "point = [0.0, 0.02]");
    let text = slab(
        &format!("[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n{floor}"),
        "[initial]\nstate = \"static\"\n",
    );
    let case = load(&text).unwrap();
    let running = assemble(&case).unwrap().running(&case).unwrap();
    let run = &running.integrator;
    let contact = run.contact().unwrap();
    let mut traction = vec![0.0; contact.len()];
    run.normal_traction(&mut traction);
    for (n, t) in contact.nodes.iter().zip(&traction) {
        assert!(t.abs() <= 1e-9 * 1e4 * d, "node {}: traction {t}", n.node);
    }
    let u = run.displacement();
    for node in 0..running.mesh.nodes.len() {
        for (c, expected) in [(0, 0.0), (1, d)] {
            if let Some(i) = running.dofs.free(node, c) {
                let v = u[i];
                assert!((v - expected).abs() <= 1e-9 * d, "node {node}, u_{c}: {v}");
            }
        }
    }
}

/// A moving foundation or a speed-dependent μ on a compliance surface is
/// not built: each is refused at its line rather than ignored.
#[test]
fn a_compliant_foundation_refuses_motion_and_a_falling_mu() {
    // Each with the remedy for its own key (a moving foundation was told
    // to "give a constant mu").
    for (swap, needle, remedy) in [
        (
            "mu = 0.3\n",
            "foundation_velocity = 0.5",
            "remove foundation_velocity, or use",
        ),
        (
            "mu = 0.3\n",
            "mu = { static = 0.3, kinetic = 0.2, speed = 0.1 }",
            "give a constant mu, or use",
        ),
    ] {
        let surface = FLOOR.replace(swap, &format!("{needle}\n"));
        let surface = if needle.starts_with("foundation_velocity") {
            format!("{surface}mu = 0.3\n")
        } else {
            surface
        };
        let text = slab(&surface, REST);
        let e = load(&text).unwrap_err();
        assert_at(
            &e,
            &text,
            needle,
            "law = \"compliance\" takes a foundation at rest",
        );
        assert!(e.contains(remedy), "{e}");
    }
}

/// A compliant floor listed before a belt whose speed follows a table:
/// the belt's history stays the belt's. Expected: the table [[0, 0], [1,
/// 1]] is θ(t) = t, so after one step of Δt = 1e-3 the belt's nodes move
/// at V θ = 2 · 1e-3 and the floor's stay at rest.
#[test]
fn a_belt_after_a_compliant_floor_keeps_its_history() {
    let belt = r#"[[contact]]
group = "support"
pressure = 200.0
mu = 0.2
eps = 1e-2
foundation_velocity = 2.0
foundation_history = { table = [[0.0, 0.0], [1.0, 1.0]] }
"#;
    let floor = FLOOR.replace("[contact]", "[[contact]]");
    let case = load(&slab(&format!("{floor}{belt}"), REST)).unwrap();
    let scene = assemble(&case).unwrap();
    assert_eq!(scene.foundation_histories.len(), 2);
    let mut integrator = scene.integrator().unwrap();
    integrator.step().unwrap();
    let c = integrator.contact().unwrap();
    assert_eq!(c.parts.len(), 2);
    for j in c.parts[1].nodes.clone() {
        let v = c.foundation_speed(j);
        assert!((v - 2.0e-3).abs() <= 1e-15, "belt node {j}: V = {v}");
    }
    for j in c.parts[0].nodes.clone() {
        assert_eq!(c.foundation_speed(j), 0.0, "floor node {j}");
    }
}

/// A contact node held by a [[dirichlet]] condition at a value other than
/// 0 along the foundation's normal is refused: the approach is measured by
/// the free components, so the law would not see that motion (the slab's
/// corner (0, 0) is on "left" and on "contact").
#[test]
fn a_node_held_off_zero_along_the_normal_is_refused() {
    let held = "[[dirichlet]]\ngroup = \"left\"\nuy = -0.01\n";
    let text = slab(&format!("{held}{FLOOR}"), REST);
    let e = assemble(&load(&text).unwrap()).unwrap_err().to_string();
    assert_at(
        &e,
        &text,
        "foundation =",
        "has uy = -0.01 from a [[dirichlet]]",
    );
    assert!(e.contains("node 1 at (0, 0)"), "{e}");
    // Held at 0 it is a support like any other.
    let text = slab(&format!("{}{FLOOR}", held.replace("-0.01", "0.0")), REST);
    assert!(assemble(&load(&text).unwrap()).is_ok());
}
