//! Builds the paper's slab (BENCHMARK.md) from the committed meshes.

#![allow(dead_code)]

use std::path::PathBuf;

use stickslip_contact::ContactSurface;
use stickslip_fem::{traction_load, Dirichlet, Hypothesis, Material, Model, Traction};
use stickslip_mesh::Mesh;
use stickslip_time::{Dynamics, History, Integrator, Load, Settings};

pub fn mesh_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/meshes")
        .join(name)
}

#[derive(Debug)]
pub struct Slab {
    pub mesh: Mesh,
    pub model: Model,
    pub contact: Option<ContactSurface>,
    pub loads: Vec<Load>,
}

/// The slab of BENCHMARK.md: top rollers, left end held in x, pressure
/// `pressure` on the bottom (Γ_C, friction μ with regularization ε), end
/// traction t_x = `end_load`·θ(t). `mu = None` means no contact surface.
pub fn slab(
    mesh_file: &str,
    nu: f64,
    pressure: f64,
    mu: Option<f64>,
    eps: f64,
    end_load: f64,
    theta: History,
) -> Slab {
    let mesh = Mesh::from_file(mesh_path(mesh_file)).expect("committed mesh reads");
    let material = Material::new(1000.0, nu, 1.0, Hypothesis::PlaneStrain).unwrap();
    let conditions = vec![
        Dirichlet {
            group: "support".into(),
            component: 1,
            value: 0.0,
        },
        Dirichlet {
            group: "left".into(),
            component: 0,
            value: 0.0,
        },
    ];
    let model = Model::new(&mesh, &material, &conditions).unwrap();
    let n_full = 2 * mesh.nodes.len();
    let restrict = |full: &[f64]| {
        let mut free = vec![0.0; model.dofs.n_free()];
        model.dofs.restrict(full, &mut free);
        free
    };
    let mut loads = Vec::new();
    if pressure != 0.0 {
        let mut full = vec![0.0; n_full];
        traction_load(&mesh, "contact", Traction::Pressure(pressure), &mut full).unwrap();
        loads.push(Load {
            vector: restrict(&full),
            history: History::Constant,
        });
    }
    if end_load != 0.0 {
        let mut full = vec![0.0; n_full];
        traction_load(&mesh, "load", Traction::Vector([end_load, 0.0]), &mut full).unwrap();
        loads.push(Load {
            vector: restrict(&full),
            history: theta,
        });
    }
    let contact = mu.map(|mu| {
        ContactSurface::from_group(&mesh, &model.dofs, "contact", pressure, mu, eps).unwrap()
    });
    Slab {
        mesh,
        model,
        contact,
        loads,
    }
}

impl Slab {
    pub fn integrator(&self, settings: Settings) -> Integrator {
        Integrator::new(
            Dynamics::from_model(&self.model),
            self.contact.clone(),
            self.loads.clone(),
            settings,
        )
        .expect("valid settings")
    }

    /// Mesh node nearest to (x, y).
    pub fn node_at(&self, x: f64, y: f64) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (i, p) in self.mesh.nodes.iter().enumerate() {
            let d = (p[0] - x).powi(2) + (p[1] - y).powi(2);
            if d < best.0 {
                best = (d, i);
            }
        }
        assert!(best.0 < 1e-12, "no node at ({x}, {y})");
        best.1
    }

    /// Index of mesh node `node` among the contact surface's nodes.
    pub fn contact_index(&self, node: usize) -> usize {
        self.contact
            .as_ref()
            .unwrap()
            .nodes
            .iter()
            .position(|n| n.node == node)
            .expect("a contact node")
    }

    /// u_x of mesh node `node` from a free displacement vector.
    pub fn ux(&self, r: &[f64], node: usize) -> f64 {
        self.model.dofs.free(node, 0).map_or(0.0, |d| r[d])
    }
}

/// The paper's slab with its friction (BENCHMARK.md).
pub fn paper_slab(mesh_file: &str, eps: f64, theta: History) -> Slab {
    slab(mesh_file, 0.3, 300.0, Some(0.3), eps, -150.0, theta)
}
