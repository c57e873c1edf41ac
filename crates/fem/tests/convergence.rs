//! Convergence in h against a manufactured solution, with the measured
//! errors kept in `tests/data/convergence.csv` (fenris keeps its
//! convergence data the same way).
//!
//! Problem: the unit square, its interior nodes moved by a smooth map (so
//! Q1 cells are general quadrilaterals and Q2 cells have curved edges, while
//! the boundary stays straight); plane strain E = 1, ν = 0.3;
//!   u_x = sin(αx)·sin(βy),  u_y = sin(γx)·(1 − cos(δy)),
//! which vanishes on x = 0 and y = 0 (clamped there); on x = 1 and y = 1 the
//! traction σ(u)·n is applied, and the body force is f = −div σ(u), both by
//! hand below (the derivation is checked by finite differences).
//!
//! Expected: the theory's rates (Ciarlet; METHOD.md §2-3) — L2 error
//! O(h^(k+1)) and H1 error O(h^k) for degree k — i.e. 2 and 1 for Q1, 3 and 2
//! for Q2, each measured rate within ±0.15, on 5 meshes (4 refinements).
//! Independently, the errors must match the committed data to 1e-6
//! relative, so any change in the numbers is noticed. Regenerate the data
//! (after checking the rates) with `STICKSLIP_BLESS=1 cargo test -p
//! stickslip-fem --test convergence`.

use std::fmt::Write as _;
use std::path::PathBuf;

use stickslip_fem::element::CellBasis;
use stickslip_fem::geometry::Jacobian;
use stickslip_fem::loads::body_force_load_with;
use stickslip_fem::testing::{map_nodes, rectangle};
use stickslip_fem::{static_solve, traction_load_with, Dirichlet, Hypothesis, Material, Model};
use stickslip_mesh::{CellKind, Mesh};

const A: f64 = 2.0;
const B: f64 = 3.0;
const G: f64 = 1.5;
const DL: f64 = 2.0;

fn material() -> Material {
    Material::new(1.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap()
}

/// u and its gradient [[∂u_x/∂x, ∂u_x/∂y], [∂u_y/∂x, ∂u_y/∂y]].
fn exact(p: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
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

fn stress(p: [f64; 2]) -> [f64; 3] {
    let d = material().elasticity();
    let (_, g) = exact(p);
    let e = [g[0][0], g[1][1], g[0][1] + g[1][0]];
    [0, 1, 2].map(|i| (0..3).map(|j| d[i][j] * e[j]).sum())
}

/// f = −div σ by hand: with D isotropic (D13 = D23 = 0),
/// ∂σxx/∂x + ∂σxy/∂y = D11 u_x,xx + D12 u_y,xy + D33 (u_x,yy + u_y,xy),
/// ∂σxy/∂x + ∂σyy/∂y = D33 (u_x,xy + u_y,xx) + D21 u_x,xy + D22 u_y,yy.
fn body_force(p: [f64; 2]) -> [f64; 2] {
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

#[test]
fn hand_derived_body_force_matches_finite_differences_of_the_stress() {
    let h = 1e-5;
    for p in [[0.3, 0.7], [0.9, 0.1], [0.55, 0.45]] {
        let s = |dx: f64, dy: f64| stress([p[0] + dx, p[1] + dy]);
        let dsx = [
            (s(h, 0.0)[0] - s(-h, 0.0)[0]) / (2.0 * h),
            (s(0.0, h)[2] - s(0.0, -h)[2]) / (2.0 * h),
        ];
        let dsy = [
            (s(h, 0.0)[2] - s(-h, 0.0)[2]) / (2.0 * h),
            (s(0.0, h)[1] - s(0.0, -h)[1]) / (2.0 * h),
        ];
        let f = body_force(p);
        assert!((f[0] + dsx[0] + dsx[1]).abs() < 1e-8 && (f[1] + dsy[0] + dsy[1]).abs() < 1e-8);
    }
}

fn mesh(kind: CellKind, n: usize) -> Mesh {
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

/// (L2 error, H1-seminorm error) of the FE solution on an n × n mesh.
fn errors(kind: CellKind, n: usize) -> (f64, f64) {
    let mesh = mesh(kind, n);
    let bcs: Vec<Dirichlet> = ["left", "bottom"]
        .iter()
        .flat_map(|g| [Dirichlet::new(*g, 0, 0.0), Dirichlet::new(*g, 1, 0.0)])
        .collect();
    let model = Model::new(&mesh, &material(), &bcs).unwrap();
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
        )
        .unwrap();
    }
    let mut free = vec![0.0; model.dofs.n_free()];
    model.dofs.restrict(&full, &mut free);
    let u = static_solve(&model, &free).unwrap();

    // Errors with a 5 × 5 Gauss rule per cell (exact enough: its own error
    // is far below the discretisation error at these h).
    let basis = CellBasis::new(kind, 5);
    let nn = kind.nodes_per_cell();
    let (mut l2, mut h1) = (0.0, 0.0);
    let mut g = [[0.0; 2]; 9];
    for c in 0..mesh.n_cells() {
        let cell = mesh.cell(c);
        let coords: Vec<[f64; 2]> = cell.iter().map(|&v| mesh.nodes[v]).collect();
        for q in 0..basis.n_points() {
            let j = Jacobian::from_gradients(&coords, basis.gradients(q));
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
            h1 += w
                * (0..2)
                    .flat_map(|i| (0..2).map(move |k| (i, k)))
                    .map(|(i, k)| (ge[i][k] - gh[i][k]).powi(2))
                    .sum::<f64>();
        }
    }
    (l2.sqrt(), h1.sqrt())
}

fn data_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/convergence.csv")
}

#[test]
fn q1_and_q2_converge_at_the_theoretical_rates_and_match_the_committed_errors() {
    let ladders = [
        (CellKind::Quad4, "q1", [8, 16, 32, 64, 128], 2.0),
        (CellKind::Quad9, "q2", [4, 8, 16, 32, 64], 3.0),
    ];
    let mut csv = String::from("element,n,h,l2_error,h1_error\n");
    let mut measured = Vec::new();
    for (kind, name, ns, l2_rate) in ladders {
        let errs: Vec<(f64, f64)> = ns.iter().map(|&n| errors(kind, n)).collect();
        for (&n, &(l2, h1)) in ns.iter().zip(&errs) {
            writeln!(
                csv,
                "{name},{n},{:.17e},{l2:.17e},{h1:.17e}",
                1.0 / n as f64
            )
            .unwrap();
            measured.push((name.to_string(), n, l2, h1));
        }
        for (i, w) in errs.windows(2).enumerate() {
            let r_l2 = (w[0].0 / w[1].0).log2();
            let r_h1 = (w[0].1 / w[1].1).log2();
            eprintln!(
                "{name} n={}→{}: L2 rate {r_l2:.3}, H1 rate {r_h1:.3}",
                ns[i],
                ns[i + 1]
            );
            assert!(
                (r_l2 - l2_rate).abs() <= 0.15,
                "{name} n={}→{}: L2 rate {r_l2:.3}, theory {l2_rate}",
                ns[i],
                ns[i + 1]
            );
            assert!(
                (r_h1 - (l2_rate - 1.0)).abs() <= 0.15,
                "{name} n={}→{}: H1 rate {r_h1:.3}, theory {}",
                ns[i],
                ns[i + 1],
                l2_rate - 1.0
            );
        }
    }
    if std::env::var_os("STICKSLIP_BLESS").is_some() {
        std::fs::write(data_path(), &csv).unwrap();
        return;
    }
    let stored = std::fs::read_to_string(data_path()).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; create it with STICKSLIP_BLESS=1",
            data_path().display()
        )
    });
    let rows: Vec<Vec<String>> = stored
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(
        rows.len(),
        measured.len(),
        "rows in {}",
        data_path().display()
    );
    for (row, (name, n, l2, h1)) in rows.iter().zip(&measured) {
        assert_eq!((&row[0], row[1].parse::<usize>().unwrap()), (name, *n));
        let (sl2, sh1): (f64, f64) = (row[3].parse().unwrap(), row[4].parse().unwrap());
        assert!(
            ((l2 - sl2) / sl2).abs() < 1e-6,
            "{name} n={n}: L2 {l2:e} vs stored {sl2:e}"
        );
        assert!(
            ((h1 - sh1) / sh1).abs() < 1e-6,
            "{name} n={n}: H1 {h1:e} vs stored {sh1:e}"
        );
    }
}
