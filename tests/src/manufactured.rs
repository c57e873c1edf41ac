//! The static manufactured solution of `crates/fem/tests/convergence.rs`
//! (also measured by `cargo xtask verify`'s rates suite): the unit square,
//! its interior nodes moved by a smooth map (Q1 cells become general
//! quadrilaterals, Q2 cells get curved edges, the boundary stays straight);
//! plane strain E = 1, ν = 0.3;
//!   u_x = sin(αx)·sin(βy),  u_y = sin(γx)·(1 − cos(δy)),
//! clamped on x = 0 and y = 0 (where u vanishes), the traction σ(u)·n on
//! x = 1 and y = 1 and the body force f = −div σ(u), both derived by hand
//! (the convergence test checks [`body_force`] by finite differences of
//! [`stress`]).

use stickslip_mesh::{CellKind, Mesh};

use stickslip_fem::element::CellBasis;
use stickslip_fem::geometry::Jacobian;
use stickslip_fem::{
    body_force_load_with, static_solve, traction_load_with, Dirichlet, FemError, Hypothesis,
    Material, Model,
};

use crate::grid::{map_nodes, rectangle};

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
