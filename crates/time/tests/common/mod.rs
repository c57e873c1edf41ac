//! The paper's slab (BENCHMARK.md) on the committed meshes, built by
//! `stickslip_time::scenes` (shared with `verify` and `study`); these
//! wrapper only reads the mesh by file name and panics on a bad scene.

#![allow(dead_code)]

pub use stickslip_time::scenes::{read_mesh, Slab};
use stickslip_time::History;

/// The paper's slab with its friction (BENCHMARK.md).
pub fn paper_slab(mesh_file: &str, eps: f64, theta: History) -> Slab {
    let mesh = read_mesh(mesh_file).expect("committed mesh reads");
    Slab::paper(mesh, eps, theta, true).expect("the slab's scene builds")
}
