//! Real Gmsh 4.15.2 output (`data/make_fixtures.py`): the reader's result
//! is checked against the geometry the meshes were made from, not against
//! numbers the reader produced.

mod common;
use common::*;
use stickslip_mesh::{CellKind, MeshErrorKind};

/// The slab is the trapezoid (0,0) (8,0) (8,1.5) (0,1), 4 x 2 transfinite.
const SLAB_AREA: f64 = 8.0 * (1.0 + 1.5) / 2.0;

fn near(a: f64, b: f64, scale: f64) -> bool {
    // Gmsh's transfinite coordinates are off by up to ~1e-11 (DEPENDENCIES.md §2).
    (a - b).abs() <= 1e-9 * scale
}

#[test]
fn slab_quad4_matches_its_geometry() {
    let m = load("slab_q4_v41_ascii.msh");
    assert_eq!(m.kind, CellKind::Quad4);
    assert_eq!(m.nodes.len(), 5 * 3, "(4+1) x (2+1) grid");
    assert_eq!(m.n_cells(), 4 * 2);
    assert_eq!(
        m.group_names(),
        ["corner", "contact", "#2", "load", "support", "body"]
    );
    assert_eq!(m.bbox(), [[0.0, 0.0], [8.0, 1.5]]);
    let area: f64 = (0..m.n_cells())
        .map(|c| twice_area(&corners(&m, c)) / 2.0)
        .sum();
    assert!(near(area, SLAB_AREA, SLAB_AREA), "area {area}");
    // 4 + 2 + 4 + 2 boundary lines and the corner point.
    assert_eq!(m.source.boundary_elements.get("line2"), Some(&12));
    assert_eq!(m.source.boundary_elements.get("point"), Some(&1));
    assert_eq!(m.source.boundary_elements.get("line3"), None);

    let contact = m.group("contact").unwrap();
    assert_eq!(
        (
            contact.dim,
            contact.tag,
            contact.elements,
            contact.nodes.len()
        ),
        (1, 1, 4, 5)
    );
    for e in &contact.edges {
        let (a, b) = (m.nodes[e.nodes[0]], m.nodes[e.nodes[1]]);
        assert!(near(a[1], 0.0, 8.0) && near(b[1], 0.0, 8.0));
        // The body is above the bottom side: on the left when walking +x.
        assert!(b[0] > a[0]);
    }
    let load = m.group("load").unwrap();
    for e in &load.edges {
        let (a, b) = (m.nodes[e.nodes[0]], m.nodes[e.nodes[1]]);
        for p in [a, b] {
            assert!(near(p[1], 1.0 + p[0] / 16.0, 8.0), "top side y = 1 + x/16");
        }
        assert!(b[0] < a[0], "body below the top side: walk -x");
    }
    let right = m.group("#2").unwrap();
    assert_eq!((right.dim, right.elements), (1, 2));
    assert!(
        right
            .edges
            .iter()
            .all(|e| m.nodes[e.nodes[1]][1] > m.nodes[e.nodes[0]][1]),
        "right side walked +y"
    );
    let support = m.group("support").unwrap();
    assert!(support.nodes.iter().all(|&n| near(m.nodes[n][0], 0.0, 8.0)));
    let corner = m.group("corner").unwrap();
    assert_eq!((corner.dim, corner.points.len()), (0, 1));
    assert_eq!(m.nodes[corner.points[0]], [0.0, 0.0]);
    let body = m.group("body").unwrap();
    assert_eq!((body.dim, body.cells.len(), body.nodes.len()), (2, 8, 15));

    // The oriented boundary encloses the body: its shoelace sum is twice the area.
    let twice: f64 = ["contact", "#2", "load", "support"]
        .iter()
        .flat_map(|g| m.group(g).unwrap().edges.iter())
        .map(|e| {
            let (a, b) = (m.nodes[e.nodes[0]], m.nodes[e.nodes[1]]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    assert!(near(twice, 2.0 * SLAB_AREA, SLAB_AREA));
    check_invariants(&m);
}

#[test]
fn slab_quad9_mid_nodes_follow_the_documented_order() {
    let m = load("slab_q9_v22_bin.msh");
    assert_eq!(m.kind, CellKind::Quad9);
    assert_eq!(m.nodes.len(), 9 * 5, "(2*4+1) x (2*2+1) grid");
    assert_eq!(m.source.boundary_elements.get("line3"), Some(&12));
    for c in 0..m.n_cells() {
        let p: Vec<[f64; 2]> = m.cell(c).iter().map(|&n| m.nodes[n]).collect();
        // Straight sides: node 4+i is the midpoint of corners i, i+1
        // (GMSH_TO_FEM_QUAD9 and the CellKind::Quad9 doc).
        for i in 0..4 {
            let (a, b) = (p[i], p[(i + 1) % 4]);
            for k in 0..2 {
                assert!(
                    near(p[4 + i][k], 0.5 * (a[k] + b[k]), 8.0),
                    "cell {c} mid {i}"
                );
            }
        }
        // Centre node: the bilinear map's centre, the mean of the corners.
        for k in 0..2 {
            let mean = (p[0][k] + p[1][k] + p[2][k] + p[3][k]) / 4.0;
            assert!(near(p[8][k], mean, 8.0), "cell {c} centre");
        }
    }
    let contact = m.group("contact").unwrap();
    assert_eq!(contact.nodes.len(), 9);
    for e in &contact.edges {
        let (a, b, mid) = (
            m.nodes[e.nodes[0]],
            m.nodes[e.nodes[1]],
            m.nodes[e.mid.unwrap()],
        );
        assert!(near(mid[0], 0.5 * (a[0] + b[0]), 8.0));
    }
    check_invariants(&m);
}

fn hole_checks(name: &str) {
    let m = load(name);
    let centre = [2.0, 1.0];
    let hole = m.group("hole").unwrap();
    // Gmsh puts boundary nodes (also quad9 mid-side nodes) on the circle.
    for &n in &hole.nodes {
        let p = m.nodes[n];
        let r = (p[0] - centre[0]).hypot(p[1] - centre[1]);
        assert!(near(r, 0.5, 1.0), "{name}: hole node at radius {r}");
    }
    for e in &hole.edges {
        let (a, b) = (m.nodes[e.nodes[0]], m.nodes[e.nodes[1]]);
        // Body on the left of the hole's edges: the hole is walked clockwise.
        let cross =
            (a[0] - centre[0]) * (b[1] - centre[1]) - (a[1] - centre[1]) * (b[0] - centre[0]);
        assert!(cross < 0.0, "{name}: hole edge walked clockwise");
    }
    let outer = m.group("outer").unwrap();
    for &n in &outer.nodes {
        let p = m.nodes[n];
        let on_side = near(p[0], 0.0, 4.0)
            || near(p[0], 4.0, 4.0)
            || near(p[1], 0.0, 4.0)
            || near(p[1], 2.0, 4.0);
        assert!(on_side, "{name}: outer node {p:?} on the rectangle");
    }
    // One element in two groups: bottom (3) and contact (4) are the same lines.
    let (bottom, contact) = (m.group("bottom").unwrap(), m.group("contact").unwrap());
    assert_eq!(bottom.edges, contact.edges);
    assert_eq!(bottom.nodes, contact.nodes);
    assert_eq!((bottom.tag, contact.tag), (3, 4));
    assert!(bottom
        .edges
        .iter()
        .all(|e| m.nodes[e.nodes[0]][0] < m.nodes[e.nodes[1]][0]));
    assert_eq!(
        m.group_names(),
        ["outer", "hole", "bottom", "contact", "body"]
    );
    assert_eq!(m.group("body").unwrap().cells.len(), m.n_cells());
    check_invariants(&m);
}

#[test]
fn unstructured_hole_quad4_matches_its_geometry() {
    for e in ENCODINGS {
        hole_checks(&format!("hole_q4_{e}.msh"));
    }
    // Straight-sided cells tile the rectangle minus the polygon through the
    // hole's nodes (angle order).
    let m = load("hole_q4_v41_bin.msh");
    let mut ring: Vec<[f64; 2]> = m
        .group("hole")
        .unwrap()
        .nodes
        .iter()
        .map(|&n| m.nodes[n])
        .collect();
    ring.sort_by(|a, b| {
        (a[1] - 1.0)
            .atan2(a[0] - 2.0)
            .total_cmp(&(b[1] - 1.0).atan2(b[0] - 2.0))
    });
    let expected = 8.0 - twice_area(&ring) / 2.0;
    let area: f64 = (0..m.n_cells())
        .map(|c| twice_area(&corners(&m, c)) / 2.0)
        .sum();
    assert!(
        near(area, expected, 8.0),
        "cells {area} vs geometry {expected}"
    );
    let twice: f64 = ["outer", "hole"]
        .iter()
        .flat_map(|g| m.group(g).unwrap().edges.iter())
        .map(|e| {
            let (a, b) = (m.nodes[e.nodes[0]], m.nodes[e.nodes[1]]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    assert!(
        near(twice / 2.0, expected, 8.0),
        "oriented boundary encloses the body"
    );
}

#[test]
fn unstructured_hole_quad9_matches_its_geometry() {
    for e in ENCODINGS {
        hole_checks(&format!("hole_q9_{e}.msh"));
    }
}

#[test]
fn groups_by_name_and_number() {
    let m = load("slab_q4_v22_ascii.msh");
    assert_eq!(m.group("#2").unwrap().tag, 2);
    let err = m.group("free").unwrap_err();
    match &err.kind {
        MeshErrorKind::UnknownGroup { name, available } => {
            assert_eq!(name, "free");
            assert_eq!(
                available,
                &["corner", "contact", "#2", "load", "support", "body"]
            );
        }
        k => panic!("{k:?}"),
    }
    assert!(err.to_string().contains("contact"));
}

#[test]
fn triangles_are_refused_with_how_to_get_quads() {
    let name = "hole_tri_v41_ascii.msh";
    let err = stickslip_mesh::Mesh::from_file(path(name)).unwrap_err();
    assert!(
        matches!(&err.kind, MeshErrorKind::NotQuads { found } if found.contains("tri3")),
        "{err}"
    );
    // The block header "2 <entity> 2 <count>" of the triangles.
    let t = text(name);
    let line = t.lines().position(|l| {
        let f: Vec<&str> = l.split_whitespace().collect();
        f.len() == 4 && f[0] == "2" && f[2] == "2"
    });
    assert_eq!(
        err.location,
        stickslip_mesh::Location::Line(line.unwrap() + 1)
    );
    let msg = err.to_string();
    for hint in [
        "Recombine Surface",
        "Mesh.ElementOrder",
        "-order 2",
        "Mesh.SecondOrderIncomplete = 0",
        name,
    ] {
        assert!(msg.contains(hint), "message lacks {hint:?}: {msg}");
    }
}

#[test]
fn quad8_is_refused() {
    let t = text("slab_q8_v22_ascii.msh");
    let err = parse_str(&t).unwrap_err();
    assert!(
        matches!(&err.kind, MeshErrorKind::NotQuads { found } if found.contains("quad8")),
        "{err}"
    );
    // The first 2.2 element line of type 16: "tag 16 ...".
    let line = t.lines().position(|l| {
        l.split_whitespace().nth(1) == Some("16") && l.split_whitespace().count() > 8
    });
    assert_eq!(
        err.location,
        stickslip_mesh::Location::Line(line.unwrap() + 1)
    );
}
