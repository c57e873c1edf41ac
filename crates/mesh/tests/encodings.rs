//! The same mesh written by Gmsh 4.15.2 in MSH 2.2 and 4.1, ASCII and
//! binary (`data/make_fixtures.py`) must give identical `Mesh` values.

mod common;
use common::*;

fn all_four(stem: &str) -> Vec<stickslip_mesh::Mesh> {
    ENCODINGS
        .iter()
        .map(|e| load(&format!("{stem}_{e}.msh")))
        .collect()
}

fn check_source(meshes: &[stickslip_mesh::Mesh]) {
    let got: Vec<(&str, bool)> = meshes
        .iter()
        .map(|m| (m.source.version.as_str(), m.source.binary))
        .collect();
    assert_eq!(
        got,
        [("2.2", false), ("2.2", true), ("4.1", false), ("4.1", true)]
    );
    for m in meshes {
        assert_eq!(
            m.source.boundary_elements,
            meshes[0].source.boundary_elements
        );
        assert_eq!(
            m.source.reoriented, 0,
            "Gmsh writes counter-clockwise cells"
        );
    }
}

#[test]
fn slab_quad4_four_encodings_identical() {
    let m = all_four("slab_q4");
    check_source(&m);
    for (k, mk) in m.iter().enumerate().skip(1) {
        same_mesh(&m[0], mk, ENCODINGS[k]);
    }
    check_invariants(&m[0]);
}

#[test]
fn slab_quad9_four_encodings_identical() {
    let m = all_four("slab_q9");
    check_source(&m);
    for (k, mk) in m.iter().enumerate().skip(1) {
        same_mesh(&m[0], mk, ENCODINGS[k]);
    }
    check_invariants(&m[0]);
}

/// In the hole meshes the bottom side is in two groups; Gmsh's 2.2 writer
/// then writes those lines twice under new numbers, so its element tags
/// (and hence cell_tags) differ from 4.1's. Everything else must agree, and
/// within one version the two encodings must agree completely.
fn hole_encodings(stem: &str) {
    let m = all_four(stem);
    check_source(&m);
    same_mesh(&m[0], &m[1], "2.2 ascii vs bin");
    same_mesh(&m[2], &m[3], "4.1 ascii vs bin");
    let (a, b) = (&m[0], &m[2]);
    same_nodes(&a.nodes, &b.nodes, "2.2 vs 4.1");
    assert_eq!(a.node_tags, b.node_tags);
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.groups, b.groups);
    assert_eq!(a.cell_tags.len(), b.cell_tags.len());
    for mk in &m {
        check_invariants(mk);
    }
}

#[test]
fn hole_quad4_encodings_agree() {
    hole_encodings("hole_q4");
}

#[test]
fn hole_quad9_encodings_agree() {
    hole_encodings("hole_q9");
}

/// Gmsh renumbered nodes t -> 3t + 100 and elements t -> 5t + 7
/// (`make_fixtures.py`); MSH 4.1 keeps those tags, so the mesh must equal
/// slab_q4 with mapped tags. (Gmsh's 2.2 writer renumbers contiguously.)
#[test]
fn non_contiguous_tags_map_to_dense_indices() {
    let plain = load("slab_q4_v41_ascii.msh");
    for e in ["v41_ascii", "v41_bin"] {
        let gaps = load(&format!("slab_q4_gaps_{e}.msh"));
        same_nodes(&gaps.nodes, &plain.nodes, e);
        assert_eq!(gaps.cells, plain.cells, "{e}");
        assert_eq!(gaps.groups, plain.groups, "{e}");
        let tags: Vec<u64> = plain.node_tags.iter().map(|t| 3 * t + 100).collect();
        assert_eq!(gaps.node_tags, tags, "{e}");
        let ctags: Vec<u64> = plain.cell_tags.iter().map(|t| 5 * t + 7).collect();
        assert_eq!(gaps.cell_tags, ctags, "{e}");
    }
    for e in ["v22_ascii", "v22_bin"] {
        let gaps = load(&format!("slab_q4_gaps_{e}.msh"));
        same_nodes(&gaps.nodes, &plain.nodes, e);
        assert_eq!(gaps.cells, plain.cells, "{e}");
        assert_eq!(gaps.groups, plain.groups, "{e}");
    }
}

/// `Mesh.SaveParametric = 1` adds u (curve nodes) or u v (surface nodes)
/// after x y z; skipping them must give the plain file's mesh.
#[test]
fn parametric_coordinates_are_skipped() {
    let plain = load("slab_q9_v41_ascii.msh");
    let text = text("slab_q9_param_v41_ascii.msh");
    assert!(
        text.contains("\n1 1 1 3\n") || text.contains("\n2 1 1 "),
        "the fixture has parametric blocks"
    );
    for e in ["v41_ascii", "v41_bin"] {
        same_mesh(&plain, &load(&format!("slab_q9_param_{e}.msh")), e);
    }
}

/// Gmsh's 2.2 writer puts an element that is in several physical groups
/// into the file once per group, consecutively, under new element numbers
/// (seen with Gmsh 4.15.2: `Physical Surface(10)` and `(11)` on one surface
/// give `8 3 2 10 1 …` then `9 3 2 11 1 …` with the same nodes). Emulated
/// here on slab_q4: each cell line is followed by a copy in group 11.
#[test]
fn v22_copies_per_group_are_one_cell() {
    let t = text("slab_q4_v22_ascii.msh");
    let mut out = Vec::new();
    let mut extra = 0;
    for l in t.lines() {
        out.push(l.to_string());
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() == 9 && f[1] == "3" {
            extra += 1;
            out.push(format!("{} 3 2 11 1 {}", 1000 + extra, f[5..].join(" ")));
        }
    }
    let text2 = out.join("\n").replacen(
        "$Elements\n21\n",
        &format!("$Elements\n{}\n", 21 + extra),
        1,
    ) + "\n";
    let m = stickslip_mesh::Mesh::from_bytes(text2.as_bytes()).unwrap();
    let plain = load("slab_q4_v22_ascii.msh");
    assert_eq!(m.cells, plain.cells);
    assert_eq!(m.cell_tags, plain.cell_tags, "the first copy's tag is kept");
    let g11 = m.group("#11").unwrap();
    assert_eq!(g11.cells, plain.group("body").unwrap().cells);
    assert_eq!(g11.dim, 2);
}
