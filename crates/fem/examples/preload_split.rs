//! The explicit run's preload, K x = b refined to double's accuracy, by
//! the whole single-precision factor and by the dissection's two halves
//! at once (`stickslip_linalg::SplitSingle`): the analysis, the factor and
//! the refined solve (s), CG's iterations, and how far the two solutions
//! are apart (docs/performance.md, "The preload by halves").
//!
//!     cargo run --release -p stickslip-fem --example preload_split -- MESH [ROUNDS]
//!
//! MESH: a .msh file with the slab's support groups (`support`, `left`).

use std::time::Instant;

use stickslip_fem::ordering::dissection_with_halves;
use stickslip_fem::Model;
use stickslip_linalg::{FillOrder, SparseCholesky, SplitSingle, BACKWARD_ERROR};
use stickslip_mesh::Mesh;
use stickslip_testkit::{paper_material, paper_supports};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(name), rounds) = (args.first(), args.get(1).and_then(|r| r.parse().ok())) else {
        eprintln!("usage: preload_split MESH [ROUNDS]");
        std::process::exit(2);
    };
    let mesh = Mesh::from_file(name).unwrap_or_else(|e| panic!("{e}"));
    let model = Model::new(&mesh, &paper_material(), &paper_supports()).unwrap();
    let (order, halves) = dissection_with_halves(&mesh, &model.dofs);
    let Some(halves) = halves else {
        eprintln!("{name}: the dissection's first split left a half empty");
        std::process::exit(1);
    };
    let k = &model.stiffness;
    let n = k.nrows();
    println!(
        "{name}: {n} DOFs, halves {} and {}, separator {}",
        halves[0],
        halves[1],
        n - halves[0] - halves[1]
    );
    println!("round,whole_analysis_s,whole_factor_s,whole_solve_s,whole_iterations,split_analysis_s,split_factor_s,split_solve_s,split_iterations,difference");
    let b: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
    for round in 0..rounds.unwrap_or(3) {
        let t = Instant::now();
        let mut whole = SparseCholesky::analyze(k, &FillOrder::dissection(order.clone())).unwrap();
        let whole_analysis = t.elapsed().as_secs_f64();
        let t = Instant::now();
        whole.factorize_single(k).unwrap();
        let whole_factor = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut x_whole = b.clone();
        let r_whole = whole
            .solve_refined(k, &mut x_whole, BACKWARD_ERROR)
            .unwrap();
        let whole_solve = t.elapsed().as_secs_f64();
        drop(whole);
        let t = Instant::now();
        let mut split = SplitSingle::analyze(k, &order, halves).unwrap().unwrap();
        let split_analysis = t.elapsed().as_secs_f64();
        let t = Instant::now();
        split.factorize(k).unwrap();
        let split_factor = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut x_split = b.clone();
        let r_split = split
            .solve_refined(k, &mut x_split, BACKWARD_ERROR)
            .unwrap();
        let split_solve = t.elapsed().as_secs_f64();
        let scale = x_whole.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let difference = x_whole
            .iter()
            .zip(&x_split)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / scale;
        println!(
            "{round},{whole_analysis:.3},{whole_factor:.3},{whole_solve:.3},{},{split_analysis:.3},{split_factor:.3},{split_solve:.3},{},{difference:.1e}",
            r_whole.iterations, r_split.iterations
        );
    }
}
