//! Element classes for a matrix-free K·x (the explicit step's product on
//! structured meshes, `stickslip-time`'s kernels).
//!
//! On a structured mesh every cell is a translate of every other up to the
//! rounding of its node coordinates (about ulp(max |x|)), which is why their
//! element matrices differ in the last bits and an exact-bits dictionary of
//! K's blocks fails for Q2. Cells are grouped into classes by geometry: two
//! cells are alike when their node coordinates relative to their first node
//! agree within [`CLASS_ULPS`]·ε·max |x| (the level of the coordinates' own
//! rounding), and one element stiffness per class is computed, from the
//! class's first cell with the routine the assembly uses
//! ([`CellBasis::stiffness`]). A K·x from them differs from the assembled
//! K's in the last bits (another summation order, the class matrices): the
//! tests bound it row-wise by 1e-12 · max_i Σ_j |K_ij x_j|.
//!
//! The product is node-centric ([`ElementClasses`]: each free row is summed
//! by the node that owns it over its cells, so rows are independent and
//! their values do not depend on how rows are split among threads). The
//! data: per cell its class and its 2n free DOFs, per node its cells with
//! the node's local index. Where classes do not pay (an unstructured mesh:
//! nearly one class per cell) [`ElementClasses::new`] returns `None` and the
//! assembled K stays the operator.

use std::collections::HashMap;

use stickslip_mesh::Mesh;

use crate::assembly::node_entries;
use crate::dofs::DofMap;
use crate::element::CellBasis;
use crate::material::Material;

/// Cells are alike when their relative node coordinates agree within
/// `CLASS_ULPS · ε · max |x|`: a few ulps of the mesh's largest coordinate,
/// the rounding its generator left in the coordinates.
pub const CLASS_ULPS: f64 = 8.0;

/// Most classes [`ElementClasses::new`] accepts (and at most one per
/// [`MIN_CELLS_PER_CLASS`] cells): their matrices must stay in cache.
pub const MAX_CLASSES: usize = 64;

/// See [`MAX_CLASSES`].
pub const MIN_CELLS_PER_CLASS: usize = 16;

/// Fewest free DOFs for which [`ElementClasses::new`] accepts classes: on
/// smaller meshes the assembled K's blocks stay in cache and stream faster
/// than the class products (bench_step, structured Q2 slabs, 2 threads,
/// explicit step assembled vs classes, 2026-11-22: 8,352 DOFs 117 vs 142
/// µs; 62,392 DOFs 0.53 vs 0.53 ms, K 18 MB; 124,624 DOFs 1.88 vs 0.98
/// ms, K 36 MB, more than the 32 MB L3).
pub const MIN_FREE_DOFS: usize = 100_000;

/// Marks a fixed DOF in [`ElementClasses::cell_dofs`].
pub const FIXED_DOF: u32 = u32::MAX;

/// Set in [`ElementClasses::cell_class`] on a cell with a fixed DOF (its
/// gather must read those as 0).
pub const HAS_FIXED: u32 = 1 << 31;

/// Bits of a node's local index in an adjacency entry
/// ([`ElementClasses::node_cells`]: `cell << LOCAL_BITS | local`).
pub const LOCAL_BITS: u32 = 4;

/// The element classes of a mesh and the node-centric data of K·x (see
/// the module documentation).
#[derive(Clone, Debug)]
pub struct ElementClasses {
    nodes_per_cell: usize,
    n_free: usize,
    classes: usize,
    matrices: Vec<[f64; 2]>,
    cell_class: Vec<u32>,
    cell_dofs: Vec<u32>,
    group_rows: Vec<u32>,
    group_mask: Vec<u8>,
    group_cells: Vec<u32>,
    node_cells: Vec<u32>,
}

impl ElementClasses {
    /// The classes of `mesh`'s cells for `material` and the free DOFs of
    /// `dofs`, or `None` when they do not pay: fewer than
    /// [`MIN_FREE_DOFS`] free DOFs, Q1 cells (the assembled K's
    /// blocks then form a small dictionary of exact bits, whose product
    /// needs 9 blocks per node against 4 cells of 8 columns here: measured
    /// 2× faster, `stickslip-time`'s kernels.rs), more than [`MAX_CLASSES`]
    /// classes or than one per [`MIN_CELLS_PER_CLASS`] cells (an
    /// unstructured mesh), an inverted cell, or indices beyond u32.
    pub fn new(mesh: &Mesh, material: &Material, dofs: &DofMap) -> Option<ElementClasses> {
        if mesh.kind.nodes_per_cell() != 9 || dofs.n_free() < MIN_FREE_DOFS {
            return None;
        }
        let limit = MAX_CLASSES.min(mesh.n_cells() / MIN_CELLS_PER_CLASS);
        ElementClasses::with_limit(mesh, material, dofs, limit)
    }

    /// [`ElementClasses::new`] accepting up to `max_classes` classes, Q1
    /// cells too (tests and the kernel lab).
    pub fn with_limit(
        mesh: &Mesh,
        material: &Material,
        dofs: &DofMap,
        max_classes: usize,
    ) -> Option<ElementClasses> {
        let n = mesh.kind.nodes_per_cell();
        let nd = 2 * n;
        let n_cells = mesh.n_cells();
        let n_free = dofs.n_free();
        if n_cells == 0
            || n_free == 0
            || n_free >= FIXED_DOF as usize
            || n_cells >= (HAS_FIXED >> LOCAL_BITS) as usize
        {
            return None;
        }
        let scale = mesh
            .nodes
            .iter()
            .fold(0.0_f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
        let tol = CLASS_ULPS * f64::EPSILON * scale;
        if !(tol > 0.0 && tol.is_finite()) {
            return None;
        }
        // Candidates by relative coordinates rounded to bins of 1024 tol:
        // alike cells nearly always share a bin (one that straddles a bin
        // edge only costs a class), and membership is checked against the
        // class's first cell to tol.
        let bin = 1024.0 * tol;
        let relative = |c: usize| -> Vec<f64> {
            let cell = mesh.cell(c);
            let o = mesh.nodes[cell[0]];
            cell[1..]
                .iter()
                .flat_map(|&v| [mesh.nodes[v][0] - o[0], mesh.nodes[v][1] - o[1]])
                .collect()
        };
        let mut bins: HashMap<Vec<i64>, Vec<u32>> = HashMap::new();
        let mut firsts: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut cell_class = Vec::with_capacity(n_cells);
        for c in 0..n_cells {
            let rel = relative(c);
            let key: Vec<i64> = rel.iter().map(|r| (r / bin).round() as i64).collect();
            let list = bins.entry(key).or_default();
            let found = list.iter().copied().find(|&k| {
                firsts[k as usize]
                    .1
                    .iter()
                    .zip(&rel)
                    .all(|(a, b)| (a - b).abs() <= tol)
            });
            let k = match found {
                Some(k) => k,
                None => {
                    if firsts.len() >= max_classes {
                        return None;
                    }
                    let k = firsts.len() as u32;
                    firsts.push((c, rel));
                    list.push(k);
                    k
                }
            };
            cell_class.push(k);
        }
        // One element matrix per class, stored by local node and column as
        // the node's two rows' pair: matrices[(k·n + a)·nd + j] =
        // [K_e[2a][j], K_e[2a + 1][j]].
        let basis = CellBasis::full(mesh.kind);
        let d = material.elasticity();
        let mut ke = vec![0.0; nd * nd];
        let mut matrices = Vec::with_capacity(firsts.len() * n * nd);
        for (c, _) in &firsts {
            let coords: Vec<[f64; 2]> = mesh.cell(*c).iter().map(|&v| mesh.nodes[v]).collect();
            basis.stiffness(&coords, &d, &mut ke).ok()?;
            for a in 0..n {
                for j in 0..nd {
                    matrices.push([ke[2 * a * nd + j], ke[(2 * a + 1) * nd + j]]);
                }
            }
        }
        let mut cell_dofs = Vec::with_capacity(n_cells * nd);
        for (c, class) in cell_class.iter_mut().enumerate() {
            for &v in mesh.cell(c) {
                for comp in 0..2 {
                    match dofs.free(v, comp) {
                        Some(f) => cell_dofs.push(f as u32),
                        None => {
                            cell_dofs.push(FIXED_DOF);
                            *class |= HAS_FIXED;
                        }
                    }
                }
            }
        }
        // Node → (cell, local index), cells ascending.
        let (offsets, entries) = node_entries(mesh);
        let adjacency: Vec<u32> = entries
            .iter()
            .map(|&k| ((k / n) as u32) << LOCAL_BITS | (k % n) as u32)
            .collect();
        // Groups: the nodes with a free DOF, in free-DOF order (free DOFs
        // are numbered by node, then component).
        let mut group_rows = Vec::new();
        let mut group_mask = Vec::new();
        let mut group_cells = vec![0u32];
        let mut node_cells = Vec::with_capacity(adjacency.len());
        for v in dofs.free_nodes() {
            let mask = dofs.free(v, 0).is_some() as u8 | (dofs.free(v, 1).is_some() as u8) << 1;
            let first = dofs.free(v, 0).or(dofs.free(v, 1)).expect("a free DOF");
            group_rows.push(first as u32);
            group_mask.push(mask);
            node_cells.extend_from_slice(&adjacency[offsets[v]..offsets[v + 1]]);
            group_cells.push(node_cells.len() as u32);
        }
        group_rows.push(n_free as u32);
        Some(ElementClasses {
            nodes_per_cell: n,
            n_free,
            classes: firsts.len(),
            matrices,
            cell_class,
            cell_dofs,
            group_rows,
            group_mask,
            group_cells,
            node_cells,
        })
    }

    /// Nodes per cell (n; a cell has 2n DOFs).
    #[inline]
    pub fn nodes_per_cell(&self) -> usize {
        self.nodes_per_cell
    }
    /// Number of free DOFs (rows of K).
    #[inline]
    pub fn n_free(&self) -> usize {
        self.n_free
    }
    /// Number of classes.
    #[inline]
    pub fn classes(&self) -> usize {
        self.classes
    }
    /// The class matrices by class, local node and column:
    /// `[(k·n + a)·2n + j]` holds `[K_e[2a][j], K_e[2a + 1][j]]`.
    #[inline]
    pub fn matrices(&self) -> &[[f64; 2]] {
        &self.matrices
    }
    /// Each cell's class, with [`HAS_FIXED`] set when a DOF of it is fixed.
    #[inline]
    pub fn cell_class(&self) -> &[u32] {
        &self.cell_class
    }
    /// Each cell's 2n free DOFs (local DOF 2a + i is component i of node
    /// a), [`FIXED_DOF`] for a fixed one.
    #[inline]
    pub fn cell_dofs(&self) -> &[u32] {
        &self.cell_dofs
    }
    /// First free row of each group (a node with a free DOF, in free-DOF
    /// order), then n_free.
    #[inline]
    pub fn group_rows(&self) -> &[u32] {
        &self.group_rows
    }
    /// Each group's free components (bit i: component i).
    #[inline]
    pub fn group_mask(&self) -> &[u8] {
        &self.group_mask
    }
    /// Each group's entries of [`ElementClasses::node_cells`]:
    /// `group_cells[g]..group_cells[g + 1]`.
    #[inline]
    pub fn group_cells(&self) -> &[u32] {
        &self.group_cells
    }
    /// The groups' cells: `cell << LOCAL_BITS | local index of the node`,
    /// cells ascending per group.
    #[inline]
    pub fn node_cells(&self) -> &[u32] {
        &self.node_cells
    }
    /// Bytes a K·x streams from this data (the class matrices counted
    /// once: they stay in cache).
    pub fn bytes(&self) -> usize {
        16 * self.matrices.len()
            + 4 * (self.cell_class.len()
                + self.cell_dofs.len()
                + self.group_rows.len()
                + self.group_cells.len()
                + self.node_cells.len())
            + self.group_mask.len()
    }
}
