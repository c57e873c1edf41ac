//! Scenes on a slab mesh built in code, for the tests, `cargo xtask
//! verify` and the studies (`stickslip-study`), so that each is assembled
//! in one place: any slab-shaped scene ([`Slab::assemble`]), the slab of
//! BENCHMARK.md ([`Slab::new`]) and the paper's own ([`Slab::paper`],
//! [`paper_slab`] on a committed mesh). The binary builds its scenes from a
//! case file instead (`stickslip-case`).

use std::path::PathBuf;

use stickslip_contact::{ContactError, ContactSurface};
use stickslip_fem::{traction_load, Dirichlet, FemError, Hypothesis, Material, Model, Traction};
use stickslip_mesh::{Mesh, MeshError};
use stickslip_time::{Dynamics, History, Integrator, Load, Settings, TimeError};

use crate::paths::read_mesh;

/// E of the slab (BENCHMARK.md).
pub const E: f64 = 1000.0;
/// ν of the slab.
pub const NU: f64 = 0.3;
/// F_n on Γ_C.
pub const PRESSURE: f64 = 300.0;
/// Friction coefficient.
pub const MU: f64 = 0.3;
/// Friction bound g = μ F_n.
pub const G: f64 = MU * PRESSURE;
/// End traction t_x at θ = 1 (compressive).
pub const END_LOAD: f64 = -150.0;

/// The slab's material (BENCHMARK.md): E = 1000, ν = 0.3, ρ = 1, plane
/// strain.
pub fn paper_material() -> Material {
    Material::new(E, NU, 1.0, Hypothesis::PlaneStrain).expect("the paper's material is valid")
}

/// The slab's supports (BENCHMARK.md): rollers on top ("support",
/// u_y = 0), the left end ("left") held in x.
pub fn paper_supports() -> [Dirichlet; 2] {
    [
        Dirichlet::new("support", 1, 0.0),
        Dirichlet::new("left", 0, 0.0),
    ]
}

/// Why a scene could not be built or run.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A mesh file that does not read.
    #[error("{}: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// The reader's error (boxed: it is the largest variant).
        source: Box<MeshError>,
    },
    /// The model or a load (a missing group, a bad material).
    #[error(transparent)]
    Fem(#[from] FemError),
    /// The contact surface.
    #[error(transparent)]
    Contact(#[from] ContactError),
    /// The integrator refused the settings or a step failed.
    #[error(transparent)]
    Time(#[from] TimeError),
    /// No mesh node where one was expected.
    #[error("the mesh has no node at ({x}, {y})")]
    NoNode {
        /// x.
        x: f64,
        /// y.
        y: f64,
    },
}

/// A traction load on a line group: group, traction, history θ(t).
pub type TractionLoad<'a> = (&'a str, Traction, History);

/// Friction on a line group: group, pressure F_n, μ, ε.
pub type Friction<'a> = (&'a str, f64, f64, f64);

/// A scene on a slab mesh: the model, Γ_C (if any) and the loads.
#[derive(Debug)]
pub struct Slab {
    /// The mesh.
    pub mesh: Mesh,
    /// The finite-element model.
    pub model: Model,
    /// Friction surface (None: no friction).
    pub contact: Option<ContactSurface>,
    /// The loads, in the order given.
    pub loads: Vec<Load>,
}

impl Slab {
    /// Any scene of this shape: plane strain `material`, `conditions`, one
    /// [`Load`] per traction (consistent nodal forces, restricted to the
    /// free DOFs) and friction on a group.
    ///
    /// # Errors
    /// A missing group, bad conditions, or a contact surface refused.
    pub fn assemble(
        mesh: Mesh,
        material: &Material,
        conditions: &[Dirichlet],
        tractions: &[TractionLoad],
        friction: Option<Friction>,
    ) -> Result<Slab, SceneError> {
        let model = Model::new(&mesh, material, conditions)?;
        let n_full = 2 * mesh.nodes.len();
        let mut loads = Vec::with_capacity(tractions.len());
        for (group, traction, history) in tractions {
            let mut full = vec![0.0; n_full];
            traction_load(&mesh, group, *traction, &mut full)?;
            let mut free = vec![0.0; model.dofs.n_free()];
            model.dofs.restrict(&full, &mut free);
            loads.push(Load {
                vector: free,
                history: history.clone(),
            });
        }
        let contact = match friction {
            Some((group, pressure, mu, eps)) => Some(ContactSurface::from_group(
                &mesh,
                &model.dofs,
                group,
                pressure,
                mu,
                eps,
            )?),
            None => None,
        };
        Ok(Slab {
            mesh,
            model,
            contact,
            loads,
        })
    }

    /// The slab of BENCHMARK.md on `mesh`: E = 1000, ρ = 1, top rollers
    /// ("support", u_y = 0), left end held in x, pressure `pressure` on the
    /// bottom ("contact", a constant load present before t = 0, METHOD.md
    /// §3; friction μ with regularization ε), end traction t_x =
    /// `end_load`·θ(t) on "load". A zero pressure or end load adds no load;
    /// `mu = None` means no friction surface.
    ///
    /// # Errors
    /// A mesh without the slab's groups, a bad ν, or ε ≤ 0.
    pub fn new(
        mesh: Mesh,
        nu: f64,
        pressure: f64,
        mu: Option<f64>,
        eps: f64,
        end_load: f64,
        theta: History,
    ) -> Result<Slab, SceneError> {
        let material = Material::new(E, nu, 1.0, Hypothesis::PlaneStrain)?;
        let mut tractions = Vec::new();
        if pressure != 0.0 {
            tractions.push(("contact", Traction::Pressure(pressure), History::Constant));
        }
        if end_load != 0.0 {
            tractions.push(("load", Traction::Vector([end_load, 0.0]), theta));
        }
        let friction = mu.map(|mu| ("contact", pressure, mu, eps));
        Slab::assemble(mesh, &material, &paper_supports(), &tractions, friction)
    }

    /// The paper's slab: ν = 0.3, F_n = 300, μ = 0.3 (or no friction
    /// surface when `friction` is false; the pressure stays), end load
    /// −150·θ(t).
    ///
    /// # Errors
    /// As [`Slab::new`].
    pub fn paper(mesh: Mesh, eps: f64, theta: History, friction: bool) -> Result<Slab, SceneError> {
        Slab::new(
            mesh,
            NU,
            PRESSURE,
            friction.then_some(MU),
            eps,
            END_LOAD,
            theta,
        )
    }

    /// The integrator of this scene.
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

    /// The mesh node at (x, y) (the nearest, within 1e-6).
    ///
    /// # Errors
    /// No node there.
    pub fn node_at(&self, x: f64, y: f64) -> Result<usize, SceneError> {
        let mut best = (f64::INFINITY, 0);
        for (i, p) in self.mesh.nodes.iter().enumerate() {
            let d = (p[0] - x).powi(2) + (p[1] - y).powi(2);
            if d < best.0 {
                best = (d, i);
            }
        }
        if best.0 < 1e-12 {
            Ok(best.1)
        } else {
            Err(SceneError::NoNode { x, y })
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

    /// u_x of mesh node `node` from a free displacement vector (0 where
    /// fixed).
    pub fn ux(&self, r: &[f64], node: usize) -> f64 {
        self.dof(node, 0).map_or(0.0, |d| r[d])
    }
}

/// The paper's slab with its friction ([`Slab::paper`]) on the committed
/// mesh `mesh_file`; panics on a mesh or scene that does not build, as a
/// test should.
pub fn paper_slab(mesh_file: &str, eps: f64, theta: History) -> Slab {
    let mesh = read_mesh(mesh_file).expect("committed mesh reads");
    Slab::paper(mesh, eps, theta, true).expect("the slab's scene builds")
}
