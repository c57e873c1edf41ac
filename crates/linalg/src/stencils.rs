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
use crate::simd::{Batches, Kernel};

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

    /// The sums of group g's rows (the second is 0 for a single row).
    #[inline(always)]
    fn group_sums(&self, g: usize, x: &[f64]) -> [f64; 2] {
        self.lockstep::<1>(self.types[g], [self.group_rows[g] as usize], x)[0]
    }

    /// Q groups of type t whose first rows are `rows`, in lockstep: each
    /// block's values are loaded once for all. Each row is summed in two
    /// partial sums, its own column's terms (the block's first column for
    /// a group's first row, the second for its second) and the other
    /// column's, added at the end: the same terms in the same order
    /// whatever Q, so the same bits, and 4Q independent chains of
    /// additions. Four consecutive groups read one contiguous run of x
    /// per block, which the compiler keeps in vector registers.
    #[inline(always)]
    fn lockstep<const Q: usize>(&self, t: u32, rows: [usize; Q], x: &[f64]) -> [[f64; 2]; Q] {
        let b = self.type_blocks[t as usize] as usize..self.type_blocks[t as usize + 1] as usize;
        let (mut own, mut other) = ([[0.0; 2]; Q], [[0.0; 2]; Q]);
        for (&o, v) in self.offsets[b.clone()].iter().zip(&self.values[b]) {
            for q in 0..Q {
                let c = (rows[q] as isize + o as isize) as usize;
                let xs = &x[c..c + 2];
                own[q][0] += v[0] * xs[0];
                own[q][1] += v[3] * xs[1];
                other[q][0] += v[2] * xs[1];
                other[q][1] += v[1] * xs[0];
            }
        }
        std::array::from_fn(|q| [own[q][0] + other[q][0], own[q][1] + other[q][1]])
    }

    /// K x on the rows of groups g0..g1 into `out` (from g0's first row):
    /// four alike node pairs on consecutive rows in lockstep (a structured
    /// Q1 node row), or two pairs of alike pairs alternating (a Q2 node
    /// row, corner and mid-side nodes in turn), else a group at a time.
    #[inline(always)]
    fn groups_into(&self, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        let base = self.group_rows[g0] as usize;
        let rows = |g: usize| self.group_rows[g] as usize;
        let mut g = g0;
        while g < g1 {
            let r = rows(g);
            let pairs = g + 4 <= g1 && (1..=4).all(|q| rows(g + q) == r + 2 * q);
            let t = &self.types;
            if pairs && t[g] == t[g + 1] && t[g] == t[g + 2] && t[g] == t[g + 3] {
                let s = self.lockstep::<4>(t[g], [r, r + 2, r + 4, r + 6], x);
                for (q, s) in s.iter().enumerate() {
                    out[r + 2 * q - base..r + 2 * q + 2 - base].copy_from_slice(s);
                }
                g += 4;
            } else if pairs && t[g] == t[g + 2] && t[g + 1] == t[g + 3] {
                let a = self.lockstep::<2>(t[g], [r, r + 4], x);
                let b = self.lockstep::<2>(t[g + 1], [r + 2, r + 6], x);
                for (q, s) in [a[0], b[0], a[1], b[1]].iter().enumerate() {
                    out[r + 2 * q - base..r + 2 * q + 2 - base].copy_from_slice(s);
                }
                g += 4;
            } else {
                let (r0, r1) = (r, rows(g + 1));
                let s = self.group_sums(g, x);
                out[r0 - base] = s[0];
                if r1 - r0 == 2 {
                    out[r0 + 1 - base] = s[1];
                }
                g += 1;
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
            crate::simd::vectorized(Groups {
                k: self,
                g: g0..g1,
                x,
                out: y,
            });
        });
    }

    /// Hands `to` K x on consecutive batches of at most [`BATCH`] rows
    /// covering chunk `c`, in order (call inside a
    /// [`crate::simd::Kernel`]).
    #[inline(always)]
    pub fn batches(&self, c: usize, x: &[f64], to: &mut impl Batches) {
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
            to.batch(ra, out);
            g = gb;
        }
    }

    /// (K x)_i, with the bits the batches give it.
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        let g = self.group_rows.partition_point(|&r| r as usize <= i) - 1;
        self.group_sums(g, x)[i - self.group_rows[g] as usize]
    }
}

/// K x on groups `g` into `out`, as a dispatched kernel.
struct Groups<'a> {
    k: &'a Stencils,
    g: std::ops::Range<usize>,
    x: &'a [f64],
    out: &'a mut [f64],
}

impl Kernel for Groups<'_> {
    type Output = ();

    #[inline(always)]
    fn run(self) {
        self.k
            .groups_into(self.g.start, self.g.end, self.x, self.out);
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
