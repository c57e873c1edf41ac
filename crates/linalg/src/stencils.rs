//! K·x by stencil types, for structured meshes.
//!
//! On a structured mesh most of K's node rows (a node's two rows, see
//! [`row_groups`]) are the same stencil: the same 2×2 blocks at the same
//! column offsets from the node's first row, equal up to the rounding of
//! the coordinates they were assembled from. [`Stencils`] keeps one copy of
//! each distinct stencil (a *type*: groups alike when their row count and
//! block offsets are equal and every block value is within [`TOLERANCE`] ·
//! max |K_ij| of the type's first member) and per group only its type, so a
//! product streams 8 bytes per node instead of the node's blocks, and reads
//! the few types' blocks from cache. A product is then bound by the vectors,
//! not by the matrix.
//!
//! Each row is summed in its type's block order whatever batch or thread
//! computes it: the same bits on any number of threads. Not the bits of the
//! assembled K's product: within [`TOLERANCE`] · max |K_ij| · Σ_j |x_j| of
//! it (tests below). Declined ([`Stencils::new`] returns `None`) where the
//! types would not shrink the matrix: unstructured meshes, where nearly
//! every node is its own stencil.

use std::collections::HashMap;

use nalgebra_sparse::CsrMatrix;

use crate::chunks::{chunks, each_chunk, CHUNK};

/// Block values within this fraction of max |K_ij| of a type's are the
/// type's. The committed slabs spread by about 1e-13; Gmsh's transfinite
/// nodes are off their grid lines by up to about 1e-9 of a cell, and alike
/// node rows of K then differ by up to about 1e-11. A product within 1e-10
/// · max |K_ij| · Σ_j |x_j| of the assembled K's is that of nodes moved by
/// less than Gmsh's rounding moved them.
pub const TOLERANCE: f64 = 1e-10;

/// The coarse grid, in tolerances, on which a stencil's values are hashed
/// (alike stencils land in one bucket unless a value straddles a grid line,
/// which costs a type, never a wrong merge: members are compared to the
/// tolerance).
const COARSE: f64 = (1u64 << 24) as f64;

/// Rows per batch of [`Stencils::batches`]: small enough to stay in L1
/// between the product and the caller's per-row work.
pub const BATCH: usize = 64;

/// K by stencil types (module documentation).
#[derive(Clone, Debug)]
pub struct Stencils {
    /// First row of each group, then n.
    group_rows: Vec<u32>,
    /// Type of each group.
    types: Vec<u32>,
    /// Blocks of type t: type_blocks[t]..type_blocks[t + 1].
    type_blocks: Vec<u32>,
    /// Each type block's first column minus its group's first row.
    offsets: Vec<i32>,
    /// Each type block's values by columns: [K00, K10, K01, K11].
    values: Vec<[f64; 4]>,
    /// Groups of chunk c: chunk_groups[c]..chunk_groups[c + 1].
    chunk_groups: Vec<u32>,
}

impl Stencils {
    /// The stencil types of a square CSR matrix with sorted columns at
    /// [`TOLERANCE`], or `None` where they would not cut the bytes a product
    /// streams from the matrix by at least 4×.
    pub fn new(a: &CsrMatrix<f64>) -> Option<Stencils> {
        Stencils::with_tolerance(a, TOLERANCE)
    }

    /// [`Stencils::new`] at tolerance `tol` (relative to max |K_ij|; 0:
    /// equal bits only).
    pub fn with_tolerance(a: &CsrMatrix<f64>, tol: f64) -> Option<Stencils> {
        // The types may hold at most 1/8 of the stored blocks: then they
        // and the 8 bytes per group are at most about a quarter of the
        // blocks' stream.
        let n = a.nrows();
        if n < 2 || a.ncols() != n || n >= i32::MAX as usize {
            return None;
        }
        let limit = (a.nnz() / 32).max(64);
        let max = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let tol = tol * max;
        let grid = if tol > 0.0 { COARSE * tol } else { f64::NAN };
        let mut index: HashMap<Vec<i64>, Vec<u32>> = HashMap::new();
        let mut key: Vec<i64> = Vec::new();
        let (mut types, mut type_blocks) = (Vec::with_capacity(n / 2 + 1), vec![0u32]);
        let (mut offsets, mut values): (Vec<i32>, Vec<[f64; 4]>) = (Vec::new(), Vec::new());
        let mut declined = false;
        let group_rows = row_groups(a, |r0, r1, cols, vals| {
            if declined {
                return;
            }
            key.clear();
            key.extend([(r1 - r0) as i64, cols.len() as i64]);
            for (&c, v) in cols.iter().zip(vals) {
                key.push(c as i64 - r0 as i64);
                for &x in v {
                    // Equal bits only at tol = 0 (NaN grid).
                    key.push(if grid.is_nan() {
                        x.to_bits() as i64
                    } else {
                        (x / grid).round() as i64
                    });
                }
            }
            let alike = |t: u32| {
                let b = type_blocks[t as usize] as usize..type_blocks[t as usize + 1] as usize;
                values[b]
                    .iter()
                    .zip(vals)
                    .all(|(p, q)| (0..4).all(|k| (p[k] - q[k]).abs() <= tol))
            };
            let found = index
                .get(&key)
                .and_then(|ts| ts.iter().copied().find(|&t| alike(t)));
            let t = match found {
                Some(t) => t,
                None => {
                    let t = (type_blocks.len() - 1) as u32;
                    offsets.extend(cols.iter().map(|&c| (c as i64 - r0 as i64) as i32));
                    values.extend_from_slice(vals);
                    type_blocks.push(values.len() as u32);
                    index.entry(key.clone()).or_default().push(t);
                    declined = values.len() > limit;
                    t
                }
            };
            types.push(t);
        });
        if declined {
            return None;
        }
        let chunk_groups = chunk_groups(&group_rows, n);
        types.shrink_to_fit();
        Some(Stencils {
            group_rows,
            types,
            type_blocks,
            offsets,
            values,
            chunk_groups,
        })
    }

    /// Rows.
    pub fn n(&self) -> usize {
        *self.group_rows.last().expect("then n") as usize
    }

    /// Distinct stencils.
    pub fn types(&self) -> usize {
        self.type_blocks.len() - 1
    }

    /// Bytes a product streams from the operator's data.
    pub fn bytes(&self) -> usize {
        8 * self.types.len() + 36 * self.values.len()
    }

    /// The sums of group g's rows (the second is 0 for a single row), each
    /// in two partial sums, its blocks' first columns' terms and their
    /// second columns', added at the end: four independent chains of
    /// additions instead of two.
    #[inline]
    fn group_sums(&self, g: usize, x: &[f64]) -> [f64; 2] {
        let r = self.group_rows[g] as isize;
        let t = self.types[g] as usize;
        let b = self.type_blocks[t] as usize..self.type_blocks[t + 1] as usize;
        let mut s = [[0.0; 2]; 2];
        for (&o, v) in self.offsets[b.clone()].iter().zip(&self.values[b]) {
            let c = (r + o as isize) as usize;
            let xs = &x[c..c + 2];
            s[0][0] += v[0] * xs[0];
            s[0][1] += v[1] * xs[0];
            s[1][0] += v[2] * xs[1];
            s[1][1] += v[3] * xs[1];
        }
        [s[0][0] + s[1][0], s[0][1] + s[1][1]]
    }

    /// K x on the rows of groups g0..g1 into `out` (from g0's first row).
    #[inline]
    fn groups_into(&self, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        let base = self.group_rows[g0] as usize;
        for g in g0..g1 {
            let (r0, r1) = (self.group_rows[g] as usize, self.group_rows[g + 1] as usize);
            let s = self.group_sums(g, x);
            out[r0 - base] = s[0];
            if r1 - r0 == 2 {
                out[r0 + 1 - base] = s[1];
            }
        }
    }

    /// y = K x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        each_chunk(y, |c, y| {
            let (g0, g1) = (
                self.chunk_groups[c] as usize,
                self.chunk_groups[c + 1] as usize,
            );
            self.groups_into(g0, g1, x, y);
        });
    }

    /// Calls `f(first row, K x on the batch's rows)` for consecutive
    /// batches of at most [`BATCH`] rows covering chunk `c`, in order.
    #[inline]
    pub fn batches(&self, c: usize, x: &[f64], mut f: impl FnMut(usize, &[f64])) {
        let (g0, g1) = (
            self.chunk_groups[c] as usize,
            self.chunk_groups[c + 1] as usize,
        );
        let mut buf = [0.0; BATCH];
        let mut g = g0;
        while g < g1 {
            let gb = (g + BATCH / 2).min(g1);
            let (ra, rb) = (self.group_rows[g] as usize, self.group_rows[gb] as usize);
            let out = &mut buf[..rb - ra];
            self.groups_into(g, gb, x, out);
            f(ra, out);
            g = gb;
        }
    }

    /// (K x)_i, with the bits the batches give it.
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        let g = self.group_rows.partition_point(|&r| r as usize <= i) - 1;
        self.group_sums(g, x)[i - self.group_rows[g] as usize]
    }
}

/// Groups K's rows by node: two consecutive rows with the same columns (a
/// node's x and y rows) are one group unless a chunk seam divides them,
/// else a row is a group of its own. Calls `visit(first row, end row,
/// block columns, block values)` for each group in order, its 2×2 blocks
/// in ascending column order (a block's first column is the pair start of
/// its columns: a single DOF is padded into the block before it, the
/// padding +0; values by columns), and returns the groups' first rows,
/// then n.
fn row_groups(
    a: &CsrMatrix<f64>,
    mut visit: impl FnMut(usize, usize, &[u32], &[[f64; 4]]),
) -> Vec<u32> {
    let n = a.nrows();
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let row = |i: usize| &cols[offsets[i]..offsets[i + 1]];
    // Pair start of each DOF: i for the first of a node's pair of rows
    // (same columns), i − 1 for the second; a single DOF is padded into the
    // block before it.
    let mut start = vec![0u32; n];
    let mut pair = vec![false; n];
    let mut i = 0;
    while i < n {
        if i + 1 < n && row(i) == row(i + 1) {
            start[i] = i as u32;
            start[i + 1] = i as u32;
            pair[i] = true;
            i += 2;
        } else {
            start[i] = i.saturating_sub(1) as u32;
            i += 1;
        }
    }
    let mut group_rows = Vec::with_capacity(n / 2 + 2);
    let mut i = 0;
    while i < n {
        group_rows.push(i as u32);
        i += if pair[i] && (i + 1) % CHUNK != 0 {
            2
        } else {
            1
        };
    }
    group_rows.push(n as u32);
    let (mut block_cols, mut block_vals): (Vec<u32>, Vec<[f64; 4]>) = (Vec::new(), Vec::new());
    for g in 0..group_rows.len() - 1 {
        let (r0, r1) = (group_rows[g] as usize, group_rows[g + 1] as usize);
        block_cols.clear();
        block_vals.clear();
        for (k, r) in (r0..r1).enumerate() {
            let mut next = 0;
            for p in offsets[r]..offsets[r + 1] {
                let c = cols[p];
                let s = start[c];
                // Both rows of a pair have the same columns, so the second
                // row finds the blocks the first one made.
                while next < block_cols.len() && block_cols[next] < s {
                    next += 1;
                }
                if next == block_cols.len() {
                    block_cols.push(s);
                    block_vals.push([0.0; 4]);
                }
                block_vals[next][2 * (c - s as usize) + k] = vals[p];
            }
        }
        visit(r0, r1, &block_cols, &block_vals);
    }
    group_rows
}

/// The first group of each chunk of n rows, then the number of groups.
fn chunk_groups(group_rows: &[u32], n: usize) -> Vec<u32> {
    let groups = group_rows.len() - 1;
    let mut chunk_groups = Vec::with_capacity(chunks(n) + 1);
    for (g, &r) in group_rows.iter().enumerate() {
        while chunk_groups.len() * CHUNK <= r as usize && chunk_groups.len() <= chunks(n) {
            chunk_groups.push(g as u32);
        }
    }
    while chunk_groups.len() <= chunks(n) {
        chunk_groups.push(groups as u32);
    }
    chunk_groups
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// A grid of nx × ny nodes, two DOFs each, numbered node by node, row
    /// by row, coupled to their 8 neighbours by 2×2 blocks as a Q1
    /// stiffness couples them; `wobble` perturbs every value by up to that
    /// relative amount (the rounding of a mesh's coordinates), `fixed`
    /// removes the x DOF of the first node (a support: single DOFs).
    fn grid(nx: usize, ny: usize, wobble: f64, fixed: bool) -> CsrMatrix<f64> {
        let node = |i: usize, j: usize| j * nx + i;
        let all = 2 * nx * ny;
        let skip = usize::from(fixed);
        let mut coo = CooMatrix::new(all - skip, all - skip);
        let mut k = 0u64;
        let mut jitter = || {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            1.0 + wobble * ((k >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        };
        for j in 0..ny {
            for i in 0..nx {
                for dj in -1i64..=1 {
                    for di in -1i64..=1 {
                        let (ii, jj) = (i as i64 + di, j as i64 + dj);
                        if ii < 0 || jj < 0 || ii >= nx as i64 || jj >= ny as i64 {
                            continue;
                        }
                        let (a, b) = (node(i, j), node(ii as usize, jj as usize));
                        for p in 0..2 {
                            for q in 0..2 {
                                let (r, c) = (2 * a + p, 2 * b + q);
                                if r < skip || c < skip {
                                    continue;
                                }
                                let base = if a == b {
                                    if p == q {
                                        8.0
                                    } else {
                                        0.5
                                    }
                                } else {
                                    -1.0 - 0.25 * (p + q) as f64 - 0.1 * (di + 2 * dj) as f64
                                };
                                coo.push(r - skip, c - skip, base * jitter());
                            }
                        }
                    }
                }
            }
        }
        CsrMatrix::from(&coo)
    }

    fn vector(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0)
            .collect()
    }

    /// Within TOLERANCE · max|K| · Σ|x| of the assembled product, row by
    /// row, on a grid with rounding-sized wobble and a fixed DOF; few types.
    #[test]
    fn product_within_the_tolerance_of_the_assembled_one() {
        for fixed in [false, true] {
            let a = grid(300, 40, 1e-13, fixed);
            let s = Stencils::new(&a).expect("a structured grid has few stencils");
            assert!(s.types() < 40, "{} types", s.types());
            let n = a.nrows();
            let x = vector(n);
            let mut y = vec![0.0; n];
            s.spmv(&x, &mut y);
            let max = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for (i, r) in a.row_iter().enumerate() {
                let want: f64 = r
                    .col_indices()
                    .iter()
                    .zip(r.values())
                    .map(|(&j, v)| v * x[j])
                    .sum();
                let scale: f64 = r.col_indices().iter().map(|&j| x[j].abs()).sum();
                assert!(
                    (y[i] - want).abs() <= 2.0 * TOLERANCE * max * scale,
                    "row {i}: {} against {want}",
                    y[i]
                );
            }
        }
    }

    /// Batches, single rows, one thread and two: the same bits.
    #[test]
    fn rows_have_the_same_bits_every_way() {
        let a = grid(200, 60, 1e-13, true);
        let s = Stencils::new(&a).unwrap();
        let n = a.nrows();
        assert!(chunks(n) > 2);
        let x = vector(n);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut y = vec![0.0; n];
            pool.install(|| s.spmv(&x, &mut y));
            y
        };
        let (one, two) = (on(1), on(2));
        let mut batched = vec![f64::NAN; n];
        for c in 0..chunks(n) {
            s.batches(c, &x, |r0, ku| {
                batched[r0..r0 + ku.len()].copy_from_slice(ku)
            });
        }
        for i in 0..n {
            assert_eq!(one[i].to_bits(), two[i].to_bits(), "row {i}");
            assert_eq!(one[i].to_bits(), batched[i].to_bits(), "row {i}");
            assert_eq!(one[i].to_bits(), s.row(i, &x).to_bits(), "row {i}");
        }
    }

    /// Values that differ by more than the tolerance make types of their
    /// own: a wobble of 1e-6 leaves too many for the types to pay.
    #[test]
    fn declines_what_has_no_structure() {
        assert!(Stencils::new(&grid(100, 20, 1e-6, false)).is_none());
    }
}
