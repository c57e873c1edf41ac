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
//! Where the CPU's vectors hold w ≥ 4 doubles, w/2 consecutive node pairs
//! (a *unit*, typed by its groups' types) are summed as one vector of w
//! rows ([`Units`]): per block of the unit's types (the union of their
//! offsets) one load of x, a fused multiply-add with the diagonal terms,
//! and one with the other column's on x with each pair of lanes swapped.
//!
//! Each row is summed in its type's block order whatever batch or thread
//! computes it: the same bits on any number of threads. Not the bits of the
//! assembled K's product: within [`TOLERANCE`] · max |K_ij| · Σ_j |x_j| of
//! it (tests below). Declined ([`Stencils::new`] returns `None`) where the
//! types would not shrink the matrix: unstructured meshes, where nearly
//! every node is its own stencil.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use nalgebra_sparse::CsrMatrix;

use crate::chunks::{chunk_groups, each_chunk, CHUNK};
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
pub const BATCH: usize = 256;

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
    /// The units for this CPU's vectors, if they are wide enough.
    units: Option<Units>,
}

/// Units of w/2 alike-typed consecutive node pairs, summed w rows a vector.
#[derive(Clone, Debug)]
struct Units {
    /// Doubles per vector (and rows per unit).
    width: usize,
    /// Unit of the w/2 groups from group g, or [`NO_UNIT`].
    of_group: Vec<u32>,
    /// Blocks of unit u: blocks[u]..blocks[u + 1].
    blocks: Vec<u32>,
    /// Each unit block's column offset from each row's own column.
    offsets: Vec<i32>,
    /// Per unit block, two vectors of w lanes: the diagonal terms (on x
    /// at the offset) and the other column's (on x with its pairs of lanes
    /// swapped); zero where a lane's group has no such block.
    lanes: Vec<f64>,
}

/// No unit starts at this group.
const NO_UNIT: u32 = u32::MAX;

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
        Stencils::build(a, tol, (a.nnz() / 32).max(64))
    }

    /// The types at tolerance `tol`, or `None` where they would hold more
    /// blocks than `limit`.
    fn build(a: &CsrMatrix<f64>, tol: f64, limit: usize) -> Option<Stencils> {
        let n = a.nrows();
        if n < 2 || a.ncols() != n || n >= i32::MAX as usize {
            return None;
        }
        let max = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let tol = tol * max;
        let grid = if tol > 0.0 { COARSE * tol } else { f64::NAN };
        let mut index: HashMap<Vec<i64>, Vec<u32>, Keys> = HashMap::default();
        let mut key: Vec<i64> = Vec::new();
        let (mut types, mut type_blocks) = (Vec::with_capacity(n / 2 + 1), vec![0u32]);
        let (mut offsets, mut values): (Vec<i32>, Vec<[f64; 4]>) = (Vec::new(), Vec::new());
        let group_rows = row_groups(a, |r0, r1, cols, vals| {
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
                    t
                }
            };
            types.push(t);
            // Past the limit the types are declined: the rest of the rows
            // are not grouped (on an unstructured mesh, most of them).
            values.len() <= limit
        })?;
        let chunk_groups = chunk_groups(&group_rows, n);
        types.shrink_to_fit();
        let mut k = Stencils {
            group_rows,
            types,
            type_blocks,
            offsets,
            values,
            chunk_groups,
            units: None,
        };
        let width = crate::simd::lanes();
        if width >= 4 && width.is_multiple_of(2) {
            k.units = Some(k.units(width));
        }
        Some(k)
    }

    /// The units of `width` rows: one from every group that starts w/2
    /// consecutive node pairs whose every load stays inside x.
    fn units(&self, width: usize) -> Units {
        let (n, h) = (self.n(), width / 2);
        let groups = self.types.len();
        let mut index: HashMap<&[u32], u32, Keys> = HashMap::default();
        let mut u = Units {
            width,
            of_group: vec![NO_UNIT; groups],
            blocks: vec![0],
            offsets: Vec::new(),
            lanes: Vec::new(),
        };
        for g in 0..groups.saturating_sub(h - 1) {
            let r = self.group_rows[g] as usize;
            if !(1..=h).all(|q| self.group_rows[g + q] as usize == r + 2 * q) {
                continue;
            }
            let key = &self.types[g..g + h];
            let id = match index.get(key) {
                Some(&id) => id,
                None => {
                    let id = u.blocks.len() as u32 - 1;
                    self.add_unit(key, &mut u);
                    index.insert(key, id);
                    id
                }
            };
            let b = u.blocks[id as usize] as usize..u.blocks[id as usize + 1] as usize;
            let lo = u.offsets[b.clone()].iter().min().map_or(0, |&o| o as isize);
            let hi = u.offsets[b].iter().max().map_or(0, |&o| o as isize);
            if r as isize + lo >= 0 && r as isize + hi + width as isize <= n as isize {
                u.of_group[g] = id;
            }
        }
        u
    }

    /// Appends the unit of consecutive groups of types `key` to `u`: the
    /// union of their block offsets, ascending (each type's own order), and
    /// per offset the lanes of [`Units::lanes`].
    fn add_unit(&self, key: &[u32], u: &mut Units) {
        let w = u.width;
        let mut offsets: Vec<i32> = key
            .iter()
            .flat_map(|&t| self.offsets[self.type_range(t)].iter().copied())
            .collect();
        offsets.sort_unstable();
        offsets.dedup();
        for &o in &offsets {
            let mut lanes = vec![0.0; 2 * w];
            for (q, &t) in key.iter().enumerate() {
                let b = self.type_range(t);
                if let Some(k) = self.offsets[b.clone()].iter().position(|&p| p == o) {
                    let v = self.values[b.start + k];
                    // Rows 2q (first) and 2q + 1 (second) of the unit.
                    lanes[2 * q] = v[0];
                    lanes[2 * q + 1] = v[3];
                    lanes[w + 2 * q] = v[2];
                    lanes[w + 2 * q + 1] = v[1];
                }
            }
            u.offsets.push(o);
            u.lanes.extend(lanes);
        }
        u.blocks.push(u.offsets.len() as u32);
    }

    /// Blocks of type t.
    fn type_range(&self, t: u32) -> std::ops::Range<usize> {
        self.type_blocks[t as usize] as usize..self.type_blocks[t as usize + 1] as usize
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
    /// column's, added at the end, each term fused into its sum (one
    /// rounding, as the units' vectors add them): the same terms in the
    /// same order whatever Q, so the same bits, and 4Q independent chains.
    /// Four consecutive groups read one contiguous run of x per block,
    /// which the compiler keeps in vector registers.
    #[inline(always)]
    fn lockstep<const Q: usize>(&self, t: u32, rows: [usize; Q], x: &[f64]) -> [[f64; 2]; Q] {
        let b = self.type_blocks[t as usize] as usize..self.type_blocks[t as usize + 1] as usize;
        let (mut own, mut other) = ([[0.0; 2]; Q], [[0.0; 2]; Q]);
        for (&o, v) in self.offsets[b.clone()].iter().zip(&self.values[b]) {
            for q in 0..Q {
                let c = (rows[q] as isize + o as isize) as usize;
                let xs = &x[c..c + 2];
                own[q][0] = v[0].mul_add(xs[0], own[q][0]);
                own[q][1] = v[3].mul_add(xs[1], own[q][1]);
                other[q][0] = v[2].mul_add(xs[1], other[q][0]);
                other[q][1] = v[1].mul_add(xs[0], other[q][1]);
            }
        }
        std::array::from_fn(|q| [own[q][0] + other[q][0], own[q][1] + other[q][1]])
    }

    /// K x on the rows of groups g0..g1 into `out` (from g0's first row):
    /// four alike node pairs on consecutive rows in lockstep (a structured
    /// Q1 node row), or two pairs of alike pairs alternating (a Q2 node
    /// row, corner and mid-side nodes in turn), else a group at a time.
    #[inline(always)]
    fn groups_into<S: crate::simd::Simd>(
        &self,
        simd: S,
        g0: usize,
        g1: usize,
        x: &[f64],
        out: &mut [f64],
    ) {
        let base = self.group_rows[g0] as usize;
        let rows = |g: usize| self.group_rows[g] as usize;
        let units = self.units.as_ref().filter(|u| u.width == S::F64_LANES);
        let mut g = g0;
        while g < g1 {
            let r = rows(g);
            if let Some(u) = units {
                let (w, h) = (u.width, u.width / 2);
                let id = if g + h <= g1 { u.of_group[g] } else { NO_UNIT };
                if id != NO_UNIT {
                    let o = r - base;
                    // Alike units in a row share each block's loads and
                    // give the sums independent chains.
                    let alike = |q: usize| g + (q + 1) * h <= g1 && u.of_group[g + q * h] == id;
                    let q = if (1..4).all(alike) {
                        let sums = unit_sums::<S, 4>(simd, u, id, r, x);
                        store_units::<S, _>(&mut out[o..o + 4 * w], sums);
                        4
                    } else if alike(1) {
                        store_units::<S, _>(
                            &mut out[o..o + 2 * w],
                            unit_sums::<S, 2>(simd, u, id, r, x),
                        );
                        2
                    } else {
                        store_units::<S, _>(
                            &mut out[o..o + w],
                            unit_sums::<S, 1>(simd, u, id, r, x),
                        );
                        1
                    };
                    g += q * h;
                    continue;
                }
            }
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
    pub fn batches<S: crate::simd::Simd>(
        &self,
        simd: S,
        c: usize,
        x: &[f64],
        to: &mut impl Batches,
    ) {
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
            self.groups_into(simd, g, gb, x, out);
            to.batch(ra, out);
            g = gb;
        }
    }

    /// (K x)_i, with the bits the batches give it.
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        let mut out = [0.0];
        self.rows(&[i], x, &mut out);
        out[0]
    }

    /// (K x)_i for each i of `rows` into `out`, with the bits the batches
    /// give them. Rows of consecutive groups (a contact face along a node
    /// row of the grid) are summed as a batch is, in units where the
    /// CPU's vectors allow, up to [`BATCH`] rows at a time.
    pub fn rows(&self, rows: &[usize], x: &[f64], out: &mut [f64]) {
        // Dispatched, so that the fused terms are the CPU's instruction.
        struct Rows<'a>(&'a Stencils, &'a [usize], &'a [f64], &'a mut [f64]);
        impl Kernel for Rows<'_> {
            type Output = ();
            #[inline(always)]
            fn run<S: crate::simd::Simd>(self, simd: S) {
                let Rows(k, rows, x, out) = self;
                let starts = &k.group_rows;
                let group_of = |i: usize| starts.partition_point(|&r| r as usize <= i) - 1;
                let mut buf = [0.0; BATCH];
                let mut j = 0;
                while j < rows.len() {
                    // The run of groups g0..g1 from row j's group on that
                    // holds rows j..e, each in its predecessor's group or the
                    // next, within BATCH rows.
                    let g0 = group_of(rows[j]);
                    let base = starts[g0] as usize;
                    let (mut g1, mut e) = (g0 + 1, j + 1);
                    while e < rows.len() {
                        let i = rows[e];
                        if i >= base && i < starts[g1] as usize {
                            e += 1;
                        } else if g1 < starts.len() - 1
                            && i >= starts[g1] as usize
                            && i < starts[g1 + 1] as usize
                            && starts[g1 + 1] as usize - base <= BATCH
                        {
                            g1 += 1;
                            e += 1;
                        } else {
                            break;
                        }
                    }
                    let len = starts[g1] as usize - base;
                    k.groups_into(simd, g0, g1, x, &mut buf[..len]);
                    for (o, &i) in out[j..e].iter_mut().zip(&rows[j..e]) {
                        *o = buf[i - base];
                    }
                    j = e;
                }
            }
        }
        crate::simd::vectorized(Rows(self, rows, x, out));
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
    fn run<S: crate::simd::Simd>(self, simd: S) {
        self.k
            .groups_into(simd, self.g.start, self.g.end, self.x, self.out);
    }
}

/// Stores consecutive units' sums into `out` (w doubles each), in order.
#[inline(always)]
fn store_units<S: crate::simd::Simd, const Q: usize>(out: &mut [f64], sums: [S::f64s; Q]) {
    for (o, s) in out.chunks_exact_mut(S::F64_LANES).zip(sums) {
        crate::simd::store::<S>(o, s);
    }
}

/// The sums of Q consecutive units of type `id` whose first rows are r,
/// r + w, … (the caller's to ensure), in lockstep (each block's lanes
/// loaded once for all): per row its own column's terms and the other
/// column's in two fused sums, in the unit's block order, added at the
/// end, as [`Stencils::lockstep`] sums them (a lane's zero terms add ±0
/// to a sum that started at +0, which changes no bit), so the same bits
/// whatever Q. The other column's x is the own column's with each pair
/// of lanes swapped.
#[inline(always)]
fn unit_sums<S: crate::simd::Simd, const Q: usize>(
    simd: S,
    u: &Units,
    id: u32,
    r: usize,
    x: &[f64],
) -> [S::f64s; Q] {
    let w = S::F64_LANES;
    let b = u.blocks[id as usize] as usize..u.blocks[id as usize + 1] as usize;
    let load = crate::simd::load::<S>;
    let (mut own, mut other) = ([simd.splat_f64s(0.0); Q], [simd.splat_f64s(0.0); Q]);
    let lanes = u.lanes[2 * w * b.start..2 * w * b.end].chunks_exact(2 * w);
    for (&o, l) in u.offsets[b].iter().zip(lanes) {
        let (diagonal, across) = (load(&l[..w]), load(&l[w..]));
        // The Q units' x at this block, sliced once: each unit's part is
        // then at a constant offset, its bounds known at compile time.
        let c = (r as isize + o as isize) as usize;
        let xs = &x[c..c + Q * w];
        for q in 0..Q {
            let xc = load(&xs[q * w..(q + 1) * w]);
            own[q] = simd.mul_add_f64s(diagonal, xc, own[q]);
            other[q] = simd.mul_add_f64s(across, crate::simd::swap_pairs(simd, xc), other[q]);
        }
    }
    std::array::from_fn(|q| simd.add_f64s(own[q], other[q]))
}

/// Groups K's rows by node: two consecutive rows with the same columns (a
/// node's x and y rows) are one group unless a chunk seam divides them,
/// else a row is a group of its own. Calls `visit(first row, end row,
/// block columns, block values)` for each group in order, its 2×2 blocks
/// in ascending column order (a block's first column is the pair start of
/// its columns: a single DOF is padded into the block before it, the
/// padding +0; values by columns), and returns the groups' first rows,
/// then n; `None` as soon as `visit` returns false.
fn row_groups(
    a: &CsrMatrix<f64>,
    mut visit: impl FnMut(usize, usize, &[u32], &[[f64; 4]]) -> bool,
) -> Option<Vec<u32>> {
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
        if !visit(r0, r1, &block_cols, &block_vals) {
            return None;
        }
    }
    Some(group_rows)
}

/// The hash of the types' and units' keys: a multiply-rotate over 8-byte
/// words (as rustc's FxHash). SipHash, the standard map's, resists keys
/// chosen to collide, which K's stencils are not, and costs more than
/// that resistance is worth here (docs/performance.md).
#[derive(Default)]
struct KeyHasher(u64);

type Keys = BuildHasherDefault<KeyHasher>;

impl KeyHasher {
    #[inline]
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for KeyHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.add(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        for &b in words.remainder() {
            self.add(u64::from(b));
        }
    }

    #[inline]
    fn write_u64(&mut self, word: u64) {
        self.add(word);
    }

    #[inline]
    fn write_usize(&mut self, word: usize) {
        self.add(word as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}
