//! Timings of one rung of the Q2 (or Q1) slab ladder, for `cargo xtask
//! bench fem`: pattern, assembly of K and M, symbolic and numeric Cholesky,
//! solve, and peak memory. One rung per process so the peak RSS is that of
//! the rung.
//!
//!     cargo run -p stickslip-fem --example bench_assembly -- --refine 64 [--q1] [--threads N] [--dump DIR]
//!
//! Prints one line `key=value ...`. `--dump DIR` writes the free-DOF K as raw
//! little-endian arrays (indptr i64, indices i64, data f64) and the load as
//! f64, for the Python peer to solve the same matrix.

use std::io::Write as _;
use std::time::Instant;

use stickslip_fem::{free_dof_pattern, static_solve, traction_load, Model, Traction};
use stickslip_mesh::CellKind;
use stickslip_testkit::{paper_material, paper_supports, slab};

fn peak_rss_mb() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let refine: usize = value("--refine").map_or(8, |v| v.parse().expect("--refine N"));
    let kind = if args.iter().any(|a| a == "--q1") {
        CellKind::Quad4
    } else {
        CellKind::Quad9
    };
    if let Some(t) = value("--threads") {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t.parse().expect("--threads N"))
            .build_global()
            .unwrap();
    }
    let mesh = slab(kind, refine);
    let mat = paper_material();
    let bcs = paper_supports();

    let t = Instant::now();
    let dofs = stickslip_fem::DofMap::new(&mesh, &bcs).unwrap();
    let pattern = free_dof_pattern(&mesh, &dofs);
    let pattern_s = t.elapsed().as_secs_f64();
    drop(pattern);
    // Model::new = DOF map + pattern + K, M, lumped M in one pass, and the
    // factors' ordering (from 500 free DOFs a nested dissection, on large
    // meshes made beside the DOF map): the assembly is its own part, and
    // the ordering is timed alone and counted with the factorization, as
    // AMD's is (and SuperLU's COLAMD in the peer's).
    let t = Instant::now();
    let model = Model::new(&mesh, &mat, &bcs).unwrap();
    let model_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let order = stickslip_fem::ordering::choose(&mesh, &model.dofs, None);
    let order_s = t.elapsed().as_secs_f64();
    assert_eq!(
        order.dissection_order(),
        model.fill_order.dissection_order()
    );
    drop(order);
    let assembly_s = model
        .setup
        .parts()
        .iter()
        .find_map(|&(name, s)| (name == "assembly").then_some(s))
        .expect("Model::new times its assembly");
    let t = Instant::now();
    let mut combined = model.stiffness.clone();
    let clone_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    model.combine(0.25, 40.0, &mut combined);
    let combine_s = t.elapsed().as_secs_f64();

    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    traction_load(&mesh, "contact", Traction::Pressure(300.0), &mut full).unwrap();
    let mut load = vec![0.0; model.dofs.n_free()];
    model.dofs.restrict(&full, &mut load);

    let t = Instant::now();
    let mut chol =
        stickslip_linalg::SparseCholesky::analyze(&model.stiffness, &model.fill_order).unwrap();
    let symbolic_s = order_s + t.elapsed().as_secs_f64();
    let t = Instant::now();
    chol.factorize(&model.stiffness).unwrap();
    let numeric_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut x = load.clone();
    chol.solve_in_place(&mut x);
    let solve_s = t.elapsed().as_secs_f64();
    // Accuracy: the uniform state u_x = 0.117x (BENCHMARK.md) at the far corner.
    let u = static_solve(&model, &load).unwrap();
    let corner = mesh
        .nodes
        .iter()
        .position(|p| p[0] == 8.0 && p[1] == 0.0)
        .unwrap();
    let err = (u[2 * corner] - 0.936).abs();

    if let Some(dir) = value("--dump") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        let write = |name: &str, bytes: Vec<u8>| {
            std::fs::File::create(dir.join(name))
                .unwrap()
                .write_all(&bytes)
                .unwrap()
        };
        let i64s = |v: &[usize]| {
            v.iter()
                .flat_map(|&i| (i as i64).to_le_bytes())
                .collect::<Vec<u8>>()
        };
        let f64s = |v: &[f64]| v.iter().flat_map(|&f| f.to_le_bytes()).collect::<Vec<u8>>();
        write("indptr.i64", i64s(model.stiffness.row_offsets()));
        write("indices.i64", i64s(model.stiffness.col_indices()));
        write("data.f64", f64s(model.stiffness.values()));
        write("rhs.f64", f64s(&load));
    }
    println!(
        "kind={} refine={} cells={} nodes={} free_dofs={} nnz={} factor_nnz={} order={} threads={} pattern_s={:.4} assembly_s={:.4} model_s={:.4} clone_s={:.4} combine_s={:.4} order_s={:.4} symbolic_s={:.4} numeric_s={:.4} solve_s={:.4} corner_error={:.2e} peak_rss_mb={:.1}",
        kind.name(),
        refine,
        mesh.n_cells(),
        mesh.nodes.len(),
        model.dofs.n_free(),
        model.stiffness.nnz(),
        chol.factor_nnz(),
        if model.fill_order.name() == "AMD" { "amd" } else { "nd" },
        rayon::current_num_threads(),
        pattern_s,
        assembly_s,
        model_s,
        clone_s,
        combine_s,
        order_s,
        symbolic_s,
        numeric_s,
        solve_s,
        err,
        peak_rss_mb()
    );
}
