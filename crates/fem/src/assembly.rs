//! Sparse assembly on free DOFs.
//!
//! Values are accumulated in place in the pattern of [`crate::pattern`].
//! Element matrices are computed in parallel (rayon) in fixed-size chunks
//! together with the CSR positions of their entries, then scattered by
//! *parts*: each part owns a range of rows (and of nodes, for the lumped
//! mass) and visits the chunk's cells in element order, adding only to
//! what it owns, so every sum takes its terms in element order, as one
//! thread scattering everything would: the same bits for any number of
//! threads and parts. The chunk's buffers are allocated once per assembly,
//! sized to the cells' kind.

use nalgebra_sparse::pattern::SparsityPattern;
use rayon::prelude::*;
use stickslip_mesh::Mesh;

use crate::dofs::DofMap;
use crate::element::{hrz_lumped_mass, CellBasis, MAX_NODES};
use crate::error::FemError;
use crate::material::Material;

/// Marks a local entry with no CSR position (its column DOF is fixed).
const NO_POSITION: usize = usize::MAX;

/// Bytes of element data per chunk of cells (≈ 6 KB a Q2 cell, 1.2 KB a
/// Q1): a chunk costs two parallel loops, each a wait for every thread of
/// the pool, which on a host shared with other work can be a time slice
/// long; about 3,500 Q1 or 700 Q2 cells a chunk keep those waits fewer
/// than the cells' work.
const CHUNK_BYTES: usize = 1 << 22;

/// Cells from which the element kernels run on rayon's pool: below, its
/// threads' start (at the first parallel loop of a run) and their
/// spinning after each job cost more than the cells (the paper's slab
/// has 16).
const PARALLEL_CELLS: usize = 64;

/// Values from which zeroing a value array is shared out between the
/// pool's threads (one block of its chunks).
const PARALLEL_ZEROING: usize = 1 << 16;

/// The element data of a chunk of cells, for the kernels to fill (one
/// slot per cell, sized to the cells' kind) and the parts to scatter.
struct ChunkWork {
    /// Per cell its (2n)² stiffness, row-major.
    ke: Vec<f64>,
    /// Per cell its n² node-pair mass.
    me: Vec<f64>,
    /// Per cell its n lumped masses.
    lumped: Vec<f64>,
    /// Per cell the CSR position of each of its (2n)² entries (rows of
    /// fixed DOFs left as they were: nothing reads them).
    positions: Vec<usize>,
    /// Per cell its area, or det J where the cell folds.
    areas: Vec<Result<f64, f64>>,
}

/// One cell's slots of a [`ChunkWork`], as the kernels receive them.
type Slots<'a> = (
    (
        ((&'a mut [f64], &'a mut [f64]), &'a mut [f64]),
        &'a mut [usize],
    ),
    &'a mut Result<f64, f64>,
);

/// What one part of the scatter owns: rows `rows` of K, M and the
/// Dirichlet load (their values from `row_offsets[rows.start]`; `mass`
/// empty where M is left out), and the lumped masses of nodes `nodes`.
struct Part<'a> {
    rows: std::ops::Range<usize>,
    nodes: std::ops::Range<usize>,
    stiffness: &'a mut [f64],
    mass: &'a mut [f64],
    dirichlet_load: &'a mut [f64],
    lumped_nodal: &'a mut [f64],
}

/// The output split into `count` parts of about equal entries (rows) and
/// nodes.
fn parts<'a>(out: Assembly<'a>, row_offsets: &[usize], count: usize) -> Vec<Part<'a>> {
    let Assembly {
        mut stiffness,
        mass,
        mut lumped_nodal,
        mut dirichlet_load,
    } = out;
    let mut mass = mass.unwrap_or_default();
    let (n_rows, n_nodes) = (dirichlet_load.len(), lumped_nodal.len());
    let nnz = stiffness.len();
    let (mut row, mut node) = (0, 0);
    let mut parts = Vec::with_capacity(count);
    for t in 1..=count {
        let end_row = if t == count {
            n_rows
        } else {
            row_offsets
                .partition_point(|&o| o < nnz * t / count)
                .min(n_rows)
                .max(row)
        };
        let end_node = n_nodes * t / count;
        let values = row_offsets[end_row] - row_offsets[row];
        let (k, k_rest) = std::mem::take(&mut stiffness).split_at_mut(values);
        let (m, m_rest) = if mass.is_empty() {
            (&mut [][..], &mut [][..])
        } else {
            std::mem::take(&mut mass).split_at_mut(values)
        };
        let (d, d_rest) = std::mem::take(&mut dirichlet_load).split_at_mut(end_row - row);
        let (l, l_rest) = std::mem::take(&mut lumped_nodal).split_at_mut(end_node - node);
        (stiffness, mass, dirichlet_load, lumped_nodal) = (k_rest, m_rest, d_rest, l_rest);
        parts.push(Part {
            rows: row..end_row,
            nodes: node..end_node,
            stiffness: k,
            mass: m,
            dirichlet_load: d,
            lumped_nodal: l,
        });
        (row, node) = (end_row, end_node);
    }
    parts
}

/// Everything assembled in one pass over the cells.
#[derive(Debug)]
pub struct Assembly<'a> {
    /// K values (pattern of [`crate::free_dof_pattern`]), overwritten.
    pub stiffness: &'a mut [f64],
    /// Consistent M values (same pattern), overwritten; `None` leaves M
    /// out (explicit, quasi-static and lumped-mass Newmark runs never read
    /// it).
    pub mass: Option<&'a mut [f64]>,
    /// HRZ lumped mass per node (same for both components), overwritten.
    pub lumped_nodal: &'a mut [f64],
    /// −K_fc u_c on free DOFs, overwritten.
    pub dirichlet_load: &'a mut [f64],
}

/// Assembles K, consistent M (where asked), HRZ-lumped nodal masses and the Dirichlet load
/// into `out` (values in the pattern `pattern`, which must be
/// [`crate::free_dof_pattern`] of `mesh` and `dofs`). Returns the mesh area.
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
        mut mass,
        lumped_nodal,
        dirichlet_load,
    } = out;
    assert_eq!(stiffness.len(), pattern.nnz());
    assert!(mass.as_ref().is_none_or(|m| m.len() == pattern.nnz()));
    assert_eq!(lumped_nodal.len(), mesh.nodes.len());
    assert_eq!(dirichlet_load.len(), dofs.n_free());
    // Zeroing touches every page of the value arrays (hundreds of MB at
    // 500k DOFs); in parallel, so the page faults are shared out too.
    for values in std::iter::once(&mut *stiffness).chain(mass.as_deref_mut()) {
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
    let parallel = n_cells >= PARALLEL_CELLS;
    // As many parts as threads: each part scans the whole chunk's cells.
    let threads = if parallel {
        rayon::current_num_threads()
    } else {
        1
    };
    let mut parts = parts(
        Assembly {
            stiffness,
            mass,
            lumped_nodal,
            dirichlet_load,
        },
        row_offsets,
        threads,
    );
    let cell_bytes = 16 * nd * nd + 8 * (n * n + n) + 16;
    let chunk = (CHUNK_BYTES / cell_bytes).max(PARALLEL_CELLS);
    let slots = chunk.min(n_cells);
    let mut work = ChunkWork {
        ke: vec![0.0; slots * nd * nd],
        me: vec![0.0; slots * n * n],
        lumped: vec![0.0; slots * n],
        positions: vec![0; slots * nd * nd],
        areas: vec![Ok(0.0); slots],
    };
    let mut area = 0.0;
    let mut first = 0;
    while first < n_cells {
        let count = chunk.min(n_cells - first);
        let kernels = |(i, ((((ke, me), lumped), positions), area)): (usize, Slots<'_>)| {
            let cell = mesh.cell(first + i);
            let mut coords = [[0.0; 2]; MAX_NODES];
            for (c, &v) in coords.iter_mut().zip(cell) {
                *c = mesh.nodes[v];
            }
            match basis.stiffness_and_mass(&coords[..n], &d, rho, ke, me) {
                Ok(a) => *area = Ok(a),
                Err(e) => {
                    *area = Err(e.det);
                    return;
                }
            }
            hrz_lumped_mass(me, n, lumped);
            cell_positions(cell, free_index, row_offsets, cols, positions);
        };
        // Each cell's kernels write its own slots only: the same bits on
        // the pool or not (one chain, by rayon's or std's chunks).
        macro_rules! each_cell {
            ($chunks:ident, $iter:ident) => {
                work.ke[..count * nd * nd]
                    .$chunks(nd * nd)
                    .zip(work.me[..count * n * n].$chunks(n * n))
                    .zip(work.lumped[..count * n].$chunks(n))
                    .zip(work.positions[..count * nd * nd].$chunks(nd * nd))
                    .zip(work.areas[..count].$iter())
                    .enumerate()
                    .for_each(kernels)
            };
        }
        if parallel {
            each_cell!(par_chunks_mut, par_iter_mut);
        } else {
            each_cell!(chunks_mut, iter_mut);
        }
        for (i, a) in work.areas[..count].iter().enumerate() {
            match *a {
                Ok(a) => area += a,
                Err(det) => {
                    let c = first + i;
                    let p = mesh.nodes[mesh.cell(c)[0]];
                    return Err(FemError::InvertedCell {
                        cell: c,
                        x: p[0],
                        y: p[1],
                        det,
                    });
                }
            }
        }
        let cells = first..first + count;
        let own = |part: &mut Part<'_>| {
            let constants = (row_offsets, prescribed, nonzero_prescribed);
            scatter(mesh, dofs, constants, &work, cells.clone(), part)
        };
        if parallel {
            parts.par_iter_mut().for_each(own);
        } else {
            parts.iter_mut().for_each(own);
        }
        first += count;
    }
    Ok(area)
}

/// The CSR positions of a cell's entries: for each free row DOF, each
/// free column node's first free component by binary search (a node's
/// two free DOFs are adjacent columns).
fn cell_positions(
    cell: &[usize],
    free_index: &[usize],
    row_offsets: &[usize],
    cols: &[usize],
    positions: &mut [usize],
) {
    let n = cell.len();
    let nd = 2 * n;
    let mut free = [NO_POSITION; 2 * MAX_NODES];
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
        // Both DOFs of a node free: their rows have the same columns (the
        // node's neighbours), so y's positions are x's shifted by x's row
        // length.
        if alpha % 2 == 1 && free[alpha - 1] != NO_POSITION {
            let shift = start - row_offsets[r - 1];
            let (prev, row) = positions[(alpha - 1) * nd..(alpha + 1) * nd].split_at_mut(nd);
            for (p, &q) in row.iter_mut().zip(prev.iter()) {
                *p = if q == NO_POSITION {
                    NO_POSITION
                } else {
                    q + shift
                };
            }
            continue;
        }
        let row = &mut positions[alpha * nd..(alpha + 1) * nd];
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
}

/// Adds the element data of `cells` (slots from 0 in `work`) to what
/// `part` owns, in element order.
fn scatter(
    mesh: &Mesh,
    dofs: &DofMap,
    (row_offsets, prescribed, nonzero_prescribed): (&[usize], &[f64], bool),
    work: &ChunkWork,
    cells: std::ops::Range<usize>,
    part: &mut Part<'_>,
) {
    let free_index = dofs.free_index_table();
    let n = mesh.kind.nodes_per_cell();
    let nd = 2 * n;
    let base = row_offsets[part.rows.start];
    let with_mass = !part.mass.is_empty();
    let first = cells.start;
    for c in cells {
        let i = c - first;
        let cell = mesh.cell(c);
        let lumped = &work.lumped[i * n..(i + 1) * n];
        for (a, &v) in cell.iter().enumerate() {
            if part.nodes.contains(&v) {
                part.lumped_nodal[v - part.nodes.start] += lumped[a];
            }
        }
        let ke = &work.ke[i * nd * nd..(i + 1) * nd * nd];
        let me = &work.me[i * n * n..(i + 1) * n * n];
        let positions = &work.positions[i * nd * nd..(i + 1) * nd * nd];
        for alpha in 0..nd {
            let r = free_index[2 * cell[alpha / 2] + alpha % 2];
            if !part.rows.contains(&r) {
                continue;
            }
            let krow = &ke[alpha * nd..(alpha + 1) * nd];
            let prow = &positions[alpha * nd..(alpha + 1) * nd];
            let mrow = &me[(alpha / 2) * n..(alpha / 2 + 1) * n];
            let comp = alpha % 2;
            for b in 0..n {
                for j in 0..2 {
                    let beta = 2 * b + j;
                    let p = prow[beta];
                    if p != NO_POSITION {
                        part.stiffness[p - base] += krow[beta];
                        if j == comp && with_mass {
                            part.mass[p - base] += mrow[b];
                        }
                    } else if nonzero_prescribed {
                        part.dirichlet_load[r - part.rows.start] -=
                            krow[beta] * prescribed[2 * cell[b] + j];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dofs::Dirichlet;
    use crate::material::Hypothesis;
    use crate::pattern::free_dof_pattern;
    use stickslip_mesh::CellKind;

    /// K, M, lumped M, the Dirichlet load and the area.
    type Assembled = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, f64);

    /// The assembly before the scatter by parts, kept as the reference:
    /// each cell's matrices added on one thread in element order, every
    /// position found by binary search in its row.
    fn sequential(
        mesh: &Mesh,
        material: &Material,
        dofs: &DofMap,
        pattern: &SparsityPattern,
    ) -> Assembled {
        let (offsets, cols) = (pattern.major_offsets(), pattern.minor_indices());
        let (mut k, mut m) = (vec![0.0; pattern.nnz()], vec![0.0; pattern.nnz()]);
        let (mut lumped, mut load) = (vec![0.0; mesh.nodes.len()], vec![0.0; dofs.n_free()]);
        let basis = CellBasis::full(mesh.kind);
        let n = mesh.kind.nodes_per_cell();
        let nd = 2 * n;
        let (mut ke, mut me, mut le) = (vec![0.0; nd * nd], vec![0.0; n * n], vec![0.0; n]);
        let mut area = 0.0;
        for c in 0..mesh.n_cells() {
            let cell = mesh.cell(c);
            let coords: Vec<[f64; 2]> = cell.iter().map(|&v| mesh.nodes[v]).collect();
            let elasticity = material.elasticity();
            area += basis
                .stiffness_and_mass(&coords, &elasticity, material.density, &mut ke, &mut me)
                .expect("valid cells");
            hrz_lumped_mass(&me, n, &mut le);
            for (a, &v) in cell.iter().enumerate() {
                lumped[v] += le[a];
            }
            for alpha in 0..nd {
                let Some(r) = dofs.free(cell[alpha / 2], alpha % 2) else {
                    continue;
                };
                let row = &cols[offsets[r]..offsets[r + 1]];
                for beta in 0..nd {
                    let (b, j) = (beta / 2, beta % 2);
                    match dofs.free(cell[b], j) {
                        Some(col) => {
                            let p = offsets[r] + row.binary_search(&col).expect("covered");
                            k[p] += ke[alpha * nd + beta];
                            if j == alpha % 2 {
                                m[p] += me[(alpha / 2) * n + b];
                            }
                        }
                        None => {
                            let u = dofs.prescribed(cell[b], j).expect("fixed");
                            if dofs.has_nonzero_prescribed() {
                                load[r] -= ke[alpha * nd + beta] * u;
                            }
                        }
                    }
                }
            }
        }
        (k, m, lumped, load, area)
    }

    /// [`assemble`] into arrays of ones (overwritten); M left at its ones
    /// without `with_mass`.
    fn parallel(
        mesh: &Mesh,
        material: &Material,
        dofs: &DofMap,
        pattern: &SparsityPattern,
        with_mass: bool,
    ) -> Assembled {
        let (mut k, mut m) = (vec![1.0; pattern.nnz()], vec![1.0; pattern.nnz()]);
        let (mut lumped, mut load) = (vec![1.0; mesh.nodes.len()], vec![1.0; dofs.n_free()]);
        let out = Assembly {
            stiffness: &mut k,
            mass: with_mass.then_some(&mut m[..]),
            lumped_nodal: &mut lumped,
            dirichlet_load: &mut load,
        };
        let area = assemble(mesh, material, dofs, pattern, out).expect("valid cells");
        (k, m, lumped, load, area)
    }

    /// A slab of `kind`, its nodes moved off the grid (so that the DOF
    /// map takes the bandwidth order and no two cells are alike), the
    /// left end pulled in x (a non-zero Dirichlet load).
    fn bent_slab(kind: CellKind, refine: usize) -> (Mesh, DofMap, Material) {
        let mut mesh = stickslip_testkit::slab(kind, refine);
        stickslip_testkit::map_nodes(&mut mesh, |[x, y]| {
            [x + 0.01 * (3.0 * y).sin(), y + 0.02 * (1.7 * x).sin() * y]
        });
        let conditions = [
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("left", 0, 0.01),
        ];
        let dofs = DofMap::new(&mesh, &conditions).expect("valid conditions");
        assert_eq!(dofs.node_order(), crate::NodeOrder::Bandwidth);
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).expect("valid");
        (mesh, dofs, material)
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// The scatter by parts gives every value the bits of the sequential
    /// scatter in element order, on one thread and on several (parts of
    /// other sizes), for Q1 and Q2 cells, with M or without it.
    #[test]
    fn parts_scatter_with_the_sequential_bits() {
        for (kind, refine) in [(CellKind::Quad4, 8), (CellKind::Quad9, 4)] {
            let (mesh, dofs, material) = bent_slab(kind, refine);
            assert!(mesh.n_cells() >= PARALLEL_CELLS);
            let pattern = free_dof_pattern(&mesh, &dofs);
            let expected = sequential(&mesh, &material, &dofs, &pattern);
            assert!(expected.3.iter().any(|&f| f != 0.0), "a Dirichlet load");
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a pool");
                for with_mass in [true, false] {
                    let got =
                        pool.install(|| parallel(&mesh, &material, &dofs, &pattern, with_mass));
                    let at = format!("{threads} threads, M assembled: {with_mass}");
                    assert_eq!(bits(&got.0), bits(&expected.0), "K, {at}");
                    if with_mass {
                        assert_eq!(bits(&got.1), bits(&expected.1), "M, {at}");
                    } else {
                        assert!(got.1.iter().all(|&m| m == 1.0), "M untouched, {at}");
                    }
                    assert_eq!(bits(&got.2), bits(&expected.2), "lumped M, {at}");
                    assert_eq!(bits(&got.3), bits(&expected.3), "Dirichlet load, {at}");
                    assert_eq!(got.4.to_bits(), expected.4.to_bits(), "area, {at}");
                }
            }
        }
    }
}
