//! Meshes above [`DISSECTION_MIN_DOFS`] on which the nested dissection by
//! cells (`ordering.rs`) gives a larger factor of K than faer's AMD: a comb
//! (a base and teeth, non-convex) and long thin strips, all clamped at the
//! bottom (the comb) or the left end (the strips). Prints the factor
//! values of both orderings:
//!
//!     cargo run --release -p stickslip-fem --example fill_order_shapes

use stickslip_fem::ordering::{nested_dissection, DISSECTION_MIN_DOFS};
use stickslip_fem::testing::{add_point_group, rectangle};
use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
use stickslip_linalg::{analyze_symbolic, FillOrder};
use stickslip_mesh::{CellKind, Mesh};

/// The cells of an `nx × ny` grid of `kind` on unit squares that `keep`
/// keeps, with a point group "clamp" of the kept nodes `clamp` selects and
/// the nodes left in no cell (clamped too, so that they add no DOF).
fn shape(
    kind: CellKind,
    nx: usize,
    ny: usize,
    keep: impl Fn(usize, usize) -> bool,
    clamp: impl Fn([f64; 2]) -> bool,
) -> Mesh {
    let grid = rectangle(kind, nx, ny, [0.0, 0.0], [nx as f64, ny as f64]);
    let per = kind.nodes_per_cell();
    let mut m = grid.clone();
    m.cells.clear();
    for ey in 0..ny {
        for ex in (0..nx).filter(|&ex| keep(ex, ey)) {
            let c = ey * nx + ex;
            m.cells
                .extend_from_slice(&grid.cells[c * per..(c + 1) * per]);
        }
    }
    m.cell_tags = (1..=(m.cells.len() / per) as u64).collect();
    let mut used = vec![false; m.nodes.len()];
    for &v in &m.cells {
        used[v] = true;
    }
    let clamped: Vec<usize> = (0..m.nodes.len())
        .filter(|&v| !used[v] || clamp(m.nodes[v]))
        .collect();
    m.groups.clear();
    add_point_group(&mut m, "clamp", &clamped);
    m
}

fn main() {
    let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
    let clamp = [
        Dirichlet::new("clamp", 0, 0.0),
        Dirichlet::new("clamp", 1, 0.0),
    ];
    let comb = |ex: usize, ey: usize| ey < 20 || ex % 20 < 10;
    let comb2 = |ex: usize, ey: usize| ey < 10 || ex % 10 < 5;
    let all = |_: usize, _: usize| true;
    let bottom = |p: [f64; 2]| p[1] == 0.0;
    let left = |p: [f64; 2]| p[0] == 0.0;
    let meshes = [
        (
            "comb Q1 480x200",
            shape(CellKind::Quad4, 480, 200, comb, bottom),
        ),
        (
            "comb Q2 240x100",
            shape(CellKind::Quad9, 240, 100, comb2, bottom),
        ),
        (
            "strip Q1 5000x10",
            shape(CellKind::Quad4, 5000, 10, all, left),
        ),
        (
            "strip Q1 3500x18",
            shape(CellKind::Quad4, 3500, 18, all, left),
        ),
        (
            "strip Q2 4000x3",
            shape(CellKind::Quad9, 4000, 3, all, left),
        ),
    ];
    println!("mesh,dofs,nd_values,amd_values,nd_over_amd");
    for (name, mesh) in meshes {
        let model = Model::new(&mesh, &material, &clamp).unwrap();
        assert!(model.dofs.n_free() >= DISSECTION_MIN_DOFS);
        let values =
            |order: &FillOrder| analyze_symbolic(&model.stiffness, order).unwrap().len_val();
        let nd = values(&FillOrder::dissection(nested_dissection(
            &mesh,
            &model.dofs,
        )));
        let amd = values(&FillOrder::amd());
        println!(
            "{name},{},{nd},{amd},{:.3}",
            model.dofs.n_free(),
            nd as f64 / amd as f64
        );
    }
}
