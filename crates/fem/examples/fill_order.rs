//! The table of `ordering.rs`: faer's AMD against the nested dissection by
//! cells, on K of the slab problem's supports (groups `support`, `left`, as
//! `cases/hole.geo` and the slabs name them): factor values, the numeric
//! factorization and the ordering with the symbolic analysis.
//!
//!     cargo run --release -p stickslip-fem --example fill_order -- MESH...
//!
//! MESH: a .msh file, or `q1-R` / `q2-R`, the slab built in code at
//! refinement R (`testing::slab`, numbered row by row).

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{Par, Side};
use stickslip_fem::ordering::nested_dissection;
use stickslip_fem::testing::slab;
use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
use stickslip_linalg::{analyze_symbolic, csc_view, FillOrder};
use stickslip_mesh::{CellKind, Mesh};

/// Ordering + symbolic (s), factor values, numeric factorization (s).
fn factorize(model: &Model, order: &FillOrder, ordering_s: f64) -> (f64, usize, f64) {
    let a = &model.stiffness;
    let t = Instant::now();
    let symbolic = analyze_symbolic(a, order).unwrap();
    let analysis_s = ordering_s + t.elapsed().as_secs_f64();
    let mut l = vec![0.0; symbolic.len_val()];
    let mut scratch =
        MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
    let t = Instant::now();
    symbolic
        .factorize_numeric_llt(
            &mut l,
            csc_view(a, a.values()),
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .unwrap();
    (analysis_s, symbolic.len_val(), t.elapsed().as_secs_f64())
}

fn main() {
    let names: Vec<String> = std::env::args().skip(1).collect();
    if names.is_empty() || names.iter().any(|a| a.starts_with('-')) {
        eprintln!(
            "usage: fill_order MESH...   (a .msh file, or q1-R / q2-R: the slab at refinement R)"
        );
        std::process::exit(2);
    }
    let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
    let supports = [
        Dirichlet::new("support", 1, 0.0),
        Dirichlet::new("left", 0, 0.0),
    ];
    println!(
        "mesh,dofs,nd_values,amd_values,nd_numeric_s,amd_numeric_s,nd_analysis_s,amd_analysis_s"
    );
    for name in names {
        let refined = |prefix: &str| name.strip_prefix(prefix).and_then(|r| r.parse().ok());
        let mesh = match (refined("q1-"), refined("q2-")) {
            (Some(r), _) => slab(CellKind::Quad4, r),
            (_, Some(r)) => slab(CellKind::Quad9, r),
            _ => Mesh::from_file(&name).unwrap_or_else(|e| panic!("{e}")),
        };
        let model = Model::new(&mesh, &material, &supports).unwrap();
        let t = Instant::now();
        let nd = FillOrder::dissection(nested_dissection(&mesh, &model.dofs));
        let nd_s = t.elapsed().as_secs_f64();
        let (nd_analysis, nd_values, nd_numeric) = factorize(&model, &nd, nd_s);
        let (amd_analysis, amd_values, amd_numeric) = factorize(&model, &FillOrder::amd(), 0.0);
        println!(
            "{name},{},{nd_values},{amd_values},{nd_numeric:.3},{amd_numeric:.3},{nd_analysis:.3},{amd_analysis:.3}",
            model.dofs.n_free()
        );
    }
}
