//! Helpers shared by the integration tests: fixture loading (files made by
//! Gmsh 4.15.2 through `data/make_fixtures.py`) and geometric checks.
#![allow(dead_code)]

use stickslip_mesh::{Mesh, MeshError};

pub const ENCODINGS: [&str; 4] = ["v22_ascii", "v22_bin", "v41_ascii", "v41_bin"];

pub fn path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

pub fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(path(name)).unwrap_or_else(|e| panic!("fixture {name}: {e}"))
}

pub fn text(name: &str) -> String {
    String::from_utf8(bytes(name)).expect("ASCII fixture")
}

pub fn load(name: &str) -> Mesh {
    Mesh::from_file(path(name)).unwrap_or_else(|e| panic!("{e}"))
}

pub fn parse_str(s: &str) -> Result<Mesh, MeshError> {
    Mesh::from_bytes(s.as_bytes())
}

/// 1-based number of the first line equal to `line` (trailing blanks ignored).
pub fn line_no(text: &str, line: &str) -> usize {
    text.lines()
        .position(|l| l.trim_end() == line)
        .unwrap_or_else(|| panic!("no line {line:?}"))
        + 1
}

/// Replaces the first line equal to `old` by `new`.
pub fn replace_line(text: &str, old: &str, new: &str) -> String {
    let mut found = false;
    let out: Vec<&str> = text
        .lines()
        .map(|l| {
            if !found && l.trim_end() == old {
                found = true;
                new
            } else {
                l
            }
        })
        .collect();
    assert!(found, "no line {old:?}");
    out.join("\n") + "\n"
}

/// Byte offset of the first occurrence of `needle`.
pub fn find(hay: &[u8], needle: &[u8]) -> usize {
    hay.windows(needle.len())
        .position(|w| w == needle)
        .unwrap_or_else(|| panic!("{:?} not found", String::from_utf8_lossy(needle)))
}

/// Twice the signed area of the polygon through `pts` (shoelace).
pub fn twice_area(pts: &[[f64; 2]]) -> f64 {
    (0..pts.len())
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

pub fn corners(m: &Mesh, c: usize) -> Vec<[f64; 2]> {
    m.cell(c)[..4].iter().map(|&n| m.nodes[n]).collect()
}

/// Checks every documented invariant of a mesh that can be checked from
/// the outside, geometrically.
pub fn check_invariants(m: &Mesh) {
    let n = m.nodes.len();
    assert_eq!(m.node_tags.len(), n);
    assert_eq!(m.cells.len(), m.n_cells() * m.kind.nodes_per_cell());
    assert!(m.cells.iter().all(|&i| i < n));
    for c in 0..m.n_cells() {
        // Counter-clockwise: positive shoelace area of the corners.
        assert!(twice_area(&corners(m, c)) > 0.0, "cell {c} not CCW");
    }
    let mut keys: Vec<(u8, i32)> = m.groups.iter().map(|g| (g.dim, g.tag)).collect();
    let sorted = {
        let mut k = keys.clone();
        k.sort();
        k
    };
    assert_eq!(keys, sorted, "groups sorted by (dim, tag)");
    keys.dedup();
    assert_eq!(keys.len(), m.groups.len());
    for g in &m.groups {
        assert!(
            g.nodes.windows(2).all(|w| w[0] < w[1]),
            "{}: nodes sorted unique",
            g.name
        );
        match g.dim {
            0 => assert_eq!(g.elements, g.points.len()),
            1 => assert_eq!(g.elements, g.edges.len()),
            2 => assert_eq!(g.elements, g.cells.len()),
            d => panic!("group dim {d}"),
        }
        for e in &g.edges {
            let cell = m.cell(e.cell);
            // The edge is a side of its cell, walked counter-clockwise.
            let i = (0..4)
                .find(|&i| cell[i] == e.nodes[0])
                .expect("edge start is a corner of its cell");
            assert_eq!(
                cell[(i + 1) % 4],
                e.nodes[1],
                "{}: edge walks its cell CCW",
                g.name
            );
            match m.kind.nodes_per_edge() {
                3 => assert_eq!(e.mid, Some(cell[4 + i])),
                _ => assert_eq!(e.mid, None),
            }
            // Geometrically: the cell's centroid is on the left of the edge.
            let (a, b) = (m.nodes[e.nodes[0]], m.nodes[e.nodes[1]]);
            let cs = corners(m, e.cell);
            let c = [
                cs.iter().map(|p| p[0]).sum::<f64>() / 4.0,
                cs.iter().map(|p| p[1]).sum::<f64>() / 4.0,
            ];
            let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(cross > 0.0, "{}: cell centroid left of edge", g.name);
        }
    }
}

/// Gmsh writes ASCII coordinates with `%.16g`, binary ones as exact
/// doubles: the two differ by up to half a unit in the 16th significant
/// digit, 5e-16 relative; 1e-15 of the coordinate's size allows for that and
/// nothing more.
pub fn same_nodes(a: &[[f64; 2]], b: &[[f64; 2]], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: node count");
    let scale = a
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1e-300);
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        for k in 0..2 {
            assert!(
                (p[k] - q[k]).abs() <= 1e-15 * scale,
                "{what}: node {i}: {p:?} vs {q:?}"
            );
        }
    }
}

/// The Mesh without `source` (which legitimately differs between encodings);
/// coordinates to the precision of Gmsh's ASCII output, the rest exactly.
pub fn same_mesh(a: &Mesh, b: &Mesh, what: &str) {
    same_nodes(&a.nodes, &b.nodes, what);
    assert_eq!(a.node_tags, b.node_tags, "{what}: node_tags");
    assert_eq!(a.kind, b.kind, "{what}: kind");
    assert_eq!(a.cells, b.cells, "{what}: cells");
    assert_eq!(a.cell_tags, b.cell_tags, "{what}: cell_tags");
    assert_eq!(a.groups, b.groups, "{what}: groups");
}

/// One element record of an MSH 2.2 binary `$Elements` section.
#[derive(Debug, Clone, Copy)]
pub struct Record {
    /// Offset of the block header `{type, following, ntags}` it came under.
    pub header: usize,
    /// Offset of the record (`tag, tags[ntags], nodes[n]`).
    pub offset: usize,
    pub type_id: i32,
    pub ntags: usize,
    pub nn: usize,
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// Walks a Gmsh 2.2 binary `$Elements` section (layout from the MSH 2.2
/// specification, DEPENDENCIES.md §2) independently of the reader.
pub fn v22_bin_elements(b: &[u8]) -> Vec<Record> {
    let mut pos = find(b, b"$Elements\n") + 10;
    let eol = pos + b[pos..].iter().position(|&c| c == b'\n').unwrap();
    let count: usize = std::str::from_utf8(&b[pos..eol])
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    pos = eol + 1;
    let mut out = Vec::new();
    while out.len() < count {
        let header = pos;
        let (type_id, following, ntags) = (
            i32_at(b, pos),
            i32_at(b, pos + 4) as usize,
            i32_at(b, pos + 8) as usize,
        );
        pos += 12;
        let nn = match type_id {
            15 => 1,
            1 => 2,
            8 => 3,
            3 => 4,
            10 => 9,
            t => panic!("type {t}"),
        };
        for _ in 0..following {
            out.push(Record {
                header,
                offset: pos,
                type_id,
                ntags,
                nn,
            });
            pos += 4 * (1 + ntags + nn);
        }
    }
    out
}
