//! End-to-end tests of `stickslip mesh` and of the command line itself,
//! driving the built binary as a user does.
//!
//! Expected counts come from the slab's geometry (shared/BENCHMARK.md): an
//! 8 × 2 grid of quad9 cells is a 17 × 5 grid of 85 nodes; the bottom
//! (`contact`) and top (`support`) each have 8 line3 elements and 17 nodes,
//! the ends (`left`, `load`) 2 line3 elements and 5 nodes; bbox [0, 8] × [0, 1].

use std::path::{Path, PathBuf};

mod common;
use common::{bin, data, root, stderr};

fn mesh_json(file: &Path) -> serde_json::Value {
    let o = bin().arg("mesh").arg(file).arg("--json").output().unwrap();
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        stderr(&o)
    );
    serde_json::from_slice(&o.stdout).expect("stdout is one JSON object")
}

fn check_slab_q2_8x2(j: &serde_json::Value, version: &str) {
    assert_eq!(j["format"], "msh");
    assert_eq!(j["version"], version);
    assert_eq!(j["binary"], false);
    assert_eq!(j["nodes"], 85);
    assert_eq!(j["cells"], serde_json::json!({"quad9": 16}));
    assert_eq!(j["boundary_elements"], serde_json::json!({"line3": 20}));
    assert_eq!(j["reoriented"], 0);
    let g = &j["groups"];
    for (name, dim, elements, nodes) in [
        ("contact", 1, 8, 17),
        ("support", 1, 8, 17),
        ("left", 1, 2, 5),
        ("load", 1, 2, 5),
        ("body", 2, 16, 85),
    ] {
        let want = serde_json::json!({"dim": dim, "elements": elements, "nodes": nodes});
        assert_eq!(g[name], want, "group {name}");
    }
    assert_eq!(
        g.as_object().unwrap().len(),
        5,
        "exactly the groups of cases/slab.geo"
    );
    // Gmsh's transfinite coordinates are not exact (DEPENDENCIES.md §2).
    let bbox: Vec<f64> = j["bbox"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|p| p.as_array().unwrap().clone())
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (got, want) in bbox.iter().zip([0.0, 0.0, 8.0, 1.0]) {
        assert!((got - want).abs() < 1e-9, "bbox {bbox:?}");
    }
}

#[test]
fn mesh_json_of_the_paper_mesh() {
    check_slab_q2_8x2(
        &mesh_json(&root().join("cases/meshes/slab-q2-8x2.msh")),
        "4.1",
    );
}

#[test]
fn mesh_json_of_the_msh22_copy() {
    check_slab_q2_8x2(
        &mesh_json(&root().join("cases/meshes/slab-q2-8x2-v22.msh")),
        "2.2",
    );
}

#[test]
fn mesh_table_lists_groups() {
    let o = bin()
        .arg("mesh")
        .arg(root().join("cases/meshes/slab-q2-8x2.msh"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(out.contains("MSH 4.1 ASCII"), "{out}");
    assert!(out.contains("16 quad9"), "{out}");
    let contact = out
        .lines()
        .find(|l| l.trim_start().starts_with("contact"))
        .expect("a contact row");
    assert_eq!(
        contact.split_whitespace().collect::<Vec<_>>(),
        ["contact", "1", "8", "17"]
    );
}

#[test]
fn bad_meshes_exit_2_naming_the_file() {
    for (name, line) in [
        ("not-a-mesh.msh", Some(1)),
        ("truncated.msh", None),
        ("no-such-file.msh", None),
    ] {
        let path = data(name);
        let o = bin().arg("mesh").arg(&path).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.starts_with("error: ") && e.contains(name), "{name}: {e}");
        if let Some(l) = line {
            assert!(e.contains(&format!("{name}:{l}:")), "{name}: {e}");
        }
        // A missing file says what to do, not only the OS's words.
        if name == "no-such-file.msh" {
            assert!(e.contains("check the path"), "{e}");
        }
        assert!(o.stdout.is_empty(), "nothing on stdout for a bad mesh");
    }
}

#[test]
fn truncated_mesh_names_a_line() {
    // truncated.msh is the first 40 lines of slab-q2-8x2.msh: the reader
    // runs out inside $Nodes, at the end of the file (line 41).
    let o = bin()
        .arg("mesh")
        .arg(data("truncated.msh"))
        .output()
        .unwrap();
    let e = stderr(&o);
    assert!(e.contains("truncated.msh:41:"), "{e}");
}

#[test]
fn usage_errors_exit_2_and_help_has_examples() {
    for args in [
        &["mesh"][..],
        &["frobnicate"],
        &["run"],
        &["probe", "x.h5"],
        &["mesh", "a.msh", "--jsn"],
    ] {
        let o = bin().args(args).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    for sub in ["run", "check", "mesh", "probe"] {
        let o = bin().args([sub, "--help"]).output().unwrap();
        assert!(o.status.success());
        let out = String::from_utf8(o.stdout).unwrap();
        assert!(
            out.contains("Example"),
            "{sub} --help has no example:\n{out}"
        );
    }
    let o = bin().arg("--version").output().unwrap();
    assert!(String::from_utf8(o.stdout)
        .unwrap()
        .starts_with("stickslip "));
}

/// A mesh written to a file of its own in the temp directory (the tests of
/// one binary run in parallel, so each file name is the test's).
fn temp_mesh(name: &str, text: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!("stickslip-cli-mesh-{}-{name}", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

/// Two quad4 cells and two nodes used by no cell (tags 7 and 8, far out).
const ORPHANS: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n\
1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n7 5 5 0\n8 -3 7 0\n$EndNodes\n\
$Elements\n2\n1 3 2 2 1 1 2 5 4\n2 3 2 2 1 2 3 6 5\n$EndElements\n";

#[test]
fn mesh_reports_dropped_unused_nodes() {
    let p = temp_mesh("orphans.msh", ORPHANS);
    let j = mesh_json(&p);
    assert_eq!(j["nodes"], 6);
    assert_eq!(j["unused_nodes"], 2);
    assert_eq!(j["bbox"], serde_json::json!([[0.0, 0.0], [2.0, 1.0]]));
    let o = bin().arg("mesh").arg(&p).output().unwrap();
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(
        out.contains(
            "  unused nodes  2 dropped (in no cell: Gmsh's Mesh.SaveAll or geometry points)\n"
        ),
        "{out}"
    );
    std::fs::remove_file(&p).unwrap();
    // Shown only when there are some; the JSON key always.
    let slab = root().join("cases/meshes/slab-q2-8x2.msh");
    assert_eq!(mesh_json(&slab)["unused_nodes"], 0);
    let o = bin().arg("mesh").arg(&slab).output().unwrap();
    assert!(!String::from_utf8(o.stdout).unwrap().contains("unused"));
}

#[test]
fn mesh_json_keeps_groups_sharing_a_name() {
    // Groups "body" of dimension 1 (the bottom) and 2; the first keeps the name.
    let text = ORPHANS
        .replace(
            "$EndMeshFormat\n",
            "$EndMeshFormat\n$PhysicalNames\n2\n1 1 \"body\"\n2 2 \"body\"\n$EndPhysicalNames\n",
        )
        .replace("$Elements\n2\n", "$Elements\n3\n3 1 2 1 1 1 2\n");
    let p = temp_mesh("same-name.msh", &text);
    let j = mesh_json(&p);
    std::fs::remove_file(&p).unwrap();
    assert_eq!(
        j["groups"],
        serde_json::json!({
            "body": {"dim": 1, "elements": 1, "nodes": 2},
            "body (dim 2)": {"dim": 2, "elements": 2, "nodes": 6},
        })
    );
}

#[test]
fn an_empty_mesh_file_is_called_empty() {
    let p = temp_mesh("empty.msh", "");
    let o = bin().arg("mesh").arg(&p).output().unwrap();
    std::fs::remove_file(&p).unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.starts_with(&format!("error: {}: the file is empty", p.display())),
        "{e}"
    );
}

#[test]
fn mesh_table_notes_a_line_group_inside_the_body() {
    // Gmsh output of a slab with an embedded curve, group "crack" (16 edges).
    let p = root().join("crates/mesh/tests/data/slab_q4_embedded_v41_ascii.msh");
    let o = bin().arg("mesh").arg(&p).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    let notes: Vec<&str> = out.lines().filter(|l| l.contains("note:")).collect();
    assert_eq!(
        notes,
        [
            "  note: group \"crack\" has 16 edges inside the body (shared by two cells); \
          as a traction or contact surface it would act inside the body"
        ],
        "{out}"
    );
    // None for a mesh whose line groups are all on the boundary.
    let o = bin()
        .arg("mesh")
        .arg(root().join("cases/meshes/slab-q2-8x2.msh"))
        .output()
        .unwrap();
    assert!(!String::from_utf8(o.stdout).unwrap().contains("note:"));
}

#[test]
fn mesh_notes_a_group_without_elements() {
    // ORPHANS with the named groups "bottom" (its one edge) and "top",
    // which has none: a Physical Curve whose curve is missing.
    let text = ORPHANS
        .replace(
            "$EndMeshFormat\n",
            "$EndMeshFormat\n$PhysicalNames\n2\n1 1 \"bottom\"\n1 2 \"top\"\n$EndPhysicalNames\n",
        )
        .replace("$Elements\n2\n", "$Elements\n3\n3 1 2 1 1 1 2\n");
    let p = temp_mesh("empty-group.msh", &text);
    let o = bin().arg("mesh").arg(&p).output().unwrap();
    let j = mesh_json(&p);
    std::fs::remove_file(&p).unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    let notes: Vec<&str> = out.lines().filter(|l| l.contains("note:")).collect();
    assert_eq!(notes.len(), 1, "{out}");
    assert!(
        notes[0].contains("group \"top\" (dim 1) has no elements")
            && notes[0].contains("Physical Curve"),
        "{out}"
    );
    let warnings = j["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{j}");
    assert!(warnings[0].as_str().unwrap().contains("\"top\""), "{j}");
}

/// An element block whose type's dimension is not its entity's (the
/// paper mesh's quad9 block moved onto curve 1): it was read, its cells
/// taking the curve's physical group. Refused at the block's line.
#[test]
fn a_block_on_an_entity_of_another_dimension_is_refused() {
    let text = std::fs::read_to_string(root().join("cases/meshes/slab-q2-8x2.msh")).unwrap();
    let line = text.lines().position(|l| l == "2 1 10 16").unwrap() + 1;
    let dir = stickslip_testkit::scratch("mesh-block-dim");
    let path = dir.join("curve.msh");
    std::fs::write(&path, text.replace("\n2 1 10 16\n", "\n1 1 10 16\n")).unwrap();
    let o = bin().arg("mesh").arg(&path).output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains(&format!("curve.msh:{line}:")) && e.contains("quad9 elements (dim 2)"),
        "{e}"
    );
}

/// Two groups of one dimension and one name (the paper mesh's "load"
/// renamed "contact"): `mesh` listed both without a word, and --json
/// only keyed the second by tag, while a case naming it is refused. A
/// note says so, in the table and in --json's warnings.
#[test]
fn mesh_notes_two_groups_of_one_name_and_dimension() {
    let text = std::fs::read_to_string(root().join("cases/meshes/slab-q2-8x2.msh")).unwrap();
    let dir = stickslip_testkit::scratch("mesh-twins");
    let path = dir.join("twins.msh");
    std::fs::write(&path, text.replace("1 2 \"load\"", "1 2 \"contact\"")).unwrap();
    let note = "groups 1 and 2 (dim 1) are both named \"contact\"";
    let o = bin().arg("mesh").arg(&path).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && out.contains(&format!("note: {note}")),
        "{out}"
    );
    let j = mesh_json(&path);
    let warned = j["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().is_some_and(|w| w.starts_with(note)));
    assert!(warned, "{j}");
}
