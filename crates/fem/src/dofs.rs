//! Degrees of freedom and Dirichlet conditions.
//!
//! Full vectors have length `2·n_nodes`, interleaved (`2·node + component`).
//! Dirichlet conditions fix one component on every node of a named group
//! (a roller fixes one component, a clamp both) to a prescribed value; the
//! fixed DOFs are eliminated and the rest numbered node by node in mesh
//! order (x before y). That numbering keeps each node's DOFs adjacent, which
//! the assembly exploits; bandwidth is left to the Cholesky's fill-reducing
//! ordering (AMD), which does not depend on it.

use stickslip_mesh::Mesh;

use crate::error::FemError;

/// Marks a fixed DOF in the full → free index table.
const FIXED: usize = usize::MAX;

/// One Dirichlet condition: component `component` (0 = x, 1 = y) of every
/// node of group `group` is `value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Dirichlet {
    /// Physical group name (any dimension: points, lines or cells).
    pub group: String,
    /// 0 = x, 1 = y.
    pub component: usize,
    /// Prescribed displacement.
    pub value: f64,
}

impl Dirichlet {
    /// `u_component = value` on `group`.
    pub fn new(group: impl Into<String>, component: usize, value: f64) -> Self {
        Dirichlet {
            group: group.into(),
            component,
            value,
        }
    }
}

/// The map between full (interleaved nodal) and free DOF indices, with the
/// prescribed values of the fixed DOFs.
#[derive(Clone, Debug)]
pub struct DofMap {
    n_nodes: usize,
    free_index: Vec<usize>,
    prescribed: Vec<f64>,
    free_to_full: Vec<usize>,
    any_nonzero_prescribed: bool,
    free_rigid_motions: Vec<String>,
}

impl DofMap {
    /// Applies `conditions` to `mesh`.
    ///
    /// # Errors
    /// Unknown group (the error lists the mesh's groups), a component other
    /// than 0/1, a non-finite value, or one DOF given two different values.
    pub fn new(mesh: &Mesh, conditions: &[Dirichlet]) -> Result<DofMap, FemError> {
        let n_nodes = mesh.nodes.len();
        let mut source: Vec<usize> = vec![usize::MAX; 2 * n_nodes];
        let mut prescribed = vec![0.0; 2 * n_nodes];
        for (k, c) in conditions.iter().enumerate() {
            let group = crate::find_group(mesh, &c.group, "a Dirichlet condition")?;
            if c.component > 1 {
                return Err(FemError::InvalidComponent {
                    group: c.group.clone(),
                    component: c.component,
                });
            }
            if !c.value.is_finite() {
                return Err(FemError::NonFiniteDirichlet {
                    group: c.group.clone(),
                    value: c.value,
                });
            }
            for &node in &group.nodes {
                let dof = 2 * node + c.component;
                if source[dof] != usize::MAX && prescribed[dof] != c.value {
                    let first = &conditions[source[dof]];
                    return Err(FemError::ConflictingDirichlet {
                        node,
                        x: mesh.nodes[node][0],
                        y: mesh.nodes[node][1],
                        comp: if c.component == 0 { "x" } else { "y" },
                        first: first.value,
                        first_group: first.group.clone(),
                        second: c.value,
                        second_group: c.group.clone(),
                    });
                }
                source[dof] = k;
                prescribed[dof] = c.value;
            }
        }
        let mut free_index = vec![FIXED; 2 * n_nodes];
        let mut free_to_full = Vec::with_capacity(2 * n_nodes);
        for dof in 0..2 * n_nodes {
            if source[dof] == usize::MAX {
                free_index[dof] = free_to_full.len();
                free_to_full.push(dof);
            }
        }
        let any_nonzero_prescribed = prescribed.iter().any(|&v| v != 0.0);
        let free_rigid_motions = rigid_motions_left_free(mesh, &free_index);
        Ok(DofMap {
            n_nodes,
            free_index,
            prescribed,
            free_to_full,
            any_nonzero_prescribed,
            free_rigid_motions,
        })
    }

    /// Number of mesh nodes.
    pub fn n_nodes(&self) -> usize {
        self.n_nodes
    }
    /// Number of free DOFs.
    pub fn n_free(&self) -> usize {
        self.free_to_full.len()
    }
    /// Number of full DOFs (2 · nodes).
    pub fn n_full(&self) -> usize {
        2 * self.n_nodes
    }
    /// Free DOF index of (node, component), `None` when fixed.
    #[inline]
    pub fn free(&self, node: usize, component: usize) -> Option<usize> {
        let i = self.free_index[2 * node + component];
        (i != FIXED).then_some(i)
    }
    /// Free index of a full DOF, `None` when fixed.
    #[inline]
    pub fn free_of_full(&self, dof: usize) -> Option<usize> {
        let i = self.free_index[dof];
        (i != FIXED).then_some(i)
    }
    /// The full DOF of a free DOF.
    #[inline]
    pub fn full_of_free(&self, free: usize) -> usize {
        self.free_to_full[free]
    }
    /// Prescribed value of (node, component), `None` when free.
    pub fn prescribed(&self, node: usize, component: usize) -> Option<f64> {
        let dof = 2 * node + component;
        (self.free_index[dof] == FIXED).then_some(self.prescribed[dof])
    }
    /// Whether some prescribed value is non-zero.
    pub fn has_nonzero_prescribed(&self) -> bool {
        self.any_nonzero_prescribed
    }
    /// Rigid-body motions the conditions leave free ("translation in x",
    /// "translation in y", "rotation about (x, y)"); empty when K restricted
    /// to the free DOFs can be positive definite.
    pub fn free_rigid_motions(&self) -> &[String] {
        &self.free_rigid_motions
    }

    /// Gathers the free entries of a full vector.
    ///
    /// # Panics
    /// If the lengths are not `2·n_nodes` and `n_free`.
    pub fn restrict(&self, full: &[f64], free: &mut [f64]) {
        assert_eq!(full.len(), self.n_full(), "full vector length");
        assert_eq!(free.len(), self.n_free(), "free vector length");
        for (f, &dof) in free.iter_mut().zip(&self.free_to_full) {
            *f = full[dof];
        }
    }

    /// Scatters free values into a full vector; fixed entries get their
    /// prescribed values.
    ///
    /// # Panics
    /// If the lengths are not `n_free` and `2·n_nodes`.
    pub fn expand(&self, free: &[f64], full: &mut [f64]) {
        assert_eq!(full.len(), self.n_full(), "full vector length");
        full.copy_from_slice(&self.prescribed);
        self.scatter(free, full);
    }

    /// Scatters free values into a full vector; fixed entries get 0 (for
    /// velocities, accelerations, increments).
    ///
    /// # Panics
    /// If the lengths are not `n_free` and `2·n_nodes`.
    pub fn expand_homogeneous(&self, free: &[f64], full: &mut [f64]) {
        assert_eq!(full.len(), self.n_full(), "full vector length");
        full.fill(0.0);
        self.scatter(free, full);
    }

    fn scatter(&self, free: &[f64], full: &mut [f64]) {
        assert_eq!(free.len(), self.n_free(), "free vector length");
        for (&f, &dof) in free.iter().zip(&self.free_to_full) {
            full[dof] = f;
        }
    }

    /// The full → free table (`usize::MAX` for fixed DOFs), for assembly.
    pub(crate) fn free_index_table(&self) -> &[usize] {
        &self.free_index
    }
    /// The prescribed value of every full DOF (0 for free ones).
    pub(crate) fn prescribed_values(&self) -> &[f64] {
        &self.prescribed
    }
}

/// Which rigid motions u = (a − c·y, b + c·x) of each connected part of the
/// mesh satisfy every homogeneous constraint on that part. Each fixed x-DOF
/// at (x, y) adds the row (1, 0, −y), each fixed y-DOF the row (0, 1, x);
/// the free motions span the null space of the 3×3 Gram matrix of these
/// rows (coordinates centred and scaled per part so the test is independent
/// of units). Parts are the connected components of the cell graph: a part
/// that touches no support is as singular as an unsupported mesh, and the
/// Cholesky cannot be relied on to notice (rounding leaves a tiny positive
/// pivot).
fn rigid_motions_left_free(mesh: &Mesh, free_index: &[usize]) -> Vec<String> {
    let n_nodes = mesh.nodes.len();
    let part = connected_parts(mesh);
    let n_parts = part
        .iter()
        .filter(|&&p| p != usize::MAX)
        .max()
        .map_or(0, |&p| p + 1);
    let mut motions = Vec::new();
    // Nodes in no cell have no stiffness at all.
    for v in 0..n_nodes {
        if part[v] == usize::MAX && (free_index[2 * v] != FIXED || free_index[2 * v + 1] != FIXED) {
            let p = mesh.nodes[v];
            motions.push(format!(
                "node {v} at ({}, {}) belongs to no cell, so nothing holds it",
                p[0], p[1]
            ));
        }
    }
    let mut bbox = vec![
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY
        ];
        n_parts
    ];
    let mut first_node = vec![usize::MAX; n_parts];
    for v in 0..n_nodes {
        if part[v] == usize::MAX {
            continue;
        }
        let (b, p) = (&mut bbox[part[v]], mesh.nodes[v]);
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
        if first_node[part[v]] == usize::MAX {
            first_node[part[v]] = v;
        }
    }
    let mut gram = vec![[[0.0; 3]; 3]; n_parts];
    let mut any = vec![[false; 2]; n_parts];
    for (dof, &f) in free_index.iter().enumerate() {
        let k = part[dof / 2];
        if f != FIXED || k == usize::MAX {
            continue;
        }
        let b = bbox[k];
        let (cx, cy) = (0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]));
        let scale = (b[2] - b[0]).max(b[3] - b[1]).max(f64::MIN_POSITIVE);
        let p = mesh.nodes[dof / 2];
        let (x, y) = ((p[0] - cx) / scale, (p[1] - cy) / scale);
        let row = if dof % 2 == 0 {
            [1.0, 0.0, -y]
        } else {
            [0.0, 1.0, x]
        };
        any[k][dof % 2] = true;
        for i in 0..3 {
            for j in 0..3 {
                gram[k][i][j] += row[i] * row[j];
            }
        }
    }
    for k in 0..n_parts {
        let b = bbox[k];
        let (cx, cy) = (0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]));
        let scale = (b[2] - b[0]).max(b[3] - b[1]).max(f64::MIN_POSITIVE);
        let (values, vectors) = symmetric_eigen3(gram[k]);
        let largest = values.iter().fold(0.0f64, |m, &v| m.max(v));
        let null: Vec<usize> = (0..3)
            .filter(|&i| largest == 0.0 || values[i] <= 1e-12 * largest)
            .collect();
        let mut free = Vec::new();
        if !any[k][0] {
            free.push("translation in x".to_string());
        }
        if !any[k][1] {
            free.push("translation in y".to_string());
        }
        if null.len() > free.len() {
            if free.is_empty() {
                // The null vector (a, b, c) is a rotation about (−b/c, a/c).
                let i = null[0];
                let (a, bb, c) = (vectors[0][i], vectors[1][i], vectors[2][i]);
                let (px, py) = (cx - bb / c * scale, cy + a / c * scale);
                free.push(format!("rotation about ({px:.6}, {py:.6})"));
            } else {
                free.push("rotation".to_string());
            }
        }
        if n_parts > 1 {
            let v = first_node[k];
            let p = mesh.nodes[v];
            let whose = format!(
                " of the separate part of the mesh containing node {v} at ({}, {})",
                p[0], p[1]
            );
            for m in &mut free {
                m.push_str(&whose);
            }
        }
        motions.extend(free);
    }
    motions
}

/// Connected component of each node in the graph where the nodes of a cell
/// are connected (`usize::MAX` for nodes in no cell), numbered in order of
/// their first node.
fn connected_parts(mesh: &Mesh) -> Vec<usize> {
    let n = mesh.nodes.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    let mut in_cell = vec![false; n];
    for c in 0..mesh.n_cells() {
        let cell = mesh.cell(c);
        let r0 = root(&mut parent, cell[0]);
        in_cell[cell[0]] = true;
        for &v in &cell[1..] {
            in_cell[v] = true;
            let r = root(&mut parent, v);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    let mut label = vec![usize::MAX; n];
    let mut part = vec![usize::MAX; n];
    let mut next = 0;
    for v in 0..n {
        if !in_cell[v] {
            continue;
        }
        let r = root(&mut parent, v);
        if label[r] == usize::MAX {
            label[r] = next;
            next += 1;
        }
        part[v] = label[r];
    }
    part
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3×3 matrix by
/// cyclic Jacobi rotations.
fn symmetric_eigen3(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off <= 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A ← Jᵀ A J with J the rotation in the (p, q) plane.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_diagonalises_a_symmetric_matrix() {
        let m = [[4.0, 1.0, -2.0], [1.0, 2.0, 0.5], [-2.0, 0.5, 3.0]];
        let (w, v) = symmetric_eigen3(m);
        for k in 0..3 {
            for i in 0..3 {
                let mv: f64 = (0..3).map(|j| m[i][j] * v[j][k]).sum();
                assert!((mv - w[k] * v[i][k]).abs() < 1e-12);
            }
        }
    }
}
