//! Structured meshes built in code, for tests, examples and benchmarks that
//! should not depend on mesh files: a rectangle of Q1 or Q2 cells with its
//! four sides as named line groups, optionally distorted or curved by a map
//! of the nodes; and the manufactured static solution ([`manufactured`])
//! whose errors the fem convergence test and `cargo xtask verify` measure.
//! Also two helpers the workspace's tests share: [`on_threads`] and the
//! reference product [`plain_spmv`].

use nalgebra_sparse::CsrMatrix;
use stickslip_mesh::{CellKind, Edge, Group, Mesh, SourceInfo};

/// Runs `f` on a rayon pool of `threads` threads (the thread-independence
/// tests run the same work on 1 and on 2).
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// A x as plain row sums in storage order: the reference the tests hold the
/// optimized products and the solves' residuals against.
pub fn plain_spmv(a: &CsrMatrix<f64>, x: &[f64]) -> Vec<f64> {
    a.row_iter()
        .map(|r| {
            r.col_indices()
                .iter()
                .zip(r.values())
                .map(|(&j, v)| v * x[j])
                .sum()
        })
        .collect()
}

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

/// The paper's slab ([0, 8] × [0, 1], BENCHMARK.md) as a structured mesh:
/// 8 × 2 Q2 cells or 16 × 4 Q1 cells scaled by `refine` per direction,
/// with groups "contact" (bottom), "load" (right), "support" (top), "left".
pub fn slab(kind: CellKind, refine: usize) -> Mesh {
    let (nx, ny) = if kind == CellKind::Quad9 {
        (8, 2)
    } else {
        (16, 4)
    };
    let mut m = rectangle(kind, nx * refine, ny * refine, [0.0, 0.0], [8.0, 1.0]);
    for (g, name) in m
        .groups
        .iter_mut()
        .zip(["contact", "load", "support", "left"])
    {
        g.name = name.to_string();
    }
    m
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

/// The static manufactured solution of `crates/fem/tests/convergence.rs`
/// (also measured by `cargo xtask verify`'s rates suite): the unit square,
/// its interior nodes moved by a smooth map (Q1 cells become general
/// quadrilaterals, Q2 cells get curved edges, the boundary stays straight);
/// plane strain E = 1, ν = 0.3;
///   u_x = sin(αx)·sin(βy),  u_y = sin(γx)·(1 − cos(δy)),
/// clamped on x = 0 and y = 0 (where u vanishes), the traction σ(u)·n on
/// x = 1 and y = 1 and the body force f = −div σ(u), both derived by hand
/// (the convergence test checks [`body_force`](manufactured::body_force) by
/// finite differences of [`stress`](manufactured::stress)).
pub mod manufactured {
    use stickslip_mesh::{CellKind, Mesh};

    use super::{map_nodes, rectangle};
    use crate::element::CellBasis;
    use crate::geometry::Jacobian;
    use crate::{
        body_force_load_with, static_solve, traction_load_with, Dirichlet, FemError, Hypothesis,
        Material, Model,
    };

    /// α.
    pub const A: f64 = 2.0;
    /// β.
    pub const B: f64 = 3.0;
    /// γ.
    pub const G: f64 = 1.5;
    /// δ.
    pub const DL: f64 = 2.0;

    /// Plane strain, E = 1, ν = 0.3, ρ = 1.
    pub fn material() -> Material {
        Material::new(1.0, 0.3, 1.0, Hypothesis::PlaneStrain).expect("valid material")
    }

    /// u and its gradient [[∂u_x/∂x, ∂u_x/∂y], [∂u_y/∂x, ∂u_y/∂y]].
    pub fn exact(p: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
        let [x, y] = p;
        let u = [
            (A * x).sin() * (B * y).sin(),
            (G * x).sin() * (1.0 - (DL * y).cos()),
        ];
        let g = [
            [
                A * (A * x).cos() * (B * y).sin(),
                B * (A * x).sin() * (B * y).cos(),
            ],
            [
                G * (G * x).cos() * (1.0 - (DL * y).cos()),
                DL * (G * x).sin() * (DL * y).sin(),
            ],
        ];
        (u, g)
    }

    /// σ(u) = D ε(u) as [σxx, σyy, σxy].
    pub fn stress(p: [f64; 2]) -> [f64; 3] {
        let d = material().elasticity();
        let (_, g) = exact(p);
        let e = [g[0][0], g[1][1], g[0][1] + g[1][0]];
        [0, 1, 2].map(|i| (0..3).map(|j| d[i][j] * e[j]).sum())
    }

    /// f = −div σ by hand: with D isotropic (D13 = D23 = 0),
    /// ∂σxx/∂x + ∂σxy/∂y = D11 u_x,xx + D12 u_y,xy + D33 (u_x,yy + u_y,xy),
    /// ∂σxy/∂x + ∂σyy/∂y = D33 (u_x,xy + u_y,xx) + D21 u_x,xy + D22 u_y,yy.
    pub fn body_force(p: [f64; 2]) -> [f64; 2] {
        let d = material().elasticity();
        let [x, y] = p;
        let ux = (A * x).sin() * (B * y).sin();
        let ux_xx = -A * A * ux;
        let ux_yy = -B * B * ux;
        let ux_xy = A * B * (A * x).cos() * (B * y).cos();
        let uy_xx = -G * G * (G * x).sin() * (1.0 - (DL * y).cos());
        let uy_yy = DL * DL * (G * x).sin() * (DL * y).cos();
        let uy_xy = G * DL * (G * x).cos() * (DL * y).sin();
        let div_x = d[0][0] * ux_xx + d[0][1] * uy_xy + d[2][2] * (ux_yy + uy_xy);
        let div_y = d[2][2] * (ux_xy + uy_xx) + d[1][0] * ux_xy + d[1][1] * uy_yy;
        [-div_x, -div_y]
    }

    /// The n × n mesh of the unit square with its interior nodes moved by
    /// a smooth map.
    pub fn mesh(kind: CellKind, n: usize) -> Mesh {
        let mut m = rectangle(kind, n, n, [0.0, 0.0], [1.0, 1.0]);
        let pi = std::f64::consts::PI;
        map_nodes(&mut m, |[x, y]| {
            [
                x + 0.04 * (2.0 * pi * x).sin() * (pi * y).sin(),
                y + 0.04 * (pi * x).sin() * (2.0 * pi * y).sin(),
            ]
        });
        m
    }

    /// (L2 error, H1-seminorm error) of the FE solution on the n × n mesh.
    ///
    /// # Errors
    /// The model, the loads or the static solve failing.
    pub fn errors(kind: CellKind, n: usize) -> Result<(f64, f64), FemError> {
        let mesh = mesh(kind, n);
        let bcs: Vec<Dirichlet> = ["left", "bottom"]
            .iter()
            .flat_map(|g| [Dirichlet::new(*g, 0, 0.0), Dirichlet::new(*g, 1, 0.0)])
            .collect();
        let model = Model::new(&mesh, &material(), &bcs)?;
        let mut full = vec![0.0; 2 * mesh.nodes.len()];
        body_force_load_with(&mesh, body_force, &mut full);
        for g in ["right", "top"] {
            traction_load_with(
                &mesh,
                g,
                |x, nrm| {
                    let s = stress(x);
                    [s[0] * nrm[0] + s[2] * nrm[1], s[2] * nrm[0] + s[1] * nrm[1]]
                },
                &mut full,
            )?;
        }
        let mut free = vec![0.0; model.dofs.n_free()];
        model.dofs.restrict(&full, &mut free);
        let u = static_solve(&model, &free)?;
        // 5 × 5 Gauss points per cell: their own error is far below the
        // discretization error at these h.
        let basis = CellBasis::new(kind, 5);
        let nn = kind.nodes_per_cell();
        let (mut l2, mut h1) = (0.0, 0.0);
        let mut g = [[0.0; 2]; 9];
        let mut coords = [[0.0; 2]; 9];
        for c in 0..mesh.n_cells() {
            let cell = mesh.cell(c);
            for (a, &v) in cell.iter().enumerate() {
                coords[a] = mesh.nodes[v];
            }
            for q in 0..basis.n_points() {
                let j = Jacobian::from_gradients(&coords[..nn], basis.gradients(q));
                j.physical_gradients(basis.gradients(q), &mut g[..nn]);
                let nv = basis.values(q);
                let (mut x, mut uh, mut gh) = ([0.0; 2], [0.0; 2], [[0.0; 2]; 2]);
                for a in 0..nn {
                    for i in 0..2 {
                        x[i] += nv[a] * coords[a][i];
                        let ua = u[2 * cell[a] + i];
                        uh[i] += nv[a] * ua;
                        gh[i][0] += g[a][0] * ua;
                        gh[i][1] += g[a][1] * ua;
                    }
                }
                let (ue, ge) = exact(x);
                let w = basis.weight(q) * j.det;
                l2 += w * ((ue[0] - uh[0]).powi(2) + (ue[1] - uh[1]).powi(2));
                for i in 0..2 {
                    for k in 0..2 {
                        h1 += w * (ge[i][k] - gh[i][k]).powi(2);
                    }
                }
            }
        }
        Ok((l2.sqrt(), h1.sqrt()))
    }
}
