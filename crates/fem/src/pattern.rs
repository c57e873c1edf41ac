//! The node adjacency and the sparsity pattern of K and M on the free DOFs.
//!
//! Both are built row by row, each row from its node's cells (or
//! neighbours) alone, so that blocks of rows are built on rayon's pool at
//! once: the same pattern on any number of threads. The DOF map's
//! bandwidth order and the pattern read one adjacency
//! ([`SharedAdjacency`]).

use std::cell::OnceCell;

use nalgebra_sparse::pattern::SparsityPattern;
use rayon::prelude::*;
use stickslip_mesh::Mesh;

use crate::dofs::DofMap;

/// Rows from which a pattern is built on rayon's pool: below, a few
/// milliseconds of rows at most, the wake of the pool's threads (or their
/// start, when this is the run's first parallel loop) costs about as much.
const PARALLEL_ROWS: usize = 1 << 16;

/// Rows per block built on one thread.
const BLOCK: usize = 2048;

/// Node-to-node adjacency as CSR: node p's neighbours (itself among them)
/// are `neighbours[offsets[p]..offsets[p + 1]]`, ascending.
pub type Adjacency = (Vec<usize>, Vec<usize>);

/// The adjacency of a mesh, built the first time it is asked for: the
/// DOF map's bandwidth order and the pattern share it.
pub(crate) type SharedAdjacency = OnceCell<Adjacency>;

/// The adjacency in `shared`, built there from `mesh` if it is not yet.
pub(crate) fn shared_adjacency<'a>(mesh: &Mesh, shared: &'a SharedAdjacency) -> &'a Adjacency {
    shared.get_or_init(|| node_adjacency(mesh))
}

/// Node → its places in the connectivity, by counting: node p's entries
/// are `entries[offsets[p]..offsets[p + 1]]`, each an index k into
/// `mesh.cells` (cell k / nodes per cell, local node k % nodes per cell),
/// ascending.
fn node_entries(mesh: &Mesh) -> (Vec<usize>, Vec<usize>) {
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
pub fn node_adjacency(mesh: &Mesh) -> Adjacency {
    let npc = mesh.kind.nodes_per_cell();
    let (cell_offsets, entries) = node_entries(mesh);
    rows(mesh.nodes.len(), |nodes, lengths, neighbours| {
        // At most each cell's nodes, before the duplicates go.
        neighbours.reserve(npc * (cell_offsets[nodes.end] - cell_offsets[nodes.start]));
        for p in nodes {
            let start = neighbours.len();
            for &k in &entries[cell_offsets[p]..cell_offsets[p + 1]] {
                neighbours.extend_from_slice(mesh.cell(k / npc));
            }
            neighbours[start..].sort_unstable();
            let mut kept = start;
            for i in start..neighbours.len() {
                if kept == start || neighbours[i] != neighbours[kept - 1] {
                    neighbours[kept] = neighbours[i];
                    kept += 1;
                }
            }
            neighbours.truncate(kept);
            lengths.push(kept - start);
        }
    })
}

/// The sparsity pattern of K (and M) on the free DOFs: free DOF r couples to
/// free DOF c when their nodes share a cell. Columns sorted; both triangles.
pub fn free_dof_pattern(mesh: &Mesh, dofs: &DofMap) -> SparsityPattern {
    pattern_of(&node_adjacency(mesh), dofs)
}

/// [`free_dof_pattern`] from the mesh's adjacency: the rows' lengths,
/// then their columns in place, both by blocks of rows on rayon's pool
/// from [`PARALLEL_ROWS`] rows (each block its own part of the columns,
/// so nothing is copied or allocated twice).
pub(crate) fn pattern_of(adjacency: &Adjacency, dofs: &DofMap) -> SparsityPattern {
    let (offsets, neighbours) = adjacency;
    let n_free = dofs.n_free();
    let parallel = n_free >= PARALLEL_ROWS;
    let node_neighbours = |r: usize| {
        let node = dofs.full_of_free(r) / 2;
        &neighbours[offsets[node]..offsets[node + 1]]
    };
    let mut row_offsets = vec![0; n_free + 1];
    let lengths = |(b, out): (usize, &mut [usize])| {
        for (i, o) in out.iter_mut().enumerate() {
            *o = node_neighbours(b * BLOCK + i)
                .iter()
                .map(|&q| dofs.free(q, 0).is_some() as usize + dofs.free(q, 1).is_some() as usize)
                .sum();
        }
    };
    if parallel {
        row_offsets[1..]
            .par_chunks_mut(BLOCK)
            .enumerate()
            .for_each(lengths);
    } else {
        row_offsets[1..]
            .chunks_mut(BLOCK)
            .enumerate()
            .for_each(lengths);
    }
    for r in 0..n_free {
        row_offsets[r + 1] += row_offsets[r];
    }
    let mut cols = vec![0; row_offsets[n_free]];
    let mut blocks = Vec::with_capacity(n_free.div_ceil(BLOCK));
    let mut rest = &mut cols[..];
    for first in (0..n_free).step_by(BLOCK) {
        let end = (first + BLOCK).min(n_free);
        let (block, r) = rest.split_at_mut(row_offsets[end] - row_offsets[first]);
        blocks.push((first..end, block));
        rest = r;
    }
    // In the mesh's node order free indices grow with (node, component),
    // so walking sorted neighbours yields sorted columns; in another order
    // a row is sorted after.
    let sort = dofs.node_order() != crate::NodeOrder::Mesh;
    let columns = |(rows, block): (std::ops::Range<usize>, &mut [usize])| {
        let base = row_offsets[rows.start];
        for r in rows.clone() {
            let (start, end) = (row_offsets[r] - base, row_offsets[r + 1] - base);
            // A node's two free DOFs have the same columns.
            if r > rows.start && dofs.full_of_free(r - 1) / 2 == dofs.full_of_free(r) / 2 {
                block.copy_within(row_offsets[r - 1] - base..start, start);
                continue;
            }
            let mut c = start;
            for &q in node_neighbours(r) {
                for comp in 0..2 {
                    if let Some(f) = dofs.free(q, comp) {
                        block[c] = f;
                        c += 1;
                    }
                }
            }
            if sort {
                block[start..end].sort_unstable();
            }
        }
    };
    if parallel {
        blocks.into_par_iter().for_each(columns);
    } else {
        blocks.into_iter().for_each(columns);
    }
    SparsityPattern::try_from_offsets_and_indices(n_free, n_free, row_offsets, cols)
        .expect("columns are sorted and in range by construction")
}

/// CSR rows 0..n: `block(rows, lengths, entries)` appends the lengths and
/// the entries of a range of rows; ranges of [`BLOCK`] rows are built on
/// rayon's pool from [`PARALLEL_ROWS`] rows, and joined in order.
fn rows<T: Copy + Send + Sync>(
    n: usize,
    block: impl Fn(std::ops::Range<usize>, &mut Vec<usize>, &mut Vec<T>) + Sync,
) -> (Vec<usize>, Vec<T>) {
    let one = |range: std::ops::Range<usize>| {
        let (mut lengths, mut entries) = (Vec::with_capacity(range.len()), Vec::new());
        block(range, &mut lengths, &mut entries);
        (lengths, entries)
    };
    let mut blocks: Vec<(Vec<usize>, Vec<T>)> = if n < PARALLEL_ROWS {
        vec![one(0..n)]
    } else {
        (0..n.div_ceil(BLOCK))
            .into_par_iter()
            .map(|b| one(b * BLOCK..((b + 1) * BLOCK).min(n)))
            .collect()
    };
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0);
    let mut end = 0;
    for (lengths, _) in &blocks {
        offsets.extend(lengths.iter().map(|l| {
            end += l;
            end
        }));
    }
    let entries = match blocks.len() {
        1 => blocks.pop().map(|(_, e)| e).unwrap_or_default(),
        _ => {
            let mut entries = Vec::with_capacity(end);
            for (_, block_entries) in &blocks {
                entries.extend_from_slice(block_entries);
            }
            entries
        }
    };
    (offsets, entries)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dofs::Dirichlet;
    use stickslip_mesh::CellKind;

    /// The pattern built in blocks on several threads is the one of sets
    /// of the free DOFs each cell couples, in both node orders of a
    /// mesh: the grid's and (nodes moved off it) the bandwidth order.
    #[test]
    fn the_pattern_is_the_cells_couplings() {
        for (kind, refine, bent) in [
            (CellKind::Quad4, 32, false),
            (CellKind::Quad4, 32, true),
            (CellKind::Quad9, 24, true),
        ] {
            let mut mesh = stickslip_testkit::slab(kind, refine);
            if bent {
                stickslip_testkit::map_nodes(&mut mesh, |[x, y]| [x + 0.01 * (3.0 * y).sin(), y]);
            }
            let conditions = [
                Dirichlet::new("support", 1, 0.0),
                Dirichlet::new("left", 0, 0.0),
            ];
            let dofs = DofMap::new(&mesh, &conditions).expect("valid conditions");
            assert!(dofs.n_free() >= PARALLEL_ROWS);
            let mut rows = vec![Vec::new(); dofs.n_free()];
            for c in 0..mesh.n_cells() {
                let free: Vec<usize> = mesh
                    .cell(c)
                    .iter()
                    .flat_map(|&v| [dofs.free(v, 0), dofs.free(v, 1)])
                    .flatten()
                    .collect();
                for &r in &free {
                    rows[r].extend(free.iter().copied());
                }
            }
            for row in &mut rows {
                row.sort_unstable();
                row.dedup();
            }
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .expect("a pool");
            let pattern = pool.install(|| free_dof_pattern(&mesh, &dofs));
            for (r, row) in rows.iter().enumerate() {
                assert!(pattern.lane(r).iter().eq(row.iter()), "row {r}");
            }
        }
    }
}
