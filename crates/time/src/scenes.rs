//! Scenes built in code for the tests, `cargo xtask verify` and the studies
//! (`stickslip-study`), so that each is assembled in one place: the paper's
//! slab (BENCHMARK.md) on a committed mesh, the 1-D wave on the slab mesh
//! with its d'Alembert solution ([`wave`]), and the single-DOF friction
//! oscillator with its closed form ([`sdof`]). The integrator does not use
//! this module; it is the callers' common way to set up a run.

use std::path::{Path, PathBuf};

use stickslip_contact::{ContactError, ContactSurface};
use stickslip_fem::{traction_load, Dirichlet, FemError, Hypothesis, Material, Model, Traction};
use stickslip_mesh::{CellKind, Mesh, MeshError};

use crate::{Dynamics, History, Integrator, Load, Settings, TimeError};

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

/// Why a scene could not be built or run.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A mesh file that does not read.
    #[error("{}: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// The reader's error.
        source: MeshError,
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

/// The committed mesh directory (`cases/meshes` of the workspace).
pub fn meshes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes")
}

/// Reads a committed mesh by file name.
///
/// # Errors
/// The file is missing or unreadable (the error names it).
pub fn read_mesh(name: &str) -> Result<Mesh, SceneError> {
    let path = meshes_dir().join(name);
    Mesh::from_file(&path).map_err(|source| SceneError::Mesh { path, source })
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
        let conditions = [
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let mut tractions = Vec::new();
        if pressure != 0.0 {
            tractions.push(("contact", Traction::Pressure(pressure), History::Constant));
        }
        if end_load != 0.0 {
            tractions.push(("load", Traction::Vector([end_load, 0.0]), theta));
        }
        let friction = mu.map(|mu| ("contact", pressure, mu, eps));
        Slab::assemble(mesh, &material, &conditions, &tractions, friction)
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

/// A 1-D wave: the slab mesh with ν = 0, rollers on top and bottom, held at
/// x = 0, a step traction −p at x = L, no friction. Every section moves as a
/// bar with c = √(E/ρ) (ν = 0 makes plane strain uniaxial), so d'Alembert
/// gives the end displacement: a triangle wave between 0 and −2pL/E with
/// period 4L/c, u(L, t) = −(p c/E)·t for t ≤ 2L/c, then back to 0 at 4L/c.
pub mod wave {
    use super::*;
    use crate::Scheme;

    /// E (ρ = 1).
    pub const E: f64 = 1000.0;
    /// Bar length.
    pub const L: f64 = 8.0;
    /// End traction.
    pub const P: f64 = 1.0;

    /// d'Alembert's u_x(L, t).
    pub fn exact_end_displacement(t: f64) -> f64 {
        let c = E.sqrt();
        let period = 4.0 * L / c;
        let tau = t.rem_euclid(period);
        let rise = if tau <= period / 2.0 {
            tau
        } else {
            period - tau
        };
        -P * c / E * rise
    }

    /// The bar on `mesh` (a slab mesh with groups "support", "contact",
    /// "left", "load").
    ///
    /// # Errors
    /// A mesh without those groups.
    pub fn scene(mesh: Mesh) -> Result<Slab, SceneError> {
        let material = Material::new(E, 0.0, 1.0, Hypothesis::PlaneStrain)?;
        let conditions = [
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("contact", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let tractions = [("load", Traction::Vector([-P, 0.0]), History::Step)];
        Slab::assemble(mesh, &material, &conditions, &tractions, None)
    }

    /// Relative L2-in-time error of u_x(L, 0) over one period against
    /// [`exact_end_displacement`].
    ///
    /// # Errors
    /// A mesh without the slab's groups or node (L, 0), settings refused
    /// or a failed step.
    pub fn end_error(mesh: Mesh, scheme: Scheme, dt: f64) -> Result<f64, SceneError> {
        let s = scene(mesh)?;
        let end = s.node_at(L, 0.0)?;
        let end_dof = s.dof(end, 0).ok_or(SceneError::NoNode { x: L, y: 0.0 })?;
        let period = 4.0 * L / E.sqrt();
        let mut i = s.integrator(Settings::new(scheme, dt, period))?;
        let (mut err2, mut ref2) = (0.0, 0.0);
        while !i.done() {
            i.step()?;
            let exact = exact_end_displacement(i.time());
            err2 += (i.displacement()[end_dof] - exact).powi(2);
            ref2 += exact * exact;
        }
        Ok((err2 / ref2).sqrt())
    }
}

/// The single-DOF oscillator with Coulomb friction: m = 1, k = 100
/// (ω = 10), friction force g = 1 (weight 1, bound 1), step force P from
/// t = 0, at rest at 0.
pub mod sdof {
    use nalgebra_sparse::{CooMatrix, CsrMatrix};
    use stickslip_contact::{ContactNode, ContactSurface};

    use super::SceneError;
    use crate::{Dynamics, History, Integrator, Load, Scheme, Settings};

    /// Spring stiffness.
    pub const K: f64 = 100.0;
    /// Friction force.
    pub const G: f64 = 1.0;
    /// Natural frequency √(k/m).
    pub const OMEGA: f64 = 10.0;

    /// Exact Coulomb displacement at time t: from rest at x_i the mass moves
    /// if |P − k x_i| > g, along x_e + (x_i − x_e) cos ω(t − t_i) with
    /// x_e = (P − s g)/k, s = sign(P − k x_i), for half a period π/ω, and is
    /// at rest again at 2x_e − x_i.
    pub fn closed_form(p: f64, t: f64) -> f64 {
        let half = std::f64::consts::PI / OMEGA;
        let (mut x, mut t0) = (0.0, 0.0);
        loop {
            let f = p - K * x;
            if f.abs() <= G + 1e-12 {
                return x; // stuck for good: the load is constant
            }
            let xe = (p - f.signum() * G) / K;
            if t <= t0 + half {
                return xe + (x - xe) * (OMEGA * (t - t0)).cos();
            }
            x = 2.0 * xe - x;
            t0 += half;
        }
    }

    /// The integrator of the oscillator.
    ///
    /// # Errors
    /// ε ≤ 0 or settings the integrator refuses.
    pub fn integrator(
        p: f64,
        eps: f64,
        scheme: Scheme,
        dt: f64,
        t_end: f64,
    ) -> Result<Integrator, SceneError> {
        let scalar = |v: f64| {
            let mut coo = CooMatrix::new(1, 1);
            coo.push(0, 0, v);
            CsrMatrix::from(&coo)
        };
        let dynamics = Dynamics {
            stiffness: scalar(K),
            consistent_mass: scalar(1.0),
            lumped_mass: vec![1.0],
            constant_load: vec![0.0],
            stencils: true,
            fill_order: Default::default(),
        };
        let node = ContactNode {
            node: 0,
            dofs: [Some(0), None],
            weight: 1.0,
            tangent: [1.0, 0.0],
            s: 0.0,
            bound: G,
        };
        let surface = ContactSurface::from_nodes("mass", vec![node], eps)?;
        let loads = vec![Load {
            vector: vec![p],
            history: History::Step,
        }];
        Ok(Integrator::new(
            dynamics,
            Some(surface),
            loads,
            Settings::new(scheme, dt, t_end),
        )?)
    }

    /// (largest |x − x_exact| over [0, 1], x(1)).
    ///
    /// # Errors
    /// A refused setting or a failed step.
    pub fn max_error(p: f64, eps: f64, scheme: Scheme, dt: f64) -> Result<(f64, f64), SceneError> {
        let mut i = integrator(p, eps, scheme, dt, 1.0)?;
        let mut err: f64 = 0.0;
        while !i.done() {
            i.step()?;
            err = err.max((i.displacement()[0] - closed_form(p, i.time())).abs());
        }
        Ok((err, i.displacement()[0]))
    }
}

/// The structured slab [0, 8] × [0, 1] with nx × ny Q1 or Q2 cells and the
/// groups of cases/meshes/README.md (`stickslip_fem::testing::rectangle`,
/// its edges renamed: contact below, load on the right, support on top),
/// its nodes numbered row by row (the step bench's ladder; K's node rows
/// then share stencils).
pub fn structured_slab(nx: usize, ny: usize, q2: bool) -> Mesh {
    let kind = if q2 { CellKind::Quad9 } else { CellKind::Quad4 };
    let mut mesh = stickslip_fem::testing::rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
    for g in &mut mesh.groups {
        let (name, tag) = match g.name.as_str() {
            "bottom" => ("contact", 1),
            "right" => ("load", 2),
            "top" => ("support", 3),
            "left" => ("left", 4),
            _ => ("body", 10),
        };
        (g.name, g.tag) = (name.into(), tag);
    }
    mesh
}
