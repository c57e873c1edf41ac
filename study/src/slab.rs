//! The paper's slab (BENCHMARK.md) built from the committed meshes, as in
//! crates/time/tests/common: top rollers, left end held in x, pressure on
//! Γ_C with friction, compressive end traction t_x = −150·θ(t).

use std::path::{Path, PathBuf};

use stickslip_contact::ContactSurface;
use stickslip_fem::{traction_load, Dirichlet, Hypothesis, Material, Model, Traction};
use stickslip_mesh::Mesh;
use stickslip_time::{Dynamics, History, Integrator, Load, Settings, TimeError};

/// F_n on Γ_C (BENCHMARK.md).
pub const PRESSURE: f64 = 300.0;
/// Friction coefficient.
pub const MU: f64 = 0.3;
/// Friction bound g = μ F_n.
pub const G: f64 = MU * PRESSURE;
/// End traction t_x at θ = 1 (compressive).
pub const END_LOAD: f64 = -150.0;

/// The committed mesh directory.
pub fn meshes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/meshes")
}

/// Reads a committed mesh by file name.
///
/// # Errors
/// The file is missing or unreadable (names it).
pub fn read_mesh(name: &str) -> Result<Mesh, String> {
    let path = meshes_dir().join(name);
    Mesh::from_file(&path).map_err(|e| format!("{}: {e}", path.display()))
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
    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            LoadKind::Step => "step",
            LoadKind::Sin => "sin8pit",
        }
    }
}

/// The assembled slab.
#[derive(Debug)]
pub struct Slab {
    /// Finite-element model.
    pub model: Model,
    /// Friction surface (None: a scene without a contact group).
    pub contact: Option<ContactSurface>,
    /// Pressure (constant) and end load (θ(t)).
    pub loads: Vec<Load>,
    /// Node coordinates.
    pub nodes: Vec<[f64; 2]>,
}

impl Slab {
    /// The paper's slab on `mesh` with regularization ε; `friction = false`
    /// drops the contact surface (the pressure stays).
    ///
    /// # Errors
    /// A mesh without the slab's groups, or ε ≤ 0.
    pub fn new(mesh: &Mesh, eps: f64, load: LoadKind, friction: bool) -> Result<Slab, String> {
        let material =
            Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).map_err(|e| e.to_string())?;
        let conditions = vec![
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let model = Model::new(mesh, &material, &conditions).map_err(|e| e.to_string())?;
        let n_full = 2 * mesh.nodes.len();
        let restrict = |full: &[f64]| {
            let mut free = vec![0.0; model.dofs.n_free()];
            model.dofs.restrict(full, &mut free);
            free
        };
        let mut full = vec![0.0; n_full];
        traction_load(mesh, "contact", Traction::Pressure(PRESSURE), &mut full)
            .map_err(|e| e.to_string())?;
        let mut loads = vec![Load {
            vector: restrict(&full),
            history: History::Constant,
        }];
        full.iter_mut().for_each(|x| *x = 0.0);
        traction_load(mesh, "load", Traction::Vector([END_LOAD, 0.0]), &mut full)
            .map_err(|e| e.to_string())?;
        loads.push(Load {
            vector: restrict(&full),
            history: load.history(),
        });
        let contact = if friction {
            Some(
                ContactSurface::from_group(mesh, &model.dofs, "contact", PRESSURE, MU, eps)
                    .map_err(|e| e.to_string())?,
            )
        } else {
            None
        };
        Ok(Slab {
            model,
            contact,
            loads,
            nodes: mesh.nodes.clone(),
        })
    }

    /// The integrator of this slab.
    ///
    /// # Errors
    /// The time crate's (settings, Δt above the critical step).
    pub fn integrator(&self, settings: Settings) -> Result<Integrator, TimeError> {
        Integrator::new(
            Dynamics::from_model(&self.model),
            self.contact.clone(),
            self.loads.clone(),
            settings,
        )
    }

    /// Mesh node at (x, y).
    ///
    /// # Errors
    /// No node there.
    pub fn node_at(&self, x: f64, y: f64) -> Result<usize, String> {
        let mut best = (f64::INFINITY, 0);
        for (i, p) in self.nodes.iter().enumerate() {
            let d = (p[0] - x).powi(2) + (p[1] - y).powi(2);
            if d < best.0 {
                best = (d, i);
            }
        }
        if best.0 < 1e-12 {
            Ok(best.1)
        } else {
            Err(format!("the mesh has no node at ({x}, {y})"))
        }
    }

    /// Index of mesh node `node` among the contact nodes.
    pub fn contact_index(&self, node: usize) -> Option<usize> {
        self.contact
            .as_ref()?
            .nodes
            .iter()
            .position(|n| n.node == node)
    }

    /// Free DOF of (node, component).
    pub fn dof(&self, node: usize, component: usize) -> Option<usize> {
        self.model.dofs.free(node, component)
    }

    /// Number of free DOFs.
    pub fn n_free(&self) -> usize {
        self.model.dofs.n_free()
    }
}
