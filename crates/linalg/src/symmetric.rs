//! K·x from the upper triangle of K's node blocks, for unstructured meshes.
//!
//! K is symmetric: K_ji = K_ijᵀ. Each node row (a *group*: a node's two
//! rows, or a single row where a Dirichlet condition took the other DOF)
//! keeps its diagonal block's upper triangle and its 2×2 blocks right of
//! it, with 32-bit offsets; a product reads each off-diagonal block once
//! and uses it twice, y_i += K_ij x_j and y_j += K_ijᵀ x_i, so it streams
//! about half the bytes of every row's full blocks. After the DOF map's
//! reverse Cuthill–McKee order the scattered rows are near the row being
//! summed, in cache.
//!
//! Rows are summed in the fixed chunks of [`crate::chunks`]: a chunk
//! accumulates its own rows and, in a *halo*, the rows after its end its
//! blocks reach; the halos are then added to those rows in chunk order.
//! Every row's terms are added in one order whatever thread runs a chunk:
//! the same bits on any number of threads. The upper triangle's values
//! stand for the lower's, so the product is within rounding of the
//! assembled K's (whose triangles may differ in their last bits), not its
//! bits. Declined ([`Symmetric::new`] returns `None`) where K's pattern or
//! values are not symmetric.

use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

use crate::chunks::{chunk_groups, chunks, parallel, CHUNK};
use crate::simd::Kernel;

/// Two entries K_ij and K_ji differing by more than this fraction of
/// max |K_ij| make K unsymmetric (assembly rounds the two triangles
/// separately, by far less).
const ASYMMETRY: f64 = 1e-12;

/// K by the upper triangle of its node blocks (module documentation).
#[derive(Clone, Debug)]
pub struct Symmetric {
    /// First row of each group, then n.
    group_rows: Vec<u32>,
    /// Blocks of group g: group_blocks[g]..group_blocks[g + 1].
    group_blocks: Vec<u32>,
    /// Per group its diagonal block's upper triangle (K00, K01, K11);
    /// (K00, 0, 0) for a single row.
    diagonal: Vec<[f64; 3]>,
    /// Each block's first column minus its group's first row: a window of
    /// two columns right of the group's diagonal block.
    offsets: Vec<u32>,
    /// Each block's values by columns: [K00, K10, K01, K11] (rows: the
    /// group's; +0 where a window's column is not right of the group, or
    /// the group has one row).
    values: Vec<[f64; 4]>,
    /// Groups of chunk c: chunk_groups[c]..chunk_groups[c + 1].
    chunk_groups: Vec<u32>,
    /// Chunk c's halo (the rows from its end its blocks reach):
    /// halos[c]..halos[c + 1] of the halo scratch.
    halos: Vec<usize>,
    /// The last product [`Symmetric::form`] formed, and its halo scratch.
    formed: Vec<f64>,
    halo: Vec<f64>,
    /// A chunk's sums on this thread.
    scratch: Vec<f64>,
}

impl Symmetric {
    /// The upper node blocks of a square CSR matrix with sorted columns,
    /// or `None` where its pattern is not symmetric or its values differ
    /// from their transposes by more than [`ASYMMETRY`] · max |K_ij|.
    pub fn new(a: &CsrMatrix<f64>) -> Option<Symmetric> {
        let n = a.nrows();
        if n < 2 || a.ncols() != n || n >= u32::MAX as usize - 2 || !symmetric(a) {
            return None;
        }
        let offsets = a.row_offsets();
        let cols = a.col_indices();
        let vals = a.values();
        let row = |i: usize| &cols[offsets[i]..offsets[i + 1]];
        // A node's two rows have the same columns; a pair never spans a
        // chunk seam, so that chunks hold whole groups.
        let mut group_rows = Vec::with_capacity(n / 2 + 2);
        let mut second = vec![false; n];
        let mut i = 0;
        while i < n {
            group_rows.push(i as u32);
            if i + 1 < n && (i + 1) % CHUNK != 0 && row(i) == row(i + 1) {
                second[i + 1] = true;
                i += 2;
            } else {
                i += 1;
            }
        }
        group_rows.push(n as u32);
        // The window (first of two columns) column c is read through: its
        // pair's first row, else the column before it (+0 there).
        let window = |c: usize| {
            if second[c] || !pair_first(&second, c) {
                c.saturating_sub(1)
            } else {
                c
            }
        };
        let groups = group_rows.len() - 1;
        let mut k = Symmetric {
            group_rows,
            group_blocks: Vec::with_capacity(groups + 1),
            diagonal: Vec::with_capacity(groups),
            offsets: Vec::new(),
            values: Vec::new(),
            chunk_groups: Vec::new(),
            halos: vec![0],
            formed: Vec::new(),
            halo: Vec::new(),
            scratch: Vec::new(),
        };
        k.group_blocks.push(0);
        for g in 0..groups {
            let (r0, r1) = (k.group_rows[g] as usize, k.group_rows[g + 1] as usize);
            let first = k.offsets.len();
            let mut d = [0.0; 3];
            for (q, r) in (r0..r1).enumerate() {
                let mut next = first;
                for p in offsets[r]..offsets[r + 1] {
                    let c = cols[p];
                    if c < r0 {
                        continue;
                    }
                    if c < r1 {
                        // The diagonal block's upper triangle (K01 from
                        // the first row).
                        match (q, c - r0) {
                            (0, 0) => d[0] = vals[p],
                            (0, 1) => d[1] = vals[p],
                            (1, 1) => d[2] = vals[p],
                            _ => {}
                        }
                        continue;
                    }
                    let w = window(c) as u32 - r0 as u32;
                    while next < k.offsets.len() && k.offsets[next] < w {
                        next += 1;
                    }
                    if next == k.offsets.len() {
                        k.offsets.push(w);
                        k.values.push([0.0; 4]);
                    }
                    debug_assert_eq!(k.offsets[next], w);
                    k.values[next][2 * (c - r0 - w as usize) + q] = vals[p];
                }
            }
            k.diagonal.push(d);
            k.group_blocks.push(k.offsets.len() as u32);
        }
        k.chunk_groups = chunk_groups(&k.group_rows, n);
        for c in 0..chunks(n) {
            let end = ((c + 1) * CHUNK).min(n);
            let (g0, g1) = (k.chunk_groups[c] as usize, k.chunk_groups[c + 1] as usize);
            let reach = (g0..g1)
                .flat_map(|g| {
                    let r0 = k.group_rows[g] as usize;
                    k.block_range(g).map(move |b| (r0, b))
                })
                .map(|(r0, b)| r0 + k.offsets[b] as usize + 2)
                .max()
                .unwrap_or(0);
            let last = *k.halos.last().expect("from 0");
            k.halos.push(last + reach.saturating_sub(end));
        }
        k.offsets.shrink_to_fit();
        k.values.shrink_to_fit();
        Some(k)
    }

    /// Rows.
    pub fn n(&self) -> usize {
        *self.group_rows.last().expect("then n") as usize
    }

    /// Bytes a product streams from the operator's data.
    pub fn bytes(&self) -> usize {
        8 * self.diagonal.len() + 24 * self.diagonal.len() + 36 * self.values.len()
    }

    /// Doubles of the halo scratch [`Symmetric::spmv_with`] needs.
    pub fn halo_len(&self) -> usize {
        *self.halos.last().expect("from 0")
    }

    fn block_range(&self, g: usize) -> std::ops::Range<usize> {
        self.group_blocks[g] as usize..self.group_blocks[g + 1] as usize
    }

    /// Forms K x whole, for [`Symmetric::formed`].
    pub fn form(&mut self, x: &[f64]) {
        let mut formed = std::mem::take(&mut self.formed);
        let mut halo = std::mem::take(&mut self.halo);
        let mut scratch = std::mem::take(&mut self.scratch);
        formed.resize(self.n(), 0.0);
        halo.resize(self.halo_len(), 0.0);
        self.spmv_with(x, &mut formed, &mut halo, &mut scratch);
        (self.formed, self.halo, self.scratch) = (formed, halo, scratch);
    }

    /// The product [`Symmetric::form`] formed last.
    pub fn formed(&self) -> &[f64] {
        &self.formed
    }

    /// y = K x (allocating its halo scratch).
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        let mut halo = vec![0.0; self.halo_len()];
        self.spmv_with(x, y, &mut halo, &mut Vec::new());
    }

    /// y = K x, with `halo` (at least [`Symmetric::halo_len`] doubles) and
    /// `scratch` as scratch.
    pub fn spmv_with(&self, x: &[f64], y: &mut [f64], halo: &mut [f64], scratch: &mut Vec<f64>) {
        let n = self.n();
        assert!(x.len() == n && y.len() == n && halo.len() >= self.halo_len());
        let halo = &mut halo[..self.halo_len()];
        let body = |scratch: &mut Vec<f64>, c: usize, y: &mut [f64], h: &mut [f64]| {
            scratch.clear();
            scratch.resize(y.len() + h.len(), 0.0);
            crate::simd::vectorized(Chunk {
                k: self,
                c,
                x,
                acc: scratch,
            });
            y.copy_from_slice(&scratch[..y.len()]);
            h.copy_from_slice(&scratch[y.len()..]);
        };
        if parallel(n) {
            // Each chunk's halo slice, in chunk order.
            let mut slices: Vec<&mut [f64]> = Vec::with_capacity(chunks(n));
            let mut rest = &mut *halo;
            for c in 0..chunks(n) {
                let (h, r) = rest.split_at_mut(self.halos[c + 1] - self.halos[c]);
                slices.push(h);
                rest = r;
            }
            y.par_chunks_mut(CHUNK)
                .zip(slices.par_iter_mut())
                .enumerate()
                .for_each_init(Vec::new, |s, (c, (y, h))| body(s, c, y, h));
        } else {
            // On this thread, without allocating (a small model's steps).
            let mut rest = &mut *halo;
            for (c, y) in y.chunks_mut(CHUNK).enumerate() {
                let (h, r) = rest.split_at_mut(self.halos[c + 1] - self.halos[c]);
                body(scratch, c, y, h);
                rest = r;
            }
        }
        // The halos into the rows they reach, in chunk order.
        for c in 0..chunks(n) {
            let end = ((c + 1) * CHUNK).min(n);
            let h = &halo[self.halos[c]..self.halos[c + 1]];
            for (yi, hi) in y[end..end + h.len()].iter_mut().zip(h) {
                *yi += hi;
            }
        }
    }

    /// Chunk c's own sums into `acc` (its rows, then its halo; zeroed):
    /// per group, in order, its rows' sums over the diagonal block and the
    /// blocks right of it (each row's own column's terms and the other
    /// column's in two fused sums, added at the end) added to what earlier
    /// groups scattered there, and each block's transpose times the
    /// group's x scattered to the block's rows.
    #[inline(always)]
    fn chunk_into(&self, c: usize, x: &[f64], acc: &mut [f64]) {
        let a = c * CHUNK;
        let (g0, g1) = (
            self.chunk_groups[c] as usize,
            self.chunk_groups[c + 1] as usize,
        );
        for g in g0..g1 {
            let r = self.group_rows[g] as usize;
            let pair = self.group_rows[g + 1] as usize - r == 2;
            let x0 = x[r];
            let x1 = if pair { x[r + 1] } else { 0.0 };
            let d = self.diagonal[g];
            let (mut own0, mut other0) = (d[0] * x0, d[1] * x1);
            let (mut own1, mut other1) = (d[2] * x1, d[1] * x0);
            let b = self.block_range(g);
            for (&o, v) in self.offsets[b.clone()].iter().zip(&self.values[b]) {
                // The block's two columns and rows, each one bounds check.
                let w = r + o as usize;
                let [xa, xb]: [f64; 2] = x[w..w + 2].try_into().expect("two columns");
                own0 = v[0].mul_add(xa, own0);
                other0 = v[2].mul_add(xb, other0);
                other1 = v[1].mul_add(xa, other1);
                own1 = v[3].mul_add(xb, own1);
                let l = w - a;
                let rows: &mut [f64; 2] = (&mut acc[l..l + 2]).try_into().expect("two rows");
                rows[0] += v[1].mul_add(x1, v[0] * x0);
                rows[1] += v[3].mul_add(x1, v[2] * x0);
            }
            acc[r - a] += own0 + other0;
            if pair {
                acc[r + 1 - a] += own1 + other1;
            }
        }
    }
}

/// True where c is the first row of a node's pair (`second` marks the
/// pairs' second rows).
fn pair_first(second: &[bool], c: usize) -> bool {
    second.get(c + 1).copied().unwrap_or(false)
}

/// K's pattern is symmetric and K_ji is within [`ASYMMETRY`] · max |K_ij|
/// of K_ij.
fn symmetric(a: &CsrMatrix<f64>) -> bool {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let max = vals.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let tol = ASYMMETRY * max;
    let twins = |i: usize| {
        let mut count = 0usize;
        for p in offsets[i]..offsets[i + 1] {
            let c = cols[p];
            if c >= i {
                break;
            }
            let row = &cols[offsets[c]..offsets[c + 1]];
            match row.binary_search(&i) {
                Ok(q) if (vals[offsets[c] + q] - vals[p]).abs() <= tol => count += 1,
                _ => return None,
            }
        }
        Some(count)
    };
    // A small model stays on this thread: starting rayon's pool costs more
    // than its whole run of products.
    let lower: Option<usize> = if parallel(a.nrows()) {
        (0..a.nrows()).into_par_iter().map(twins).sum()
    } else {
        (0..a.nrows()).map(twins).sum()
    };
    // Every lower entry has its upper twin; as many upper entries as
    // lower ones then means no upper entry lacks its twin.
    let upper = (0..a.nrows())
        .map(|i| {
            cols[offsets[i]..offsets[i + 1]]
                .iter()
                .filter(|&&c| c > i)
                .count()
        })
        .sum::<usize>();
    lower == Some(upper)
}

/// Chunk c's sums as a dispatched kernel (so that the fused terms are the
/// CPU's instruction).
struct Chunk<'a> {
    k: &'a Symmetric,
    c: usize,
    x: &'a [f64],
    acc: &'a mut [f64],
}

impl Kernel for Chunk<'_> {
    type Output = ();

    #[inline(always)]
    fn run<S: crate::simd::Simd>(self, _simd: S) {
        self.k.chunk_into(self.c, self.x, self.acc);
    }
}
