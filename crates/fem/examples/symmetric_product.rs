//! K·x by the upper node blocks ([`Symmetric`]) against the assembled CSR
//! on a Gmsh mesh's K, assembled as a run assembles it (the paper's
//! material and supports, the DOF map's node order): medians of
//! interleaved products on 1 and 2 threads, and the largest difference
//! from the CSR product relative to Σ|K_ij||x_j|. (The node blocks it was
//! first timed against, every row's full 2×2 blocks, are gone: see
//! docs/performance.md.)
//!
//!     cargo run --release -p stickslip-fem --example symmetric_product -- MESH [ROUNDS]

use std::time::Instant;

use stickslip_fem::Model;
use stickslip_linalg::{csr, Symmetric};
use stickslip_mesh::Mesh;
use stickslip_testkit::{paper_material, paper_supports};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().expect("a .msh file");
    let rounds: usize = args.get(1).map_or(9, |r| r.parse().expect("ROUNDS"));
    let mesh = Mesh::from_file(path).expect("mesh");
    let model = Model::new(&mesh, &paper_material(), &paper_supports()).expect("model");
    let k = &model.stiffness;
    let n = k.nrows();
    let t = Instant::now();
    let sym = Symmetric::new(k).expect("symmetric");
    let sym_build = t.elapsed().as_secs_f64();
    println!(
        "n={n} nnz={} CSR: {:.1} MB; symmetric: {:.1} MB built {:.3} s, halo {} doubles",
        k.nnz(),
        (16 * k.nnz() + 8 * n) as f64 / 1e6,
        sym.bytes() as f64 / 1e6,
        sym_build,
        sym.halo_len()
    );
    let x: Vec<f64> = (0..n)
        .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.4)
        .collect();
    let mut want = vec![0.0; n];
    csr::spmv(k, &x, &mut want);
    let mut scale = vec![0.0; n];
    for (i, r) in k.row_iter().enumerate() {
        scale[i] = r
            .col_indices()
            .iter()
            .zip(r.values())
            .map(|(&j, v)| (v * x[j]).abs())
            .sum();
    }
    let mut halo = vec![0.0; sym.halo_len()];
    let mut scratch = Vec::new();
    let mut bits: Option<Vec<u64>> = None;
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let (mut tb, mut ts) = (Vec::new(), Vec::new());
        let (mut yb, mut ys) = (vec![0.0; n], vec![0.0; n]);
        pool.install(|| {
            for _ in 0..rounds {
                let t = Instant::now();
                csr::spmv(k, &x, &mut yb);
                tb.push(t.elapsed().as_secs_f64());
                let t = Instant::now();
                sym.spmv_with(&x, &mut ys, &mut halo, &mut scratch);
                ts.push(t.elapsed().as_secs_f64());
            }
        });
        let worst = (0..n)
            .map(|i| (ys[i] - want[i]).abs() / scale[i].max(f64::MIN_POSITIVE))
            .fold(0.0_f64, f64::max);
        let b: Vec<u64> = ys.iter().map(|v| v.to_bits()).collect();
        let same = bits.as_ref().is_none_or(|p| *p == b);
        bits = Some(b);
        let (mb, ms) = (median(tb), median(ts));
        println!(
            "threads={threads} CSR {:.2} ms symmetric {:.2} ms ratio {:.2} | max |Δ|/Σ|K||x| {worst:.1e} | bits as on 1 thread: {same}",
            mb * 1e3,
            ms * 1e3,
            mb / ms
        );
    }
}
