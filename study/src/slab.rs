//! The paper's slab (BENCHMARK.md) on the committed meshes: top rollers,
//! left end held in x, pressure on Γ_C with friction, compressive end
//! traction t_x = −150·θ(t). The scene is `stickslip_time::scenes::Slab`
//! (shared with the time crate's tests and `verify`); this module adds the
//! studies' two load histories and errors as text.

use stickslip_mesh::Mesh;
pub use stickslip_time::scenes::{meshes_dir, Slab, END_LOAD, G, MU, PRESSURE};
use stickslip_time::{scenes, History};

/// Reads a committed mesh by file name.
///
/// # Errors
/// The file is missing or unreadable (names it).
pub fn read_mesh(name: &str) -> Result<Mesh, String> {
    scenes::read_mesh(name).map_err(|e| e.to_string())
}

/// The load history θ(t) of the paper's two experiments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadKind {
    /// θ = H(t) (Figs. 3-15).
    Step,
    /// θ = sin 8πt (Figs. 16-18).
    Sin,
}

impl LoadKind {
    /// The time crate's history.
    pub fn history(self) -> History {
        match self {
            LoadKind::Step => History::Step,
            LoadKind::Sin => History::Sin {
                omega: 8.0 * std::f64::consts::PI,
            },
        }
    }
    /// The paper's case file of this history (cases/martins-oden).
    pub fn case_file(self) -> &'static str {
        match self {
            LoadKind::Step => "cd-step-eps1e-4.toml",
            LoadKind::Sin => "cd-sin-eps1e-4.toml",
        }
    }
    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            LoadKind::Step => "step",
            LoadKind::Sin => "sin8pit",
        }
    }
}

/// The paper's slab on `mesh` with regularization ε ([`Slab::paper`]);
/// `friction = false` drops the contact surface (the pressure stays).
///
/// # Errors
/// A mesh without the slab's groups, or ε ≤ 0.
pub fn paper(mesh: &Mesh, eps: f64, load: LoadKind, friction: bool) -> Result<Slab, String> {
    Slab::paper(mesh.clone(), eps, load.history(), friction).map_err(|e| e.to_string())
}
