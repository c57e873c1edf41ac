//! The static solve K r = R (the paper's initial state, METHOD.md §4: the
//! frictionless equilibrium under the loads present at t = 0) and stress
//! recovery at Gauss points and at nodes.

use stickslip_mesh::Mesh;

use crate::element::{full_rule, strain_at, stress_from_strain, MAX_NODES};
use crate::error::FemError;
use crate::material::Material;
use crate::model::Model;
use crate::quadrature::square_rule;
use crate::reference::cell_nodes;
use stickslip_linalg::{SolverError, SparseCholesky};

/// Solves `K u_f = load_free + dirichlet_load` and returns the FULL
/// displacement (interleaved, prescribed values filled in).
///
/// # Errors
/// [`FemError::RigidBodyMotion`] when the supports leave a rigid motion free
/// (named, checked before factorizing) or K is otherwise singular;
/// [`FemError::Solver`] for other solver failures.
///
/// # Panics
/// If `load_free.len() != model.dofs.n_free()`.
pub fn static_solve(model: &Model, load_free: &[f64]) -> Result<Vec<f64>, FemError> {
    let dofs = &model.dofs;
    assert_eq!(load_free.len(), dofs.n_free(), "load_free length");
    let free_motions = dofs.free_rigid_motions();
    if !free_motions.is_empty() {
        return Err(FemError::RigidBodyMotion {
            motions: free_motions.join(", "),
        });
    }
    let mut u: Vec<f64> = load_free
        .iter()
        .zip(&model.dirichlet_load)
        .map(|(a, b)| a + b)
        .collect();
    if dofs.n_free() > 0 {
        let mut chol = SparseCholesky::analyze(&model.stiffness, &model.fill_order)
            .map_err(|e| FemError::Solver(e.to_string()))?;
        chol.factorize(&model.stiffness).map_err(|e| match e {
            SolverError::NotPositiveDefinite { .. } => FemError::RigidBodyMotion {
                motions: "the stiffness matrix is singular although the supports hold every rigid motion of each part of the mesh: a mechanism (cells joined only at a corner node) or a degenerate cell".to_string(),
            },
            other => FemError::Solver(other.to_string()),
        })?;
        chol.solve_in_place(&mut u);
    }
    let mut full = vec![0.0; dofs.n_full()];
    dofs.expand(&u, &mut full);
    Ok(full)
}

/// Stress at one Gauss point of one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussPointStress {
    /// Cell index.
    pub cell: usize,
    /// Physical position of the point.
    pub position: [f64; 2],
    /// (σ_xx, σ_yy, σ_xy).
    pub stress: [f64; 3],
}

/// Stresses at the full-rule Gauss points (2×2 Q1, 3×3 Q2) of every cell,
/// cell by cell, ξ fastest.
///
/// # Panics
/// If `u_full` is not `2·n_nodes` long.
pub fn gauss_point_stresses(
    mesh: &Mesh,
    material: &Material,
    u_full: &[f64],
) -> Vec<GaussPointStress> {
    assert_eq!(u_full.len(), 2 * mesh.nodes.len(), "u_full length");
    let rule = square_rule(full_rule(mesh.kind));
    let d = material.elasticity();
    let n = mesh.kind.nodes_per_cell();
    let mut out = Vec::with_capacity(mesh.n_cells() * rule.len());
    let (mut coords, mut ue) = ([[0.0; 2]; MAX_NODES], [0.0; 2 * MAX_NODES]);
    for c in 0..mesh.n_cells() {
        gather(mesh, c, u_full, &mut coords, &mut ue);
        for &(xi, _) in &rule {
            let e = strain_at(mesh.kind, &coords[..n], &ue[..2 * n], xi).unwrap_or([f64::NAN; 3]);
            out.push(GaussPointStress {
                cell: c,
                position: crate::geometry::map_point(mesh.kind, &coords[..n], xi),
                stress: stress_from_strain(&d, e),
            });
        }
    }
    out
}

/// Nodal stresses (σ_xx, σ_yy, σ_xy): each cell's stress evaluated at its
/// nodes, averaged over the cells sharing the node (exact for fields whose
/// stress is continuous and within the element space).
///
/// # Panics
/// If `u_full` is not `2·n_nodes` long.
pub fn nodal_stresses(mesh: &Mesh, material: &Material, u_full: &[f64]) -> Vec<[f64; 3]> {
    assert_eq!(u_full.len(), 2 * mesh.nodes.len(), "u_full length");
    let d = material.elasticity();
    let n = mesh.kind.nodes_per_cell();
    let mut sum = vec![[0.0; 3]; mesh.nodes.len()];
    let mut count = vec![0u32; mesh.nodes.len()];
    let (mut coords, mut ue) = ([[0.0; 2]; MAX_NODES], [0.0; 2 * MAX_NODES]);
    for c in 0..mesh.n_cells() {
        gather(mesh, c, u_full, &mut coords, &mut ue);
        for (a, &xi) in cell_nodes(mesh.kind).iter().enumerate() {
            let e = strain_at(mesh.kind, &coords[..n], &ue[..2 * n], xi).unwrap_or([f64::NAN; 3]);
            let s = stress_from_strain(&d, e);
            let v = mesh.cell(c)[a];
            for k in 0..3 {
                sum[v][k] += s[k];
            }
            count[v] += 1;
        }
    }
    for (s, &k) in sum.iter_mut().zip(&count) {
        if k > 0 {
            for v in s.iter_mut() {
                *v /= k as f64;
            }
        }
    }
    sum
}

/// The stress at `node` as [`nodal_stresses`] gives it (the average over
/// its cells of each cell's stress there, the same operations in the same
/// order: the same bits), from `cells`, the cells holding `node` in
/// ascending order, and `u(v)`, the displacement of each of their nodes.
/// For a history at one node without the whole mesh's displacement.
///
/// # Panics
/// If `node` is not a node of every cell of `cells`.
pub fn stress_at_node(
    mesh: &Mesh,
    material: &Material,
    node: usize,
    cells: &[usize],
    u: impl Fn(usize) -> [f64; 2],
) -> [f64; 3] {
    let d = material.elasticity();
    let n = mesh.kind.nodes_per_cell();
    let (mut coords, mut ue) = ([[0.0; 2]; MAX_NODES], [0.0; 2 * MAX_NODES]);
    let mut sum = [0.0; 3];
    for &c in cells {
        let cell = mesh.cell(c);
        for (a, &v) in cell.iter().enumerate() {
            coords[a] = mesh.nodes[v];
            let [x, y] = u(v);
            ue[2 * a] = x;
            ue[2 * a + 1] = y;
        }
        let a = cell
            .iter()
            .position(|&v| v == node)
            .expect("node of the cell");
        let xi = cell_nodes(mesh.kind)[a];
        let e = strain_at(mesh.kind, &coords[..n], &ue[..2 * n], xi).unwrap_or([f64::NAN; 3]);
        let s = stress_from_strain(&d, e);
        for k in 0..3 {
            sum[k] += s[k];
        }
    }
    if !cells.is_empty() {
        for v in sum.iter_mut() {
            *v /= cells.len() as f64;
        }
    }
    sum
}

/// The von Mises stress of an in-plane stress state [σxx, σyy, σxy]: with
/// σzz = ν(σxx + σyy) in plane strain, 0 in plane stress.
pub fn von_mises(material: &Material, s: [f64; 3]) -> f64 {
    let szz = match material.hypothesis {
        crate::Hypothesis::PlaneStrain => material.poisson_ratio * (s[0] + s[1]),
        crate::Hypothesis::PlaneStress => 0.0,
    };
    let [sxx, syy, sxy] = s;
    (sxx * sxx + syy * syy + szz * szz - sxx * syy - syy * szz - szz * sxx + 3.0 * sxy * sxy)
        .max(0.0)
        .sqrt()
}

fn gather(
    mesh: &Mesh,
    c: usize,
    u_full: &[f64],
    coords: &mut [[f64; 2]; MAX_NODES],
    ue: &mut [f64; 2 * MAX_NODES],
) {
    for (a, &v) in mesh.cell(c).iter().enumerate() {
        coords[a] = mesh.nodes[v];
        ue[2 * a] = u_full[2 * v];
        ue[2 * a + 1] = u_full[2 * v + 1];
    }
}
