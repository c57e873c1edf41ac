//! Meshes built in code, for tests, examples and benchmarks that should
//! not depend on mesh files: a rectangle of Q1 or Q2 cells with its four
//! sides as named line groups, the paper's slab as such a rectangle with
//! the groups of the committed meshes, and edits (moving the nodes, adding
//! a group of points).

use stickslip_mesh::{CellKind, Edge, Group, Mesh, SourceInfo};

/// A rectangle `[x0, x0 + lx] × [y0, y0 + ly]` of `nx × ny` cells of `kind`.
/// Groups: lines "bottom", "right", "top", "left" (tags 1-4, edges oriented
/// with the cell on their left, i.e. counter-clockwise around the
/// rectangle) and the cells "domain" (tag 5). Nodes are numbered row by row
/// from the bottom-left on the grid of spacing `lx / (order·nx)`.
pub fn rectangle(kind: CellKind, nx: usize, ny: usize, origin: [f64; 2], size: [f64; 2]) -> Mesh {
    assert!(nx > 0 && ny > 0, "at least one cell per direction");
    let order = if kind == CellKind::Quad9 { 2 } else { 1 };
    let (mx, my) = (order * nx, order * ny);
    let id = |i: usize, j: usize| j * (mx + 1) + i;
    let mut nodes = Vec::with_capacity((mx + 1) * (my + 1));
    for j in 0..=my {
        for i in 0..=mx {
            nodes.push([
                origin[0] + size[0] * i as f64 / mx as f64,
                origin[1] + size[1] * j as f64 / my as f64,
            ]);
        }
    }
    let mut cells = Vec::with_capacity(nx * ny * kind.nodes_per_cell());
    for ey in 0..ny {
        for ex in 0..nx {
            let (i, j) = (order * ex, order * ey);
            if order == 1 {
                cells.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                cells.extend([
                    id(i, j),
                    id(i + 2, j),
                    id(i + 2, j + 2),
                    id(i, j + 2),
                    id(i + 1, j),
                    id(i + 2, j + 1),
                    id(i + 1, j + 2),
                    id(i, j + 1),
                    id(i + 1, j + 1),
                ]);
            }
        }
    }
    let cell_of = |ex: usize, ey: usize| ey * nx + ex;
    let mid = |i: usize, j: usize| (order == 2).then(|| id(i, j));
    let bottom: Vec<Edge> = (0..nx)
        .map(|e| Edge {
            nodes: [id(order * e, 0), id(order * (e + 1), 0)],
            mid: mid(order * e + 1, 0),
            cell: cell_of(e, 0),
        })
        .collect();
    let right: Vec<Edge> = (0..ny)
        .map(|e| Edge {
            nodes: [id(mx, order * e), id(mx, order * (e + 1))],
            mid: mid(mx, order * e + 1),
            cell: cell_of(nx - 1, e),
        })
        .collect();
    let top: Vec<Edge> = (0..nx)
        .rev()
        .map(|e| Edge {
            nodes: [id(order * (e + 1), my), id(order * e, my)],
            mid: mid(order * e + 1, my),
            cell: cell_of(e, ny - 1),
        })
        .collect();
    let left: Vec<Edge> = (0..ny)
        .rev()
        .map(|e| Edge {
            nodes: [id(0, order * (e + 1)), id(0, order * e)],
            mid: mid(0, order * e + 1),
            cell: cell_of(0, e),
        })
        .collect();
    let line_group = |name: &str, tag: i32, edges: Vec<Edge>| {
        let mut gn: Vec<usize> = edges
            .iter()
            .flat_map(|e| [e.nodes[0], e.nodes[1]].into_iter().chain(e.mid))
            .collect();
        gn.sort_unstable();
        gn.dedup();
        Group {
            name: name.to_string(),
            tag,
            dim: 1,
            elements: edges.len(),
            edges,
            cells: vec![],
            points: vec![],
            nodes: gn,
        }
    };
    let n_cells = nx * ny;
    let mut groups = vec![
        line_group("bottom", 1, bottom),
        line_group("right", 2, right),
        line_group("top", 3, top),
        line_group("left", 4, left),
    ];
    groups.push(Group {
        name: "domain".to_string(),
        tag: 5,
        dim: 2,
        edges: vec![],
        cells: (0..n_cells).collect(),
        points: vec![],
        nodes: (0..nodes.len()).collect(),
        elements: n_cells,
    });
    let n_nodes = nodes.len();
    Mesh {
        nodes,
        node_tags: (1..=n_nodes as u64).collect(),
        kind,
        cells,
        cell_tags: (1..=n_cells as u64).collect(),
        groups,
        source: SourceInfo {
            version: "structured (built in code)".to_string(),
            ..SourceInfo::default()
        },
    }
}

/// The slab [0, 8] × [0, 1] (BENCHMARK.md) with nx × ny Q1 or Q2 cells and
/// the groups of cases/meshes/README.md ([`rectangle`]'s, renamed: contact
/// below, load on the right, support on top, left, and the cells "body"),
/// its nodes numbered row by row (the step bench's ladder; K's node rows
/// then share stencils).
pub fn structured_slab(nx: usize, ny: usize, q2: bool) -> Mesh {
    let kind = if q2 { CellKind::Quad9 } else { CellKind::Quad4 };
    let mut mesh = rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
    for g in &mut mesh.groups {
        let (name, tag) = match g.name.as_str() {
            "bottom" => ("contact", 1),
            "right" => ("load", 2),
            "top" => ("support", 3),
            "left" => ("left", 4),
            _ => ("body", 10),
        };
        (g.name, g.tag) = (name.into(), tag);
    }
    mesh
}

/// The paper's slab as [`structured_slab`]: 8 × 2 Q2 cells or 16 × 4 Q1
/// cells (the paper's 17 × 5 nodes) scaled by `refine` per direction.
pub fn slab(kind: CellKind, refine: usize) -> Mesh {
    let (nx, ny) = if kind == CellKind::Quad9 {
        (8, 2)
    } else {
        (16, 4)
    };
    structured_slab(nx * refine, ny * refine, kind == CellKind::Quad9)
}

/// Moves every node: `x ← f(x)`. Mid-side and centre nodes move too, so a
/// non-affine `f` curves Q2 edges.
pub fn map_nodes(mesh: &mut Mesh, f: impl Fn([f64; 2]) -> [f64; 2]) {
    for p in &mut mesh.nodes {
        *p = f(*p);
    }
}

/// Adds a dimension-0 group of the given nodes (e.g. to prescribe a
/// displacement on a single node).
pub fn add_point_group(mesh: &mut Mesh, name: &str, nodes: &[usize]) {
    let tag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0) + 1;
    let mut sorted = nodes.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    mesh.groups.push(Group {
        name: name.to_string(),
        tag,
        dim: 0,
        edges: vec![],
        cells: vec![],
        points: nodes.to_vec(),
        nodes: sorted,
        elements: nodes.len(),
    });
}
