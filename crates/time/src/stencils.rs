//! K·x by stencil types (issue 7, the explicit step on structured meshes).
//!
//! On a structured mesh most of K's row groups (a node's two rows,
//! [`kernels::row_groups`]) are the same stencil: the same blocks at the
//! same column offsets from the group's first row, equal up to the rounding
//! of the coordinates they were assembled from (the Q1 slab of 1M DOFs has
//! 211,770 bit-distinct blocks of 4.5M, nearly all of them one of nine
//! values to 1e-13). [`Stencils`] keeps one copy of each distinct stencil
//! (a *type*: groups alike when their row count and block offsets are equal
//! and every block value is within [`TOLERANCE`] · max |K_ij| of the type's
//! first member) and per group only its type, so a product streams 8 bytes
//! per group (first row, type) instead of the blocks, and reads the blocks
//! of the few types from L1. Runs of alike node pairs are summed 4 doubles
//! wide (AVX) or, where the CPU has AVX-512, 8 wide, each term by a fused
//! multiply-add where it has FMA (on every path: the same bits): `sweep_lab`,
//! 2026-11-24, 1M DOFs, K·x Q1 1.2 → 0.95-1.0 ms, Q2 1.9 → 1.7 ms (2
//! threads, median of 20, two runs each); with four 8-row blocks in
//! lockstep ([`avx::run_512`]), 2026-11-25, Q1 0.89-0.93, Q2 1.32-1.35
//! ms. Rows are independent and each is summed in its type's block order
//! whatever batch or thread computes it: the same bits on any number of
//! threads. Not the bits of the
//! assembled K's product: within [`TOLERANCE`] · max |K_ij| · Σ_j |x_j|
//! over the row's columns of it (tests below); the classes of
//! `stickslip_fem::ElementClasses` make the same trade on Q2 meshes.
//!
//! Declined ([`Stencils::new`] returns `None`) when the types would not
//! shrink the matrix: unstructured meshes, where nearly every group is its
//! own stencil.

use std::collections::HashMap;

use nalgebra_sparse::CsrMatrix;

use crate::kernels::{self, RowProduct};

/// Block values within this fraction of max |K_ij| of a type's are the
/// type's. The committed slabs, snapped to their grid, spread by up to
/// ~1e-13 (`stencil_types_on_the_slabs`); Gmsh's own transfinite nodes
/// are off their grid lines by up to 1.4e-9 of a cell (Q1 700×175 slab),
/// and alike node rows of K then differ by up to about 1e-11: at 1e-12
/// the Q1 slab of 1M DOFs from Gmsh kept 7.4M of 303M groups a step out of
/// the 8-wide sums and stepped in 4.5 ms, at 1e-10 3.1M (as many as the
/// generator's slab) and 3.3 ms (bench_step, 2026-11-24). A product within
/// 1e-10 · max |K_ij| · Σ_j |x_j| of the assembled K's is that of nodes
/// moved by less than Gmsh's rounding moved them.
pub const TOLERANCE: f64 = 1e-10;

/// The coarse grid, in tolerances, on which a stencil's values are hashed
/// (alike stencils land in one bucket unless a value straddles a grid
/// line, which costs a type, never a wrong merge: members are compared to
/// the tolerance).
const COARSE: f64 = (1u64 << 24) as f64;

/// Rows from which the sweep forms K r_K in its own kernel: where the
/// step's vectors (7 × 8 bytes a row) outgrow the L3 (32 MB here), the
/// vectors' traffic it overlaps with the sums pays for its per-8-row
/// work; below, that work costs more (`fused_lab`, 2026-11-24, against
/// the sweep by batches, two to four runs each: Q1 1M 0.78-0.97 of its
/// time, Q2 1M 0.86-0.94; Q1 502k 0.84-0.88, Q2 501k 0.97-1.00; Q1 252k
/// 1.00-1.07, Q2 249k 1.11-1.15). With four blocks in lockstep
/// ([`avx::run_512`], both paths), 2026-11-25: Q1 1M 0.89-0.95, Q2 1M
/// 0.81-0.89 (three runs); Q1 502k 0.90-0.99, Q2 501k 0.83-0.89; Q1 252k
/// 0.94-1.00, Q2 249k 1.00-1.01 (two runs): the threshold stayed. The
/// whole step (`bench_step --case cd MESH STEPS 5`, the two thresholds
/// alternating four times, 2026-11-26 04:10, medians, batches → own
/// kernel) says otherwise at every size of several chunks: Q1 708×177
/// (252k rows) 633 → 331 µs, Q2 352×88 (249k) 744 → 485, Q1 352×88 (62k)
/// 153 → 113, Q2 176×44 (62k) 176 → 126, Q1 128×32 (8,352) 38.8 → 27.7,
/// Q2 64×16 (8,352) 49.5 → 40.8 µs; on a host busy with a build the same
/// (0.60-0.75). So every system of more than one chunk takes it (one
/// chunk forms K r_K whole first, for the friction).
const FUSED_MIN_ROWS: usize = 0;

/// Groups of one type summed in lockstep ([`Stencils::lockstep`]).
const LOCKSTEP: usize = 4;

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
    /// Each type block's values, by columns (as `kernels::block` reads them).
    values: Vec<[f64; 4]>,
    /// Groups of chunk c: chunk_groups[c]..chunk_groups[c + 1].
    chunk_groups: Vec<u32>,
    /// Units: two consecutive node pairs (rows r..r + 4, types A and B)
    /// read as one 4-row stencil, for the 4-wide sums ([`avx::units`]):
    /// each group's unit with the next group, or [`NO_UNIT`].
    unit_of: Vec<u32>,
    /// Blocks of unit u: unit_blocks[u]..unit_blocks[u + 1].
    unit_blocks: Vec<u32>,
    /// The union of A's and B's block offsets, ascending.
    unit_offsets: Vec<i32>,
    /// Per unit block, the values of rows [A 0, A 1, B 0, B 1] that
    /// multiply [x_c, x_c+1, x_c+2, x_c+3] (each row's diagonal term: the
    /// blocks' first column for row 0, the second for row 1) and those
    /// that multiply the pairs swapped, [x_c+1, x_c, x_c+3, x_c+2] (the
    /// other column); +0 where A or B has no block at the offset (s + 0·x
    /// = s: the bits of the pair's own blocks).
    unit_values: Vec<[[f64; 4]; 2]>,
    /// The unit runs the sweep's own kernel takes, found once
    /// ([`Stencils::build_units`], by [`Stencils::unit_run`] and
    /// [`Stencils::run_length`] from each chunk's first group on): per run
    /// its first group, its count of fours of groups and its unit. Chunk
    /// c's are runs[chunk_runs[c]..chunk_runs[c + 1]]. The kernel then
    /// reads nothing per group of a run (before, `unit_of` of each, a
    /// scan 6% of the Q2 1M step's samples, 2026-11-25).
    runs: Vec<[u32; 3]>,
    chunk_runs: Vec<u32>,
    /// The CPU has AVX (checked at run time): runs of two alike units are
    /// summed 4 doubles wide ([`avx::units`]), the same bits.
    avx: bool,
    /// The CPU has AVX-512: the runs are summed 8 doubles wide, two
    /// units to a register (the same bits).
    pub(crate) avx512: bool,
    /// The CPU has AVX and FMA: every term is added by a fused
    /// multiply-add, on every path (scalar, 4 and 8 wide), so that they
    /// keep giving the same bits ([`Stencils::groups_into`]).
    pub(crate) fma: bool,
    /// From this many rows the sweep forms K r_K in its own kernel
    /// ([`Stencils::sweep_chunk_512`]) where the CPU allows
    /// ([`FUSED_MIN_ROWS`]; tests and labs set 0 or `usize::MAX`).
    pub(crate) fused_min_rows: usize,
}

/// [`Stencils::unit_of`] of a group that starts no unit.
const NO_UNIT: u32 = u32::MAX;

impl Stencils {
    /// The stencil types of a square CSR matrix with sorted columns at
    /// [`TOLERANCE`], or `None` when they do not cut the bytes a product
    /// streams from the matrix by at least 4× against its blocks stored.
    pub fn new(a: &CsrMatrix<f64>) -> Option<Stencils> {
        Stencils::with_tolerance(a, TOLERANCE)
    }

    /// [`Stencils::new`] at tolerance `tol` (relative to max |K_ij|; 0:
    /// equal bits only).
    pub fn with_tolerance(a: &CsrMatrix<f64>, tol: f64) -> Option<Stencils> {
        // Types may hold at most 1/8 of the stored blocks (36 bytes each
        // with the offset): then the types and the 8 bytes per group are
        // at most about a quarter of the stored form's stream.
        Stencils::build(a, tol, (a.nnz() / 32).max(64))
    }

    /// The types at tolerance `tol`, `None` past `limit` type blocks.
    fn build(a: &CsrMatrix<f64>, tol: f64, limit: usize) -> Option<Stencils> {
        let n = a.nrows();
        if n < 2 || a.ncols() != n || n >= i32::MAX as usize {
            return None;
        }
        let max = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let tol = tol * max;
        let grid = if tol > 0.0 { COARSE * tol } else { f64::NAN };
        let mut index: HashMap<Vec<i64>, Vec<u32>> = HashMap::new();
        let mut key: Vec<i64> = Vec::new();
        let (mut types, mut type_blocks) = (Vec::with_capacity(n / 2 + 1), vec![0u32]);
        let (mut offsets, mut values): (Vec<i32>, Vec<[f64; 4]>) = (Vec::new(), Vec::new());
        let mut declined = false;
        let group_rows = kernels::row_groups(a, |r0, r1, cols, vals| {
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
        let chunk_groups = kernels::chunk_groups(&group_rows, n);
        types.shrink_to_fit();
        let mut stencils = Stencils {
            group_rows,
            types,
            type_blocks,
            offsets,
            values,
            chunk_groups,
            unit_of: Vec::new(),
            unit_blocks: vec![0],
            unit_offsets: Vec::new(),
            unit_values: Vec::new(),
            runs: Vec::new(),
            chunk_runs: vec![0],
            avx: avx::available(),
            avx512: avx::available() && avx::available_512(),
            fma: avx::available() && kernels::fma(),
            fused_min_rows: FUSED_MIN_ROWS,
        };
        if stencils.avx {
            stencils.build_units();
        }
        Some(stencils)
    }

    /// The units of consecutive node pairs (see [`Stencils::unit_of`]).
    fn build_units(&mut self) {
        let groups = self.types.len();
        let mut index: HashMap<(u32, u32), u32> = HashMap::new();
        let mut unit_of = vec![NO_UNIT; groups];
        let (mut blocks, mut offsets, mut values) = (vec![0u32], Vec::new(), Vec::new());
        for g in 0..groups.saturating_sub(1) {
            let r = self.group_rows[g];
            if self.group_rows[g + 1] != r + 2 || self.group_rows[g + 2] != r + 4 {
                continue;
            }
            let key = (self.types[g], self.types[g + 1]);
            let next = (blocks.len() - 1) as u32;
            let u = *index.entry(key).or_insert(next);
            if u == next {
                let ((oa, va), (ob, vb)) = (self.stencil(key.0), self.stencil(key.1));
                let (mut i, mut j) = (0, 0);
                while i < oa.len() || j < ob.len() {
                    let o = match (oa.get(i), ob.get(j)) {
                        (Some(&a), Some(&b)) => a.min(b),
                        (Some(&a), None) => a,
                        (None, Some(&b)) => b,
                        (None, None) => unreachable!(),
                    };
                    let mut a = [0.0; 4];
                    let mut b = [0.0; 4];
                    if oa.get(i) == Some(&o) {
                        a = va[i];
                        i += 1;
                    }
                    if ob.get(j) == Some(&o) {
                        b = vb[j];
                        j += 1;
                    }
                    offsets.push(o);
                    // Blocks by columns: [K00, K10, K01, K11].
                    values.push([[a[0], a[3], b[0], b[3]], [a[2], a[1], b[2], b[1]]]);
                }
                blocks.push(offsets.len() as u32);
            }
            unit_of[g] = u;
        }
        (self.unit_of, self.unit_blocks) = (unit_of, blocks);
        (self.unit_offsets, self.unit_values) = (offsets, values);
        let n = *self.group_rows.last().expect("then n") as usize;
        for c in 0..self.chunk_groups.len() - 1 {
            let (g0, g1) = (
                self.chunk_groups[c] as usize,
                self.chunk_groups[c + 1] as usize,
            );
            let mut g = g0;
            while g < g1 {
                match self.unit_run(g, g1, n) {
                    Some(b) => {
                        let count = self.run_length(g, g1, &b, n);
                        self.runs.push([g as u32, count as u32, self.unit_of[g]]);
                        g += 4 * count;
                    }
                    None => g += 1,
                }
            }
            self.chunk_runs.push(self.runs.len() as u32);
        }
        self.runs.shrink_to_fit();
    }

    /// Whether the sweep over `n` rows forms K r_K in its own kernel
    /// ([`Stencils::sweep_chunk_512`]).
    fn fused(&self, n: usize) -> bool {
        n >= self.fused_min_rows && self.avx512 && self.fma && kernels::avx2()
    }

    /// The sweep of chunk `c` with its per-row work on each 8 rows of a
    /// unit run as soon as their K r_K is in a register
    /// ([`kernels::Rows8::eight`] for runs with no load or friction row,
    /// else [`kernels::SweepRows::eight`]), so that their vectors' loads and
    /// stores issue while the next rows' sums run, instead of K r_K of a
    /// 64-row batch into L1 and then the batch's rows (from
    /// [`FUSED_MIN_ROWS`], which has the figures). K r_K has the bits of
    /// [`Stencils::groups_into`] (the same operations per row) and the
    /// rows the bits of [`kernels::batch_rows`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    #[allow(unsafe_code)]
    fn sweep_chunk_512(&self, c: usize, rows: &mut kernels::SweepRows) {
        let (g0, g1) = (
            self.chunk_groups[c] as usize,
            self.chunk_groups[c + 1] as usize,
        );
        let x = rows.x();
        let mut g = g0;
        let runs = &self.runs[self.chunk_runs[c] as usize..self.chunk_runs[c + 1] as usize];
        for &[first, count, u] in runs.iter().chain([&[g1 as u32, 0, NO_UNIT]]) {
            // The groups before the run (a node row's ends, chunk seams):
            // their sums one group at a time, their rows up to 8 at once.
            while g < first as usize {
                let r0 = self.group_rows[g] as usize;
                let mut ku = [0.0; 8];
                while g < first as usize && self.group_rows[g + 1] as usize - r0 <= 8 {
                    let sums = self.group_sums::<true>(g, x);
                    let (a, b) = (self.group_rows[g] as usize, self.group_rows[g + 1] as usize);
                    // Element by element: a copy of one or two doubles
                    // was a call of memcpy.
                    ku[a - r0] = sums[0];
                    if b - a == 2 {
                        ku[a - r0 + 1] = sums[1];
                    }
                    g += 1;
                }
                let len = self.group_rows[g] as usize - r0;
                // SAFETY: this function's features.
                unsafe { rows.few(r0, &ku[..len]) };
            }
            if u == NO_UNIT {
                break;
            }
            let b =
                self.unit_blocks[u as usize] as usize..self.unit_blocks[u as usize + 1] as usize;
            let (offsets, values) = (&self.unit_offsets[b.clone()], &self.unit_values[b]);
            let r = self.group_rows[g] as usize;
            let count = count as usize;
            // SAFETY: this function's features; the run's rows are in
            // chunk c (`build_units`), and plain where `Plain` takes them.
            unsafe {
                if rows.plain(r, r + 8 * count) {
                    let eight = rows.rows8();
                    avx::run_512::<true>(
                        offsets,
                        values,
                        r,
                        count,
                        x,
                        &mut avx::Plain { rows, eight },
                    );
                } else {
                    avx::run_512::<true>(offsets, values, r, count, x, rows);
                }
            }
            g += 4 * count;
        }
    }

    /// The group that holds row i.
    fn group_of(&self, i: usize) -> usize {
        self.group_rows.partition_point(|&r| r as usize <= i) - 1
    }

    /// Type t's blocks: offsets and values.
    #[inline(always)]
    fn stencil(&self, t: u32) -> (&[i32], &[[f64; 4]]) {
        let b = self.type_blocks[t as usize] as usize..self.type_blocks[t as usize + 1] as usize;
        (&self.offsets[b.clone()], &self.values[b])
    }

    /// Distinct stencils.
    pub fn types(&self) -> usize {
        self.type_blocks.len() - 1
    }

    /// The sums of group g's rows (the second is 0 for a single row).
    #[inline(always)]
    fn group_sums<const F: bool>(&self, g: usize, x: &[f64]) -> [f64; 2] {
        self.lockstep::<1, F>(g, x)[0]
    }

    /// G groups of one type in lockstep, the type's blocks loaded once
    /// for all. Each row in two partial sums, the blocks' first columns'
    /// terms and their second columns', added at the end ([`split_block`]):
    /// 4G independent chains of additions (one chain per row would wait on
    /// the adder's latency); the order every kernel here keeps.
    #[inline(always)]
    fn lockstep<const G: usize, const F: bool>(&self, g: usize, x: &[f64]) -> [[f64; 2]; G] {
        let r: [isize; G] = std::array::from_fn(|q| self.group_rows[g + q] as isize);
        let (offsets, values) = self.stencil(self.types[g]);
        let mut s = [[[0.0; 2]; 2]; G];
        for (&o, v) in offsets.iter().zip(values) {
            let o = o as isize;
            for q in 0..G {
                split_block::<F>((r[q] + o) as usize, v, x, &mut s[q]);
            }
        }
        s.map(|[lo, hi]| [lo[0] + hi[0], lo[1] + hi[1]])
    }

    /// The blocks of the unit that groups g..g + 4 (below g1) form twice,
    /// when they do and its padded lanes read inside x (of length n; near
    /// the first and last rows they may not); `None` otherwise.
    #[inline(always)]
    fn unit_run(&self, g: usize, g1: usize, n: usize) -> Option<std::ops::Range<usize>> {
        let u = *self.unit_of.get(g)?;
        if u == NO_UNIT || g + 4 > g1 || self.unit_of[g + 2] != u {
            return None;
        }
        let b = self.unit_blocks[u as usize] as usize..self.unit_blocks[u as usize + 1] as usize;
        let r = self.group_rows[g] as isize;
        let inside = !b.is_empty()
            && r + self.unit_offsets[b.start] as isize >= 0
            && r + self.unit_offsets[b.end - 1] as isize + 8 <= n as isize;
        inside.then_some(b)
    }

    /// How many fours of groups from g (below g1) hold the unit of
    /// [`Stencils::unit_run`]'s blocks `b` (their 8 rows each follow on:
    /// `build_units`) with their padded lanes inside x (of length n).
    #[inline(always)]
    fn run_length(&self, g: usize, g1: usize, b: &std::ops::Range<usize>, n: usize) -> usize {
        let (u, r) = (self.unit_of[g], self.group_rows[g] as usize);
        let last = self.unit_offsets[b.end - 1] as isize;
        let mut count = 1;
        while self.unit_run_continues(g + 4 * count, g1, u)
            && (r + 8 * (count + 1)) as isize + last <= n as isize
        {
            count += 1;
        }
        count
    }

    /// Whether groups g..g + 4 (below g1) are two units `u` again (their
    /// rows follow the previous four's).
    #[inline(always)]
    fn unit_run_continues(&self, g: usize, g1: usize, u: u32) -> bool {
        g + 4 <= g1 && self.unit_of[g] == u && self.unit_of[g + 2] == u
    }

    /// K x on the rows of groups g0..g1 into `out` (from g0's first row),
    /// by fused multiply-adds where the CPU has them: half the
    /// arithmetic instructions of a product and a sum, which bound the
    /// 8-wide sums of Q2 node rows (`kx_lab`, 2026-11-24, 1M DOFs, 2
    /// threads, fused and unfused alternating in one process, three runs:
    /// K·x 0.89-0.95 of the unfused time on Q2, 0.92-0.96 on Q1; about
    /// 1.45 against 1.6 ms on Q2), and one rounding per term instead of
    /// two.
    #[inline(always)]
    fn groups_into(&self, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` only where the CPU has AVX and FMA.
            #[allow(unsafe_code)]
            unsafe {
                self.groups_into_fma(g0, g1, x, out)
            };
            return;
        }
        self.groups_into_with::<false>(g0, g1, x, out);
    }

    /// [`Stencils::groups_into`] compiled for FMA: `f64::mul_add` in the
    /// scalar sums becomes one instruction, the same bits as the vector
    /// lanes' (both round once).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,fma")]
    #[allow(unsafe_code)]
    fn groups_into_fma(&self, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        self.groups_into_with::<true>(g0, g1, x, out);
    }

    /// One group's sums ([`Stencils::group_sums`]) by the same operations
    /// as [`Stencils::groups_into`]'s.
    fn sums_of(&self, g: usize, x: &[f64]) -> [f64; 2] {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` only where the CPU has AVX and FMA.
            #[allow(unsafe_code)]
            return unsafe { self.sums_fma(g, x) };
        }
        self.group_sums::<false>(g, x)
    }

    /// [`Stencils::sums_of`] compiled for FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,fma")]
    #[allow(unsafe_code)]
    fn sums_fma(&self, g: usize, x: &[f64]) -> [f64; 2] {
        self.group_sums::<true>(g, x)
    }

    /// [`Stencils::groups_into`], fused (`F`) or not.
    #[inline(always)]
    fn groups_into_with<const F: bool>(&self, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        let base = self.group_rows[g0] as usize;
        let put = |out: &mut [f64], g: usize, s: [f64; 2]| {
            let (r0, r1) = (self.group_rows[g] as usize, self.group_rows[g + 1] as usize);
            out[r0 - base] = s[0];
            if r1 - r0 == 2 {
                out[r0 + 1 - base] = s[1];
            }
        };
        let mut g = g0;
        while g < g1 {
            let t = self.types[g];
            let alike = |k: usize| g + k <= g1 && self.types[g + 1..g + k].iter().all(|&u| u == t);
            if let Some(b) = self.unit_run(g, g1, x.len()) {
                // Two alike units on consecutive rows: four node pairs of
                // one type (Q1) or of two types in turn (a Q2 node row),
                // and as many more fours after them as hold the same unit
                // (their 8 rows each follow on: `build_units`).
                let r = self.group_rows[g] as usize;
                let count = self.run_length(g, g1, &b, x.len());
                let run = &mut out[r - base..r - base + 8 * count];
                let (o, v) = (&self.unit_offsets[b.clone()], &self.unit_values[b]);
                avx::units::<F>(self.avx512, o, v, r, x, run);
                g += 4 * count;
            } else if alike(LOCKSTEP) {
                for (q, s) in self.lockstep::<LOCKSTEP, F>(g, x).into_iter().enumerate() {
                    put(out, g + q, s);
                }
                g += LOCKSTEP;
            } else {
                put(out, g, self.group_sums::<F>(g, x));
                g += 1;
            }
        }
    }
}

/// One 2×2 block (by columns) at column c into a pair's partial sums:
/// s[0] the first column's terms of rows 0 and 1, s[1] the second's; by
/// fused multiply-adds with `F` (call it so only from code compiled for
/// FMA, where `mul_add` is one instruction, not a library call).
#[inline(always)]
fn split_block<const F: bool>(c: usize, v: &[f64; 4], x: &[f64], s: &mut [[f64; 2]; 2]) {
    let xs = &x[c..c + 2];
    if F {
        s[0][0] = v[0].mul_add(xs[0], s[0][0]);
        s[0][1] = v[1].mul_add(xs[0], s[0][1]);
        s[1][0] = v[2].mul_add(xs[1], s[1][0]);
        s[1][1] = v[3].mul_add(xs[1], s[1][1]);
    } else {
        s[0][0] += v[0] * xs[0];
        s[0][1] += v[1] * xs[0];
        s[1][0] += v[2] * xs[1];
        s[1][1] += v[3] * xs[1];
    }
}

/// The 4-wide sums of two units of consecutive node pairs.
mod avx {
    /// Whether this CPU runs [`units`] (it has AVX).
    pub(super) use crate::kernels::avx as available;

    /// Whether this CPU has AVX-512 (foundation) for `units(true, ..)`.
    pub(super) use crate::kernels::avx512 as available_512;

    /// The sums of rows r..r + out.len() (a multiple of 8) into `out`:
    /// per 8 rows, the node pairs at rows r, r + 2 (one unit: blocks at
    /// `offsets` with `values`) and r + 4, r + 6 (the same unit), each
    /// row's products in two partial sums, its diagonal terms and its
    /// other column's, added at the end: per row the scalar kernel's two
    /// partial sums (`split_block`: first and second columns' terms) in
    /// the same order, and a + b = b + a, so the same bits.
    /// Each term by a fused multiply-add with `F` (the scalar kernel's
    /// then), else a product and a sum. Call only where [`available`]
    /// said yes (`Stencils::unit_of` is empty otherwise), with `wide` (8
    /// doubles a register: AVX-512) only where [`available_512`] did, and
    /// with `F` only where the CPU has FMA.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn units<const F: bool>(
        wide: bool,
        offsets: &[i32],
        values: &[[[f64; 4]; 2]],
        r: usize,
        x: &[f64],
        out: &mut [f64],
    ) {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: units exist only where `available()` said yes
            // (`Stencils::build_units`), `wide` only where
            // `available_512()` did, `F` only where the CPU has FMA.
            match (wide, F) {
                (true, true) => unsafe { units_avx512_fma(offsets, values, r, x, out) },
                (true, false) => unsafe { units_avx512(offsets, values, r, x, out) },
                (false, true) => unsafe { units_avx_fma(offsets, values, r, x, out) },
                (false, false) => unsafe { units_avx(offsets, values, r, x, out) },
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (wide, offsets, values, r, x, out);
            unreachable!("AVX is x86_64 only")
        }
    }

    /// [`units`] 8 wide with fused multiply-adds ([`body_512`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,fma")]
    #[allow(unsafe_code)]
    fn units_avx512_fma(o: &[i32], v: &[[[f64; 4]; 2]], r: usize, x: &[f64], out: &mut [f64]) {
        // SAFETY: this function's features are the body's.
        unsafe { body_512::<true>(o, v, r, x, out) }
    }

    /// [`units`] 8 wide, products and sums ([`body_512`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[allow(unsafe_code)]
    fn units_avx512(o: &[i32], v: &[[[f64; 4]; 2]], r: usize, x: &[f64], out: &mut [f64]) {
        // SAFETY: this function's features are the body's.
        unsafe { body_512::<false>(o, v, r, x, out) }
    }

    /// [`units`] 4 wide with fused multiply-adds ([`body_256`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,fma")]
    #[allow(unsafe_code)]
    fn units_avx_fma(o: &[i32], v: &[[[f64; 4]; 2]], r: usize, x: &[f64], out: &mut [f64]) {
        // SAFETY: this function's features are the body's.
        unsafe { body_256::<true>(o, v, r, x, out) }
    }

    /// [`units`] 4 wide, products and sums ([`body_256`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[allow(unsafe_code)]
    fn units_avx(o: &[i32], v: &[[[f64; 4]; 2]], r: usize, x: &[f64], out: &mut [f64]) {
        // SAFETY: this function's features are the body's.
        unsafe { body_256::<false>(o, v, r, x, out) }
    }

    /// acc + a·b, fused with `F`.
    ///
    /// # Safety
    /// The CPU has AVX-512 (and FMA with `F`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn term_512<const F: bool>(
        acc: std::arch::x86_64::__m512d,
        a: std::arch::x86_64::__m512d,
        b: std::arch::x86_64::__m512d,
    ) -> std::arch::x86_64::__m512d {
        use std::arch::x86_64::*;
        // SAFETY: the caller's.
        unsafe {
            if F {
                _mm512_fmadd_pd(a, b, acc)
            } else {
                _mm512_add_pd(acc, _mm512_mul_pd(a, b))
            }
        }
    }

    /// acc + a·b, fused with `F`.
    ///
    /// # Safety
    /// The CPU has AVX (and FMA with `F`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn term_256<const F: bool>(
        acc: std::arch::x86_64::__m256d,
        a: std::arch::x86_64::__m256d,
        b: std::arch::x86_64::__m256d,
    ) -> std::arch::x86_64::__m256d {
        use std::arch::x86_64::*;
        // SAFETY: the caller's.
        unsafe {
            if F {
                _mm256_fmadd_pd(a, b, acc)
            } else {
                _mm256_add_pd(acc, _mm256_mul_pd(a, b))
            }
        }
    }

    /// [`units`] 8 wide: the 8 rows of two units in one register each for
    /// the diagonal and the other terms, into `out`.
    /// Inlined into the callers above, which give it their features.
    ///
    /// # Safety
    /// The CPU has AVX-512 (and FMA with `F`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn body_512<const F: bool>(
        offsets: &[i32],
        values: &[[[f64; 4]; 2]],
        r: usize,
        x: &[f64],
        out: &mut [f64],
    ) {
        let blocks = out.len() / 8;
        // SAFETY: the caller's features; out holds 8 doubles from row - r
        // for each of the blocks' rows.
        unsafe { run_512::<F>(offsets, values, r, blocks, x, &mut Stored { r, out }) }
    }

    /// Where [`run_512`] hands each block's sums: a trait with an
    /// always-inlined method, not a closure, which the compiler left as a
    /// call per block (40% of the Q2 1M step's samples, 2026-11-25).
    #[cfg(target_arch = "x86_64")]
    pub(super) trait Sink {
        /// What the sink keeps in registers over a run.
        type Regs: Copy;
        /// A run's blocks from `row` on are coming.
        ///
        /// # Safety
        /// As for [`Sink::put`].
        #[allow(unsafe_code)]
        unsafe fn begin(&mut self, row: usize) -> Self::Regs;
        /// Rows row..row + 8 sum to `sum`.
        ///
        /// # Safety
        /// The CPU has AVX-512 (foundation), and AVX2 for the sweep's rows
        /// ([`crate::kernels::SweepRows::eight`]).
        #[allow(unsafe_code)]
        unsafe fn put(
            &mut self,
            regs: &mut Self::Regs,
            row: usize,
            sum: std::arch::x86_64::__m512d,
        );
        /// The run is over.
        ///
        /// # Safety
        /// As for [`Sink::put`].
        #[allow(unsafe_code)]
        unsafe fn end(&mut self, regs: Self::Regs);
    }

    /// The sweep's sink for a run with no load or friction row: each
    /// block's rows by [`crate::kernels::Rows8::eight`] from operands
    /// held over the run.
    #[cfg(target_arch = "x86_64")]
    pub(super) struct Plain<'r, 'a, 'b> {
        pub rows: &'r mut crate::kernels::SweepRows<'a, 'b>,
        pub eight: crate::kernels::Rows8,
    }

    #[cfg(target_arch = "x86_64")]
    impl Sink for Plain<'_, '_, '_> {
        type Regs = crate::kernels::SumRegs;
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn begin(&mut self, row: usize) -> Self::Regs {
            // SAFETY: the caller's features.
            unsafe { self.rows.begin_sums(row) }
        }
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn end(&mut self, regs: Self::Regs) {
            // SAFETY: the caller's features.
            unsafe { self.rows.end_sums(regs) }
        }
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn put(
            &mut self,
            regs: &mut Self::Regs,
            row: usize,
            sum: std::arch::x86_64::__m512d,
        ) {
            // SAFETY: the caller's features; the run's rows are plain
            // rows of the chunk `eight` came from.
            unsafe { self.eight.eight(regs, row, sum) };
        }
    }

    /// [`body_512`]'s sink: the sums stored into `out` from row r.
    #[cfg(target_arch = "x86_64")]
    struct Stored<'o> {
        r: usize,
        out: &'o mut [f64],
    }

    #[cfg(target_arch = "x86_64")]
    impl Sink for Stored<'_> {
        type Regs = ();
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn begin(&mut self, _row: usize) {}
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn end(&mut self, _regs: ()) {}
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn put(&mut self, _regs: &mut (), row: usize, sum: std::arch::x86_64::__m512d) {
            let o = &mut self.out[row - self.r..row - self.r + 8];
            // SAFETY: the caller's features; o holds 8 doubles.
            unsafe { std::arch::x86_64::_mm512_storeu_pd(o.as_mut_ptr(), sum) };
        }
    }

    #[cfg(target_arch = "x86_64")]
    impl Sink for crate::kernels::SweepRows<'_, '_> {
        type Regs = crate::kernels::SumRegs;
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn begin(&mut self, row: usize) -> Self::Regs {
            // SAFETY: the caller's features.
            unsafe { self.begin_sums(row) }
        }
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn end(&mut self, regs: Self::Regs) {
            // SAFETY: the caller's features.
            unsafe { self.end_sums(regs) }
        }
        #[inline(always)]
        #[allow(unsafe_code)]
        unsafe fn put(
            &mut self,
            regs: &mut Self::Regs,
            row: usize,
            sum: std::arch::x86_64::__m512d,
        ) {
            // SAFETY: the caller's features.
            unsafe { self.eight(regs, row, sum) };
        }
    }

    /// The sums of rows r..r + 8 `blocks` of a run of one unit (8 rows a
    /// block, as [`body_512`] reads them), each block's handed to `f` with
    /// its first row, in row order: four blocks in lockstep, then two,
    /// then one, so that each value's broadcast serves four blocks' terms
    /// (2026-11-25, 1M DOFs, the fused sweep of `fused_lab`'s data, the
    /// variants alternating in one process, 2 threads, medians of 30:
    /// against one block at a time, two took 0.86-0.90 of its time on Q2
    /// and 0.92-1.02 on Q1 (four runs); against two, four took 0.91-0.95
    /// on Q2 and 0.95-0.97 on Q1 (three runs); eight against four
    /// 0.96-1.02 on both (two runs)). Each row's terms are summed in the
    /// same order whatever the lockstep: the same bits.
    ///
    /// # Safety
    /// The CPU has AVX-512 (and FMA with `F`) and what `f`'s
    /// [`Sink::put`] needs.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(super) unsafe fn run_512<const F: bool>(
        offsets: &[i32],
        values: &[[[f64; 4]; 2]],
        r: usize,
        blocks: usize,
        x: &[f64],
        f: &mut impl Sink,
    ) {
        let mut j = 0;
        // SAFETY (each block): the caller's.
        let mut regs = unsafe { f.begin(r) };
        while j + 4 <= blocks {
            let sums = unsafe { lockstep_512::<F, 4>(offsets, values, r + 8 * j, x) };
            for (q, sum) in sums.into_iter().enumerate() {
                unsafe { f.put(&mut regs, r + 8 * (j + q), sum) };
            }
            j += 4;
        }
        if j + 2 <= blocks {
            let sums = unsafe { lockstep_512::<F, 2>(offsets, values, r + 8 * j, x) };
            for (q, sum) in sums.into_iter().enumerate() {
                unsafe { f.put(&mut regs, r + 8 * (j + q), sum) };
            }
            j += 2;
        }
        if j < blocks {
            let [sum] = unsafe { lockstep_512::<F, 1>(offsets, values, r + 8 * j, x) };
            unsafe { f.put(&mut regs, r + 8 * j, sum) };
        }
        unsafe { f.end(regs) };
    }

    /// The sums of N blocks of 8 rows from row r ([`run_512`]): per
    /// block, the diagonal and the other terms in one register each, x in
    /// one load and its pairs swapped in one shuffle.
    ///
    /// # Safety
    /// The CPU has AVX-512 (and FMA with `F`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn lockstep_512<const F: bool, const N: usize>(
        offsets: &[i32],
        values: &[[[f64; 4]; 2]],
        r: usize,
        x: &[f64],
    ) -> [std::arch::x86_64::__m512d; N] {
        use std::arch::x86_64::*;
        // SAFETY (every block below): the caller's features; v holds 8
        // doubles, xs 8 N (unaligned loads).
        let mut d = [unsafe { _mm512_setzero_pd() }; N];
        let mut o = d;
        for (&off, v) in offsets.iter().zip(values) {
            let c = (r as isize + off as isize) as usize;
            let xs = &x[c..c + 8 * N];
            unsafe {
                let vd = _mm512_broadcast_f64x4(_mm256_loadu_pd(v[0].as_ptr()));
                let vo = _mm512_broadcast_f64x4(_mm256_loadu_pd(v[1].as_ptr()));
                for q in 0..N {
                    let xv = _mm512_loadu_pd(xs.as_ptr().add(8 * q));
                    d[q] = term_512::<F>(d[q], vd, xv);
                    let swapped = _mm512_permute_pd::<0b0101_0101>(xv);
                    o[q] = term_512::<F>(o[q], vo, swapped);
                }
            }
        }
        // SAFETY: the caller's features.
        std::array::from_fn(|q| unsafe { _mm512_add_pd(d[q], o[q]) })
    }

    /// [`units`] 4 wide: a unit's four rows in one register each for the
    /// diagonal and the other terms, x[c..c + 4] in one load and its pairs
    /// swapped in one shuffle. Inlined into the callers above.
    ///
    /// # Safety
    /// The CPU has AVX (and FMA with `F`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn body_256<const F: bool>(
        offsets: &[i32],
        values: &[[[f64; 4]; 2]],
        r: usize,
        x: &[f64],
        out: &mut [f64],
    ) {
        use std::arch::x86_64::*;
        for (j, out) in out.chunks_exact_mut(8).enumerate() {
            let rj = (r + 8 * j) as isize;
            // SAFETY (every block below): the caller's features; xs and v
            // hold 8 doubles each (unaligned loads), out 8.
            let mut d = [unsafe { _mm256_setzero_pd() }; 2];
            let mut o = d;
            for (&off, v) in offsets.iter().zip(values) {
                let c = (rj + off as isize) as usize;
                let xs: &[f64; 8] = x[c..c + 8].try_into().expect("8 columns");
                unsafe {
                    let (xa, xb) = (
                        _mm256_loadu_pd(xs.as_ptr()),
                        _mm256_loadu_pd(xs.as_ptr().add(4)),
                    );
                    let (vd, vo) = (
                        _mm256_loadu_pd(v[0].as_ptr()),
                        _mm256_loadu_pd(v[1].as_ptr()),
                    );
                    for (h, xh) in [xa, xb].into_iter().enumerate() {
                        d[h] = term_256::<F>(d[h], vd, xh);
                        let swapped = _mm256_permute_pd::<0b0101>(xh);
                        o[h] = term_256::<F>(o[h], vo, swapped);
                    }
                }
            }
            unsafe {
                _mm256_storeu_pd(out.as_mut_ptr(), _mm256_add_pd(d[0], o[0]));
                _mm256_storeu_pd(out.as_mut_ptr().add(4), _mm256_add_pd(d[1], o[1]));
            }
        }
    }
}

impl RowProduct for Stencils {
    #[inline]
    fn chunk_batches(&self, c: usize, x: &[f64], f: impl FnMut(usize, &[f64])) {
        let sums = |g: usize, gb: usize, out: &mut [f64]| self.groups_into(g, gb, x, out);
        kernels::group_batches(&self.chunk_groups, &self.group_rows, c, sums, f);
    }

    fn row(&self, i: usize, x: &[f64]) -> f64 {
        let g = self.group_of(i);
        let s = self.sums_of(g, x);
        if i == self.group_rows[g] as usize {
            s[0]
        } else {
            s[1]
        }
    }

    /// Where rows follow on over whole groups (a contact surface numbered
    /// along a grid line), those groups' rows at once by
    /// [`Stencils::groups_into`] (vector-wide); elsewhere a group's sums
    /// once for its rows. The same bits as [`Stencils::row`].
    fn rows_at(&self, rows: &[usize], x: &[f64], out: &mut [f64]) {
        let mut k = 0;
        while k < rows.len() {
            let i = rows[k];
            let g = self.group_of(i);
            let r0 = self.group_rows[g] as usize;
            // Rows i, i + 1, … of `rows` from k.
            let on = rows[k..]
                .iter()
                .enumerate()
                .take_while(|&(m, &r)| r == i + m)
                .count();
            if i == r0 {
                // The whole groups g..g1 among them.
                let end = i + on;
                let g1 = g + self.group_rows[g..].partition_point(|&r| r as usize <= end) - 1;
                let r1 = self.group_rows[g1] as usize;
                if g1 > g + 1 {
                    self.groups_into(g, g1, x, &mut out[k..k + r1 - r0]);
                    k += r1 - r0;
                    continue;
                }
            }
            let s = self.sums_of(g, x);
            let r1 = self.group_rows[g + 1] as usize;
            while k < rows.len() && (r0..r1).contains(&rows[k]) {
                out[k] = s[rows[k] - r0];
                k += 1;
            }
        }
    }

    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        kernels::each_chunk(y, |c, y| {
            let (g0, g1) = (
                self.chunk_groups[c] as usize,
                self.chunk_groups[c + 1] as usize,
            );
            self.groups_into(g0, g1, x, y);
        });
    }

    fn sweep_chunk(&self, c: usize, rows: &mut kernels::SweepRows) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.fused(rows.x().len()) {
            // SAFETY: AVX-512, AVX2 and FMA, as the CPU reported them.
            #[allow(unsafe_code)]
            unsafe {
                self.sweep_chunk_512(c, rows)
            };
            return true;
        }
        let _ = (c, rows);
        false
    }

    /// Where the sweep's own kernel runs, the runs, the groups outside
    /// them (first row and type each) and the stencils; else [`bytes`].
    ///
    /// [`bytes`]: RowProduct::bytes
    fn sweep_bytes(&self, n: usize) -> usize {
        if !self.fused(n) {
            return self.bytes();
        }
        let in_runs: usize = self.runs.iter().map(|r| 4 * r[1] as usize).sum();
        4 * (3 * self.runs.len() + self.chunk_runs.len() + self.chunk_groups.len())
            + 8 * (self.types.len() - in_runs)
            + 4 * (self.type_blocks.len() + self.unit_blocks.len())
            + 36 * self.values.len()
            + 68 * self.unit_values.len()
    }

    fn bytes(&self) -> usize {
        4 * (self.group_rows.len() + self.types.len() + self.chunk_groups.len())
            + 4 * (self.type_blocks.len() + self.unit_of.len() + self.unit_blocks.len())
            + 36 * self.values.len()
            + 68 * self.unit_values.len()
            + 4 * (3 * self.runs.len() + self.chunk_runs.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::spmv;
    use crate::kernels::tests::x_of;
    use stickslip_fem::testing::on_threads;
    use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
    use stickslip_mesh::Mesh;

    /// Every row within TOLERANCE · max|K| · Σ_j |x_j| (its columns) of the
    /// CSR's product, and the rows alone and on two threads the same bits.
    fn check(k: &CsrMatrix<f64>, s: &Stencils, name: &str) {
        let n = k.nrows();
        let x = x_of(n);
        let mut y0 = vec![0.0; n];
        spmv(k, &x, &mut y0);
        let max = k.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let (o, c) = (k.row_offsets(), k.col_indices());
        let mut y1 = vec![0.0; n];
        on_threads(1, || s.spmv(&x, &mut y1));
        let mut y2 = vec![0.0; n];
        on_threads(2, || s.spmv(&x, &mut y2));
        let mut y3 = vec![0.0; n];
        on_threads(2, || {
            kernels::each_chunk(&mut y3, |ch, y| {
                s.chunk_batches(ch, &x, |r0, ku| {
                    y[r0 - ch * kernels::CHUNK..][..ku.len()].copy_from_slice(ku)
                })
            })
        });
        for i in 0..n {
            // A block of a single-DOF column reads its neighbour too.
            let xs: f64 = (o[i]..o[i + 1])
                .flat_map(|p| (c[p].saturating_sub(1)..(c[p] + 2).min(n)).map(|j| x[j].abs()))
                .sum();
            // Rounding of the sums themselves: ~25 terms.
            let bound = TOLERANCE * max * xs + 64.0 * f64::EPSILON * max * xs;
            assert!(
                (y0[i] - y1[i]).abs() <= bound,
                "{name} row {i}: {} vs {} (bound {bound:.2e})",
                y1[i],
                y0[i]
            );
            assert_eq!(y1[i].to_bits(), y2[i].to_bits(), "{name} row {i} threads");
            assert_eq!(y1[i].to_bits(), y3[i].to_bits(), "{name} row {i} batches");
            assert_eq!(y1[i].to_bits(), s.row(i, &x).to_bits(), "{name} row {i}");
        }
    }

    /// The slab's supports: u_y fixed on `support`, u_x on "left".
    fn slab_model(mesh: &Mesh, support: &str) -> Model {
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new(support, 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        Model::new(mesh, &material, &supports).unwrap()
    }

    /// Structured slabs (the bench's numbering, row by row, and the
    /// committed Gmsh Q1 slab, boundary nodes numbered first): few types,
    /// products within the tolerance of the CSR's, the same bits on 1 and
    /// 2 threads, by batches and row by row, for K and M; with tolerance 0
    /// (equal bits only) the product has, to the last bit, each row's own
    /// blocks ([`kernels::row_groups`], as the compact form reads them)
    /// summed in the order of [`split_block`].
    #[test]
    fn stencil_types_on_the_slabs() {
        use stickslip_fem::testing::rectangle;
        use stickslip_mesh::CellKind;
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        let rect = |kind, nx, ny| rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
        let meshes = [
            ("q1 128x32", rect(CellKind::Quad4, 128, 32), "top"),
            ("q2 96x24", rect(CellKind::Quad9, 96, 24), "top"),
            ("q1 200x50", rect(CellKind::Quad4, 200, 50), "top"),
            (
                "slab-q1-128x32.msh",
                Mesh::from_file(dir.join("slab-q1-128x32.msh")).unwrap(),
                "support",
            ),
        ];
        for (name, mesh, support) in meshes {
            let model = slab_model(&mesh, support);
            for k in [&model.stiffness, &model.mass] {
                let s = Stencils::new(k).expect("structured: applies");
                // Types on the boundary rows (Gmsh numbers those nodes
                // first: more of them), one inside.
                let groups = s.types.len();
                assert!(6 * s.types() <= groups, "{name}: {} types", s.types());
                // The 4-wide path ran (the bits against the row-by-row
                // sums in `check`).
                assert!(!avx::available() || s.unit_of.iter().any(|&u| u != NO_UNIT));
                check(k, &s, name);
                // The 4-wide sums too where the CPU would take 8, and
                // products and sums where it would fuse them.
                if s.avx512 {
                    let narrow = Stencils {
                        avx512: false,
                        ..s.clone()
                    };
                    check(k, &narrow, &format!("{name}, 4 wide"));
                }
                if s.fma {
                    for avx512 in [s.avx512, false] {
                        let unfused = Stencils {
                            avx512,
                            fma: false,
                            ..s.clone()
                        };
                        check(k, &unfused, &format!("{name}, unfused, AVX-512 {avx512}"));
                    }
                }
                let exact = Stencils::build(k, 0.0, usize::MAX).unwrap();
                assert!(exact.types() > s.types(), "{name}");
                let x = x_of(k.nrows());
                let (mut y0, mut y1) = (vec![0.0; k.nrows()], vec![0.0; k.nrows()]);
                kernels::row_groups(k, |r0, r1, cols, vals| {
                    let mut s = [[0.0; 2]; 2];
                    for (&c, v) in cols.iter().zip(vals) {
                        if exact.fma {
                            split_block::<true>(c as usize, v, &x, &mut s);
                        } else {
                            split_block::<false>(c as usize, v, &x, &mut s);
                        }
                    }
                    for (k, y) in y0[r0..r1].iter_mut().enumerate() {
                        *y = s[0][k] + s[1][k];
                    }
                });
                exact.spmv(&x, &mut y1);
                for i in 0..k.nrows() {
                    assert_eq!(y0[i].to_bits(), y1[i].to_bits(), "{name} row {i} exact");
                }
            }
        }
    }

    /// `rows_at` gives each row `row`'s bits: runs of rows over whole
    /// groups (the vector-wide sums), runs starting or ending inside a
    /// group, single rows, rows out of order and repeated, on a Q1 and a
    /// Q2 slab and the Gmsh slab whose single-DOF nodes make one-row
    /// groups.
    #[test]
    fn rows_at_has_the_bits_of_row() {
        for (name, mesh, support) in sweep_meshes() {
            let model = slab_model(&mesh, support);
            let k = &model.stiffness;
            let n = k.nrows();
            let s = Stencils::new(k).unwrap();
            let x = x_of(n);
            let lists: Vec<Vec<usize>> = vec![
                (0..260).collect(),
                (1..261).collect(),
                (n - 300..n).collect(),
                (0..n).step_by(3).collect(),
                vec![7, 6, 5, 40, 41, 42, 43, 44, 45, 46, 47, 48, 3, 3, n - 1, 0],
                (100..140).chain(141..200).chain(10..20).collect(),
            ];
            for rows in lists {
                let mut got = vec![f64::NAN; rows.len()];
                s.rows_at(&rows, &x, &mut got);
                for (&i, g) in rows.iter().zip(&got) {
                    assert_eq!(g.to_bits(), s.row(i, &x).to_bits(), "{name}: row {i}");
                }
            }
        }
    }

    /// Q1 and Q2 slabs of several chunks numbered row by row (at least
    /// [`kernels::PARALLEL_MIN`] whole ones, so that two threads share
    /// them), and Gmsh's Q1 slab, whose nodes with one free DOF make
    /// one-row groups: name, mesh, the group held.
    fn sweep_meshes() -> [(&'static str, Mesh, &'static str); 3] {
        use stickslip_fem::testing::rectangle;
        use stickslip_mesh::CellKind;
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        let rect = |kind, nx, ny| rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
        [
            ("q1 200x50", rect(CellKind::Quad4, 200, 50), "top"),
            ("q2 96x24", rect(CellKind::Quad9, 96, 24), "top"),
            (
                "slab-q1-128x32.msh",
                Mesh::from_file(dir.join("slab-q1-128x32.msh")).unwrap(),
                "support",
            ),
        ]
    }

    /// The sweep with K r_K formed in its own kernel (`sweep_chunk_512`)
    /// has the bits of the sweep by batches: ṙ_K, r̈_K, the next predictor,
    /// the strain and kinetic sums and the finiteness flag, with load and
    /// friction rows (on both sides of chunk seams and inside unit runs),
    /// on 1 and 2 threads, apart and in place (both kernels); on slabs
    /// numbered row by row and on Gmsh's Q1 slab, whose nodes with one
    /// free DOF shift the rows' lanes. The in-place guard's bound is the
    /// sum of the three vectors' magnitudes.
    #[test]
    fn fused_sweep_has_the_bits_of_the_batches() {
        use crate::kernels::{partials, sweep, StepData, CHUNK};
        for (name, mesh, support) in sweep_meshes() {
            let model = slab_model(&mesh, support);
            let k = &model.stiffness;
            let n = k.nrows();
            assert!(n > CHUNK, "{name}: several chunks");
            // Forced (whatever FUSED_MIN_ROWS says).
            let fused = Stencils {
                fused_min_rows: 0,
                ..Stencils::new(k).unwrap()
            };
            let ran = fused.avx512 && fused.fma && kernels::avx2();
            let batched = Stencils {
                fused_min_rows: usize::MAX,
                ..fused.clone()
            };
            // What the sweep reads of K: all of it by batches; by the
            // kernel, the runs cover most node pairs, which it then reads
            // nothing of, so less, but never less than the stencils.
            assert_eq!(batched.sweep_bytes(n), batched.bytes(), "{name}");
            if ran {
                let stencils = 36 * fused.values.len() + 68 * fused.unit_values.len();
                let covered: usize = fused.runs.iter().map(|r| 4 * r[1] as usize).sum();
                assert!(
                    2 * covered > fused.types.len(),
                    "{name}: runs cover most groups"
                );
                assert!(fused.sweep_bytes(n) < fused.bytes(), "{name}");
                assert!(fused.sweep_bytes(n) > stencils, "{name}");
            }
            let x = x_of(n);
            let w = |c: f64| -> Vec<f64> { x.iter().map(|v| v * c + 0.1 * c).collect() };
            let (r_new, v, a) = (w(1.0), w(-0.7), w(3.0));
            let mass: Vec<f64> = x.iter().map(|x| 1.0 + x.abs()).collect();
            // Load and friction rows every 61 and 97 rows (in every unit
            // run: each block by SweepRows::eight's check), then every 4099
            // and 5003 (most runs and gaps plain: Rows8 throughout).
            for every in [(61, 97), (4099, 5003)] {
                let load_rows: Vec<usize> = (0..n)
                    .filter(|i| i % every.0 == 5 || i % CHUNK == 0 || i % CHUNK == CHUNK - 1)
                    .collect();
                let mut load_new = vec![0.0; n];
                for &i in &load_rows {
                    load_new[i] = 0.3 + 1e-3 * i as f64;
                }
                let friction: Vec<(usize, f64)> = (0..n)
                    .filter(|i| i % every.1 == 0 || i % CHUNK == 1 || i % CHUNK == CHUNK - 2)
                    .map(|i| (i, -0.25 * i as f64))
                    .collect();
                let data = StepData {
                    load_rows: &load_rows,
                    ..crate::kernels::tests::lab_data(&load_new, &mass, &r_new, &v, &a)
                };
                // The runs the sparse rows leave plain (Rows8's path).
                let special = |r: usize, hi: usize| {
                    load_rows
                        .iter()
                        .chain(friction.iter().map(|f| &f.0))
                        .any(|&i| r <= i && i < hi)
                };
                let plain = fused
                    .runs
                    .iter()
                    .filter(|&&[g, count, _]| {
                        let r = fused.group_rows[g as usize] as usize;
                        !special(r, r + 8 * count as usize)
                    })
                    .count();
                assert!(!ran || every.0 < 1000 || plain > 0, "{name}: no plain run");
                // In place: ṙ_{K−1} and r̈_{K−1} handed in the outputs.
                let in_place = StepData {
                    v: &[],
                    a: &[],
                    in_place: true,
                    ..data
                };
                let run = |s: &Stencils, threads: usize, here: bool| {
                    let (mut vn, mut an, mut rx) = if here {
                        (v.clone(), a.clone(), vec![0.0; n])
                    } else {
                        (vec![0.0; n], vec![0.0; n], vec![0.0; n])
                    };
                    let mut p = partials(n);
                    let (strain, sums) = on_threads(threads, || {
                        let out = [&mut vn[..], &mut an[..], &mut rx[..]];
                        let data = if here { &in_place } else { &data };
                        sweep(kernels::avx(), s, data, &friction, None, out, &mut p)
                    });
                    // The guard's bound: the sum of the magnitudes, whatever
                    // its order of additions.
                    let exact: f64 = (0..n)
                        .map(|i| vn[i].abs() + an[i].abs() + rx[i].abs())
                        .sum();
                    let what = format!("{name} {every:?}, {threads} threads, in place {here}");
                    assert!((sums.bound - exact).abs() <= 1e-12 * exact, "{what}: bound");
                    (strain, sums.kinetic, sums.finite, vn, an, rx)
                };
                let reference = run(&batched, 1, false);
                for (threads, kernel, here) in [1, 2]
                    .into_iter()
                    .flat_map(|t| [(t, &fused, false), (t, &fused, true), (t, &batched, true)])
                {
                    let got = run(kernel, threads, here);
                    let fused_ran = ran && std::ptr::eq(kernel, &fused);
                    let what = format!(
                    "{name} {every:?}, {threads} threads, in place {here} (fused kernel ran: {fused_ran})"
                );
                    assert_eq!(reference.0.to_bits(), got.0.to_bits(), "{what}: strain");
                    assert_eq!(reference.1.to_bits(), got.1.to_bits(), "{what}: kinetic");
                    assert!(reference.2 && got.2, "{what}: finite");
                    for i in 0..n {
                        assert_eq!(
                            reference.3[i].to_bits(),
                            got.3[i].to_bits(),
                            "{what}: ṙ {i}"
                        );
                        assert_eq!(
                            reference.4[i].to_bits(),
                            got.4[i].to_bits(),
                            "{what}: r̈ {i}"
                        );
                        assert_eq!(
                            reference.5[i].to_bits(),
                            got.5[i].to_bits(),
                            "{what}: r {i}"
                        );
                    }
                }
                // A NaN in r_K clears the flag on the fused path too.
                let mut bad = r_new.clone();
                bad[n / 2 + 3] = f64::NAN;
                let data = StepData {
                    r_new: &bad,
                    ..data
                };
                let mut p = partials(n);
                let (mut vn, mut an, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                let out = [&mut vn[..], &mut an[..], &mut rx[..]];
                let (_, sums) = sweep(kernels::avx(), &fused, &data, &friction, None, out, &mut p);
                assert!(!sums.finite, "{name} {every:?}: NaN not flagged");
            }
        }
    }

    /// Unstructured meshes: nearly every group its own stencil, declined.
    #[test]
    fn stencils_decline_unstructured_meshes() {
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        for name in ["slab-unstructured-q1.msh", "slab-unstructured-q2.msh"] {
            let mesh = Mesh::from_file(dir.join(name)).unwrap();
            let model = slab_model(&mesh, "support");
            assert!(Stencils::new(&model.stiffness).is_none(), "{name}");
        }
    }
}

/// K·x by stencil types, fused multiply-adds against products and sums,
/// on the bench's 1M-DOF slabs, alternating in one process (the host's
/// other work falls on both alike):
///
///     cargo test --release -p stickslip-time --lib kx_lab -- --ignored --nocapture
#[cfg(test)]
mod lab {
    use super::*;
    use crate::kernels::tests::x_of;
    use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};

    #[test]
    #[ignore = "a measurement: prints times, asserts nothing"]
    fn kx_lab() {
        for (nx, ny, q2) in [(1416, 354, false), (708, 177, true)] {
            let mesh = crate::scenes::structured_slab(nx, ny, q2);
            let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
            let supports = [
                Dirichlet::new("support", 1, 0.0),
                Dirichlet::new("left", 0, 0.0),
            ];
            let model = Model::new(&mesh, &material, &supports).unwrap();
            let fused = Stencils::new(&model.stiffness).unwrap();
            let unfused = Stencils {
                fma: false,
                ..fused.clone()
            };
            let x = x_of(model.stiffness.nrows());
            let mut y = vec![0.0; x.len()];
            let mut times = [Vec::new(), Vec::new()];
            for round in 0..400 {
                let s = [&unfused, &fused][round % 2];
                let t = std::time::Instant::now();
                s.spmv(&x, &mut y);
                times[round % 2].push(t.elapsed().as_secs_f64());
            }
            let median = |t: &mut Vec<f64>| {
                t.sort_by(f64::total_cmp);
                t[t.len() / 2]
            };
            let [a, b] = times.each_mut().map(median);
            eprintln!(
                "kx_lab {} {nx}x{ny} ({} DOFs, fma {}): K·x unfused {:.3} ms, fused {:.3} ms, ratio {:.3}",
                if q2 { "Q2" } else { "Q1" },
                x.len(),
                fused.fma,
                a * 1e3,
                b * 1e3,
                b / a
            );
        }
    }
}

/// The sweep with K r_K formed in its own kernel
/// ([`Stencils::sweep_chunk_512`]) against the sweep by 64-row batches,
/// alternating in one process, 2 threads, medians of 30 (meshes:
/// STICKSLIP_LAB_MESHES, default the 1M-DOF slabs q1-1416x354,q2-708x177):
///
///     cargo test --release -p stickslip-time --lib fused_lab -- --ignored --nocapture
#[cfg(test)]
mod fused_lab {
    use super::*;
    use crate::kernels::tests::{lab_data, lab_slab, x_of};
    use crate::kernels::{partials, sweep};

    #[test]
    #[ignore = "a measurement: prints times"]
    fn fused_lab() {
        let meshes = std::env::var("STICKSLIP_LAB_MESHES")
            .unwrap_or_else(|_| "q1-1416x354,q2-708x177".into());
        for name in meshes.split(',') {
            let (_, _, model) = lab_slab(name);
            let n = model.stiffness.nrows();
            let fused = Stencils {
                fused_min_rows: 0,
                ..Stencils::new(&model.stiffness).unwrap()
            };
            drop(model);
            let batched = Stencils {
                fused_min_rows: usize::MAX,
                ..fused.clone()
            };
            let x = x_of(n);
            let w = |c: f64| -> Vec<f64> { x.iter().map(|v| v * c + c).collect() };
            let (rn, m, v, a) = (w(1.3), w(1.2), w(1.5), w(1.6));
            let zero = vec![0.0; n];
            let data = lab_data(&zero, &m, &rn, &v, &a);
            let (mut vn, mut an, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let mut p = partials(n);
            let mut t: Vec<Vec<f64>> = vec![Vec::new(); 9];
            stickslip_fem::testing::on_threads(2, || {
                for round in 0..60 {
                    let s = [&batched, &fused][round % 2];
                    let t0 = std::time::Instant::now();
                    let out = [&mut vn[..], &mut an[..], &mut rx[..]];
                    sweep(kernels::avx(), s, &data, &[], None, out, &mut p);
                    t[round % 2].push(t0.elapsed().as_secs_f64());
                }
            });
            for t in &mut t {
                t.sort_by(f64::total_cmp);
            }
            eprintln!(
                "fused_lab {name} (fused kernel: {}): sweep by batches {:.3} ms, in the kernel {:.3} ms",
                fused.avx512 && fused.fma && kernels::avx2(),
                t[0][15] * 1e3,
                t[1][15] * 1e3
            );
        }
    }
}
