//! The paper's slab (BENCHMARK.md) on the committed meshes, built by
//! `stickslip_time::scenes` (shared with `verify` and `study`); these
//! wrappers only read the mesh by file name and panic on a bad scene.

#![allow(dead_code)]

pub use stickslip_time::scenes::{read_mesh, Slab};
use stickslip_time::History;

/// The slab of BENCHMARK.md ([`Slab::new`]): top rollers, left end held in
/// x, pressure `pressure` on the bottom (Γ_C, friction μ with
/// regularization ε), end traction t_x = `end_load`·θ(t). `mu = None` means
/// no contact surface.
pub fn slab(
    mesh_file: &str,
    nu: f64,
    pressure: f64,
    mu: Option<f64>,
    eps: f64,
    end_load: f64,
    theta: History,
) -> Slab {
    let mesh = read_mesh(mesh_file).expect("committed mesh reads");
    Slab::new(mesh, nu, pressure, mu, eps, end_load, theta).expect("the slab's scene builds")
}

/// The paper's slab with its friction (BENCHMARK.md).
pub fn paper_slab(mesh_file: &str, eps: f64, theta: History) -> Slab {
    let mesh = read_mesh(mesh_file).expect("committed mesh reads");
    Slab::paper(mesh, eps, theta, true).expect("the slab's scene builds")
}
