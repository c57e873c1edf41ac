//! Sparse assembly on free DOFs.
//!
//! The sparsity pattern is built once from the mesh's node adjacency; values
//! are then accumulated in place. Element matrices are computed in parallel
//! (rayon) in fixed-size chunks together with the CSR positions of their
//! entries, and scattered sequentially in element order, so the sums are
//! bitwise identical for any number of threads. Nothing is allocated per
//! element: the chunk buffers are allocated once per assembly.

use nalgebra_sparse::pattern::SparsityPattern;
use rayon::prelude::*;
use stickslip_mesh::Mesh;

use crate::dofs::DofMap;
use crate::element::{hrz_lumped_mass, CellBasis, MAX_DOFS, MAX_NODES};
use crate::error::FemError;
use crate::material::Material;

/// Marks a local entry with no CSR position (its column DOF is fixed).
const NO_POSITION: usize = usize::MAX;

/// Elements per parallel chunk: large enough to amortise rayon's overhead,
/// small enough that the chunk's buffers (≈ 8 KB per Q2 element) stay modest.
const CHUNK: usize = 1024;

/// Cells from which the element kernels run on rayon's pool: below, its
/// threads' start (at the first parallel loop of a run) and their
/// spinning after each job cost more than the cells (the paper's slab
/// has 16).
const PARALLEL_CELLS: usize = 64;

/// Values from which zeroing a value array is shared out between the
/// pool's threads (one block of its chunks).
const PARALLEL_ZEROING: usize = 1 << 16;

/// Node → its places in the connectivity, by counting: node p's entries
/// are `entries[offsets[p]..offsets[p + 1]]`, each an index k into
/// `mesh.cells` (cell k / nodes per cell, local node k % nodes per cell),
/// ascending.
pub(crate) fn node_entries(mesh: &Mesh) -> (Vec<usize>, Vec<usize>) {
    let n_nodes = mesh.nodes.len();
    let mut offsets = vec![0usize; n_nodes + 1];
    for &v in &mesh.cells {
        offsets[v + 1] += 1;
    }
    for i in 0..n_nodes {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut entries = vec![0usize; mesh.cells.len()];
    for (k, &v) in mesh.cells.iter().enumerate() {
        entries[fill[v]] = k;
        fill[v] += 1;
    }
    (offsets, entries)
}

/// Node-to-node adjacency (two nodes are adjacent when they share a cell),
/// as CSR offsets and sorted neighbour lists including the node itself.
pub fn node_adjacency(mesh: &Mesh) -> (Vec<usize>, Vec<usize>) {
    let n_nodes = mesh.nodes.len();
    let npc = mesh.kind.nodes_per_cell();
    let (cell_offsets, entries) = node_entries(mesh);
    let mut offsets = Vec::with_capacity(n_nodes + 1);
    offsets.push(0);
    let mut neighbours = Vec::with_capacity(n_nodes * if npc == 9 { 16 } else { 9 });
    let mut marker = vec![usize::MAX; n_nodes];
    for p in 0..n_nodes {
        let start = neighbours.len();
        for &k in &entries[cell_offsets[p]..cell_offsets[p + 1]] {
            for &q in mesh.cell(k / npc) {
                if marker[q] != p {
                    marker[q] = p;
                    neighbours.push(q);
                }
            }
        }
        neighbours[start..].sort_unstable();
        offsets.push(neighbours.len());
    }
    (offsets, neighbours)
}

/// The sparsity pattern of K (and M) on the free DOFs: free DOF r couples to
/// free DOF c when their nodes share a cell. Columns sorted; both triangles.
pub fn free_dof_pattern(mesh: &Mesh, dofs: &DofMap) -> SparsityPattern {
    let (offsets, neighbours) = node_adjacency(mesh);
    let n_free = dofs.n_free();
    let mut row_offsets = Vec::with_capacity(n_free + 1);
    row_offsets.push(0);
    // Count first so the column array is allocated exactly once.
    let mut nnz = 0;
    for r in 0..n_free {
        let node = dofs.full_of_free(r) / 2;
        for &q in &neighbours[offsets[node]..offsets[node + 1]] {
            nnz += dofs.free(q, 0).is_some() as usize + dofs.free(q, 1).is_some() as usize;
        }
    }
    let mut cols = Vec::with_capacity(nnz);
    for r in 0..n_free {
        let node = dofs.full_of_free(r) / 2;
        // In the mesh's node order free indices grow with (node,
        // component), so walking sorted neighbours yields sorted columns;
        // in another order the row is sorted after.
        let start = cols.len();
        for &q in &neighbours[offsets[node]..offsets[node + 1]] {
            for comp in 0..2 {
                if let Some(c) = dofs.free(q, comp) {
                    cols.push(c);
                }
            }
        }
        if dofs.node_order() != crate::NodeOrder::Mesh {
            cols[start..].sort_unstable();
        }
        row_offsets.push(cols.len());
    }
    SparsityPattern::try_from_offsets_and_indices(n_free, n_free, row_offsets, cols)
        .expect("columns are sorted and in range by construction")
}

/// Per-element scratch of the parallel phase.
#[derive(Clone, Debug)]
struct ElementWork {
    ke: [f64; MAX_DOFS * MAX_DOFS],
    me: [f64; MAX_NODES * MAX_NODES],
    lumped: [f64; MAX_NODES],
    positions: [usize; MAX_DOFS * MAX_DOFS],
    area: f64,
    bad_det: Option<f64>,
}

impl ElementWork {
    fn new() -> Self {
        ElementWork {
            ke: [0.0; MAX_DOFS * MAX_DOFS],
            me: [0.0; MAX_NODES * MAX_NODES],
            lumped: [0.0; MAX_NODES],
            positions: [NO_POSITION; MAX_DOFS * MAX_DOFS],
            area: 0.0,
            bad_det: None,
        }
    }
}

/// Everything assembled in one pass over the cells.
#[derive(Debug)]
pub struct Assembly<'a> {
    /// K values (pattern of [`free_dof_pattern`]), overwritten.
    pub stiffness: &'a mut [f64],
    /// Consistent M values (same pattern), overwritten.
    pub mass: &'a mut [f64],
    /// HRZ lumped mass per node (same for both components), overwritten.
    pub lumped_nodal: &'a mut [f64],
    /// −K_fc u_c on free DOFs, overwritten.
    pub dirichlet_load: &'a mut [f64],
}

/// Assembles K, consistent M, HRZ-lumped nodal masses and the Dirichlet load
/// into `out` (values in the pattern `pattern`, which must be
/// [`free_dof_pattern`] of `mesh` and `dofs`). Returns the mesh area.
///
/// # Errors
/// [`FemError::InvertedCell`] for the first cell (in mesh order) with
/// det J ≤ 0 at a quadrature point.
pub fn assemble(
    mesh: &Mesh,
    material: &Material,
    dofs: &DofMap,
    pattern: &SparsityPattern,
    out: Assembly<'_>,
) -> Result<f64, FemError> {
    let Assembly {
        stiffness,
        mass,
        lumped_nodal,
        dirichlet_load,
    } = out;
    assert_eq!(stiffness.len(), pattern.nnz());
    assert_eq!(mass.len(), pattern.nnz());
    assert_eq!(lumped_nodal.len(), mesh.nodes.len());
    assert_eq!(dirichlet_load.len(), dofs.n_free());
    // Zeroing touches every page of the value arrays (hundreds of MB at
    // 500k DOFs); in parallel, so the page faults are shared out too.
    for values in [&mut *stiffness, &mut *mass] {
        if values.len() > PARALLEL_ZEROING {
            values
                .par_chunks_mut(PARALLEL_ZEROING)
                .for_each(|c| c.fill(0.0));
        } else {
            values.fill(0.0);
        }
    }
    lumped_nodal.fill(0.0);
    dirichlet_load.fill(0.0);

    let basis = CellBasis::full(mesh.kind);
    let d = material.elasticity();
    let rho = material.density;
    let n = mesh.kind.nodes_per_cell();
    let nd = 2 * n;
    let free_index = dofs.free_index_table();
    let prescribed = dofs.prescribed_values();
    let nonzero_prescribed = dofs.has_nonzero_prescribed();
    let row_offsets = pattern.major_offsets();
    let cols = pattern.minor_indices();

    let n_cells = mesh.n_cells();
    let mut work = vec![ElementWork::new(); CHUNK.min(n_cells.max(1))];
    let mut area = 0.0;
    let mut first = 0;
    while first < n_cells {
        let count = CHUNK.min(n_cells - first);
        let kernels = |(i, w): (usize, &mut ElementWork)| {
            let cell = mesh.cell(first + i);
            let mut coords = [[0.0; 2]; MAX_NODES];
            for (c, &v) in coords.iter_mut().zip(cell) {
                *c = mesh.nodes[v];
            }
            match basis.stiffness_and_mass(&coords[..n], &d, rho, &mut w.ke, &mut w.me) {
                Ok(a) => {
                    w.area = a;
                    w.bad_det = None;
                }
                Err(e) => {
                    w.bad_det = Some(e.det);
                    return;
                }
            }
            hrz_lumped_mass(&w.me, n, &mut w.lumped);
            // CSR positions: for each free row DOF, find each free column
            // node's first free component by binary search; a node's two
            // free DOFs are adjacent columns.
            let mut free = [NO_POSITION; MAX_DOFS];
            for (a, &v) in cell.iter().enumerate() {
                free[2 * a] = free_index[2 * v];
                free[2 * a + 1] = free_index[2 * v + 1];
            }
            for alpha in 0..nd {
                let r = free[alpha];
                if r == NO_POSITION {
                    continue;
                }
                let start = row_offsets[r];
                // Both DOFs of a node free: their rows have the same columns
                // (the node's neighbours), so y's positions are x's shifted
                // by x's row length.
                if alpha % 2 == 1 && free[alpha - 1] != NO_POSITION {
                    let shift = start - row_offsets[r - 1];
                    let (prev, row) =
                        w.positions[(alpha - 1) * nd..(alpha + 1) * nd].split_at_mut(nd);
                    for (p, &q) in row.iter_mut().zip(prev.iter()) {
                        *p = if q == NO_POSITION {
                            NO_POSITION
                        } else {
                            q + shift
                        };
                    }
                    continue;
                }
                let row = &mut w.positions[alpha * nd..(alpha + 1) * nd];
                let lane = &cols[start..row_offsets[r + 1]];
                for b in 0..n {
                    let (c0, c1) = (free[2 * b], free[2 * b + 1]);
                    if c0 != NO_POSITION {
                        let p = start + lane.binary_search(&c0).expect("pattern covers the cell");
                        row[2 * b] = p;
                        row[2 * b + 1] = if c1 != NO_POSITION {
                            p + 1
                        } else {
                            NO_POSITION
                        };
                    } else {
                        row[2 * b] = NO_POSITION;
                        row[2 * b + 1] = if c1 != NO_POSITION {
                            start + lane.binary_search(&c1).expect("pattern covers the cell")
                        } else {
                            NO_POSITION
                        };
                    }
                }
            }
        };
        // Each cell's kernels write its own work only: the same bits on
        // the pool or not.
        if n_cells >= PARALLEL_CELLS {
            work[..count].par_iter_mut().enumerate().for_each(kernels);
        } else {
            work[..count].iter_mut().enumerate().for_each(kernels);
        }
        // Sequential scatter in element order: deterministic sums.
        for (i, w) in work[..count].iter().enumerate() {
            let c = first + i;
            let cell = mesh.cell(c);
            if let Some(det) = w.bad_det {
                let p = mesh.nodes[cell[0]];
                return Err(FemError::InvertedCell {
                    cell: c,
                    x: p[0],
                    y: p[1],
                    det,
                });
            }
            area += w.area;
            for (a, &v) in cell.iter().enumerate() {
                lumped_nodal[v] += w.lumped[a];
            }
            for alpha in 0..nd {
                let r = free_index[2 * cell[alpha / 2] + alpha % 2];
                if r == NO_POSITION {
                    continue;
                }
                let krow = &w.ke[alpha * nd..(alpha + 1) * nd];
                let prow = &w.positions[alpha * nd..(alpha + 1) * nd];
                let mrow = &w.me[(alpha / 2) * n..(alpha / 2 + 1) * n];
                let comp = alpha % 2;
                for b in 0..n {
                    for j in 0..2 {
                        let beta = 2 * b + j;
                        let p = prow[beta];
                        if p != NO_POSITION {
                            stiffness[p] += krow[beta];
                            if j == comp {
                                mass[p] += mrow[b];
                            }
                        } else if nonzero_prescribed {
                            dirichlet_load[r] -= krow[beta] * prescribed[2 * cell[b] + j];
                        }
                    }
                }
            }
        }
        first += count;
    }
    Ok(area)
}
