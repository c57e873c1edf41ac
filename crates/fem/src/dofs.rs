//! Degrees of freedom and Dirichlet conditions.
//!
//! Full vectors have length `2·n_nodes`, interleaved (`2·node + component`).
//! Dirichlet conditions fix one component on every node of a named group
//! (a roller fixes one component, a clamp both) to a prescribed value; the
//! fixed DOFs are eliminated and the rest numbered node by node (x before
//! y), which keeps each node's DOFs adjacent (the assembly exploits it).
//! Bandwidth is left to the Cholesky's fill-reducing ordering (AMD, or
//! from 500 free DOFs a nested dissection of the cells: `ordering.rs`).
//!
//! The node order ([`NodeOrder`]) is not the file's: where the nodes form
//! a structured grid they are taken row by row, as a generator that knows
//! the grid numbers them ([`NodeOrder::Grid`]), elsewhere by reverse
//! Cuthill–McKee ([`NodeOrder::Bandwidth`]). Gmsh numbers a transfinite
//! slab's boundary nodes first, its interior column by column and a Q2
//! mesh's mid-edge and centre nodes cell by cell, so that node rows of K
//! do not repeat at fixed column offsets, which is what the explicit
//! step's fastest products need (`stickslip-linalg`'s stencil types): in
//! the file's order the explicit step is slower at every size, several
//! times slower on large slabs. Gmsh's unstructured quad meshes
//! come with a node's neighbours far apart in the numbering, so that K·x
//! gathers x from all over memory; reverse Cuthill–McKee keeps them near.
//! The factors do not depend on this order where they are ordered by
//! nested dissection (`ordering.rs`). The measurements are in
//! docs/performance.md.

use stickslip_mesh::Mesh;

use crate::error::FemError;
use crate::pattern::{shared_adjacency, Adjacency, SharedAdjacency};

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

/// Environment variable that keeps the mesh file's node order: `mesh`
/// (any other value, or none: [`NodeOrder::Grid`] or
/// [`NodeOrder::Bandwidth`]).
pub const ORDER_ENV: &str = "STICKSLIP_DOF_ORDER";

/// The order in which nodes receive their free DOF numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeOrder {
    /// The mesh file's node order.
    Mesh,
    /// Row by row of a structured grid: ascending y rows, ascending x
    /// within a row (coordinates equal to 1e-8 of the mesh's extent count
    /// as one row or column). Only where every (row, column) of the grid
    /// holds exactly one node.
    ///
    /// A row's nodes go in column order, also on Q2 meshes: taking a Q2
    /// row's even columns before its odd ones would spare the product
    /// some multiply-adds by zero, but the product is not bound by them,
    /// and the split row doubles the lines of x it reads
    /// (docs/performance.md).
    Grid,
    /// Reverse Cuthill–McKee on the node adjacency (each connected part
    /// from a pseudo-peripheral node of least degree, neighbours by
    /// ascending degree): a band, so that a row's columns sit near it.
    Bandwidth,
}

impl NodeOrder {
    /// The code stored in results files: 0 mesh, 1 grid, 2 bandwidth.
    pub fn code(self) -> u8 {
        match self {
            NodeOrder::Mesh => 0,
            NodeOrder::Grid => 1,
            NodeOrder::Bandwidth => 2,
        }
    }

    /// The order of `code` ([`NodeOrder::code`]).
    pub fn from_code(code: u8) -> Option<NodeOrder> {
        match code {
            0 => Some(NodeOrder::Mesh),
            1 => Some(NodeOrder::Grid),
            2 => Some(NodeOrder::Bandwidth),
            _ => None,
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
    rigid_modes: Vec<RigidMode>,
    order: NodeOrder,
}

/// A rigid motion the supports leave free, as a vector on the free DOFs: a
/// unit translation, or a unit rotation (one radian, small) about a point,
/// over the nodes of one connected part. K annihilates it; the work of a
/// load along it is the load's net force in that direction, or its moment
/// about that point.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidMode {
    /// "translation in x", "rotation about (x, y)", ... as
    /// [`DofMap::free_rigid_motions`] names it.
    pub label: String,
    /// What the motion is, for those who combine modes and name the sum
    /// (`None` for a sum of several parts' motions, which is no one
    /// motion).
    pub motion: Option<RigidMotion>,
    /// The label's ending that names the part of the mesh it moves (" of
    /// the separate part of the mesh containing node …"; empty where the
    /// mesh is one part).
    pub whose: String,
    /// The motion on the free DOFs (zero off its part).
    pub vector: Vec<f64>,
}

/// A [`RigidMode`]'s motion: a unit translation along a direction, or a
/// unit rotation about a centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RigidMotion {
    /// Along this unit vector.
    Translation([f64; 2]),
    /// About this point.
    Rotation([f64; 2]),
}

impl DofMap {
    /// Applies `conditions` to `mesh`.
    ///
    /// # Errors
    /// Unknown group (the error lists the mesh's groups), a component other
    /// than 0/1, a non-finite value, or one DOF given two different values.
    pub fn new(mesh: &Mesh, conditions: &[Dirichlet]) -> Result<DofMap, FemError> {
        DofMap::with_adjacency(mesh, conditions, &SharedAdjacency::new())
    }

    /// [`DofMap::new`], the bandwidth order taking the mesh's node
    /// adjacency from `adjacency` (built there if it is not yet).
    pub(crate) fn with_adjacency(
        mesh: &Mesh,
        conditions: &[Dirichlet],
        adjacency: &SharedAdjacency,
    ) -> Result<DofMap, FemError> {
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
        let fixed: Vec<bool> = source.iter().map(|&s| s != usize::MAX).collect();
        let (order, nodes) = if std::env::var(ORDER_ENV).ok().as_deref() == Some("mesh") {
            (NodeOrder::Mesh, (0..n_nodes).collect())
        } else if let Some(nodes) = grid_order(&mesh.nodes) {
            (NodeOrder::Grid, nodes)
        } else {
            (
                NodeOrder::Bandwidth,
                bandwidth_order(shared_adjacency(mesh, adjacency)),
            )
        };
        let (free_index, free_to_full) = number(&fixed, &nodes);
        let any_nonzero_prescribed = prescribed.iter().any(|&v| v != 0.0);
        let (free_rigid_motions, rigid_modes) = rigid_motions_left_free(mesh, &free_index);
        Ok(DofMap {
            n_nodes,
            free_index,
            prescribed,
            free_to_full,
            any_nonzero_prescribed,
            free_rigid_motions,
            rigid_modes,
            order,
        })
    }

    /// The node order this map numbered by ([`NodeOrder`]).
    pub fn node_order(&self) -> NodeOrder {
        self.order
    }

    /// The nodes with a free DOF, in the order of their free DOFs.
    pub fn free_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        let mut last = usize::MAX;
        self.free_to_full.iter().filter_map(move |&dof| {
            let node = dof / 2;
            (node != last).then(|| {
                last = node;
                node
            })
        })
    }

    /// The same conditions numbered in `order` (`None` when `order` is
    /// [`NodeOrder::Grid`] and `mesh`, this map's mesh, is not a grid):
    /// what a restart needs to read a state stored in another numbering.
    pub fn renumbered(&self, mesh: &Mesh, order: NodeOrder) -> Option<DofMap> {
        let nodes = match order {
            NodeOrder::Grid => grid_order(&mesh.nodes)?,
            NodeOrder::Bandwidth => bandwidth_order(&crate::node_adjacency(mesh)),
            NodeOrder::Mesh => (0..self.n_nodes).collect(),
        };
        let fixed: Vec<bool> = self.free_index.iter().map(|&i| i == FIXED).collect();
        let (free_index, free_to_full) = number(&fixed, &nodes);
        Some(DofMap {
            free_index,
            free_to_full,
            order,
            ..self.clone()
        })
    }

    /// A free vector of `other`'s numbering (the same mesh and conditions)
    /// in this map's.
    ///
    /// # Panics
    /// If `x` is not `other.n_free()` long or the maps' free DOFs differ.
    pub fn from_numbering(&self, other: &DofMap, x: &[f64]) -> Vec<f64> {
        assert_eq!(x.len(), other.n_free(), "free vector length");
        assert_eq!(self.n_free(), other.n_free(), "the same free DOFs");
        let mut out = vec![0.0; x.len()];
        for (&v, &dof) in x.iter().zip(&other.free_to_full) {
            out[self.free_index[dof]] = v;
        }
        out
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
    /// The free rigid motions of the parts as vectors (nodes of no cell,
    /// which [`DofMap::free_rigid_motions`] also names, have none): the
    /// null space of K on the free DOFs.
    pub fn rigid_modes(&self) -> &[RigidMode] {
        &self.rigid_modes
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
/// Free numbers for the DOFs not `fixed`, node by node in `nodes` order,
/// x before y: (full → free, free → full).
fn number(fixed: &[bool], nodes: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut free_index = vec![FIXED; fixed.len()];
    let mut free_to_full = Vec::with_capacity(fixed.len());
    for &node in nodes {
        for dof in [2 * node, 2 * node + 1] {
            if !fixed[dof] {
                free_index[dof] = free_to_full.len();
                free_to_full.push(dof);
            }
        }
    }
    (free_index, free_to_full)
}

/// The values of `v` in ascending clusters: cluster of each entry and the
/// number of clusters. Sorted neighbours within `tol` share a cluster.
fn clusters(v: &[f64], tol: f64) -> (Vec<usize>, usize) {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut cluster = vec![0; v.len()];
    let mut k = 0;
    for w in 1..idx.len() {
        if v[idx[w]] - v[idx[w - 1]] > tol {
            k += 1;
        }
        cluster[idx[w]] = k;
    }
    (cluster, if v.is_empty() { 0 } else { k + 1 })
}

/// The nodes row by row (ascending y, then x) when they form a complete
/// structured grid: their x values fall into nx columns and their y values
/// into ny rows (equal to 1e-8 of the extent: Gmsh's transfinite nodes sit
/// about 1e-11 off their grid lines on an 8 × 1 slab) with nx · ny nodes,
/// one at each (row, column). `None` otherwise.
fn grid_order(nodes: &[[f64; 2]]) -> Option<Vec<usize>> {
    let n = nodes.len();
    if n < 4 {
        return None;
    }
    let tol = |k: usize| {
        let (lo, hi) = nodes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[k]), h.max(p[k]))
            });
        1e-8 * (hi - lo)
    };
    let tol = [tol(0), tol(1)];
    // A node that no other node is within tol of in x (or y) is its
    // column's (row's) only node: no grid. One pass, where the sorts below
    // are the DOF map's largest part on the unstructured meshes that end
    // here.
    let probe = nodes[n / 2];
    for k in 0..2 {
        if !nodes
            .iter()
            .enumerate()
            .any(|(i, p)| i != n / 2 && (p[k] - probe[k]).abs() <= tol[k])
        {
            return None;
        }
    }
    let axis = |k: usize| -> (Vec<usize>, usize) {
        let v: Vec<f64> = nodes.iter().map(|p| p[k]).collect();
        clusters(&v, tol[k])
    };
    let (col, nx) = axis(0);
    let (row, ny) = axis(1);
    if nx < 2 || ny < 2 || nx.checked_mul(ny)? != n {
        return None;
    }
    let mut at = vec![usize::MAX; n];
    for i in 0..n {
        let slot = &mut at[row[i] * nx + col[i]];
        if *slot != usize::MAX {
            return None;
        }
        *slot = i;
    }
    Some(at)
}

/// Reverse Cuthill–McKee ([`NodeOrder::Bandwidth`]): per connected part,
/// from its node of least degree (the lowest index among equals) a
/// breadth-first search whose last node starts the search that counts
/// (a pseudo-peripheral start), neighbours visited by ascending degree
/// (stable: then by index), the part's order reversed.
fn bandwidth_order((offsets, neighbours): &Adjacency) -> Vec<usize> {
    let n = offsets.len() - 1;
    let degree = |v: usize| offsets[v + 1] - offsets[v];
    let bfs = |start: usize, seen: &mut [bool], out: &mut Vec<usize>| {
        let first = out.len();
        seen[start] = true;
        out.push(start);
        let mut head = first;
        let mut next = Vec::new();
        while head < out.len() {
            let v = out[head];
            head += 1;
            next.clear();
            next.extend(
                neighbours[offsets[v]..offsets[v + 1]]
                    .iter()
                    .copied()
                    .filter(|&q| !seen[q]),
            );
            next.sort_by_key(|&q| degree(q));
            for &q in &next {
                seen[q] = true;
                out.push(q);
            }
        }
    };
    let mut by_degree: Vec<usize> = (0..n).collect();
    by_degree.sort_by_key(|&v| degree(v));
    let (mut seen, mut probe_seen) = (vec![false; n], vec![false; n]);
    let (mut order, mut probe) = (Vec::with_capacity(n), Vec::new());
    for &s in &by_degree {
        if seen[s] {
            continue;
        }
        probe.clear();
        bfs(s, &mut probe_seen, &mut probe);
        let start = *probe.last().expect("the start itself");
        let first = order.len();
        bfs(start, &mut seen, &mut order);
        order[first..].reverse();
    }
    order
}

fn rigid_motions_left_free(mesh: &Mesh, free_index: &[usize]) -> (Vec<String>, Vec<RigidMode>) {
    let n_nodes = mesh.nodes.len();
    let part = connected_parts(mesh);
    let n_parts = part
        .iter()
        .filter(|&&p| p != usize::MAX)
        .max()
        .map_or(0, |&p| p + 1);
    let mut motions = Vec::new();
    let mut modes = Vec::new();
    let n_free = free_index.iter().filter(|&&f| f != FIXED).count();
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
        // The ending that names part k in its motions' labels.
        let whose = if n_parts > 1 {
            let v = first_node[k];
            let p = mesh.nodes[v];
            format!(
                " of the separate part of the mesh containing node {v} at ({}, {})",
                p[0], p[1]
            )
        } else {
            String::new()
        };
        let b = bbox[k];
        let (cx, cy) = (0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]));
        let scale = (b[2] - b[0]).max(b[3] - b[1]).max(f64::MIN_POSITIVE);
        let (values, vectors) = symmetric_eigen3(gram[k]);
        let largest = values.iter().fold(0.0f64, |m, &v| m.max(v));
        let null: Vec<usize> = (0..3)
            .filter(|&i| largest == 0.0 || values[i] <= 1e-12 * largest)
            .collect();
        let mut free = Vec::new();
        // Each free motion, beside its label.
        let mut shapes: Vec<RigidMotion> = Vec::new();
        if !any[k][0] {
            free.push("translation in x".to_string());
            shapes.push(RigidMotion::Translation([1.0, 0.0]));
        }
        if !any[k][1] {
            free.push("translation in y".to_string());
            shapes.push(RigidMotion::Translation([0.0, 1.0]));
        }
        if null.len() > free.len() {
            // The null vector (a, b, c) with the largest c is a rotation
            // about (−b/c, a/c) in the centred, scaled coordinates; where a
            // translation is free too the centre's coordinate across it is
            // as good as any (the difference is that translation).
            let i = null
                .iter()
                .copied()
                .max_by(|&p, &q| vectors[2][p].abs().total_cmp(&vectors[2][q].abs()))
                .expect("a null vector");
            let (a, bb, c) = (vectors[0][i], vectors[1][i], vectors[2][i]);
            let (mut px, mut py) = (cx - bb / c * scale, cy + a / c * scale);
            if !any[k][0] {
                py = cy;
            }
            if !any[k][1] {
                px = cx;
            }
            if free.is_empty() {
                free.push(format!("rotation about ({px:.6}, {py:.6})"));
            } else {
                free.push("rotation".to_string());
            }
            shapes.push(RigidMotion::Rotation([px, py]));
        }
        for (label, shape) in free.iter().zip(&shapes) {
            let mut vector = vec![0.0; n_free];
            for v in (0..n_nodes).filter(|&v| part[v] == k) {
                let [x, y] = mesh.nodes[v];
                let u = match *shape {
                    RigidMotion::Rotation([px, py]) => [-(y - py), x - px],
                    RigidMotion::Translation(t) => t,
                };
                for c in 0..2 {
                    if free_index[2 * v + c] != FIXED {
                        vector[free_index[2 * v + c]] = u[c];
                    }
                }
            }
            let label = match shape {
                RigidMotion::Rotation([px, py]) if label == "rotation" => {
                    format!("rotation about ({px:.6}, {py:.6})")
                }
                _ => label.clone(),
            };
            let motion = Some(*shape);
            modes.push(RigidMode {
                label: format!("{label}{whose}"),
                motion,
                whose: whose.clone(),
                vector,
            });
        }
        for m in &mut free {
            m.push_str(&whose);
        }
        motions.extend(free);
    }
    (motions, modes)
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
