//! Several contact surfaces and a pressure that changes, from the case
//! file: `[[contact]]` read beside the single `[contact]` table, each
//! surface's bounds as the profile makes them, and every bad input named
//! at its line.

use std::path::Path;

use stickslip_case::{assemble, load_str, Case};
use stickslip_testkit::case_text::paper_slab_head;

/// The paper's slab (8 × 1, "contact" the bottom, "support" the top with
/// rollers, "left" held in x, "load" the right end) with `contact` as its
/// friction tables.
fn slab(contact: &str) -> String {
    format!(
        r#"{head}[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "load"
t = [-150.0, 0.0]
{contact}
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.01
"#,
        head = paper_slab_head()
    )
}

const BOTTOM: &str = r#"[[contact]]
group = "contact"
pressure = 300.0
mu = 0.3
eps = 1e-2
"#;

const TOP: &str = r#"[[contact]]
group = "support"
pressure = 200.0
mu = 0.2
eps = 1e-2
"#;

fn load(text: &str) -> Result<Case, String> {
    load_str(Path::new("case.toml"), text, &[]).map_err(|e| e.to_string())
}

/// The 1-based line of the first line of `text` containing `needle`: the
/// expected places come from the test's own text.
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

#[test]
fn one_table_and_a_list_are_both_surfaces() {
    let one = load(&slab(&BOTTOM.replace("[[contact]]", "[contact]"))).unwrap();
    assert_eq!(one.contact.len(), 1);
    assert_eq!(one.contact[0].group, "contact");
    let two = load(&slab(&format!("{BOTTOM}{TOP}"))).unwrap();
    assert_eq!(two.contact.len(), 2);
    assert_eq!(
        (two.contact[1].group.as_str(), two.contact[1].mu_at_rest()),
        ("support", 0.2)
    );
    let none = load(&slab("")).unwrap();
    assert!(none.contact.is_empty());
}

/// Bounds g_J = μ·p·profile(s_J): 90 (0.5 + s/16) on the bottom for the
/// profile 0.5 at s = 0 to 1 at s = 8, and 0.2·200 = 40 on the top.
#[test]
fn each_surface_keeps_its_own_bounds() {
    let profile = "pressure_profile = { table = [[0.0, 0.5], [8.0, 1.0]] }\n";
    let case = load(&slab(&format!("{BOTTOM}{profile}{TOP}"))).unwrap();
    let scene = assemble(&case).unwrap();
    let c = scene.contact.as_ref().unwrap();
    assert_eq!(c.parts.len(), 2);
    assert_eq!(
        (c.parts[0].group.as_str(), c.parts[1].group.as_str()),
        ("contact", "support")
    );
    assert_eq!(c.parts[0].nodes.end, c.parts[1].nodes.start);
    assert_eq!(c.parts[1].nodes.end, c.len());
    for n in &c.nodes[c.parts[0].nodes.clone()] {
        let expected = 90.0 * (0.5 + n.s / 16.0);
        assert!(
            (n.bound - expected).abs() < 1e-12,
            "s = {}: {} vs {expected}",
            n.s,
            n.bound
        );
    }
    for n in &c.nodes[c.parts[1].nodes.clone()] {
        assert!((n.bound - 40.0).abs() < 1e-12);
    }
    // One pressure load per surface after the end load, each constant by
    // default (part of the initial static state).
    assert_eq!(scene.loads.len(), 3);
    assert_eq!(scene.pressure_histories.len(), 2);
    // The profile's load: the bottom face's total normal force is
    // ∫ 300 (0.5 + x/16) dx over [0, 8] = 300·6 = 1800, pushing up (+y).
    let total_y: f64 = (0..scene.mesh.nodes.len())
        .filter_map(|v| scene.model.dofs.free(v, 1))
        .map(|d| scene.loads[1].vector[d])
        .sum();
    assert!((total_y - 1800.0).abs() < 1e-9, "{total_y}");
}

#[test]
fn bad_surfaces_are_named_at_their_line() {
    // Unsorted profile, a negative factor, the same group twice, an
    // unsorted pressure history (a different eps is the top's own).
    let text = slab(&format!(
        "{BOTTOM}pressure_profile = {{ table = [[2.0, 1.0], [1.0, 1.0]] }}\n\
         {}pressure_profile = {{ table = [[0.0, -0.5]] }}\n\
         {}pressure_history = {{ table = [[0.5, 1.0], [0.1, 0.0]] }}\n",
        TOP.replace("eps = 1e-2", "eps = 1e-3"),
        BOTTOM.replace("pressure = 300.0", "pressure = 310.0")
    ));
    let e = load(&text).unwrap_err();
    assert_at(&e, &text, "[[2.0, 1.0], [1.0, 1.0]]", "strictly increasing");
    assert_at(&e, &text, "[[0.0, -0.5]]", "must be >= 0");
    assert!(!e.contains("eps"), "{e}");
    let second_bottom = text.match_indices("group = \"contact\"").nth(1).unwrap().0;
    let line = text[..second_bottom].lines().count() + 1;
    assert!(
        e.lines().any(|l| l.contains(&format!("case.toml:{line}:"))
            && l.contains("already the group of contact.0")),
        "no repeated group at line {line} in:\n{e}"
    );
    assert_at(
        &e,
        &text,
        "[[0.5, 1.0], [0.1, 0.0]]",
        "strictly increasing times",
    );
}

/// The bottom and the loaded right end share the corner (8, 0), free to
/// slide along both; a profile past the bottom's length 8.
#[test]
fn what_the_mesh_reveals_is_named_at_its_line() {
    let end = r#"[[contact]]
group = "load"
pressure = 10.0
mu = 0.3
eps = 1e-2
"#;
    let text = slab(&format!("{BOTTOM}{end}"));
    let case = load(&text).unwrap();
    let e = assemble(&case).unwrap_err().to_string();
    let second = text.match_indices("group = \"load\"").nth(1).unwrap().0;
    let line = text[..second].lines().count() + 1;
    assert!(
        e.contains(&format!("case.toml:{line}:"))
            && e.contains(
                "at (8, 0) carries friction on both surface \"contact\" and surface \"load\""
            ),
        "{e}"
    );

    let text = slab(&format!(
        "{BOTTOM}pressure_profile = {{ table = [[0.0, 1.0], [9.0, 1.0]] }}\n"
    ));
    let e = assemble(&load(&text).unwrap()).unwrap_err().to_string();
    assert_at(
        &e,
        &text,
        "[9.0, 1.0]",
        "runs past the end of surface \"contact\", which is 8 long",
    );
}

/// Each surface keeps its own eps: the bottom's nodes 1e-2, the top's 1e-3.
#[test]
fn each_surface_keeps_its_own_eps() {
    let top = TOP.replace("eps = 1e-2", "eps = 1e-3");
    let scene = assemble(&load(&slab(&format!("{BOTTOM}{top}"))).unwrap()).unwrap();
    let c = scene.contact.unwrap();
    for (k, eps) in [(0, 1e-2), (1, 1e-3)] {
        for j in c.parts[k].nodes.clone() {
            assert_eq!(c.law_of(j).eps, eps);
        }
    }
    let same = assemble(&load(&slab(&format!("{BOTTOM}{TOP}"))).unwrap()).unwrap();
    assert!(same.contact.unwrap().node_eps.is_empty());
}

/// `foundation_velocity` reaches each surface's nodes: V on the bottom's,
/// 0 on the top's; a case without it keeps no speeds at all.
#[test]
fn each_surface_keeps_its_own_foundation_speed() {
    let belt = "foundation_velocity = 2.5\nfoundation_history = { sin = { omega = 3.0 } }\n";
    let case = load(&slab(&format!("{BOTTOM}{belt}{TOP}"))).unwrap();
    let scene = assemble(&case).unwrap();
    let c = scene.contact.as_ref().unwrap();
    for j in c.parts[0].nodes.clone() {
        assert_eq!(c.foundation_speed(j), 2.5);
    }
    for j in c.parts[1].nodes.clone() {
        assert_eq!(c.foundation_speed(j), 0.0);
    }
    assert_eq!(scene.foundation_histories.len(), 2);
    let plain = assemble(&load(&slab(BOTTOM)).unwrap()).unwrap();
    assert!(plain.contact.unwrap().foundation.is_empty());
}

#[test]
fn bad_foundations_are_named_at_their_line() {
    // A speed of the wrong type, a history of the wrong form (both found
    // before the values are read), then a table unsorted in time.
    let text = slab(&format!(
        "{BOTTOM}foundation_velocity = \"fast\"\nfoundation_history = \"ramp\"\n"
    ));
    let e = load(&text).unwrap_err();
    assert_at(
        &e,
        &text,
        "foundation_velocity = \"fast\"",
        "expected a number",
    );
    assert_at(
        &e,
        &text,
        "foundation_history = \"ramp\"",
        "unknown variant `ramp`",
    );
    let text = slab(&format!(
        "{BOTTOM}{TOP}foundation_velocity = 1.0\nfoundation_history = {{ table = [[0.5, 1.0], [0.1, 0.0]] }}\n"
    ));
    let e = load(&text).unwrap_err();
    assert_at(
        &e,
        &text,
        "[[0.5, 1.0], [0.1, 0.0]]",
        "strictly increasing times",
    );
    let text = slab(&format!("{BOTTOM}foundation_velocity = inf\n"));
    let e = load(&text).unwrap_err();
    assert_at(
        &e,
        &text,
        "foundation_velocity = inf",
        "is not a finite number",
    );
}

/// `mu = { static, kinetic, speed }`: g = μs·p on the nodes, the fall
/// r = μk/μs and vs on each; `mu = 0.3` keeps none.
#[test]
fn a_speed_dependent_mu_reaches_the_nodes() {
    let bottom = BOTTOM.replace(
        "mu = 0.3",
        "mu = { static = 0.5, kinetic = 0.25, speed = 1e-2 }",
    );
    let scene = assemble(&load(&slab(&bottom)).unwrap()).unwrap();
    let c = scene.contact.unwrap();
    for (j, n) in c.nodes.iter().enumerate() {
        assert_eq!(n.bound, 0.5 * 300.0);
        let k = c.weakening_of(j).unwrap();
        assert_eq!((k.ratio, k.speed), (0.5, 1e-2));
    }
    let plain = assemble(&load(&slab(BOTTOM)).unwrap()).unwrap();
    assert!(!plain.contact.unwrap().weakens());
}

#[test]
fn bad_speed_dependent_mus_are_named_at_their_line() {
    let with = |mu: &str| slab(&BOTTOM.replace("mu = 0.3", mu));
    for (mu, what) in [
        (
            "mu = { static = 0.3, kinetic = 0.5, speed = 1e-2 }",
            "at most static = 0.3",
        ),
        (
            "mu = { static = 0.3, kinetic = 0.2, speed = 0.0 }",
            "speed = 0 must be > 0",
        ),
        (
            "mu = { static = 0.3, kinetic = 0.2, sped = 1e-2 }",
            "mu has no key `sped`",
        ),
        ("mu = { static = 0.3, kinetic = 0.2 }", "mu lacks speed"),
        (
            "mu = \"high\"",
            "a number or a table { static, kinetic, speed }",
        ),
    ] {
        let text = with(mu);
        let e = load(&text).unwrap_err();
        assert_at(&e, &text, mu, what);
    }
}

/// Every scheme takes a speed-dependent mu (the implicit ones with μ
/// lagged by a step).
#[test]
fn a_speed_dependent_mu_runs_with_every_scheme() {
    let text = slab(&BOTTOM.replace(
        "mu = 0.3",
        "mu = { static = 0.3, kinetic = 0.2, speed = 1e-2 }",
    ));
    for scheme in ["central_difference", "newmark", "quasi_static"] {
        let text = text.replace(
            "scheme = \"central_difference\"",
            &format!("scheme = \"{scheme}\""),
        );
        let scene = assemble(&load(&text).unwrap()).unwrap();
        assert!(scene.integrator().is_ok(), "{scheme}");
    }
}
