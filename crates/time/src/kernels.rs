//! The explicit step's vector passes, fused and threaded (issue 7,
//! deliverable 2).
//!
//! An explicit step is bound by memory traffic, so it makes as few sweeps
//! over the free-DOF vectors as the data dependencies allow: (A) the
//! predictor r_K ([`predict`]), with R_K formed only on the rows where a
//! load is nonzero ([`SparseLoads`]: tractions act on a boundary; the other
//! rows of R_K are +0 and stay so) and the work and load sums over those
//! rows; then, once r_K exists everywhere, one sweep ([`fused_step`]) that
//! forms K r_K, R̂_K, ṙ_K = R̂_K/(m·scale), r̈_K, and the strain and
//! kinetic sums. The nodal friction needs R̂_K at the contact DOFs before
//! their ṙ_K: those few rows are evaluated first ([`Compact::row`],
//! [`rhs_entry`]; a one-chunk run forms all of K r_K first instead, which
//! stays in cache) and their velocities handed to the sweep. Per entry and
//! per sum this is the arithmetic of the earlier three passes (kept:
//! [`rhs_and_velocity`], [`accelerate_and_sum`], used by the iterated
//! friction, which needs R̂_K everywhere), so the results are bit-identical
//! to them (tests below; the verify references differ by 0). The sweep
//! also writes the next step's predictor r_K + Δt ṙ_K + ½Δt² r̈_K, with
//! pass A's operations, and a next step of the same Δt skips pass A's
//! dense sweep (tests/explicit_predictor.rs: bit-identical to runs that
//! form every predictor anew, across Remark 4.3's Δt changes). Vector
//! streams per step: 7 (the sweep reads r_K, m, ṙ, r̈ and writes ṙ_K,
//! r̈_K, r_{K+1}); 10 with pass A (which reads r, ṙ, r̈ and writes r_K),
//! 17 with dense loads, 24 for the three passes. On systems of several
//! chunks the sweep writes ṙ_K and r̈_K over ṙ and r̈ where the last
//! sweep's bound shows that it cannot fail half way (`Integrator`'s
//! `SweepBounds`): stores into lines just read, which the core need not
//! fetch first.
//!
//! Work is split into fixed chunks of [`CHUNK`] DOFs whatever the number of
//! threads, and sums are formed per chunk and added in chunk order, so a
//! run is bit-identical on one thread and on many. Below [`PARALLEL_MIN`]
//! whole chunks the passes run on the calling thread (a rayon dispatch costs
//! microseconds, more than a pass over the paper's 148 free DOFs). Within
//! a chunk the sweep forms K r_K for [`BATCH`] rows at a time into a buffer
//! and then runs the per-row work in loops over the batch (the divisions
//! of ṙ_K and r̈_K of different rows overlap; the strain and kinetic sums
//! go in four lanes by row, [`Lanes`]).
//!
//! On small systems (one chunk; at most 1 MB of padded lines, at least
//! half filled) K·r comes from [`Sliced`] instead (`sliced.rs`: slices of
//! four rows, a pair of columns of a slice one 64-byte line, no gathers
//! of x pairs): `sliced_lab`, the paper-sized Q2 8×2 slab, one K·x 0.63
//! → 0.47 µs in slices of eight rows (2026-11-24), 0.38 µs in the pairs
//! (2026-11-26); the paper mesh's explicit step (bench step, ten
//! alternating runs, 2026-11-24) 1.41 → 1.12 µs median, 1.27 → 1.06 µs
//! fastest, which also counts the one-chunk sweep's dense R_K
//! ([`batch_rows`]); 1.10 → 0.96 µs with the pairs (five alternating runs).
//!
//! K·r row by row from [`Compact`] (2×2 blocks with u32 columns, their
//! values stored, 36 bytes per block, or indexed into a dictionary of the
//! distinct blocks, 6 or 8) rather than nalgebra-sparse's CSR (usize
//! columns, 16 bytes per entry) or element by element, chosen by
//! measurement: the `kernel_lab` test below, Q1 slab of 1,004,298 DOFs,
//! 2026-11-22 03:44, load average 1.1 on the 2 cores:
//!
//! | one K·x, fastest of 20             | 1 thread | 2 threads |
//! |------------------------------------|----------|-----------|
//! | CSR (313 MB)                       | 13.8 ms  |  9.2 ms   |
//! | compact, stored (183 MB)           | 10.9 ms  |  6.0 ms   |
//! | compact, dictionary (63 MB)        |  8.1 ms  |  4.1 ms   |
//! | element by element (297 MB)        | 12.3 ms  |  —        |
//!
//! | step after the predictor, 30 interleaved rounds | 1 thread: median, min | 2 threads: median, min |
//! |-------------------------------------------------|-----------------------|------------------------|
//! | CSR, pass B, pass C                             | 16.9, 16.6 ms         | 13.6, 13.1 ms          |
//! | compact fused with B, pass C                    | 18.0, 17.7 ms         |  9.9,  9.7 ms          |
//! | one sweep ([`fused_step`], batches)             | 13.9, 13.6 ms         |  7.1,  7.0 ms          |
//!
//! (The lab's sweep has no load rows; the first two read dense loads.)
//! Element by element moves more bytes than the compact rows (512 bytes of
//! matrix and 32 of connectivity per element, one element per node, and a
//! scatter that reads and writes y), and threading it deterministically
//! would need a colouring (scatters of neighbouring elements collide);
//! rows are independent, so threads never share an output. For Q2 the
//! element matrices (18×18 per 4 nodes, 324 bytes per DOF) lose more.
//!
//! The dictionary ([`Compact::new`]: used when it halves the matrix
//! stream; exact bits, so K·x keeps its bits) on the structured slabs,
//! measured 2026-11-22: Q1 128×32: 10,024 distinct of 37,338 blocks;
//! 708×177: 101,880 of 1,130,778 (matrix 41.7 → 13.3 MB); 1416×354:
//! 211,770 of 4,517,896 (167 → 47 MB, the 6.8 MB dictionary read from
//! cache). The Q2 slabs have 85% distinct blocks (352×88: 1,685,723 of
//! 1,986,505; 75% distinct column pairs) but only 168,411 distinct values:
//! a dictionary of values (a 4-byte index per entry, 20 bytes per block
//! instead of 36) was tried and made the step slower (gen-q2-352x88, same
//! session: 5.7 → 8.4 ms; four gathers per block, and the Q2 product is
//! not memory-bound on this machine), so the Q2 and unstructured meshes
//! keep their blocks stored.
//!
//! Each block costs a fixed set of operations (four products and four
//! additions, its column's bounds check, the value loads; then in the
//! CSR's order): the dev profile's opt-level 2 emits them scalar (rustc
//! runs LLVM's SLP vectorizer at opt-level 3 only), about 1.5 ns per block
//! on one core in cache (paper mesh: 1,088 blocks, ~1.6 µs of its step).
//! Two groups (four row sums) in lockstep, in the CSR's order; four
//! were measured no faster (paper mesh 2.64 vs 2.49 µs per step, Q2
//! equal within the noise). (Since 2026-11-24 each row is summed in
//! eight partial sums, 4 or 8 wide: [`Compact`].) Storing the blocks by columns lets opt-level 3
//! pair the two rows' operations (mulpd/addpd, same bits): the paper mesh
//! then steps in 2.11 instead of 2.51 µs and Q1 708×177 in 1.61 instead
//! of 1.89 ms (fastest of 3, same session), but the 1M-DOF Q1 and the
//! Q2 352×88 rungs measured no faster (11.2 vs 13.3 ms, 4.9 vs 5.4 ms, one
//! or two runs, load 1.3-1.5); that is a profile choice for the workspace
//! (Cargo.toml): it now compiles stickslip-time at opt-level 3.
//!
//! The predictor from the sweep (branch `cd-predictor-fusion`) first
//! measured no faster, the sweep then being compute-bound (Q1 1416×354
//! 8.94 vs 9.17 ms); with K·x by stencil types the vectors are the stream,
//! and it is kept: same session, bench step, Q1 708×177 1.11 → 0.95 ms,
//! Q2 352×88 1.66 → 1.45 ms.
//!
//! K·x by stencil types ([`Stencils`], `stencils.rs`), preferred to all
//! below where it applies: structured meshes numbered row by row, whose
//! node rows share a few stencils up to the coordinates' rounding (Q1
//! 1416×354: 2,845 types for 502k node pairs; the product streams 8 bytes
//! per node pair, and runs of alike pairs are summed 4 wide with AVX);
//! within 1e-12 of max |K_ij| per block of the assembled K, not its bits.
//! `class_lab` (below), 2 threads, fastest of 20, 09:08-09:16: K·x Q1 1M
//! 4.44 (compact dictionary) → 1.40-1.55 ms; Q2 249k 1.74 (classes) →
//! 0.70-0.73 ms; Q2 1M 6.77 (classes) → 2.9 ms.
//!
//! Matrix-free by element classes ([`Classes`], branch `cd-matrix-free`):
//! on the structured slabs every cell is a translate of the others up to
//! the rounding of its coordinates, so one element matrix serves all
//! ([`stickslip_fem::ElementClasses`]: cells alike when their relative
//! node coordinates agree within 8 ε max |x|, the coordinates' own
//! rounding), and K·x is summed node by node over each node's cells (rows
//! independent: the same bits on any number of threads; not the CSR's
//! bits, within 1e-12 of max_i Σ_j |K_ij x_j|, measured 5e-14 to 1.5e-13).
//! The `class_lab` test below, 2026-11-22 06:08, load average 1.2 on the 2
//! cores, fastest (median) of 20 interleaved rounds, the step being pass A
//! and the sweep without loads or friction:
//!
//! | mesh (free DOFs)         | threads | K·x compact   | K·x classes   | step compact  | step classes  |
//! |--------------------------|---------|---------------|---------------|---------------|---------------|
//! | Q1 1416×354 (1,004,298)  | 1       | 7.38 (8.18)   | 11.88 (11.95) | 12.75 (13.50) | 15.59 (15.75) |
//! |                          | 2       | 3.99 (4.54)   |  6.01 (6.23)  |  6.88 (7.59)  |  8.01 (8.33)  |
//! | Q2 352×88 (248,688)      | 1       | 6.35 (6.66)   |  3.40 (3.49)  |  7.36 (7.93)  |  4.23 (4.42)  |
//! |                          | 2       | 3.23 (3.42)   |  1.75 (1.83)  |  3.97 (4.20)  |  2.14 (2.32)  |
//! | Q2 708×177 (1,004,298)   | 1       | 23.87 (24.44) | 13.44 (13.52) | 29.73 (30.29) | 17.30 (17.42) |
//! |                          | 2       | 12.54 (12.89) |  6.79 (6.86)  | 15.91 (16.45) |  9.14 (9.29)  |
//!
//! (ms.) Q2 steps 1.7-1.9× faster, so the explicit step uses the classes
//! when the caller attaches them (`Dynamics::element_classes`); Q1 keeps
//! the compact form, its dictionary needing 9 blocks (36 products) per
//! node against 4 cells of 8 columns (64), and
//! [`stickslip_fem::ElementClasses::new`] declines Q1 meshes, and Q2 meshes
//! below [`stickslip_fem::classes::MIN_FREE_DOFS`] (their stored blocks
//! stay in cache and stream faster: 8,352 DOFs 117 vs 142 µs per step). The
//! matrix-free data is 4.6 MB (Q2 249k) and 18.6 MB (Q2 1M) against 73 and
//! 293 MB of stored blocks. Tried and not kept: each cell's K_e x_e formed
//! once per chunk into a per-thread cache and the nodes summing its
//! entries (fewer loads per product, but cells recomputed in every chunk
//! they touch): Q2 708×177 K·x 11.9 vs 10.0 ms for the node sums (2
//! threads, fastest of 20, same session, load 1.1-1.5); and gathering x_e
//! per node and cell instead of through the chunk's cache of gathered
//! cells ([`Gathered`]): Q2 352×88 K·x 4.8 vs 3.6 ms on 1 thread (fastest
//! of 20, two sessions minutes apart, load 1.0-1.4). Measured no faster
//! (1 thread, fastest of 20, load 0.7-1.2, against 13.2-13.4 ms for Q2
//! 708×177 and 3.4-3.5 ms for 352×88 in the sessions around): x_e held
//! twice and both operands 16-byte aligned, so that a column is one load,
//! one mulpd with a memory operand and one addpd (checked in the
//! assembly): 14.0-14.2 and 3.5 ms; a per-thread cache wide enough for
//! all of a chunk's cells (each gathered once per chunk, not once per
//! grid row): 13.7 and 3.2 ms; 2 or 6 partial sums per row instead of 4:
//! within 5%. The kernel is then neither bound by its instruction count
//! nor by the gathers; on this machine it runs at about 2 cycles per
//! column of a node's two rows.

use crate::sliced::Sliced;
use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

pub use crate::stencils::Stencils;

/// DOFs per chunk of work.
pub const CHUNK: usize = 8192;
/// Whole chunks from which the passes go parallel: a partial second
/// chunk leaves the other thread little to do for its wake-up and join
/// (bench_step, 2026-11-25, 2 threads against 1: 8,352 DOFs, a chunk and
/// 160 rows, 59 against 47 µs a step; through the cli 10,150 DOFs 94
/// against 63 µs; 16,425 DOFs, two whole chunks, 57 against 69 µs).
pub const PARALLEL_MIN: usize = 2;
/// Rows per batch of the one-sweep step ([`Compact::chunk_batches`]).
/// Small enough that the product's arithmetic and the vectors' memory
/// streams of neighbouring batches overlap in the core: `sweep_lab`,
/// 2026-11-24, 2 threads, median of 20, 1M DOFs, Q1 (Q2): 256 rows
/// 3.85 (4.84) ms, 128 about the same, 64 2.66-2.75 (3.93-4.07), 48 2.71
/// (3.81), 32 2.72-2.96 (3.88-4.08), 16 3.19 (4.31). The paper mesh's
/// step, one batch of 148 rows before, measured no slower (1.87 vs 1.92
/// µs).
pub const BATCH: usize = 64;

/// Number of chunks of a vector of length n.
pub fn chunks(n: usize) -> usize {
    n.div_ceil(CHUNK).max(1)
}

/// True when the passes should use the thread pool.
fn parallel(n: usize) -> bool {
    n / CHUNK >= PARALLEL_MIN && rayon::current_num_threads() > 1
}

/// Runs `body(c, chunk)` over the CHUNK-sized chunks of `y`, on the pool
/// when [`parallel`]: the chunks and each one's arithmetic are the same
/// either way.
pub(crate) fn each_chunk(y: &mut [f64], body: impl Fn(usize, &mut [f64]) + Sync) {
    if parallel(y.len()) {
        y.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, y)| body(c, y));
    } else {
        y.chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, y)| body(c, y));
    }
}

/// [`each_chunk`] with the chunk's partial sums.
pub(crate) fn each_chunk_summed(
    y: &mut [f64],
    partials: &mut Partials,
    body: impl Fn(usize, &mut [f64], &mut [f64; 6]) + Sync,
) {
    if parallel(y.len()) {
        y.par_chunks_mut(CHUNK)
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, (y, p))| body(c, y, p));
    } else {
        y.chunks_mut(CHUNK)
            .zip(partials.iter_mut())
            .enumerate()
            .for_each(|(c, (y, p))| body(c, y, p));
    }
}

/// [`each_chunk_summed`] over the same chunks of two vectors.
pub(crate) fn each_chunk_pair(
    y: &mut [f64],
    z: &mut [f64],
    partials: &mut Partials,
    body: impl Fn(usize, &mut [f64], &mut [f64], &mut [f64; 6]) + Sync,
) {
    if parallel(y.len()) {
        y.par_chunks_mut(CHUNK)
            .zip(z.par_chunks_mut(CHUNK))
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, ((y, z), p))| body(c, y, z, p));
    } else {
        y.chunks_mut(CHUNK)
            .zip(z.chunks_mut(CHUNK))
            .zip(partials.iter_mut())
            .enumerate()
            .for_each(|(c, ((y, z), p))| body(c, y, z, p));
    }
}

/// [`each_chunk_summed`] over the same chunks of three vectors.
fn each_chunk_triple(
    [y, z, w]: [&mut [f64]; 3],
    partials: &mut Partials,
    body: impl Fn(usize, [&mut [f64]; 3], &mut [f64; 6]) + Sync,
) {
    if parallel(y.len()) {
        y.par_chunks_mut(CHUNK)
            .zip(z.par_chunks_mut(CHUNK))
            .zip(w.par_chunks_mut(CHUNK))
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, (((y, z), w), p))| body(c, [y, z, w], p));
    } else {
        y.chunks_mut(CHUNK)
            .zip(z.chunks_mut(CHUNK))
            .zip(w.chunks_mut(CHUNK))
            .zip(partials.iter_mut())
            .enumerate()
            .for_each(|(c, (((y, z), w), p))| body(c, [y, z, w], p));
    }
}

/// y = A x, rows in parallel chunks (each y_i is one row's sum in storage
/// order, so the threading never changes a bit).
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let body = |c: usize, y: &mut [f64]| {
        let start = c * CHUNK;
        for (k, yi) in y.iter_mut().enumerate() {
            let i = start + k;
            let mut s = 0.0;
            for p in offsets[i]..offsets[i + 1] {
                s += vals[p] * x[cols[p]];
            }
            *yi = s;
        }
    };
    each_chunk(y, body);
}

/// Per-chunk partial sums, added in chunk order.
pub type Partials = Vec<[f64; 6]>;

/// Partial sums for vectors of length n.
pub fn partials(n: usize) -> Partials {
    vec![[0.0; 6]; chunks(n)]
}

pub(crate) fn total(partials: &[[f64; 6]], k: usize) -> f64 {
    partials.iter().map(|p| p[k]).sum()
}

/// The loads on the rows where the constant load or any load vector is
/// nonzero (bit for bit: a −0 counts) — tractions act on a boundary, so a
/// few rows. Elsewhere R_K = +0 + Σ θ_l·(+0) = +0 exactly for finite θ_l,
/// and the step's pass A leaves those rows of R_K untouched.
#[derive(Clone, Debug)]
pub struct SparseLoads {
    /// Rows, ascending.
    rows: Vec<usize>,
    /// The constant load on them.
    constant: Vec<f64>,
    /// Each load vector on them.
    loads: Vec<Vec<f64>>,
}

impl SparseLoads {
    /// The loads `constant` and `loads` (vectors of one length) on their
    /// nonzero rows.
    pub fn new(constant: &[f64], loads: &[&[f64]]) -> SparseLoads {
        let rows: Vec<usize> = (0..constant.len())
            .filter(|&i| constant[i].to_bits() != 0 || loads.iter().any(|l| l[i].to_bits() != 0))
            .collect();
        SparseLoads {
            constant: rows.iter().map(|&i| constant[i]).collect(),
            loads: loads
                .iter()
                .map(|l| rows.iter().map(|&i| l[i]).collect())
                .collect(),
            rows,
        }
    }

    /// The rows, ascending.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Bytes a step moves for them: the row indices and the loads read,
    /// R_K written, R_{K−1}, r and r_K read at those rows (pass A's sums).
    pub fn bytes(&self) -> usize {
        self.rows.len() * (8 + 8 * (1 + self.loads.len()) + 8 * 4)
    }
}

/// Up to this many loads [`predict`] picks those with θ ≠ 0 once per step
/// (beyond, θ is tested per row).
const ACTIVE_LOADS: usize = 8;

/// Pass A: the predictor r_K = r + c1 ṙ + c2 r̈ into `r_new` (every row),
/// R_K = constant + Σ θ_l load_l into `load_new` at the loads' rows only
/// (its other rows must hold +0: [`SparseLoads`]), and per chunk the sums
/// work = Σ ½(R_K + R_{K−1})(r_K − r_{K−1}) and r_K·R_K over those rows
/// into `partials[c][0]` and `[2]`. Every θ_l must be finite.
///
/// The per-entry arithmetic and per-chunk order of [`accelerate_and_sum`]'s
/// sums: a row off the loads adds ½(+0)(r_K − r) = ±0, and a sum that
/// starts at +0 is never −0 (x + (−x) = +0), so s ± 0 = s and leaving those
/// rows out gives the same bits (for finite r_K − r; a non-finite r_K
/// fails the step either way).
#[allow(clippy::too_many_arguments)]
pub fn predict(
    sparse: &SparseLoads,
    thetas: &[f64],
    r: &[f64],
    v: &[f64],
    a: &[f64],
    c1: f64,
    c2: f64,
    load: &[f64],
    load_new: &mut [f64],
    r_new: &mut [f64],
    dense: bool,
    partials: &mut Partials,
) {
    debug_assert!(thetas.iter().all(|t| t.is_finite()));
    let body = |c: usize, rn: &mut [f64]| {
        let range = c * CHUNK..c * CHUNK + rn.len();
        let (r, v, a) = (&r[range.clone()], &v[range.clone()], &a[range]);
        for i in 0..rn.len() {
            rn[i] = r[i] + c1 * v[i] + c2 * a[i];
        }
    };
    if dense {
        each_chunk(r_new, body);
    }
    for p in partials.iter_mut() {
        p[0] = 0.0;
        p[2] = 0.0;
    }
    // The sums of a chunk's rows (ascending, so consecutive) in registers,
    // added to its partials (+0) when the next chunk's rows begin: through
    // memory each addition waited for the last one's store (the paper
    // mesh's predict, about 8% of its explicit step, was mostly that).
    let (mut chunk, mut work, mut dot) = (0, 0.0, 0.0);
    // The loads with θ ≠ 0 (their order kept), picked once, not per row.
    let mut active = [(0.0, &[][..]); ACTIVE_LOADS];
    let few = sparse.loads.len() <= ACTIVE_LOADS;
    let mut n_active = 0;
    if few {
        for (load, &theta) in sparse.loads.iter().zip(thetas) {
            if theta != 0.0 {
                active[n_active] = (theta, &load[..sparse.rows.len()]);
                n_active += 1;
            }
        }
    }
    let active = &active[..n_active];
    let (rows, constant) = (&sparse.rows[..], &sparse.constant[..sparse.rows.len()]);
    for (k, &i) in rows.iter().enumerate() {
        let mut l = constant[k];
        if few {
            for &(theta, load) in active {
                l += theta * load[k];
            }
        } else {
            for (load, theta) in sparse.loads.iter().zip(thetas) {
                if *theta != 0.0 {
                    l += theta * load[k];
                }
            }
        }
        load_new[i] = l;
        if i / CHUNK != chunk {
            partials[chunk][0] += work;
            partials[chunk][2] += dot;
            (chunk, work, dot) = (i / CHUNK, 0.0, 0.0);
        }
        work += 0.5 * (l + load[i]) * (r_new[i] - r[i]);
        dot += r_new[i] * l;
    }
    partials[chunk][0] += work;
    partials[chunk][2] += dot;
}

/// Pass B: with b holding K r_K on entry, b = R_K − K r_K + m(cv ṙ + ca r̈)
/// (R̂_K of METHOD.md §4 with the lumped mass) and ṙ_K = b/(m·scale)
/// without friction; returns ½ r_Kᵀ K r_K.
#[allow(clippy::too_many_arguments)]
pub fn rhs_and_velocity(
    load_new: &[f64],
    mass: &[f64],
    r_new: &[f64],
    v: &[f64],
    a: &[f64],
    cv: f64,
    ca: f64,
    scale: f64,
    b: &mut [f64],
    v_new: &mut [f64],
    partials: &mut Partials,
) -> f64 {
    let body = |c: usize, b: &mut [f64], vn: &mut [f64], partial: &mut [f64; 6]| {
        let range = c * CHUNK..c * CHUNK + b.len();
        let (l, m, rn) = (
            &load_new[range.clone()],
            &mass[range.clone()],
            &r_new[range.clone()],
        );
        let (v, a) = (&v[range.clone()], &a[range.clone()]);
        let mut strain = Lanes::default();
        strain.add_rows(range.start, b.len(), |i| rn[i] * b[i]);
        for i in 0..b.len() {
            let ku = b[i];
            let bi = l[i] - ku + m[i] * (cv * v[i] + ca * a[i]);
            b[i] = bi;
            vn[i] = bi / (m[i] * scale);
        }
        partial[0] = strain.total();
    };
    each_chunk_pair(b, v_new, partials, body);
    0.5 * total(partials, 0)
}

/// What pass C sums.
pub struct Sums {
    /// Σ ½(R_K + R_{K−1})·(r_K − r_{K−1}).
    pub work: f64,
    /// ½ ṙ_Kᵀ M_L ṙ_K.
    pub kinetic: f64,
    /// r_K · R_K.
    pub load_dot: f64,
    /// Every entry of r_K and ṙ_K is finite.
    pub finite: bool,
    /// The sweep's Σ |ṙ_K| + |r̈_K| + |r_{K+1}| over the rows ([`fused_step`]):
    /// finite, it bounds every entry of the three; ∞ where not formed.
    pub bound: f64,
}

/// Pass C: r̈_K = (ṙ_K − ṙ)·scale − (1−γ)/γ r̈ into `a_new` (scale =
/// 1/(γΔt): a product, not a division per row), and the sums.
#[allow(clippy::too_many_arguments)]
pub fn accelerate_and_sum(
    mass: &[f64],
    load: &[f64],
    load_new: &[f64],
    r: &[f64],
    r_new: &[f64],
    v: &[f64],
    v_new: &[f64],
    a: &[f64],
    scale: f64,
    ratio: f64,
    a_new: &mut [f64],
    partials: &mut Partials,
) -> Sums {
    let body = |c: usize, an: &mut [f64], partial: &mut [f64; 6]| {
        let range = c * CHUNK..c * CHUNK + an.len();
        let (m, l, ln) = (
            &mass[range.clone()],
            &load[range.clone()],
            &load_new[range.clone()],
        );
        let (r, rn, v) = (&r[range.clone()], &r_new[range.clone()], &v[range.clone()]);
        let (vn, a) = (&v_new[range.clone()], &a[range.clone()]);
        let (mut work, mut load_dot) = (0.0, 0.0);
        let mut kinetic = Lanes::default();
        kinetic.add_rows(range.start, an.len(), |i| m[i] * vn[i] * vn[i]);
        let mut finite = true;
        for i in 0..an.len() {
            an[i] = (vn[i] - v[i]) * scale - ratio * a[i];
            work += 0.5 * (ln[i] + l[i]) * (rn[i] - r[i]);
            load_dot += rn[i] * ln[i];
            finite &= rn[i].is_finite() && vn[i].is_finite();
        }
        let kinetic = kinetic.total();
        partial[..4].copy_from_slice(&[work, kinetic, load_dot, if finite { 0.0 } else { 1.0 }]);
    };
    each_chunk_summed(a_new, partials, body);
    Sums {
        work: total(partials, 0),
        kinetic: 0.5 * total(partials, 1),
        load_dot: total(partials, 2),
        finite: total(partials, 3) == 0.0,
        bound: f64::INFINITY,
    }
}

/// K in the compact form the explicit step streams (built once per run):
/// rows grouped in pairs of consecutive free DOFs with the same column
/// pattern (the x and y DOF of one node; plane elasticity couples nodes by
/// 2×2 blocks), each pair storing its row in 2-column blocks, 4 values (or
/// their index in a dictionary of distinct blocks, [`Values`]) and one u32
/// column index per block. A Q1 node's two rows then cost 9 blocks of 36
/// bytes, 162 bytes per DOF instead of 288 for nalgebra-sparse's CSR
/// (usize column index and value per entry); with the row pointers (4 bytes
/// per pair) the matrix stream is 0.57× the CSR's, and with a dictionary
/// of 2-byte (4-byte) indices 0.12× (0.16×) plus the dictionary.
///
/// Rows that have no partner (a node with one DOF constrained, or a pair
/// straddling a [`CHUNK`] boundary, so that threads never share a group)
/// are single-row groups using the same blocks. A column whose partner is
/// constrained is padded with a zero in the block starting one column
/// earlier (or at column 0): every block reads x[c], x[c+1] in bounds.
///
/// Each group has an even number of blocks (a zero block at its last
/// column pads an odd count), stored two to a 64-byte line ([`Lines`]).
/// The summation order is [`group_sums`]': eight partial sums per row
/// (block number mod 4 × column of the block), so that 8-wide registers
/// hold two blocks and a row is not one long chain of dependent additions
/// (the paper mesh's K·x, `small_lab`: 1.11 µs in the CSR's order with
/// two groups in lockstep, 0.62 µs now). Padding zeros are exact: s + 0·x
/// = s for finite x and s ≠ −0 (a sum started at +0 is never −0). (A
/// non-finite r makes the step fail on the finiteness check either way.)
/// The CSR's [`spmv`] sums each row in column order: other bits, within
/// rounding.
#[derive(Clone, Debug)]
pub struct Compact {
    /// First row of each group (1 or 2 rows), then n.
    group_rows: Vec<u32>,
    /// Blocks of group g: group_blocks[g]..group_blocks[g + 1].
    group_blocks: Vec<u32>,
    /// First column of each block.
    cols: Vec<u32>,
    /// The blocks' values, stored or by dictionary.
    values: Values,
    /// Groups of chunk c: chunk_groups[c]..chunk_groups[c + 1].
    chunk_groups: Vec<u32>,
    /// How wide the sums run (the same bits at every width).
    wide: Wide,
    /// Rows (and columns): every block's columns are below it.
    n: usize,
}

/// The values of the blocks, [row 0 · col 0, row 1 · col 0, row 0 · col 1,
/// row 1 · col 1] each (by columns): stored per block, or as an index per block into a
/// dictionary of the distinct blocks (bit for bit: no tolerance, so a
/// block read from the dictionary has the bits of the stored one).
#[derive(Clone, Debug)]
enum Values {
    /// 32 bytes per block, the pairs of blocks on 64-byte lines.
    Stored(Lines),
    /// 2 bytes per block and the dictionary (≤ 65,536 distinct blocks).
    Dict16 { ids: Vec<u16>, dict: Vec<[f64; 4]> },
    /// 4 bytes per block and the dictionary.
    Dict32 { ids: Vec<u32>, dict: Vec<[f64; 4]> },
}

/// Blocks stored two to a 64-byte-aligned line: with every group an even
/// number of blocks, each of [`avx512_groups`]' 8-double loads is one line
/// (the paper mesh's K·x took 1.04 µs with its blocks at 48 bytes past a
/// line, 0.72 at 16).
#[derive(Clone, Debug)]
pub(crate) struct Lines {
    lines: Vec<Line>,
    blocks: usize,
}

#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Line([[f64; 4]; 2]);

impl Lines {
    fn new(blocks: &[[f64; 4]]) -> Lines {
        let lines = blocks
            .chunks(2)
            .map(|p| Line([p[0], p.get(1).copied().unwrap_or([0.0; 4])]))
            .collect();
        Lines {
            lines,
            blocks: blocks.len(),
        }
    }

    fn as_blocks(&self) -> &[[f64; 4]] {
        // SAFETY: Line is repr(C) of two [f64; 4] (64 bytes, no padding),
        // so `lines` holds 2·lines.len() ≥ `blocks` consecutive blocks.
        #[allow(unsafe_code)]
        unsafe {
            std::slice::from_raw_parts(self.lines.as_ptr().cast(), self.blocks)
        }
    }
}

/// Which form [`Compact::with_form`] builds (the step uses `Auto`; the
/// tests and the lab force the others).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(not(test), allow(dead_code))]
pub enum Form {
    /// The dictionary when it cuts the matrix stream by ≥ 2× (see
    /// [`Compact::new`]).
    Auto,
    /// Values stored per block.
    Stored,
    /// The dictionary whatever it saves.
    Dictionary,
}

/// Block values as the kernels read them: a slice of per-block entries
/// (`ids`) and how an entry gives its block.
trait Blocks: Sync {
    type Id: Sync;
    fn ids(&self) -> &[Self::Id];
    fn value<'s>(&'s self, id: &'s Self::Id) -> &'s [f64; 4];
    /// The 8 values of two consecutive blocks (`ids` holds 2) when they
    /// are adjacent in memory.
    fn pair(&self, ids: &[Self::Id]) -> Option<*const f64>;
}

struct StoredBlocks<'a>(&'a [[f64; 4]]);

impl Blocks for StoredBlocks<'_> {
    type Id = [f64; 4];
    #[inline(always)]
    fn ids(&self) -> &[[f64; 4]] {
        self.0
    }
    #[inline(always)]
    fn value<'s>(&'s self, id: &'s [f64; 4]) -> &'s [f64; 4] {
        id
    }
    #[inline(always)]
    fn pair(&self, ids: &[[f64; 4]]) -> Option<*const f64> {
        let two: &[[f64; 4]; 2] = ids.try_into().ok()?;
        Some(two.as_ptr().cast())
    }
}

struct DictBlocks<'a, I> {
    ids: &'a [I],
    dict: &'a [[f64; 4]],
}

impl<I: Copy + Into<u32> + Sync> Blocks for DictBlocks<'_, I> {
    type Id = I;
    #[inline(always)]
    fn ids(&self) -> &[I] {
        self.ids
    }
    #[inline(always)]
    fn value<'s>(&'s self, id: &'s I) -> &'s [f64; 4] {
        let k: u32 = (*id).into();
        &self.dict[k as usize]
    }
    #[inline(always)]
    fn pair(&self, _: &[I]) -> Option<*const f64> {
        None
    }
}

/// A kernel over the block values in whichever form they are
/// ([`Compact::with_blocks`]: one match per call, the loops monomorphic).
trait Kernel<R> {
    fn run<B: Blocks>(self, k: &Compact, b: &B) -> R;
}

/// One 2×2 block's products added to four partial sums, laid out as the
/// block is stored (by columns): [row 0 · column c, row 1 · column c,
/// row 0 · column c + 1, row 1 · column c + 1]: one 4-wide operation per
/// block ([`avx_groups`]).
#[inline(always)]
pub(crate) fn block(col: u32, v: &[f64; 4], x: &[f64], s: &mut [f64; 4]) {
    let c = col as usize;
    let xs = &x[c..c + 2];
    s[0] += v[0] * xs[0];
    s[1] += v[1] * xs[0];
    s[2] += v[2] * xs[1];
    s[3] += v[3] * xs[1];
}

/// A group's two row sums from its blocks' products ([`block`]), in the
/// order [`Compact`] defines: four partial sums per lane, one per block
/// number mod 4 over the whole quads of blocks, each in storage order;
/// then even = s₀ + s₂ and odd = s₁ + s₃ lane by lane, the last pair of
/// blocks (a group's count is even, [`Lines`]) added to even and odd;
/// then even + odd lane by lane, and per row its first column's terms +
/// its second's. Chosen for 8-wide registers (two blocks each, two
/// registers per group, [`avx512_groups`]): a row's sum is eight short
/// chains of dependent additions instead of the CSR's one long chain.
#[inline(always)]
pub(crate) fn group_sums<'v>(
    cols: &[u32],
    mut vals: impl ExactSizeIterator<Item = &'v [f64; 4]>,
    x: &[f64],
) -> [f64; 2] {
    let quads = cols.len() & !3;
    let mut s = [[0.0; 4]; 4];
    for (j, (&c, v)) in cols[..quads].iter().zip(vals.by_ref()).enumerate() {
        block(c, v, x, &mut s[j % 4]);
    }
    let mut even: [f64; 4] = std::array::from_fn(|l| s[0][l] + s[2][l]);
    let mut odd: [f64; 4] = std::array::from_fn(|l| s[1][l] + s[3][l]);
    for (j, (&c, v)) in cols[quads..].iter().zip(vals).enumerate() {
        block(c, v, x, if j % 2 == 0 { &mut even } else { &mut odd });
    }
    let t: [f64; 4] = std::array::from_fn(|l| even[l] + odd[l]);
    [t[0] + t[2], t[1] + t[3]]
}

impl Values {
    fn bytes(&self) -> usize {
        match self {
            Values::Stored(v) => 32 * v.blocks,
            Values::Dict16 { ids, dict } => 2 * ids.len() + 32 * dict.len(),
            Values::Dict32 { ids, dict } => 4 * ids.len() + 32 * dict.len(),
        }
    }
}

/// The dictionary of distinct blocks (equal bits, in order of first
/// appearance) and each block's index into it; `None` as soon as it would
/// hold more than `max` blocks.
fn dictionary(blocks: &[[f64; 4]], max: usize) -> Option<Values> {
    let mut index: std::collections::HashMap<[u64; 4], u32, BlockHash> =
        std::collections::HashMap::with_capacity_and_hasher(max.min(blocks.len()) / 4, BlockHash);
    let mut dict = Vec::new();
    let mut ids = Vec::with_capacity(blocks.len());
    for b in blocks {
        let next = dict.len() as u32;
        let id = *index.entry(b.map(f64::to_bits)).or_insert(next);
        if id == next {
            if dict.len() == max {
                return None;
            }
            dict.push(*b);
        }
        ids.push(id);
    }
    dict.shrink_to_fit();
    Some(if dict.len() <= 1 << 16 {
        Values::Dict16 {
            ids: ids.iter().map(|&k| k as u16).collect(),
            dict,
        }
    } else {
        Values::Dict32 { ids, dict }
    })
}

/// A multiply-xor hash of a block's bits (SipHash, the default, made the
/// dictionary of a 1M-DOF Q2 matrix take seconds; no adversary here).
#[derive(Clone, Copy, Default)]
struct BlockHash;

impl std::hash::BuildHasher for BlockHash {
    type Hasher = BlockHasher;
    fn build_hasher(&self) -> BlockHasher {
        BlockHasher(0)
    }
}

struct BlockHasher(u64);

impl std::hash::Hasher for BlockHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
    fn write(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            self.write_u64(u64::from_le_bytes(w));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(23) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// The row groups of a square CSR matrix with sorted columns (the rows of
/// [`Compact`] and [`crate::stencils::Stencils`]): a node's two rows when
/// they have the same columns and no chunk seam divides them, else one row.
/// Calls `visit(first row, end row, block columns, block values)` for each
/// group in order, its 2×2 blocks in ascending column order (a block's
/// first column is the pair start of its columns: a single DOF is padded
/// into the block before it, the padding +0; values by columns, as
/// [`block`] reads them), and returns the groups' first rows, then n.
pub(crate) fn row_groups(
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
    // block before it. The pairs are the matrix's, whatever the chunks, so
    // a node's blocks are the same wherever the chunk seams fall (a seam
    // through a pair only makes its rows two groups).
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
                // Both rows of a pair have the same columns, so the
                // second row finds the blocks the first one made.
                while next < block_cols.len() && block_cols[next] < s {
                    next += 1;
                }
                if next == block_cols.len() {
                    debug_assert_eq!(k, 0);
                    block_cols.push(s);
                    block_vals.push([0.0; 4]);
                }
                debug_assert_eq!(block_cols[next], s);
                block_vals[next][2 * (c - s as usize) + k] = vals[p];
            }
        }
        visit(r0, r1, &block_cols, &block_vals);
    }
    group_rows
}

/// Calls `f(first row, K x on the batch's rows)` for consecutive batches
/// of at most [`BATCH`] rows (BATCH / 2 groups) covering chunk `c`, in
/// order, the sums of groups g..gb from `sums(g, gb, out)` into a buffer
/// held in L1 (the row groups of [`Compact`] and
/// [`crate::stencils::Stencils`]).
#[inline(always)]
pub(crate) fn group_batches(
    chunk_groups: &[u32],
    group_rows: &[u32],
    c: usize,
    mut sums: impl FnMut(usize, usize, &mut [f64]),
    mut f: impl FnMut(usize, &[f64]),
) {
    let (g0, g1) = (chunk_groups[c] as usize, chunk_groups[c + 1] as usize);
    let mut buf = [0.0; BATCH];
    let mut g = g0;
    while g < g1 {
        let gb = (g + BATCH / 2).min(g1);
        let (ra, rb) = (group_rows[g] as usize, group_rows[gb] as usize);
        let out = &mut buf[..rb - ra];
        sums(g, gb, out);
        f(ra, out);
        g = gb;
    }
}

/// The first group of each chunk of n rows, then the number of groups.
pub(crate) fn chunk_groups(group_rows: &[u32], n: usize) -> Vec<u32> {
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

impl Compact {
    /// The compact form of a square CSR matrix with sorted columns, or
    /// `None` when it does not apply (fewer than 2 rows, more than u32
    /// indices can address). The block values go into a dictionary when
    /// that cuts the bytes the SpMV streams from the matrix by ≥ 2×
    /// (structured meshes: few distinct blocks), else they are stored per
    /// block (unstructured meshes: nearly every block distinct, and a
    /// dictionary would add an index per block and a scattered read).
    pub fn new(a: &CsrMatrix<f64>) -> Option<Compact> {
        Compact::with_form(a, Form::Auto)
    }

    /// [`Compact::new`] with the form of the values chosen by the caller.
    pub fn with_form(a: &CsrMatrix<f64>, form: Form) -> Option<Compact> {
        let n = a.nrows();
        if n < 2 || a.ncols() != n || n >= u32::MAX as usize || a.nnz() >= u32::MAX as usize {
            return None;
        }
        let mut group_blocks = Vec::with_capacity(n / 2 + 2);
        let mut block_cols: Vec<u32> = Vec::with_capacity(a.nnz() / 2);
        let mut block_vals: Vec<[f64; 4]> = Vec::with_capacity(a.nnz() / 2);
        group_blocks.push(0u32);
        let group_rows = row_groups(a, |_, _, c, v| {
            block_cols.extend_from_slice(c);
            block_vals.extend_from_slice(v);
            // An even number of blocks per group: a zero block at the last
            // column (its terms +0·x leave the odd sums' bits, [`Lines`]).
            if let (true, Some(&last)) = (c.len() % 2 == 1, c.last()) {
                block_cols.push(last);
                block_vals.push([0.0; 4]);
            }
            group_blocks.push(block_cols.len().min(u32::MAX as usize) as u32);
        });
        if block_cols.len() >= u32::MAX as usize {
            return None;
        }
        let chunk_groups = chunk_groups(&group_rows, n);
        block_cols.shrink_to_fit();
        block_vals.shrink_to_fit();
        let mut compact = Compact {
            group_rows,
            group_blocks,
            cols: block_cols,
            values: Values::Stored(Lines::new(&[])),
            chunk_groups,
            wide: Wide::best(),
            n,
        };
        // avx*_groups read x[c], x[c + 1] unchecked.
        assert!(compact.cols.iter().all(|&c| (c as usize) + 1 < n));
        compact.values = match form {
            Form::Stored => Values::Stored(Lines::new(&block_vals)),
            Form::Dictionary => dictionary(&block_vals, usize::MAX).expect("no limit"),
            Form::Auto => {
                // The largest dictionary that can halve the stream (with
                // 2-byte indices, the least it can cost per block); the
                // build stops there, so a mesh with nearly all blocks
                // distinct pays for a fraction of it.
                let blocks = block_vals.len();
                let stored = compact.bytes_with(32 * blocks);
                let max = (stored / 2).saturating_sub(compact.bytes_with(2 * blocks)) / 32;
                match dictionary(&block_vals, max) {
                    Some(values) if 2 * compact.bytes_with(values.bytes()) <= stored => values,
                    _ => Values::Stored(Lines::new(&block_vals)),
                }
            }
        };
        Some(compact)
    }

    /// Bytes the SpMV streams from the matrix: block columns, group
    /// offsets and the values (a dictionary counted once: it stays in
    /// cache over a step).
    pub fn bytes(&self) -> usize {
        self.bytes_with(self.values.bytes())
    }

    fn bytes_with(&self, values: usize) -> usize {
        4 * (self.cols.len() + self.group_rows.len() + self.group_blocks.len()) + values
    }

    /// Distinct blocks in the dictionary (0 when the values are stored).
    pub fn dictionary_len(&self) -> usize {
        match &self.values {
            Values::Stored(_) => 0,
            Values::Dict16 { dict, .. } | Values::Dict32 { dict, .. } => dict.len(),
        }
    }

    /// Stored blocks.
    pub fn blocks(&self) -> usize {
        self.cols.len()
    }

    /// Runs `k` with the block values in their form.
    #[inline(always)]
    fn with_blocks<R>(&self, k: impl Kernel<R>) -> R {
        match &self.values {
            Values::Stored(v) => k.run(self, &StoredBlocks(v.as_blocks())),
            Values::Dict16 { ids, dict } => k.run(self, &DictBlocks { ids, dict }),
            Values::Dict32 { ids, dict } => k.run(self, &DictBlocks { ids, dict }),
        }
    }

    /// The sums of group g's rows (the second is 0 for a single row).
    #[inline(always)]
    fn group_sums_in<B: Blocks>(&self, b: &B, g: usize, x: &[f64]) -> [f64; 2] {
        let blocks = self.group_blocks[g] as usize..self.group_blocks[g + 1] as usize;
        let ids = &b.ids()[blocks.clone()];
        group_sums(&self.cols[blocks], ids.iter().map(|i| b.value(i)), x)
    }

    /// (K x)_i alone, with the bits the passes give it.
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        struct Row<'x>(usize, &'x [f64]);
        impl Kernel<f64> for Row<'_> {
            fn run<B: Blocks>(self, k: &Compact, b: &B) -> f64 {
                let Row(i, x) = self;
                let g = k.group_rows.partition_point(|&r| r as usize <= i) - 1;
                let s = k.group_sums_in(b, g, x);
                if i == k.group_rows[g] as usize {
                    s[0]
                } else {
                    s[1]
                }
            }
        }
        self.with_blocks(Row(i, x))
    }

    /// Calls `f(first row, K x on the batch's rows)` for consecutive
    /// batches of at most [`BATCH`] rows covering chunk `c`, in order: the
    /// caller's per-row work then runs in loops over a batch held in L1
    /// (the divisions of ṙ_K and r̈_K pipelined) instead of once per row
    /// inside the product's loop.
    #[inline]
    fn chunk_batches(&self, c: usize, x: &[f64], f: impl FnMut(usize, &[f64])) {
        struct Batches<'x, F>(usize, &'x [f64], F);
        impl<F: FnMut(usize, &[f64])> Kernel<()> for Batches<'_, F> {
            #[inline(always)]
            fn run<B: Blocks>(self, k: &Compact, b: &B) {
                let Batches(c, x, f) = self;
                let sums = |g: usize, gb: usize, out: &mut [f64]| k.groups_into(b, g, gb, x, out);
                group_batches(&k.chunk_groups, &k.group_rows, c, sums, f);
            }
        }
        self.with_blocks(Batches(c, x, f))
    }

    /// K x on the rows of groups g0..g1 into `out` (from the first row of
    /// g0 on), with the values in form `B`: 8 or 4 wide where the CPU
    /// can ([`avx512_groups`], [`avx_groups`]), the same bits.
    #[inline(always)]
    #[allow(unsafe_code)]
    fn groups_into<B: Blocks>(&self, b: &B, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        match self.wide {
            // SAFETY: `wide` says what the CPU has (Compact::with_form).
            Wide::Avx512 => return unsafe { avx512_groups(self, b, g0, g1, x, out) },
            Wide::Avx => return unsafe { avx_groups(self, b, g0, g1, x, out) },
            Wide::No => {}
        }
        let base = self.group_rows[g0] as usize;
        for g in g0..g1 {
            let s = self.group_sums_in(b, g, x);
            let r0 = self.group_rows[g] as usize;
            out[r0 - base] = s[0];
            if self.group_rows[g + 1] as usize - r0 == 2 {
                out[r0 + 1 - base] = s[1];
            }
        }
    }

    /// y = K x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        struct Into<'x, 'y>(usize, &'x [f64], &'y mut [f64]);
        impl Kernel<()> for Into<'_, '_> {
            #[inline(always)]
            fn run<B: Blocks>(self, k: &Compact, b: &B) {
                let Into(c, x, y) = self;
                let (g0, g1) = (k.chunk_groups[c] as usize, k.chunk_groups[c + 1] as usize);
                k.groups_into(b, g0, g1, x, y);
            }
        }
        let body = |c: usize, y: &mut [f64]| self.with_blocks(Into(c, x, y));
        each_chunk(y, body);
    }
}

/// The widest sums a CPU runs for [`Compact`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Wide {
    /// Scalar ([`block`], the compiler's 2-wide operations).
    No,
    /// [`avx_groups`].
    Avx,
    /// [`avx512_groups`].
    Avx512,
}

impl Wide {
    /// The widest this CPU has.
    pub(crate) fn best() -> Wide {
        if avx() && avx512() {
            Wide::Avx512
        } else if avx() {
            Wide::Avx
        } else {
            Wide::No
        }
    }
}

/// A group's row sums ([`group_sums`]) from its even and odd partial sums,
/// each 4 wide, into `out` at the group's rows.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn store_group(
    k: &Compact,
    g: usize,
    base: usize,
    even: std::arch::x86_64::__m256d,
    odd: std::arch::x86_64::__m256d,
    out: &mut [f64],
) {
    use std::arch::x86_64::*;
    let t = _mm256_add_pd(even, odd);
    let rows = _mm_add_pd(_mm256_castpd256_pd128(t), _mm256_extractf128_pd::<1>(t));
    let r0 = k.group_rows[g] as usize - base;
    if k.group_rows[g + 1] as usize - base - r0 == 2 {
        let o: &mut [f64; 2] = (&mut out[r0..r0 + 2]).try_into().expect("2 rows");
        // SAFETY: o holds 2 doubles; unaligned store.
        #[allow(unsafe_code)]
        unsafe {
            _mm_storeu_pd(o.as_mut_ptr(), rows)
        };
    } else {
        out[r0] = _mm_cvtsd_f64(rows);
    }
}

/// x[c], x[c + 1], x[c], x[c + 1]: one 16-byte broadcast.
///
/// # Safety
/// x[c + 1] must be readable from `xp`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[allow(unsafe_code)]
unsafe fn pair_twice(xp: *const f64, c: u32) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    // SAFETY: the caller's; an unaligned read (the broadcast's reference
    // wants 16-byte alignment, x has 8).
    unsafe { _mm256_broadcast_pd(&(xp.add(c as usize) as *const __m128d).read_unaligned()) }
}

/// One block's products added to `acc` ([`block`] 4 wide): x[c], x[c + 1]
/// spread to [x[c], x[c], x[c + 1], x[c + 1]] by an in-lane shuffle.
///
/// # Safety
/// x[c + 1] must be readable from `xp`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[allow(unsafe_code)]
unsafe fn block4(
    xp: *const f64,
    c: u32,
    v: &[f64; 4],
    acc: std::arch::x86_64::__m256d,
) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    // SAFETY: the caller's; v holds 4 doubles (unaligned load).
    let (xv, vv) = unsafe { (pair_twice(xp, c), _mm256_loadu_pd(v.as_ptr())) };
    _mm256_add_pd(acc, _mm256_mul_pd(vv, _mm256_permute_pd::<0b1100>(xv)))
}

/// [`Compact::groups_into`] 4 wide: per group four registers of
/// [`block`]'s partial sums, one per block number mod 4 ([`group_sums`]'s
/// order). Per lane the scalar kernel's operations in its order
/// (multiplications and additions separate, no fused multiply-add), so
/// the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[allow(unsafe_code)]
fn avx_groups<B: Blocks>(k: &Compact, b: &B, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
    use std::arch::x86_64::*;
    let base = k.group_rows[g0] as usize;
    let ids = b.ids();
    // Every block's columns c, c + 1 are below n (Compact::with_form):
    // with x this long, the reads need no check per block.
    let xp = x[..k.n].as_ptr();
    for g in g0..g1 {
        let blocks = k.group_blocks[g] as usize..k.group_blocks[g + 1] as usize;
        let (cols, ids) = (&k.cols[blocks.clone()], &ids[blocks]);
        let mut s = [_mm256_setzero_pd(); 4];
        let quads = cols.len() & !3;
        for (c, i) in cols[..quads]
            .chunks_exact(4)
            .zip(ids[..quads].chunks_exact(4))
        {
            for q in 0..4 {
                // SAFETY: c[q] + 1 < n = x's length (above).
                s[q] = unsafe { block4(xp, c[q], b.value(&i[q]), s[q]) };
            }
        }
        let (mut even, mut odd) = (_mm256_add_pd(s[0], s[2]), _mm256_add_pd(s[1], s[3]));
        for (j, (&c, i)) in cols[quads..].iter().zip(&ids[quads..]).enumerate() {
            let acc = if j % 2 == 0 { &mut even } else { &mut odd };
            // SAFETY: as above.
            *acc = unsafe { block4(xp, c, b.value(i), *acc) };
        }
        store_group(k, g, base, even, odd, out);
    }
}

/// [`Compact::groups_into`] 8 wide: two blocks to a register (the even
/// one's partial sums in the low half, the odd one's in the high), two
/// registers per group (blocks 4m, 4m + 1 and 4m + 2, 4m + 3): lane by
/// lane [`avx_groups`]'s operations, so the same bits, in half the
/// instructions. Where the values are stored, the two blocks are one
/// 64-byte line ([`Lines`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn avx512_groups<B: Blocks>(k: &Compact, b: &B, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
    use std::arch::x86_64::*;
    let base = k.group_rows[g0] as usize;
    let ids = b.ids();
    // As in avx_groups: x[c], x[c + 1] in bounds for every block.
    let xp = x[..k.n].as_ptr();
    let two = |c: &[u32], i: &[B::Id], acc: __m512d| -> __m512d {
        // SAFETY: c[0] + 1, c[1] + 1 < n = x's length (above); two blocks
        // of 4 doubles, as one 8-double load where they are adjacent.
        unsafe {
            let xv = _mm512_insertf64x4::<1>(
                _mm512_castpd256_pd512(pair_twice(xp, c[0])),
                pair_twice(xp, c[1]),
            );
            let v = match b.pair(i) {
                Some(p) => _mm512_loadu_pd(p),
                None => _mm512_insertf64x4::<1>(
                    _mm512_castpd256_pd512(_mm256_loadu_pd(b.value(&i[0]).as_ptr())),
                    _mm256_loadu_pd(b.value(&i[1]).as_ptr()),
                ),
            };
            let xv = _mm512_permute_pd::<0b1100_1100>(xv);
            _mm512_add_pd(acc, _mm512_mul_pd(v, xv))
        }
    };
    for g in g0..g1 {
        let blocks = k.group_blocks[g] as usize..k.group_blocks[g + 1] as usize;
        let (cols, ids) = (&k.cols[blocks.clone()], &ids[blocks]);
        let (mut lo, mut hi) = (_mm512_setzero_pd(), _mm512_setzero_pd());
        let quads = cols.len() & !3;
        for (c, i) in cols[..quads]
            .chunks_exact(4)
            .zip(ids[..quads].chunks_exact(4))
        {
            lo = two(&c[..2], &i[..2], lo);
            hi = two(&c[2..], &i[2..], hi);
        }
        let mut acc = _mm512_add_pd(lo, hi);
        let pairs = cols.len() & !1;
        if pairs > quads {
            acc = two(&cols[quads..pairs], &ids[quads..pairs], acc);
        }
        let (mut even, odd) = (
            _mm512_castpd512_pd256(acc),
            _mm512_extractf64x4_pd::<1>(acc),
        );
        if pairs < cols.len() {
            // SAFETY: as above.
            even = unsafe { block4(xp, cols[pairs], b.value(&ids[pairs]), even) };
        }
        store_group(k, g, base, even, odd, out);
    }
}

/// The product the step's sweeps run over: K x by rows, in batches of a
/// chunk ([`Compact`], the assembled K; [`Classes`], matrix-free). Each row's
/// value must not depend on the batches or chunks it is computed in, so
/// that a run is bit-identical on one thread and on many.
pub trait RowProduct: Sync {
    /// Calls `f(first row, K x on the batch's rows)` for consecutive
    /// batches of at most [`BATCH`] rows covering chunk `c`, in order.
    fn chunk_batches(&self, c: usize, x: &[f64], f: impl FnMut(usize, &[f64]));
    /// (K x)_i alone, with the bits the batches give it.
    fn row(&self, i: usize, x: &[f64]) -> f64;
    /// (K x)_i for each i of `rows` into `out`, with the bits the batches
    /// give them (by default [`RowProduct::row`] each).
    fn rows_at(&self, rows: &[usize], x: &[f64], out: &mut [f64]) {
        for (o, &i) in out.iter_mut().zip(rows) {
            *o = self.row(i, x);
        }
    }
    /// y = K x.
    fn spmv(&self, x: &[f64], y: &mut [f64]);
    /// Bytes one K x streams from the operator's data (all of them).
    fn bytes(&self) -> usize;
    /// Bytes the sweep over `n` rows streams from the operator's data
    /// (where it forms K r_K in its own kernel, it may need less than a
    /// product).
    fn sweep_bytes(&self, _n: usize) -> usize {
        self.bytes()
    }
    /// The sweep of chunk `c` with K r_K formed row by row in the
    /// operator's own kernel and handed to `rows` as it is formed, in row
    /// order; false (nothing done) where the operator has no such kernel.
    fn sweep_chunk(&self, _c: usize, _rows: &mut SweepRows) -> bool {
        false
    }
}

/// The sweep's per-row work for an operator that forms K r_K itself
/// ([`RowProduct::sweep_chunk`]): the rows of one chunk, in order.
pub(crate) struct SweepRows<'a, 'b> {
    avx: bool,
    s: &'a StepData<'a>,
    friction: &'a [(usize, f64)],
    start: usize,
    out: [&'b mut [f64]; 3],
    run: &'b mut Running,
}

impl<'a> SweepRows<'a, '_> {
    /// x of K x: r_K (borrowed from the step's data, not from `self`).
    pub(crate) fn x(&self) -> &'a [f64] {
        self.s.r_new
    }

    /// Rows r0..r0 + ku.len() given their K r_K ([`batch_rows`]).
    #[inline(always)]
    pub(crate) fn rows(&mut self, r0: usize, ku: &[f64]) {
        let o = r0 - self.start;
        let [vn, an, rx] = &mut self.out;
        let out = [&mut vn[o..], &mut an[o..], &mut rx[o..]];
        batch_rows_on(self.avx, self.s, self.friction, r0, ku, out, self.run);
    }

    /// Rows i..i + 8 given their K r_K in a register ([`Rows8::eight`]);
    /// through [`SweepRows::rows`] where a load or friction row is among
    /// them.
    ///
    /// # Safety
    /// The CPU has AVX-512 (foundation) and AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(crate) unsafe fn eight(
        &mut self,
        regs: &mut SumRegs,
        i: usize,
        ku: std::arch::x86_64::__m512d,
    ) {
        if !self.plain(i, i + 8) {
            let mut k = [0.0; 8];
            // SAFETY: k holds 8 doubles; the caller's features.
            unsafe {
                std::arch::x86_64::_mm512_storeu_pd(k.as_mut_ptr(), ku);
                // batch_rows sums through the lanes in memory.
                self.end_sums(*regs);
                self.rows(i, &k);
                *regs = self.begin_sums(i + 8);
            }
            return;
        }
        // SAFETY: the caller's; rows i..i + 8 are in this chunk.
        unsafe { self.rows8().eight(regs, i, ku) }
    }

    /// Rows i..i + ku.len() (at most 8) given their K r_K: by
    /// [`Rows8::some`] where plain, else [`SweepRows::rows`].
    ///
    /// # Safety
    /// The CPU has AVX-512 (foundation) and AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(crate) unsafe fn few(&mut self, i: usize, ku: &[f64]) {
        if !self.plain(i, i + ku.len()) {
            self.rows(i, ku);
            return;
        }
        // SAFETY: the caller's features; rows i..i + ku.len() are in
        // this chunk.
        unsafe {
            let mut regs = self.begin_sums(i);
            self.rows8().some(&mut regs, i, ku);
            self.end_sums(regs);
        }
    }

    /// Whether rows lo..hi of this chunk hold no load row and no friction
    /// row: then [`Rows8::eight`] serves all of them.
    #[inline(always)]
    pub(crate) fn plain(&self, lo: usize, hi: usize) -> bool {
        let (s, run) = (self.s, &*self.run);
        debug_assert!(lo >= self.start && hi - self.start <= self.out[0].len());
        let load_here = s.load_new.len() <= CHUNK
            || (run.load < s.load_rows.len() && s.load_rows[run.load] < hi);
        let friction_here =
            run.friction < self.friction.len() && self.friction[run.friction].0 < hi;
        !(load_here || friction_here)
    }

    /// The operands of [`Rows8::eight`] for this chunk's rows.
    #[inline(always)]
    pub(crate) fn rows8(&mut self) -> Rows8 {
        let s = self.s;
        let [vn, an, rx] = &mut self.out;
        // ṙ_{K−1} and r̈_{K−1} where ṙ_K and r̈_K go when in place (each
        // block reads them before it writes them).
        let (v, a) = if s.in_place {
            (vn.as_ptr(), an.as_ptr())
        } else {
            (s.v[self.start..].as_ptr(), s.a[self.start..].as_ptr())
        };
        Rows8 {
            start: self.start,
            m: s.mass[self.start..].as_ptr(),
            rn: s.r_new[self.start..].as_ptr(),
            v,
            a,
            vn: vn.as_mut_ptr(),
            an: an.as_mut_ptr(),
            rx: rx.as_mut_ptr(),
            c: [s.cv, s.ca, s.scale, s.ratio, s.next.0, s.next.1],
        }
    }

    /// The running sums for 8-row blocks from row i on (i, i + 8, ...) in
    /// registers: lane (i + k) mod 4 of the strain and kinetic sums at
    /// position k, so that each block adds its rows with no rotation (the
    /// same additions in the same order as through the lanes; before,
    /// through memory with two rotations a sum a block: `sweep_lab`,
    /// 2026-11-25, the fused sweep took 0.88-0.90 of its time without
    /// those sums). `sweep_lab`'s sweep in place, this build against the
    /// one before alternating, three runs each, fastest of 20, 2026-11-25
    /// 14:48: Q1 1M 1.50-1.59 against 1.63-1.66 ms, Q2 1M 2.06-2.09
    /// against 2.10-2.23 ms.
    ///
    /// # Safety
    /// The CPU has AVX.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(crate) unsafe fn begin_sums(&self, i: usize) -> SumRegs {
        use std::arch::x86_64::*;
        let run = &*self.run;
        let rot = i % 4;
        let turn = |l: &Lanes| std::array::from_fn::<f64, 4, _>(|k| l.0[(rot + k) % 4]);
        let (strain, kinetic) = (turn(&run.strain), turn(&run.kinetic));
        // SAFETY: the caller's features; each array holds 4 doubles.
        unsafe {
            SumRegs {
                strain: _mm256_loadu_pd(strain.as_ptr()),
                kinetic: _mm256_loadu_pd(kinetic.as_ptr()),
                bound: _mm256_loadu_pd(run.bound.0.as_ptr()),
                finite: true,
                rot,
            }
        }
    }

    /// The sums of [`SweepRows::begin_sums`] back into the lanes.
    ///
    /// # Safety
    /// The CPU has AVX.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(crate) unsafe fn end_sums(&mut self, regs: SumRegs) {
        use std::arch::x86_64::*;
        let run = &mut *self.run;
        let (mut strain, mut kinetic) = ([0.0; 4], [0.0; 4]);
        // SAFETY: the caller's features; each array holds 4 doubles.
        unsafe {
            _mm256_storeu_pd(strain.as_mut_ptr(), regs.strain);
            _mm256_storeu_pd(kinetic.as_mut_ptr(), regs.kinetic);
            _mm256_storeu_pd(run.bound.0.as_mut_ptr(), regs.bound);
        }
        for k in 0..4 {
            run.strain.0[(regs.rot + k) % 4] = strain[k];
            run.kinetic.0[(regs.rot + k) % 4] = kinetic[k];
        }
        run.finite &= regs.finite;
    }
}

/// [`SweepRows`]' running sums held in registers over a run of 8-row
/// blocks ([`SweepRows::begin_sums`]).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct SumRegs {
    strain: std::arch::x86_64::__m256d,
    kinetic: std::arch::x86_64::__m256d,
    bound: std::arch::x86_64::__m256d,
    finite: bool,
    /// The first row's residue mod 4 (every block's: they are 8 apart).
    rot: usize,
}

/// [`SweepRows::eight`]'s operands for one chunk: its vectors from the
/// chunk's first row (`start`) as pointers and the step's constants, a
/// plain value taken once per unit run with no load or friction row
/// ([`SweepRows::plain`]), so that a block neither reloads them through
/// [`SweepRows`] nor checks for those rows and bounds. With the node
/// pairs between runs taken 8 rows at a time ([`Rows8::some`]), the
/// sweep took 0.84-0.92 of its time before on the 1M slabs (`sweep_lab`'s
/// notes); the bench's Q2 1M step 1.92-2.09 against 2.25-2.28 ms, four
/// pairs of runs alternating, 2026-11-25 17:35 (Q1 1M within the host's
/// noise: 1.46-1.96 against 1.66-1.93).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct Rows8 {
    start: usize,
    m: *const f64,
    rn: *const f64,
    v: *const f64,
    a: *const f64,
    vn: *mut f64,
    an: *mut f64,
    rx: *mut f64,
    /// cv, ca, scale, ratio, next.0, next.1 of [`StepData`].
    c: [f64; 6],
}

#[cfg(target_arch = "x86_64")]
impl Rows8 {
    /// Rows i..i + 8 given their K r_K in a register: [`batch_rows`]'s
    /// operations 8 wide (no fused multiply-add; the strain and kinetic
    /// sums into the lanes of their rows, in row order), so the same bits.
    ///
    /// # Safety
    /// The CPU has AVX-512 (foundation) and AVX2; rows i..i + 8 are in
    /// the chunk these operands came from and hold no load or friction
    /// row ([`SweepRows::plain`]).
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(crate) unsafe fn eight(
        &self,
        regs: &mut SumRegs,
        i: usize,
        ku: std::arch::x86_64::__m512d,
    ) {
        use std::arch::x86_64::*;
        let o = i - self.start;
        // SAFETY: the caller's features; every pointer holds 8 doubles
        // from o (rows i..i + 8 of the chunk).
        unsafe {
            let (m, v, a, rn) = (
                _mm512_loadu_pd(self.m.add(o)),
                _mm512_loadu_pd(self.v.add(o)),
                _mm512_loadu_pd(self.a.add(o)),
                _mm512_loadu_pd(self.rn.add(o)),
            );
            let [vn, an, rx] = self.math(m, v, a, rn, ku);
            _mm512_storeu_pd(self.vn.add(o), vn);
            _mm512_storeu_pd(self.an.add(o), an);
            _mm512_storeu_pd(self.rx.add(o), rx);
            // All lanes: the masks below are all ones, which the compiler
            // drops.
            regs.tally(0xff, ku, m, rn, [vn, an, rx]);
        }
    }

    /// [`Rows8::eight`] for rows i..i + ku.len() (at most 8) given their
    /// K r_K: the other lanes neither read nor written, and +0 into their
    /// sums (which start at +0 and so never hold −0: s + 0 = s, the same
    /// bits).
    ///
    /// # Safety
    /// As for [`Rows8::eight`], for rows i..i + ku.len().
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(crate) unsafe fn some(&self, regs: &mut SumRegs, i: usize, ku: &[f64]) {
        use std::arch::x86_64::*;
        debug_assert!(!ku.is_empty() && ku.len() <= 8);
        let k: __mmask8 = (0xffu16 >> (8 - ku.len())) as u8;
        let o = i - self.start;
        // SAFETY: the caller's features; masked loads and stores touch
        // the rows i..i + ku.len() of the chunk (and of ku) only.
        unsafe {
            let ku = _mm512_maskz_loadu_pd(k, ku.as_ptr());
            let (m, v, a, rn) = (
                _mm512_maskz_loadu_pd(k, self.m.add(o)),
                _mm512_maskz_loadu_pd(k, self.v.add(o)),
                _mm512_maskz_loadu_pd(k, self.a.add(o)),
                _mm512_maskz_loadu_pd(k, self.rn.add(o)),
            );
            let [vn, an, rx] = self.math(m, v, a, rn, ku);
            _mm512_mask_storeu_pd(self.vn.add(o), k, vn);
            _mm512_mask_storeu_pd(self.an.add(o), k, an);
            _mm512_mask_storeu_pd(self.rx.add(o), k, rx);
            regs.tally(k, ku, m, rn, [vn, an, rx]);
        }
    }

    /// ṙ_K, r̈_K and r_{K+1} of 8 rows: [`batch_rows`]'s operations.
    ///
    /// # Safety
    /// The CPU has AVX-512 (foundation).
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn math(
        &self,
        m: std::arch::x86_64::__m512d,
        v: std::arch::x86_64::__m512d,
        a: std::arch::x86_64::__m512d,
        rn: std::arch::x86_64::__m512d,
        ku: std::arch::x86_64::__m512d,
    ) -> [std::arch::x86_64::__m512d; 3] {
        use std::arch::x86_64::*;
        let set = _mm512_set1_pd;
        let [cv, ca, scale, ratio, n0, n1] = self.c;
        // SAFETY: the caller's features.
        unsafe {
            // bi = 0 − ku + m (cv ṙ + ca r̈); ṙ_K = bi / (m scale).
            let bi = _mm512_add_pd(
                _mm512_sub_pd(_mm512_setzero_pd(), ku),
                _mm512_mul_pd(
                    m,
                    _mm512_add_pd(_mm512_mul_pd(set(cv), v), _mm512_mul_pd(set(ca), a)),
                ),
            );
            let vn = _mm512_div_pd(bi, _mm512_mul_pd(m, set(scale)));
            let an = _mm512_sub_pd(
                _mm512_mul_pd(_mm512_sub_pd(vn, v), set(scale)),
                _mm512_mul_pd(set(ratio), a),
            );
            let rx = _mm512_add_pd(
                _mm512_add_pd(rn, _mm512_mul_pd(set(n0), vn)),
                _mm512_mul_pd(set(n1), an),
            );
            [vn, an, rx]
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl SumRegs {
    /// The finiteness of r_K and ṙ_K and the strain, kinetic and bound
    /// terms of the rows of a block from row i in the lanes of `k`
    /// (register position p: row i + p) into their sums: positions p and
    /// p + 4 share a lane, added in row order; the other lanes add +0.
    ///
    /// # Safety
    /// The CPU has AVX-512 (foundation).
    #[inline(always)]
    #[allow(unsafe_code)]
    unsafe fn tally(
        &mut self,
        k: std::arch::x86_64::__mmask8,
        ku: std::arch::x86_64::__m512d,
        m: std::arch::x86_64::__m512d,
        rn: std::arch::x86_64::__m512d,
        [vn, an, rx]: [std::arch::x86_64::__m512d; 3],
    ) {
        use std::arch::x86_64::*;
        // SAFETY: the caller's features.
        let terms = unsafe {
            let inf = _mm512_set1_pd(f64::INFINITY);
            let finite =
                |x: __m512d| _mm512_mask_cmp_pd_mask::<_CMP_LT_OQ>(k, _mm512_abs_pd(x), inf);
            self.finite &= (finite(rn) & finite(vn)) == k;
            let abs = _mm512_abs_pd;
            [
                _mm512_maskz_mul_pd(k, rn, ku),
                _mm512_maskz_mul_pd(k, _mm512_mul_pd(m, vn), vn),
                _mm512_maskz_add_pd(k, _mm512_add_pd(abs(vn), abs(an)), abs(rx)),
            ]
        };
        for (acc, t) in [&mut self.strain, &mut self.kinetic, &mut self.bound]
            .into_iter()
            .zip(terms)
        {
            // SAFETY: the caller's features.
            unsafe {
                *acc = _mm256_add_pd(*acc, _mm512_castpd512_pd256(t));
                *acc = _mm256_add_pd(*acc, _mm512_extractf64x4_pd::<1>(t));
            }
        }
    }
}

impl RowProduct for Sliced {
    /// Row by row ([`Sliced::row`], the bits of [`Sliced::spmv`]): the
    /// sweep reads K r_K formed whole when there is one chunk, which is
    /// where [`Sliced`] is used; this serves the iterated friction's passes.
    fn chunk_batches(&self, c: usize, x: &[f64], mut f: impl FnMut(usize, &[f64])) {
        let (start, end) = (c * CHUNK, ((c + 1) * CHUNK).min(self.n()));
        let mut buf = [0.0; BATCH];
        let mut r0 = start;
        while r0 < end {
            let r1 = (r0 + BATCH).min(end);
            for (o, i) in buf.iter_mut().zip(r0..r1) {
                *o = self.row(i, x);
            }
            f(r0, &buf[..r1 - r0]);
            r0 = r1;
        }
    }
    fn row(&self, i: usize, x: &[f64]) -> f64 {
        Sliced::row(self, i, x)
    }
    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        Sliced::spmv(self, x, y)
    }
    fn bytes(&self) -> usize {
        Sliced::bytes(self)
    }
}

impl RowProduct for Compact {
    #[inline]
    fn chunk_batches(&self, c: usize, x: &[f64], f: impl FnMut(usize, &[f64])) {
        Compact::chunk_batches(self, c, x, f)
    }
    fn row(&self, i: usize, x: &[f64]) -> f64 {
        Compact::row(self, i, x)
    }
    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        Compact::spmv(self, x, y)
    }
    fn bytes(&self) -> usize {
        Compact::bytes(self)
    }
}

/// K as the explicit step reads it: the compact form of the assembled K,
/// its slices of four rows by column pairs on systems of one chunk
/// ([`Sliced`]), by stencil types on structured numberings ([`Stencils`]),
/// or matrix-free by element classes when the mesh has them
/// ([`Classes`]: measured faster on the structured Q2 slabs; the module
/// documentation gives the figures).
#[derive(Clone, Debug)]
pub enum Product {
    /// [`Compact`].
    Compact(Compact),
    /// [`Classes`].
    Classes(Classes),
    /// [`Stencils`].
    Stencils(Stencils),
    /// [`Sliced`]: small systems (one chunk).
    Sliced(Sliced),
}

impl RowProduct for Product {
    #[inline]
    fn chunk_batches(&self, c: usize, x: &[f64], f: impl FnMut(usize, &[f64])) {
        match self {
            Product::Compact(k) => RowProduct::chunk_batches(k, c, x, f),
            Product::Classes(k) => k.chunk_batches(c, x, f),
            Product::Stencils(k) => k.chunk_batches(c, x, f),
            Product::Sliced(k) => RowProduct::chunk_batches(k, c, x, f),
        }
    }
    fn row(&self, i: usize, x: &[f64]) -> f64 {
        match self {
            Product::Compact(k) => k.row(i, x),
            Product::Classes(k) => k.row(i, x),
            Product::Stencils(k) => k.row(i, x),
            Product::Sliced(k) => k.row(i, x),
        }
    }
    fn rows_at(&self, rows: &[usize], x: &[f64], out: &mut [f64]) {
        match self {
            Product::Compact(k) => k.rows_at(rows, x, out),
            Product::Classes(k) => k.rows_at(rows, x, out),
            Product::Stencils(k) => k.rows_at(rows, x, out),
            Product::Sliced(k) => k.rows_at(rows, x, out),
        }
    }
    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Product::Compact(k) => k.spmv(x, y),
            Product::Classes(k) => k.spmv(x, y),
            Product::Stencils(k) => k.spmv(x, y),
            Product::Sliced(k) => k.spmv(x, y),
        }
    }
    fn bytes(&self) -> usize {
        match self {
            Product::Compact(k) => k.bytes(),
            Product::Classes(k) => RowProduct::bytes(k),
            Product::Stencils(k) => k.bytes(),
            Product::Sliced(k) => k.bytes(),
        }
    }
    fn sweep_bytes(&self, n: usize) -> usize {
        match self {
            Product::Stencils(k) => k.sweep_bytes(n),
            _ => self.bytes(),
        }
    }
    fn sweep_chunk(&self, c: usize, rows: &mut SweepRows) -> bool {
        match self {
            Product::Stencils(k) => k.sweep_chunk(c, rows),
            _ => false,
        }
    }
}

/// Independent sums per row of a node ([`Classes`]): a node's rows are
/// chains of dependent additions, LANES of them per row hide the adder's
/// latency (the columns taken in turn).
const LANES: usize = 4;

/// K x matrix-free from element classes ([`ElementClasses`]: one element
/// matrix per class of cells alike to the coordinates' rounding), node by
/// node: a node's two rows are the sum over its cells e of the node's rows
/// of K_e times x_e (fixed DOFs read as 0). Each row is a function of x
/// alone (its node's cells in ascending order, the columns in [`LANES`]
/// sums added in a fixed order), whatever the batch or thread computing it.
/// Not the bits of the assembled K's product: within 1e-12 of
/// max_i Σ_j |K_ij x_j| (tests below).
#[derive(Clone, Debug)]
pub struct Classes {
    ec: stickslip_fem::ElementClasses,
}

impl Classes {
    /// The operator of `ec` (Q1 or Q2 cells).
    pub fn new(ec: stickslip_fem::ElementClasses) -> Option<Classes> {
        matches!(ec.nodes_per_cell(), 4 | 9).then_some(Classes { ec })
    }

    /// The element classes.
    pub fn classes(&self) -> &stickslip_fem::ElementClasses {
        &self.ec
    }

    /// K x on rows r0..r0 + out.len() into `out` (a row or two, for the
    /// friction: a one-slot cache, nothing to clear).
    #[inline]
    fn rows_into(&self, r0: usize, x: &[f64], out: &mut [f64]) {
        match self.ec.nodes_per_cell() {
            4 => self.rows_nd::<8, 1>(r0, x, out, &mut Gathered::new()),
            9 => self.rows_nd::<18, 1>(r0, x, out, &mut Gathered::new()),
            _ => unreachable!("Classes::new admits Q1 and Q2"),
        }
    }

    /// [`RowProduct::chunk_batches`] with the cells' x_e gathered once per
    /// chunk ([`Gathered`]).
    #[inline(always)]
    fn batches_nd<const ND: usize>(&self, c: usize, x: &[f64], mut f: impl FnMut(usize, &[f64])) {
        let n = self.ec.n_free();
        let (start, end) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
        let mut buf = [0.0; BATCH];
        let mut cache = Gathered::<ND>::new();
        let mut r0 = start;
        while r0 < end {
            let r1 = (r0 + BATCH).min(end);
            let out = &mut buf[..r1 - r0];
            self.rows_nd::<ND, SLOTS>(r0, x, out, &mut cache);
            f(r0, out);
            r0 = r1;
        }
    }

    #[inline(always)]
    fn rows_nd<const ND: usize, const S: usize>(
        &self,
        r0: usize,
        x: &[f64],
        out: &mut [f64],
        cache: &mut Gathered<ND, S>,
    ) {
        let ec = &self.ec;
        let group_rows = ec.group_rows();
        let mask = ec.group_mask();
        let r1 = r0 + out.len();
        let mut g = group_rows.partition_point(|&r| r as usize <= r0) - 1;
        while g + 1 < group_rows.len() && (group_rows[g] as usize) < r1 {
            let s = self.node_sums::<ND, S>(g, x, cache);
            let mut r = group_rows[g] as usize;
            for (comp, s) in s.iter().enumerate() {
                if mask[g] >> comp & 1 == 1 {
                    if (r0..r1).contains(&r) {
                        out[r - r0] = *s;
                    }
                    r += 1;
                }
            }
            g += 1;
        }
    }

    /// The sums of group g's two rows (a fixed component's too, unused).
    #[inline(always)]
    fn node_sums<const ND: usize, const S: usize>(
        &self,
        g: usize,
        x: &[f64],
        cache: &mut Gathered<ND, S>,
    ) -> [f64; 2] {
        use stickslip_fem::classes::{HAS_FIXED, LOCAL_BITS};
        let ec = &self.ec;
        let (gc, nc) = (ec.group_cells(), ec.node_cells());
        let (classes, matrices) = (ec.cell_class(), ec.matrices());
        let n = ND / 2;
        let mut acc = [[0.0; 2]; LANES];
        for &p in &nc[gc[g] as usize..gc[g + 1] as usize] {
            let e = (p >> LOCAL_BITS) as usize;
            let a = (p & ((1 << LOCAL_BITS) - 1)) as usize;
            let k = (classes[e] & !HAS_FIXED) as usize;
            let m: &[[f64; 2]; ND] = matrices[(k * n + a) * ND..][..ND].try_into().unwrap();
            let xe = cache.get(ec.cell_dofs(), e, x);
            for j in 0..ND {
                let q = j % LANES;
                acc[q][0] += m[j][0] * xe[j];
                acc[q][1] += m[j][1] * xe[j];
            }
        }
        std::array::from_fn(|r| (acc[0][r] + acc[1][r]) + (acc[2][r] + acc[3][r]))
    }
}

/// Slots of [`Gathered`] (a power of 2).
const SLOTS: usize = 256;

/// A direct-mapped cache of cells' x_e (slot: cell mod [`SLOTS`]): a cell
/// serves up to 9 nodes, most of them in one chunk, so its x_e is gathered
/// about once per chunk instead of once per node. A copy of x's entries (0
/// at fixed DOFs), so the sums do not depend on what was cached.
struct Gathered<const ND: usize, const S: usize = SLOTS> {
    tags: [u32; S],
    xe: [[f64; ND]; S],
}

impl<const ND: usize, const S: usize> Gathered<ND, S> {
    fn new() -> Self {
        Gathered {
            tags: [u32::MAX; S],
            xe: [[0.0; ND]; S],
        }
    }

    /// x_e of cell e.
    #[inline(always)]
    fn get(&mut self, dofs: &[u32], e: usize, x: &[f64]) -> &[f64; ND] {
        let slot = e % S;
        if self.tags[slot] != e as u32 {
            let d: &[u32; ND] = dofs[e * ND..][..ND].try_into().unwrap();
            // A fixed DOF (u32::MAX) is out of range: 0.
            self.xe[slot] = std::array::from_fn(|j| x.get(d[j] as usize).copied().unwrap_or(0.0));
            self.tags[slot] = e as u32;
        }
        &self.xe[slot]
    }
}

impl RowProduct for Classes {
    #[inline]
    fn chunk_batches(&self, c: usize, x: &[f64], f: impl FnMut(usize, &[f64])) {
        match self.ec.nodes_per_cell() {
            4 => self.batches_nd::<8>(c, x, f),
            9 => self.batches_nd::<18>(c, x, f),
            _ => unreachable!("Classes::new admits Q1 and Q2"),
        }
    }

    fn row(&self, i: usize, x: &[f64]) -> f64 {
        let mut out = [0.0];
        self.rows_into(i, x, &mut out);
        out[0]
    }

    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        each_chunk(y, |c, y| {
            self.chunk_batches(c, x, |r0, ku| {
                y[r0 - c * CHUNK..][..ku.len()].copy_from_slice(ku);
            })
        });
    }

    fn bytes(&self) -> usize {
        self.ec.bytes()
    }
}

/// The SpMV fused with pass B ([`rhs_and_velocity`]): each row's K r_K is
/// used as soon as it is summed, so K r_K is never written and read back
/// (two vector passes fewer). The same arithmetic per entry and the same
/// order of the strain sum, hence the same bits.
#[allow(clippy::too_many_arguments)]
pub fn spmv_rhs_and_velocity<K: RowProduct>(
    k: &K,
    load_new: &[f64],
    mass: &[f64],
    r_new: &[f64],
    v: &[f64],
    a: &[f64],
    cv: f64,
    ca: f64,
    scale: f64,
    b: &mut [f64],
    v_new: &mut [f64],
    partials: &mut Partials,
) -> f64 {
    let body = |c: usize, b: &mut [f64], vn: &mut [f64], partial: &mut [f64; 6]| {
        let start = c * CHUNK;
        let mut strain = 0.0;
        k.chunk_batches(c, r_new, |r0, kus| {
            for (j, &ku) in kus.iter().enumerate() {
                let i = r0 + j;
                strain += r_new[i] * ku;
                let bi = load_new[i] - ku + mass[i] * (cv * v[i] + ca * a[i]);
                b[i - start] = bi;
                vn[i - start] = bi / (mass[i] * scale);
            }
        });
        partial[0] = strain;
    };
    each_chunk_pair(b, v_new, partials, body);
    0.5 * total(partials, 0)
}

/// The vectors and coefficients of one explicit step for [`fused_step`].
pub struct StepData<'a> {
    /// R_K (+0 off `load_rows`).
    pub load_new: &'a [f64],
    /// The rows where R_K may be nonzero ([`SparseLoads::rows`]).
    pub load_rows: &'a [usize],
    /// Lumped mass.
    pub mass: &'a [f64],
    /// r_K (the predictor, final for β = 0).
    pub r_new: &'a [f64],
    /// ṙ_{K−1} (empty when `in_place`).
    pub v: &'a [f64],
    /// r̈_{K−1} (empty when `in_place`).
    pub a: &'a [f64],
    /// The sweep reads ṙ_{K−1} and r̈_{K−1} from its outputs for ṙ_K and
    /// r̈_K and writes those over them ([`fused_step`]).
    pub in_place: bool,
    /// Coefficients of R̂_K: 1/(γΔt) and 1/γ − 1.
    pub cv: f64,
    /// See `cv`.
    pub ca: f64,
    /// 1/(γΔt): ṙ_K = b/(m·scale), r̈_K = (ṙ_K − ṙ)·scale − ratio·r̈.
    pub scale: f64,
    /// (1−γ)/γ.
    pub ratio: f64,
    /// The next step's predictor coefficients c1, c2 for a step of the
    /// same Δt ([`predict`]'s): the sweep writes r_K + c1 ṙ_K + c2 r̈_K.
    pub next: (f64, f64),
}

impl StepData<'_> {
    /// The step's coefficients, with no vectors (their slices empty).
    pub fn coefficients(&self) -> StepData<'static> {
        StepData {
            load_new: &[],
            load_rows: &[],
            mass: &[],
            r_new: &[],
            v: &[],
            a: &[],
            in_place: self.in_place,
            cv: self.cv,
            ca: self.ca,
            scale: self.scale,
            ratio: self.ratio,
            next: self.next,
        }
    }
}

/// R̂_K at one row from its K r_K (pass B's arithmetic).
#[inline]
pub fn rhs_entry(s: &StepData, i: usize, ku: f64) -> f64 {
    rhs_value(s, i, ku, s.v[i], s.a[i])
}

/// [`rhs_entry`] with row i's ṙ_{K−1} and r̈_{K−1} given.
#[inline(always)]
fn rhs_value(s: &StepData, i: usize, ku: f64, v: f64, a: f64) -> f64 {
    s.load_new[i] - ku + s.mass[i] * (s.cv * v + s.ca * a)
}

/// A sum over rows in four lanes, row i in lane i mod 4, added
/// (l0 + l1) + (l2 + l3) at the end: four chains of additions instead of
/// one (a chain per row costs the adder's latency, 3 cycles, which the
/// sweep paid per row: `sweep_lab` 1M Q1 2.62 → 2.42 ms, fastest of 20,
/// one run each, 2026-11-24; later A/B runs drowned in the host's noise),
/// in an order fixed by the rows whatever batch or thread adds them.
#[derive(Clone, Copy, Default)]
pub(crate) struct Lanes([f64; 4]);

impl Lanes {
    /// Adds term(k) for rows i0 + k, k < n.
    #[inline(always)]
    pub(crate) fn add_rows(&mut self, i0: usize, n: usize, term: impl Fn(usize) -> f64) {
        // A local copy: summed through `self` the lanes stayed in memory,
        // a store and a reload per row (the paper mesh's sweep).
        let mut lanes = self.0;
        let mut k = 0;
        while k < n && !(i0 + k).is_multiple_of(4) {
            lanes[(i0 + k) % 4] += term(k);
            k += 1;
        }
        while k + 4 <= n {
            for l in 0..4 {
                lanes[l] += term(k + l);
            }
            k += 4;
        }
        while k < n {
            lanes[(i0 + k) % 4] += term(k);
            k += 1;
        }
        self.0 = lanes;
    }

    /// Adds term(a[k], b[k]) for rows i0 + k: [`Lanes::add_rows`]'s sums
    /// (the same lanes, the same order), over zipped slices, so that the
    /// four lanes are one AVX register with no bounds checks (the paper
    /// mesh's sweep: its strain and kinetic sums were 30% of it, scalar).
    #[inline(always)]
    pub(crate) fn add_pairs(
        &mut self,
        i0: usize,
        a: &[f64],
        b: &[f64],
        term: impl Fn(f64, f64) -> f64,
    ) {
        let n = a.len().min(b.len());
        let (a, b) = (&a[..n], &b[..n]);
        let mut lanes = self.0;
        let head = ((4 - i0 % 4) % 4).min(n);
        for k in 0..head {
            lanes[(i0 + k) % 4] += term(a[k], b[k]);
        }
        let (mut a4, mut b4) = (a[head..].chunks_exact(4), b[head..].chunks_exact(4));
        for (x, y) in (&mut a4).zip(&mut b4) {
            for l in 0..4 {
                lanes[l] += term(x[l], y[l]);
            }
        }
        // Past the whole quads row i0 + k sits in lane k.
        for (l, (x, y)) in a4.remainder().iter().zip(b4.remainder()).enumerate() {
            lanes[l] += term(*x, *y);
        }
        self.0 = lanes;
    }

    /// The sum.
    pub(crate) fn total(self) -> f64 {
        (self.0[0] + self.0[1]) + (self.0[2] + self.0[3])
    }
}

/// The sweep's running sums over a chunk ([`Lanes`]).
pub(crate) struct Running {
    strain: Lanes,
    kinetic: Lanes,
    /// Σ |ṙ_K| + |r̈_K| + |r_{K+1}|, for the in-place guard
    /// (`Integrator`): finite, it bounds every entry of the three.
    bound: Lanes,
    finite: bool,
    /// Next entries of `load_rows` and `friction`.
    load: usize,
    friction: usize,
}

/// The sweep's per-row work on rows r0..r0 + ku.len() given their K r_K:
/// ṙ_K = R̂_K/(m·scale) (with R_K = +0 first, the literal, then again at
/// the load rows with their R_K: [`rhs_entry`]'s operations either way),
/// the friction's velocities at the contact DOFs, r̈_K, and the strain and
/// kinetic sums ([`Lanes`]). Loops over the batch rather than one pass
/// per row: the first two have no dependence between rows, so their
/// divisions overlap. In place ([`StepData::in_place`]) ṙ_K waits in the
/// predictor's slot, which is written last, so that the first loops still
/// read ṙ_{K−1} and r̈_{K−1} where the last writes ṙ_K and r̈_K.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn batch_rows(
    s: &StepData,
    friction: &[(usize, f64)],
    r0: usize,
    ku: &[f64],
    out: [&mut [f64]; 3],
    run: &mut Running,
) {
    let [vn, an, r_next] = out;
    let n = ku.len();
    let rows = r0..r0 + n;
    let rn = &s.r_new[rows.clone()];
    let r_next = &mut r_next[..n];
    if s.in_place {
        let (v, a) = (&mut vn[..n], &mut an[..n]);
        velocities(s, friction, r0, ku, [&*v, &*a], r_next, run);
        let mut finite = run.finite;
        for k in 0..n {
            let vk = r_next[k];
            let [ak, rx] = accelerate(s, rn[k], vk, v[k], a[k]);
            (v[k], a[k], r_next[k]) = (vk, ak, rx);
            finite &= rn[k].is_finite() & vk.is_finite();
        }
        run.finite = finite;
        sums(s, r0, ku, [&*v, &*a, &*r_next], run);
    } else {
        let (v, a) = (&s.v[rows.clone()], &s.a[rows]);
        let (vn, an) = (&mut vn[..n], &mut an[..n]);
        velocities(s, friction, r0, ku, [v, a], vn, run);
        let mut finite = run.finite;
        for k in 0..n {
            [an[k], r_next[k]] = accelerate(s, rn[k], vn[k], v[k], a[k]);
            // `&`, not `&&`: no branch, so the loop stays vectorized.
            finite &= rn[k].is_finite() & vn[k].is_finite();
        }
        run.finite = finite;
        sums(s, r0, ku, [&*vn, &*an, &*r_next], run);
    }
}

/// [`batch_rows`]' ṙ_K into `vn` from ṙ_{K−1} and r̈_{K−1} (`old`).
#[inline(always)]
fn velocities(
    s: &StepData,
    friction: &[(usize, f64)],
    r0: usize,
    ku: &[f64],
    [v, a]: [&[f64]; 2],
    vn: &mut [f64],
    run: &mut Running,
) {
    let n = ku.len();
    let m = &s.mass[r0..r0 + n];
    let (v, a, vn) = (&v[..n], &a[..n], &mut vn[..n]);
    let (cv, ca, scale) = (s.cv, s.ca, s.scale);
    if s.load_new.len() <= CHUNK {
        // One chunk: the vectors are in cache, so R_K is read densely (+0
        // off the load rows, where +0 − K r_K has the bits of the other
        // branch's 0 − K r_K) instead of a scalar pass over the load rows
        // with a division each.
        let l = &s.load_new[r0..r0 + n];
        for k in 0..n {
            let bi = l[k] - ku[k] + m[k] * (cv * v[k] + ca * a[k]);
            vn[k] = bi / (m[k] * scale);
        }
    } else {
        for k in 0..n {
            let zero = 0.0;
            let bi = zero - ku[k] + m[k] * (cv * v[k] + ca * a[k]);
            vn[k] = bi / (m[k] * scale);
        }
    }
    while s.load_new.len() > CHUNK && run.load < s.load_rows.len() && s.load_rows[run.load] < r0 + n
    {
        let i = s.load_rows[run.load];
        let k = i - r0;
        vn[k] = rhs_value(s, i, ku[k], v[k], a[k]) / (m[k] * scale);
        run.load += 1;
    }
    while run.friction < friction.len() && friction[run.friction].0 < r0 + n {
        let (i, vi) = friction[run.friction];
        vn[i - r0] = vi;
        run.friction += 1;
    }
}

/// r̈_K and the next predictor r_K + c1 ṙ_K + c2 r̈_K of one row, from
/// r_K, ṙ_K, ṙ_{K−1} and r̈_{K−1}.
#[inline(always)]
fn accelerate(s: &StepData, rn: f64, vn: f64, v: f64, a: f64) -> [f64; 2] {
    let ak = (vn - v) * s.scale - s.ratio * a;
    [ak, rn + s.next.0 * vn + s.next.1 * ak]
}

/// [`batch_rows`]' sums over its rows from r0: strain and kinetic
/// ([`Lanes`]) and, on systems of more than one chunk (the only ones that
/// step in place), the in-place guard's Σ |ṙ_K| + |r̈_K| + |r_{K+1}|.
#[inline(always)]
fn sums(s: &StepData, r0: usize, ku: &[f64], [vn, an, rx]: [&[f64]; 3], run: &mut Running) {
    let n = ku.len();
    let (rn, m) = (&s.r_new[r0..r0 + n], &s.mass[r0..r0 + n]);
    run.strain.add_pairs(r0, rn, ku, |r, u| r * u);
    run.kinetic.add_pairs(r0, m, vn, |m, v| m * v * v);
    if s.mass.len() > CHUNK {
        run.bound.add_pairs(r0, vn, an, |v, a| v.abs() + a.abs());
        run.bound.add_pairs(r0, rx, rx, |r, _| r.abs());
    }
}

/// [`batch_rows`] compiled for AVX: the same IEEE operations (no fused
/// multiply-add), in 4-wide registers where the compiler vectorizes, so
/// the same bits: `sweep_lab`'s "sweep, SSE2" against "sweep, AVX", 1M
/// DOFs, 2026-11-24, medians of 20 in three runs: Q1 3.06 / 2.86, 3.03 /
/// 2.79, 2.97 / 2.90 ms; Q2 3.90 / 3.86, 3.92 / 3.83, 4.80 / 4.76 ms.
/// Call only where [`avx`] said yes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[allow(clippy::too_many_arguments)]
fn batch_rows_avx(
    s: &StepData,
    friction: &[(usize, f64)],
    r0: usize,
    ku: &[f64],
    out: [&mut [f64]; 3],
    run: &mut Running,
) {
    batch_rows(s, friction, r0, ku, out, run)
}

/// [`batch_rows`], by [`batch_rows_avx`] where `avx` (the CPU has AVX).
#[inline(always)]
#[allow(clippy::too_many_arguments, unsafe_code)]
fn batch_rows_on(
    avx: bool,
    s: &StepData,
    friction: &[(usize, f64)],
    r0: usize,
    ku: &[f64],
    out: [&mut [f64]; 3],
    run: &mut Running,
) {
    #[cfg(target_arch = "x86_64")]
    if avx {
        // SAFETY: `avx` is `avx()`'s answer for this CPU.
        unsafe { batch_rows_avx(s, friction, r0, ku, out, run) };
        return;
    }
    let _ = avx;
    batch_rows(s, friction, r0, ku, out, run)
}

/// Whether this CPU has AVX (checked once; cached by std).
pub(crate) fn avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether this CPU has AVX-512 (foundation).
pub(crate) fn avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether this CPU has AVX2.
pub(crate) fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether this CPU has fused multiply-add (FMA3).
pub(crate) fn fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Passes B and C and the SpMV in one sweep: per row, K r_K, R̂_K,
/// ṙ_K = R̂_K/(m·scale) — or, at the contact DOFs, the velocity the nodal
/// friction gave (`friction`, (DOF, ṙ_K) sorted by DOF, computed before
/// from [`Compact::row`] and [`rhs_entry`]) — then r̈_K and the sums. Per
/// entry the arithmetic of [`rhs_and_velocity`] and [`accelerate_and_sum`],
/// per chunk the sums in the same order: the same bits as the three passes.
/// The work and load sums are pass A's ([`predict`], over the load rows,
/// in `partials[c][0]` and `[2]`), so the sweep reads neither R_{K−1} nor
/// r_{K−1}: with pass A, 10 vector streams per step (pass A reads r, ṙ,
/// r̈ and writes r_K; the sweep reads r_K, m, ṙ, r̈ and writes ṙ_K, r̈_K)
/// instead of 24 for the three passes over dense loads, and R̂_K never
/// stored.
///
/// `ku`: K r_K when the caller has it (the one-chunk step computes it
/// first for the friction, [`Compact::spmv`]); else the sweep forms it.
///
/// `r_next`: the next step's predictor r_K + c1 ṙ_K + c2 r̈_K
/// (`s.next`), with [`predict`]'s operations, so that a next step of the
/// same Δt skips pass A's sweep (three vector streams read and one
/// written fewer, one written here: 7 streams a step instead of 10).
///
/// With [`StepData::in_place`], `v_new` and `a_new` hold ṙ_{K−1} and
/// r̈_{K−1} (`s.v`, `s.a` empty), and ṙ_K and r̈_K are written over them:
/// the same bits, and the lines written were just read, so the core does
/// not fetch them first (a store to a line not in cache reads it, the
/// write-allocate the separate outputs paid on 2 of their 3 streams).
#[allow(clippy::too_many_arguments)]
pub fn fused_step<K: RowProduct>(
    k: &K,
    s: &StepData,
    friction: &[(usize, f64)],
    ku: Option<&[f64]>,
    v_new: &mut [f64],
    a_new: &mut [f64],
    r_next: &mut [f64],
    partials: &mut Partials,
) -> (f64, Sums) {
    let out = [v_new, a_new, r_next];
    sweep(avx(), k, s, friction, ku, out, partials)
}

/// [`fused_step`], its per-row work compiled for AVX where `avx`.
pub(crate) fn sweep<K: RowProduct>(
    avx: bool,
    k: &K,
    s: &StepData,
    friction: &[(usize, f64)],
    ku: Option<&[f64]>,
    out: [&mut [f64]; 3],
    partials: &mut Partials,
) -> (f64, Sums) {
    let body = |c: usize, [vn, an, rx]: [&mut [f64]; 3], partial: &mut [f64; 6]| {
        let start = c * CHUNK;
        let mut run = Running {
            strain: Lanes::default(),
            kinetic: Lanes::default(),
            bound: Lanes::default(),
            finite: true,
            // (Chunk 0, the only one of small systems, starts at both
            // lists' starts: no binary search, a chain of dependent loads.)
            load: if start == 0 {
                0
            } else {
                s.load_rows.partition_point(|&i| i < start)
            },
            friction: if start == 0 {
                0
            } else {
                friction.partition_point(|f| f.0 < start)
            },
        };
        match ku {
            Some(ku) => {
                let ku = &ku[start..start + vn.len()];
                batch_rows_on(avx, s, friction, start, ku, [vn, an, rx], &mut run);
            }
            None => sweep_batches(avx, k, s, friction, c, [vn, an, rx], &mut run),
        }
        partial[1] = run.kinetic.total();
        partial[3] = if run.finite { 0.0 } else { 1.0 };
        partial[4] = run.strain.total();
        partial[5] = run.bound.total();
    };
    each_chunk_triple(out, partials, body);
    (
        0.5 * total(partials, 4),
        Sums {
            work: total(partials, 0),
            kinetic: 0.5 * total(partials, 1),
            load_dot: total(partials, 2),
            finite: total(partials, 3) == 0.0,
            bound: if chunks(s.mass.len()) > 1 {
                total(partials, 5)
            } else {
                f64::INFINITY
            },
        },
    )
}

/// The sweep of chunk `c` forming K r_K by batches. Not inlined into the
/// sweep: the products' batch buffers make a frame of several pages whose
/// stack probe the one-chunk sweep (K r_K given) paid on every step, about
/// 3% of the paper mesh's explicit step.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn sweep_batches<K: RowProduct>(
    avx: bool,
    k: &K,
    s: &StepData,
    friction: &[(usize, f64)],
    c: usize,
    out: [&mut [f64]; 3],
    run: &mut Running,
) {
    let mut rows = SweepRows {
        avx,
        s,
        friction,
        start: c * CHUNK,
        out,
        run,
    };
    if !k.sweep_chunk(c, &mut rows) {
        k.chunk_batches(c, s.r_new, |r0, ku| rows.rows(r0, ku));
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};
    use stickslip_fem::testing::on_threads;
    use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
    use stickslip_mesh::Mesh;

    /// `Lanes::add_pairs` gives `add_rows`'s lanes bit for bit, from every
    /// first row mod 4 and lengths with and without a head or a tail.
    #[test]
    fn lanes_add_pairs_matches_add_rows() {
        let a: Vec<f64> = (0..23)
            .map(|i| (i as f64 * 0.618_034).fract() - 0.3)
            .collect();
        let b: Vec<f64> = (0..23)
            .map(|i| (i as f64 * 0.414_214).fract() * 1e3)
            .collect();
        for i0 in 0..8 {
            for n in 0..=a.len() {
                let (mut p, mut q) = (Lanes::default(), Lanes::default());
                p.add_rows(i0, n, |k| a[k] * b[k] * b[k]);
                q.add_pairs(i0, &a[..n], &b[..n], |x, y| x * y * y);
                assert_eq!(
                    p.0.map(f64::to_bits),
                    q.0.map(f64::to_bits),
                    "i0 {i0} n {n}"
                );
                // Again onto lanes that hold sums already.
                p.add_rows(i0 + n, 5, |k| b[k] - a[k]);
                q.add_pairs(i0 + n, &b[..5], &a[..5], |x, y| x - y);
                assert_eq!(
                    p.0.map(f64::to_bits),
                    q.0.map(f64::to_bits),
                    "i0 {i0} n {n}"
                );
            }
        }
    }

    /// The labs' slab, named "q1-NXxNY" or "q2-NXxNY": 8 × 1, rollers on
    /// top, held in x at the left.
    pub(crate) fn lab_slab(name: &str) -> (Mesh, Material, Model) {
        use stickslip_fem::testing::rectangle;
        use stickslip_mesh::CellKind;
        let (order, size) = name.split_once('-').expect("q1-NXxNY or q2-NXxNY");
        let (nx, ny) = size.split_once('x').expect("NXxNY");
        let kind = if order == "q2" {
            CellKind::Quad9
        } else {
            CellKind::Quad4
        };
        let mesh = rectangle(
            kind,
            nx.parse().unwrap(),
            ny.parse().unwrap(),
            [0.0, 0.0],
            [8.0, 1.0],
        );
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new("top", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let model = Model::new(&mesh, &material, &supports).unwrap();
        (mesh, material, model)
    }

    /// A step's data with the labs' coefficients (Δt = 1e-3, γ = ½, no
    /// load rows).
    pub(crate) fn lab_data<'a>(
        load_new: &'a [f64],
        mass: &'a [f64],
        r_new: &'a [f64],
        v: &'a [f64],
        a: &'a [f64],
    ) -> StepData<'a> {
        StepData {
            load_new,
            load_rows: &[],
            mass,
            r_new,
            v,
            a,
            in_place: false,
            cv: 2e3,
            ca: 1.0,
            scale: 2e3,
            ratio: 1.0,
            next: (1e-3, 0.5e-6),
        }
    }

    /// The labs' sweep: no friction, K r_K formed in the sweep.
    fn lab_sweep<K: RowProduct>(
        k: &K,
        data: &StepData,
        [vn, an, rx]: [&mut [f64]; 3],
        p: &mut Partials,
    ) {
        fused_step(k, data, &[], None, vn, an, rx, p);
    }

    /// A deterministic, non-repeating x with entries of both signs.
    /// The labs' timing: the median over 30 rounds of `reps` calls of `f`,
    /// seconds a call.
    pub(crate) fn median_time(reps: usize, f: &mut dyn FnMut()) -> f64 {
        let mut t: Vec<f64> = (0..30)
            .map(|_| {
                let s = std::time::Instant::now();
                for _ in 0..reps {
                    f();
                }
                s.elapsed().as_secs_f64() / reps as f64
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    }

    pub(crate) fn x_of(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i as f64 * 0.618_033_988_75).fract() - 0.5) * (1.0 + i as f64 * 1e-3))
            .collect()
    }

    /// K x in [`Compact`]'s order ([`group_sums`]) from the CSR alone:
    /// each row's blocks are the pair starts of its columns (a node's two
    /// rows have the same columns; a DOF without a partner starts its
    /// block one column early, column 0 at itself), their count rounded up
    /// to even; an entry of block j in column half h goes to partial sum
    /// (j mod 4, h) while j is in the whole quads, then to even (j even) or
    /// odd; y = Σ_h (even_h + odd_h).
    pub(crate) fn compact_order_spmv(k: &CsrMatrix<f64>, x: &[f64]) -> Vec<f64> {
        let n = k.nrows();
        let (off, cols, vals) = (k.row_offsets(), k.col_indices(), k.values());
        let row = |i: usize| &cols[off[i]..off[i + 1]];
        let mut start = vec![0; n];
        let mut i = 0;
        while i < n {
            if i + 1 < n && row(i) == row(i + 1) {
                (start[i], start[i + 1]) = (i, i);
                i += 2;
            } else {
                start[i] = i.saturating_sub(1);
                i += 1;
            }
        }
        (0..n)
            .map(|i| {
                let mut blocks: Vec<usize> = row(i).iter().map(|&c| start[c]).collect();
                blocks.dedup();
                let quads = (blocks.len() + blocks.len() % 2) & !3;
                let mut p = [[0.0; 2]; 4];
                let (mut even, mut odd) = ([0.0; 2], [0.0; 2]);
                let mut formed = false;
                for e in off[i]..off[i + 1] {
                    let c = cols[e];
                    let j = blocks.binary_search(&start[c]).expect("a block");
                    let h = c - start[c];
                    if j < quads {
                        p[j % 4][h] += vals[e] * x[c];
                        continue;
                    }
                    if !formed {
                        even = [p[0][0] + p[2][0], p[0][1] + p[2][1]];
                        odd = [p[1][0] + p[3][0], p[1][1] + p[3][1]];
                        formed = true;
                    }
                    let sums = if (j - quads).is_multiple_of(2) {
                        &mut even
                    } else {
                        &mut odd
                    };
                    sums[h] += vals[e] * x[c];
                }
                if !formed {
                    even = [p[0][0] + p[2][0], p[0][1] + p[2][1]];
                    odd = [p[1][0] + p[3][0], p[1][1] + p[3][1]];
                }
                (even[0] + odd[0]) + (even[1] + odd[1])
            })
            .collect()
    }

    /// [`Compact`] at every width this CPU runs.
    pub(crate) fn widths(compact: &Compact) -> Vec<Compact> {
        [Wide::No, Wide::Avx, Wide::Avx512]
            .into_iter()
            .filter(|&w| match w {
                Wide::No => true,
                Wide::Avx => avx(),
                Wide::Avx512 => avx() && avx512(),
            })
            .map(|wide| Compact {
                wide,
                ..compact.clone()
            })
            .collect()
    }

    /// The compact K·x sums in the order [`Compact`] defines (padding
    /// zeros exact) at every width, on the committed meshes with the
    /// slab's supports (single-DOF nodes on two edges) and on a free model
    /// (every node a full pair).
    #[test]
    fn compact_spmv_has_the_bits_of_its_order() {
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        for name in [
            "slab-q2-8x2.msh",
            "slab-q1-128x32.msh",
            "slab-q2-64x16.msh",
            "slab-unstructured-q1.msh",
            "slab-unstructured-q2.msh",
        ] {
            let mesh = Mesh::from_file(dir.join(name)).unwrap();
            for conditions in [&supports[..], &[]] {
                let model = Model::new(&mesh, &material, conditions).unwrap();
                for k in [&model.stiffness, &model.mass] {
                    let n = k.nrows();
                    let x = x_of(n);
                    let y0 = compact_order_spmv(k, &x);
                    for form in [Form::Stored, Form::Dictionary, Form::Auto] {
                        let compact = Compact::with_form(k, form).expect("applies");
                        for compact in widths(&compact) {
                            let mut y1 = vec![1.0; n];
                            compact.spmv(&x, &mut y1);
                            let w = compact.wide;
                            for i in 0..n {
                                assert_eq!(
                                    y0[i].to_bits(),
                                    y1[i].to_bits(),
                                    "{name} {form:?} {w:?} row {i}"
                                );
                            }
                        }
                        for i in 0..n {
                            assert_eq!(
                                y0[i].to_bits(),
                                compact.row(i, &x).to_bits(),
                                "{name} {form:?} row {i} alone"
                            );
                        }
                        // A Q1 / Q2 node's two rows are one pair (the blocks
                        // are at most 4/3 of the CSR's entries, the padding
                        // is only at constrained nodes and chunk seams).
                        assert!(3 * compact.cols.len() <= k.nnz(), "{name}");
                        let dict = compact.dictionary_len();
                        match form {
                            Form::Stored => assert_eq!(dict, 0),
                            Form::Dictionary => assert!(dict > 0 && dict <= compact.blocks()),
                            Form::Auto => {}
                        }
                    }
                }
            }
        }
    }

    /// The one-sweep step (friction velocities handed in, loads over their
    /// rows) has the bits of the CSR SpMV and the dense passes A, B and C
    /// with the friction written between B and C, as the step did before
    /// the sweep: on a model of several chunks and on the paper's mesh (one
    /// chunk, K r_K handed in and formed in the sweep), both value forms,
    /// serial and on two threads.
    #[test]
    fn fused_step_has_the_bits_of_the_passes() {
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        for (name, several) in [("slab-q2-64x16.msh", true), ("slab-q2-8x2.msh", false)] {
            let mesh = Mesh::from_file(dir.join(name)).unwrap();
            let model = Model::new(&mesh, &material, &supports).unwrap();
            let k = &model.stiffness;
            let n = k.nrows();
            assert_eq!(chunks(n) >= 2, several, "{name}: {n} DOFs");
            let forms = [
                Compact::with_form(k, Form::Stored).unwrap(),
                Compact::with_form(k, Form::Dictionary).unwrap(),
            ];
            assert!(forms[1].dictionary_len() > 0);
            for threads in [1, 2] {
                for compact in &forms {
                    on_threads(threads, || {
                        check_fused(k, compact, &format!("{name} {threads}"))
                    });
                }
            }
        }
    }

    /// A NaN or infinite r_K or ṙ_K in any row, in either chunk, with K r_K
    /// handed in or not, clears the sweep's finiteness flag.
    #[test]
    fn fused_step_flags_non_finite() {
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        for name in ["slab-q2-8x2.msh", "slab-q2-64x16.msh"] {
            let mesh = Mesh::from_file(dir.join(name)).unwrap();
            let model = Model::new(&mesh, &material, &[]).unwrap();
            let k = &model.stiffness;
            let n = k.nrows();
            let compact = Compact::new(k).unwrap();
            let mass = vec![1.0; n];
            let zero = vec![0.0; n];
            for (row, bad, in_r) in [
                (0, f64::NAN, true),
                (n - 1, f64::INFINITY, false),
                (n / 2 + 1, f64::NEG_INFINITY, true),
                (n / 3, f64::NAN, false),
            ] {
                let mut r_new = x_of(n);
                let mut v = vec![0.5; n];
                if in_r {
                    r_new[row] = bad;
                } else {
                    v[row] = bad;
                }
                let data = StepData {
                    load_new: &zero,
                    load_rows: &[],
                    mass: &mass,
                    r_new: &r_new,
                    v: &v,
                    a: &zero,
                    in_place: false,
                    cv: 2.0,
                    ca: 1.0,
                    scale: 2.0,
                    ratio: 1.0,
                    next: (1e-3, 0.5e-6),
                };
                let mut ku = vec![0.0; n];
                compact.spmv(&r_new, &mut ku);
                for given in [None, Some(&ku[..])] {
                    let mut p = partials(n);
                    let (mut vn, mut an, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                    let (_, sums) = fused_step(
                        &compact,
                        &data,
                        &[],
                        given,
                        &mut vn,
                        &mut an,
                        &mut rx,
                        &mut p,
                    );
                    assert!(!sums.finite, "{name} row {row} {bad}");
                }
            }
        }
    }

    /// `predict`'s R_K and sums with loads past [`ACTIVE_LOADS`] (θ tested
    /// per row) and within it (the active ones picked once), some θ = 0:
    /// the bits of the dense sum in the loads' order either way.
    #[test]
    fn predict_with_few_and_many_loads() {
        let n = 40;
        for count in [3, ACTIVE_LOADS, ACTIVE_LOADS + 3] {
            let loads: Vec<Vec<f64>> = (0..count)
                .map(|l| {
                    (0..n)
                        .map(|i| {
                            if (i + l) % 7 == 0 {
                                0.1 + 0.37 * l as f64 - 1e-3 * i as f64
                            } else {
                                0.0
                            }
                        })
                        .collect()
                })
                .collect();
            let constant: Vec<f64> = (0..n)
                .map(|i| if i % 11 == 3 { 0.5 } else { 0.0 })
                .collect();
            let refs: Vec<&[f64]> = loads.iter().map(|l| &l[..]).collect();
            let sparse = SparseLoads::new(&constant, &refs);
            let thetas: Vec<f64> = (0..count)
                .map(|l| if l % 3 == 1 { 0.0 } else { 0.3 + l as f64 })
                .collect();
            let mut want = constant.clone();
            for (load, &theta) in loads.iter().zip(&thetas) {
                if theta != 0.0 {
                    for (o, f) in want.iter_mut().zip(load) {
                        *o += theta * f;
                    }
                }
            }
            let (r, v, a) = (x_of(n), vec![0.5; n], vec![-0.25; n]);
            let old = vec![0.125; n];
            let (mut load_new, mut r_new) = (vec![0.0; n], vec![0.0; n]);
            let mut p = partials(n);
            predict(
                &sparse,
                &thetas,
                &r,
                &v,
                &a,
                1e-3,
                5e-7,
                &old,
                &mut load_new,
                &mut r_new,
                true,
                &mut p,
            );
            let (mut work, mut dot) = (0.0, 0.0);
            for &i in sparse.rows() {
                work += 0.5 * (want[i] + old[i]) * (r_new[i] - r[i]);
                dot += r_new[i] * want[i];
            }
            for i in 0..n {
                assert_eq!(
                    load_new[i].to_bits(),
                    want[i].to_bits(),
                    "{count} loads, row {i}"
                );
            }
            assert_eq!(
                (p[0][0].to_bits(), p[0][2].to_bits()),
                (work.to_bits(), dot.to_bits()),
                "{count} loads"
            );
        }
    }

    /// See [`fused_step_has_the_bits_of_the_passes`].
    fn check_fused(k: &CsrMatrix<f64>, compact: &Compact, name: &str) {
        let n = k.nrows();
        let vec =
            |shift: f64| -> Vec<f64> { x_of(n).iter().map(|x| x * shift + 0.1 * shift).collect() };
        let (r, v, a) = (vec(1.0), vec(-0.7), vec(3.0));
        let mass: Vec<f64> = x_of(n).iter().map(|x| 1.0 + x.abs()).collect();
        // Loads on a few rows (both sides of chunk seams, a −0 entry, a row
        // where two loads cancel), +0 elsewhere.
        let mut constant = vec![0.0; n];
        let mut l1 = vec![0.0; n];
        let mut l2 = vec![0.0; n];
        for i in (0..n).filter(|i| i % 61 == 5 || i % CHUNK == 0 || i % CHUNK == CHUNK - 1) {
            l1[i] = 0.3 + 1e-3 * i as f64;
        }
        for i in (0..n).filter(|i| i % 89 == 7) {
            l2[i] = -0.2 * (1.0 + (i % 5) as f64);
            if i % 3 == 0 {
                l1[i] = -l2[i];
            }
        }
        constant[n / 2] = 0.25;
        constant[n / 3] = -0.0;
        let sparse = SparseLoads::new(&constant, &[&l1, &l2]);
        assert!(sparse.rows().len() < n / 8 && sparse.rows().contains(&(n / 3)));
        let (c1, c2) = (1e-3, 0.5e-6);
        // The dense pass A of before, at θ = (0.7, 1.3) (step K) and at
        // θ = (0.9, 0) (step K − 1).
        let dense = |thetas: [f64; 2]| -> Vec<f64> {
            let mut l = constant.clone();
            for (load, theta) in [&l1, &l2].iter().zip(thetas) {
                if theta != 0.0 {
                    for (o, f) in l.iter_mut().zip(load.iter()) {
                        *o += theta * f;
                    }
                }
            }
            l
        };
        let (load, load_new0) = (dense([0.9, 0.0]), dense([0.7, 1.3]));
        let r_new0: Vec<f64> = (0..n).map(|i| r[i] + c1 * v[i] + c2 * a[i]).collect();
        let (mut load_new, mut r_new) = (vec![0.0; n], vec![7.0; n]);
        let mut p1 = partials(n);
        predict(
            &sparse,
            &[0.7, 1.3],
            &r,
            &v,
            &a,
            c1,
            c2,
            &load,
            &mut load_new,
            &mut r_new,
            true,
            &mut p1,
        );
        for i in 0..n {
            assert_eq!(
                load_new0[i].to_bits(),
                load_new[i].to_bits(),
                "{name}: R_K {i}"
            );
            assert_eq!(r_new0[i].to_bits(), r_new[i].to_bits(), "{name}: r_K {i}");
        }
        let data = StepData {
            load_new: &load_new,
            load_rows: sparse.rows(),
            mass: &mass,
            r_new: &r_new,
            v: &v,
            a: &a,
            in_place: false,
            cv: 1.0 / (0.5 * 1e-3),
            ca: 1.0,
            scale: 1.0 / (0.5 * 1e-3),
            ratio: 1.0,
            next: (c1, c2),
        };
        // "Friction" at DOFs on both sides of chunk seams and at load rows.
        let friction: Vec<(usize, f64)> = (0..n)
            .filter(|i| i % 97 == 0 || i % CHUNK == 0 || i % CHUNK == CHUNK - 1 || i % 61 == 5)
            .map(|i| (i, -0.25 * i as f64))
            .collect();
        let mut p0 = partials(n);
        let (mut vn0, mut an0) = (vec![0.0; n], vec![0.0; n]);
        let mut b = compact_order_spmv(k, &r_new);
        let ku = b.clone();
        let strain0 = rhs_and_velocity(
            &load_new, &mass, &r_new, &v, &a, data.cv, data.ca, data.scale, &mut b, &mut vn0,
            &mut p0,
        );
        for &(i, vi) in &friction {
            vn0[i] = vi;
        }
        let sums0 = accelerate_and_sum(
            &mass, &load, &load_new, &r, &r_new, &v, &vn0, &a, data.scale, data.ratio, &mut an0,
            &mut p0,
        );
        assert!(sums0.work != 0.0 && sums0.load_dot != 0.0);
        // Both builds of the per-row work (SSE2 and, where the CPU has it,
        // AVX), with K r_K formed in the sweep and handed in.
        let builds = [false, avx()];
        for (given, avx) in [None, Some(&ku[..])]
            .into_iter()
            .flat_map(|g| builds.map(|b| (g, b)))
        {
            let mut p = p1.clone();
            let (mut vn1, mut an1, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let out = [&mut vn1[..], &mut an1[..], &mut rx[..]];
            let (strain1, sums1) = sweep(avx, compact, &data, &friction, given, out, &mut p);
            let name = format!("{name} K r_K given: {}, AVX: {avx}", given.is_some());
            assert_eq!(strain0.to_bits(), strain1.to_bits(), "{name}: strain");
            for (x, y) in [
                (sums0.work, sums1.work),
                (sums0.kinetic, sums1.kinetic),
                (sums0.load_dot, sums1.load_dot),
            ] {
                assert_eq!(x.to_bits(), y.to_bits(), "{name}: sums");
            }
            assert!(sums0.finite && sums1.finite);
            for i in 0..n {
                assert_eq!(vn0[i].to_bits(), vn1[i].to_bits(), "{name}: ṙ row {i}");
                assert_eq!(an0[i].to_bits(), an1[i].to_bits(), "{name}: r̈ row {i}");
                // The next predictor: pass A's bits on the new state.
                let next = r_new[i] + c1 * vn0[i] + c2 * an0[i];
                assert_eq!(next.to_bits(), rx[i].to_bits(), "{name}: r_K+1 row {i}");
                // What the friction pre-pass reads.
                let bi = rhs_entry(&data, i, compact.row(i, &r_new));
                assert_eq!(b[i].to_bits(), bi.to_bits(), "{name}: R̂ row {i}");
            }
        }
    }

    /// Rows without a partner at chunk seams (the first DOF's node has one
    /// free DOF, shifting every later pair by one), a first row without a
    /// partner, a last column whose block starts one column early, empty
    /// rows and explicit zeros.
    #[test]
    fn compact_spmv_edge_patterns() {
        let nodes = CHUNK + 5;
        let removed = [1, 2 * 700, 2 * (nodes - 1) + 1];
        let mut free = vec![usize::MAX; 2 * nodes];
        let mut n = 0;
        for (d, f) in free.iter_mut().enumerate() {
            if !removed.contains(&d) {
                *f = n;
                n += 1;
            }
        }
        let mut coo = CooMatrix::new(n, n);
        for p in 0..nodes {
            if p % 97 == 13 {
                continue; // empty rows
            }
            for q in [0, p.saturating_sub(2), p, (p + 1).min(nodes - 1), nodes - 1] {
                for (a, b) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    let (i, j) = (free[2 * p + a], free[2 * q + b]);
                    if i != usize::MAX && j != usize::MAX {
                        let v = if q == p + 1 && a == b {
                            // Explicit zeros of both signs: distinct bits,
                            // distinct dictionary entries.
                            if p % 2 == 0 {
                                0.0
                            } else {
                                -0.0
                            }
                        } else {
                            ((i * 31 + j * 17) % 101) as f64 - 50.0
                        };
                        coo.push(i, j, v);
                    }
                }
            }
        }
        let k = CsrMatrix::from(&coo);
        let x = x_of(n);
        let y0 = compact_order_spmv(&k, &x);
        for form in [Form::Stored, Form::Dictionary] {
            let compact = Compact::with_form(&k, form).unwrap();
            let pairs = (0..compact.group_rows.len() - 1)
                .filter(|&g| compact.group_rows[g + 1] - compact.group_rows[g] == 2)
                .count();
            assert!(pairs > n / 2 - 100, "{pairs} pairs of {n} rows");
            for compact in widths(&compact) {
                let mut y1 = vec![1.0; n];
                compact.spmv(&x, &mut y1);
                for i in 0..n {
                    let w = compact.wide;
                    assert_eq!(y0[i].to_bits(), y1[i].to_bits(), "{form:?} {w:?} row {i}");
                }
            }
        }
    }

    /// The tolerance of the matrix-free product: row-wise within 1e-12 of
    /// max_i Σ_j |K_ij x_j| (the class matrices come from cells alike to
    /// the coordinates' rounding, and the sums run in another order).
    fn check_classes(k: &CsrMatrix<f64>, op: &Classes, x: &[f64], name: &str) {
        let n = k.nrows();
        let (o, c, v) = (k.row_offsets(), k.col_indices(), k.values());
        let scale = (0..n)
            .map(|i| {
                (o[i]..o[i + 1])
                    .map(|p| (v[p] * x[c[p]]).abs())
                    .sum::<f64>()
            })
            .fold(0.0_f64, f64::max);
        assert!(scale > 0.0);
        let mut y0 = vec![0.0; n];
        spmv(k, x, &mut y0);
        let mut y1 = vec![f64::NAN; n];
        op.spmv(x, &mut y1);
        for i in 0..n {
            assert!(
                (y0[i] - y1[i]).abs() <= 1e-12 * scale,
                "{name} row {i}: {} vs {} (scale {scale:e})",
                y0[i],
                y1[i]
            );
        }
        // A row alone and the batches of a chunk give the same bits.
        for i in (0..n).step_by(97).chain([0, n - 1]) {
            assert_eq!(
                op.row(i, x).to_bits(),
                y1[i].to_bits(),
                "{name} row {i} alone"
            );
        }
        for c in 0..chunks(n) {
            op.chunk_batches(c, x, |r0, ku| {
                for (j, v) in ku.iter().enumerate() {
                    assert_eq!(v.to_bits(), y1[r0 + j].to_bits(), "{name} chunk {c}");
                }
            });
        }
    }

    /// Matrix-free K·x by element classes against the CSR's on structured
    /// Q1 and Q2 rectangles (several chunks) with and without Dirichlet
    /// DOFs (the slab's supports, single-DOF nodes, and a corner held in
    /// both components), and on meshes without classes: the committed
    /// unstructured ones and a perturbed rectangle, where
    /// [`ElementClasses::new`] declines and a class per cell is still right.
    #[test]
    fn classes_spmv_matches_the_csr() {
        use stickslip_fem::testing::{add_point_group, map_nodes, rectangle};
        use stickslip_fem::ElementClasses;
        use stickslip_mesh::CellKind;
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new("top", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
            Dirichlet::new("corner", 1, 0.0),
            Dirichlet::new("corner", 0, 0.0),
        ];
        for (kind, nx, ny) in [(CellKind::Quad9, 96, 24), (CellKind::Quad4, 192, 48)] {
            let mut mesh = rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
            let corner = mesh.nodes.iter().position(|p| p[0] == 8.0 && p[1] == 0.0);
            add_point_group(&mut mesh, "corner", &[corner.unwrap()]);
            for conditions in [&supports[..], &[]] {
                let model = Model::new(&mesh, &material, conditions).unwrap();
                let k = &model.stiffness;
                let n = k.nrows();
                assert!(chunks(n) >= 3, "{n}");
                // Declined: Q1 (the dictionary is faster) and fewer than
                // MIN_FREE_DOFS (K stays in cache).
                assert!(ElementClasses::new(&mesh, &material, &model.dofs).is_none());
                let ec = ElementClasses::with_limit(&mesh, &material, &model.dofs, 64).unwrap();
                assert_eq!(ec.classes(), 1);
                let op = Classes::new(ec).unwrap();
                let x = x_of(n);
                check_classes(k, &op, &x, &format!("{kind:?} {}", conditions.len()));
            }
        }
        // Accepted: a structured Q2 slab above MIN_FREE_DOFS (the DOF map
        // alone; one class, one matrix).
        let big = rectangle(CellKind::Quad9, 252, 63, [0.0, 0.0], [8.0, 1.0]);
        let dofs = stickslip_fem::DofMap::new(&big, &[Dirichlet::new("top", 1, 0.0)]).unwrap();
        assert!(dofs.n_free() >= stickslip_fem::classes::MIN_FREE_DOFS);
        let ec = ElementClasses::new(&big, &material, &dofs).expect("classes pay");
        assert_eq!(ec.classes(), 1);
        // No classes: every cell its own (or nearly).
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        let mut perturbed = rectangle(CellKind::Quad9, 24, 6, [0.0, 0.0], [8.0, 1.0]);
        map_nodes(&mut perturbed, |p| {
            [
                p[0] + 1e-3 * (7.0 * p[1] + 3.0 * p[0]).sin(),
                p[1] + 1e-3 * (5.0 * p[0]).cos(),
            ]
        });
        let meshes = [
            ("perturbed", perturbed),
            (
                "unstructured q1",
                Mesh::from_file(dir.join("slab-unstructured-q1.msh")).unwrap(),
            ),
            (
                "unstructured q2",
                Mesh::from_file(dir.join("slab-unstructured-q2.msh")).unwrap(),
            ),
        ];
        let supports = [
            Dirichlet::new("left", 0, 0.0),
            Dirichlet::new("left", 1, 0.0),
        ];
        for (name, mesh) in meshes {
            let model = Model::new(&mesh, &material, &supports).unwrap();
            // Declined by the class count alone (MAX_CLASSES), whatever
            // the size.
            let limit = stickslip_fem::classes::MAX_CLASSES;
            assert!(
                ElementClasses::with_limit(&mesh, &material, &model.dofs, limit).is_none(),
                "{name}"
            );
            let ec = ElementClasses::with_limit(&mesh, &material, &model.dofs, usize::MAX).unwrap();
            assert!(
                2 * ec.classes() > mesh.n_cells(),
                "{name}: {} classes",
                ec.classes()
            );
            let op = Classes::new(ec).unwrap();
            let k = &model.stiffness;
            check_classes(k, &op, &x_of(k.nrows()), name);
        }
    }

    /// The matrix-free product and the one-sweep step on it have the same
    /// bits on one thread and on two (rows are independent of the chunks'
    /// assignment to threads).
    #[test]
    fn classes_one_thread_and_two_give_the_same_bits() {
        use stickslip_fem::testing::rectangle;
        use stickslip_fem::ElementClasses;
        use stickslip_mesh::CellKind;
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let mesh = rectangle(CellKind::Quad9, 96, 24, [0.0, 0.0], [8.0, 1.0]);
        let supports = [
            Dirichlet::new("top", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let model = Model::new(&mesh, &material, &supports).unwrap();
        let n = model.dofs.n_free();
        let ec = ElementClasses::with_limit(&mesh, &material, &model.dofs, 64).unwrap();
        let op = Classes::new(ec).unwrap();
        let x = x_of(n);
        let w = |c: f64| -> Vec<f64> { x.iter().map(|v| v * c + c).collect() };
        let (m, v, a) = (w(1.2), w(1.5), w(1.6));
        let mass: Vec<f64> = m.iter().map(|m| 1.0 + m.abs()).collect();
        let zero = vec![0.0; n];
        let friction: Vec<(usize, f64)> = (0..n).step_by(301).map(|i| (i, 0.5)).collect();
        let run = |threads: usize| {
            on_threads(threads, || {
                let mut y = vec![0.0; n];
                op.spmv(&x, &mut y);
                let data = lab_data(&zero, &mass, &x, &v, &a);
                let mut p = partials(n);
                let (mut vn, mut an, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                let (strain, sums) = fused_step(
                    &op, &data, &friction, None, &mut vn, &mut an, &mut rx, &mut p,
                );
                (y, vn, an, strain, sums.kinetic)
            })
        };
        let one = run(1);
        let two = run(2);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.0), bits(&two.0));
        assert_eq!(bits(&one.1), bits(&two.1));
        assert_eq!(bits(&one.2), bits(&two.2));
        assert_eq!(one.3.to_bits(), two.3.to_bits());
        assert_eq!(one.4.to_bits(), two.4.to_bits());
    }

    /// Kernel lab (issue 7: "K·r by CSR SpMV or element by element, choose
    /// by measurement"): K·x on a structured Q1 slab (default 1416 × 354
    /// cells, 1,004,298 free DOFs; `STICKSLIP_LAB_NY` sets ny, nx = 4 ny)
    /// with the slab's supports, by nalgebra-sparse's CSR (the previous
    /// kernel), by [`Compact`] and element by element with stored element
    /// matrices (gather 8 values, 8×8 product, scatter; sequential, a
    /// threaded one would need colouring). Prints medians of 10; checks the
    /// element-by-element product against the CSR's to 1e-12 (different
    /// summation order, so not bits).
    ///
    ///     cargo test -p stickslip-time --lib kernel_lab -- --ignored --nocapture
    #[test]
    #[ignore = "timing; run by hand (see the doc comment)"]
    fn kernel_lab() {
        use std::time::Instant;
        use stickslip_fem::element::CellBasis;
        use stickslip_mesh::{CellKind, Group, SourceInfo};

        let ny: usize = std::env::var("STICKSLIP_LAB_NY")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(354);
        let nx = 4 * ny;
        let (gx, gy) = (nx + 1, ny + 1);
        let mut nodes = Vec::with_capacity(gx * gy);
        for j in 0..gy {
            for i in 0..gx {
                nodes.push([8.0 * i as f64 / nx as f64, j as f64 / ny as f64]);
            }
        }
        let mut cells = Vec::with_capacity(4 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let id = |i: usize, j: usize| j * gx + i;
                cells.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let group = |name: &str, nodes: Vec<usize>| Group {
            name: name.into(),
            tag: 1,
            dim: 0,
            edges: vec![],
            cells: vec![],
            points: nodes.clone(),
            elements: nodes.len(),
            nodes,
        };
        let mesh = Mesh {
            node_tags: (1..=nodes.len() as u64).collect(),
            nodes,
            kind: CellKind::Quad4,
            cell_tags: (1..=(nx * ny) as u64).collect(),
            cells,
            groups: vec![
                group("support", (0..gx).map(|i| ny * gx + i).collect()),
                group("left", (0..gy).map(|j| j * gx).collect()),
            ],
            source: SourceInfo::default(),
        };
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new("support", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let model = Model::new(&mesh, &material, &supports).unwrap();
        let k = &model.stiffness;
        let n = k.nrows();
        let compact = Compact::new(k).unwrap();
        let stored = Compact::with_form(k, Form::Stored).unwrap();
        // Element matrices (64 values) and free DOFs (u32::MAX = fixed).
        let basis = CellBasis::full(CellKind::Quad4);
        let d = material.elasticity();
        let n_cells = nx * ny;
        let mut ke = vec![0.0; 64 * n_cells];
        let mut edofs = vec![u32::MAX; 8 * n_cells];
        for c in 0..n_cells {
            let cell = &mesh.cells[4 * c..4 * c + 4];
            let coords: Vec<[f64; 2]> = cell.iter().map(|&v| mesh.nodes[v]).collect();
            basis
                .stiffness(&coords, &d, &mut ke[64 * c..64 * c + 64])
                .unwrap();
            for (a, &v) in cell.iter().enumerate() {
                for comp in 0..2 {
                    if let Some(f) = model.dofs.free(v, comp) {
                        edofs[8 * c + 2 * a + comp] = f as u32;
                    }
                }
            }
        }
        let ebe = |x: &[f64], y: &mut [f64]| {
            y.fill(0.0);
            for (ke, dofs) in ke.chunks_exact(64).zip(edofs.chunks_exact(8)) {
                let mut xe = [0.0; 8];
                for (xa, &f) in xe.iter_mut().zip(dofs) {
                    if f != u32::MAX {
                        *xa = x[f as usize];
                    }
                }
                for (a, &f) in dofs.iter().enumerate() {
                    if f != u32::MAX {
                        let row = &ke[8 * a..8 * a + 8];
                        let mut s = 0.0;
                        for b in 0..8 {
                            s += row[b] * xe[b];
                        }
                        y[f as usize] += s;
                    }
                }
            }
        };
        let x = x_of(n);
        let (mut y0, mut y1) = (vec![0.0; n], vec![0.0; n]);
        spmv(k, &x, &mut y0);
        ebe(&x, &mut y1);
        let scale = y0.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let diff = y0
            .iter()
            .zip(&y1)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-12 * scale, "EBE vs CSR: {diff:e} of {scale:e}");
        // The fastest of 20: on a shared machine the least disturbed run.
        let time = |f: &mut dyn FnMut()| {
            let mut t: Vec<f64> = (0..20)
                .map(|_| {
                    let s = Instant::now();
                    f();
                    s.elapsed().as_secs_f64()
                })
                .collect();
            t.sort_by(f64::total_cmp);
            t[0]
        };
        let vectors = 16.0 * n as f64; // x read once, y written once
        let csr_bytes = 16.0 * k.nnz() as f64 + 8.0 * (n + 1) as f64 + vectors;
        let compact_bytes = compact.bytes() as f64 + vectors;
        // y is read and written by the scatter.
        let ebe_bytes = (512.0 + 32.0) * n_cells as f64 + vectors + 8.0 * n as f64;
        println!(
            "kernel lab: Q1 {nx}×{ny}, n = {n}, nnz = {}, load: {:?}",
            k.nnz(),
            std::fs::read_to_string("/proc/loadavg")
                .unwrap_or_default()
                .trim()
        );
        for threads in [1, 2] {
            on_threads(threads, || {
                let t = time(&mut || spmv(k, &x, &mut y0));
                println!(
                    "  {threads} thread(s) CSR usize   : {:.3} ms, {:.0} MB, {:.1} GB/s",
                    1e3 * t,
                    csr_bytes / 1e6,
                    csr_bytes / t / 1e9
                );
                let t = time(&mut || compact.spmv(&x, &mut y1));
                println!(
                    "  {threads} thread(s) compact 2×2 : {:.3} ms, {:.0} MB, {:.1} GB/s ({} distinct blocks)",
                    1e3 * t,
                    compact_bytes / 1e6,
                    compact_bytes / t / 1e9,
                    compact.dictionary_len()
                );
                let t = time(&mut || stored.spmv(&x, &mut y1));
                let stored_bytes = stored.bytes() as f64 + vectors;
                println!(
                    "  {threads} thread(s) stored 2×2  : {:.3} ms, {:.0} MB, {:.1} GB/s",
                    1e3 * t,
                    stored_bytes / 1e6,
                    stored_bytes / t / 1e9
                );
                // The step's passes after the predictor, three ways, on
                // distinct vectors as in a step.
                let w = |c: f64| -> Vec<f64> { x.iter().map(|v| v * c + c).collect() };
                let (ln, l, m, r, rn, v, a) =
                    (w(1.0), w(1.1), w(1.2), w(1.3), w(1.4), w(1.5), w(1.6));
                // (The sweep with no load rows: pass A does the loads'.)
                let data = lab_data(&ln, &m, &rn, &v, &a);
                let mut p = partials(n);
                let (mut b, mut vn, mut an) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                let mut rx = vec![0.0; n];
                // Interleaved, 30 rounds: every variant sees the same
                // disturbances of a shared machine; medians and minima.
                let mut t = [vec![], vec![], vec![]];
                for _ in 0..30 {
                    let s = Instant::now();
                    spmv(k, &rn, &mut b);
                    rhs_and_velocity(&ln, &m, &rn, &v, &a, 2e3, 1.0, 2e3, &mut b, &mut vn, &mut p);
                    accelerate_and_sum(
                        &m, &l, &ln, &r, &rn, &v, &vn, &a, 2e3, 1.0, &mut an, &mut p,
                    );
                    t[0].push(s.elapsed().as_secs_f64());
                    let s = Instant::now();
                    spmv_rhs_and_velocity(
                        &compact, &ln, &m, &rn, &v, &a, 2e3, 1.0, 2e3, &mut b, &mut vn, &mut p,
                    );
                    accelerate_and_sum(
                        &m, &l, &ln, &r, &rn, &v, &vn, &a, 2e3, 1.0, &mut an, &mut p,
                    );
                    t[1].push(s.elapsed().as_secs_f64());
                    let s = Instant::now();
                    lab_sweep(&compact, &data, [&mut vn, &mut an, &mut rx], &mut p);
                    t[2].push(s.elapsed().as_secs_f64());
                }
                for (name, t) in ["CSR, B, C", "compact·B, C", "one sweep"]
                    .iter()
                    .zip(&mut t)
                {
                    t.sort_by(f64::total_cmp);
                    println!(
                        "  {threads} thread(s) {name:13}: median {:.3} ms, min {:.3} ms",
                        1e3 * t[15],
                        1e3 * t[0]
                    );
                }
                if threads == 1 {
                    let t = time(&mut || ebe(&x, &mut y1));
                    println!(
                        "  1 thread    element-by-element: {:.3} ms, {:.0} MB, {:.1} GB/s",
                        1e3 * t,
                        ebe_bytes / 1e6,
                        ebe_bytes / t / 1e9
                    );
                }
            });
        }
    }

    /// Class lab: K·x matrix-free by element classes ([`Classes`]) against
    /// [`Compact`] (the form the step picks, [`Compact::new`]) on the bench's
    /// structured slabs (`testing::rectangle`, the coordinates of
    /// bench_step's `structured_slab`) with the slab's supports: one K·x and
    /// the whole explicit step (pass A and the sweep, no loads or friction),
    /// the variants interleaved, fastest and median of 20, on 1 and 2
    /// threads; checks the matrix-free rows against the CSR's to 1e-12 of
    /// max_i Σ_j |K_ij x_j|. `STICKSLIP_LAB_MESHES` = comma-separated
    /// `q1-NXxNY` / `q2-NXxNY` (default the three rungs below).
    ///
    ///     cargo test --profile dev -p stickslip-time --lib class_lab -- --ignored --nocapture
    #[test]
    #[ignore = "timing; run by hand (see the doc comment)"]
    fn class_lab() {
        use std::time::Instant;
        use stickslip_fem::ElementClasses;

        let meshes = std::env::var("STICKSLIP_LAB_MESHES")
            .unwrap_or_else(|_| "q1-1416x354,q2-352x88,q2-708x177".into());
        println!(
            "class lab, load: {:?}",
            std::fs::read_to_string("/proc/loadavg")
                .unwrap_or_default()
                .trim()
        );
        for name in meshes.split(',') {
            let (mesh, material, model) = lab_slab(name);
            let k = &model.stiffness;
            let n = k.nrows();
            let t0 = Instant::now();
            let compact = Compact::new(k).unwrap();
            let t_compact = t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let ec =
                ElementClasses::with_limit(&mesh, &material, &model.dofs, 1).expect("one class");
            let classes = Classes::new(ec).unwrap();
            let t_classes = t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let stencils = Stencils::new(k).expect("structured");
            let t_stencils = t0.elapsed().as_secs_f64();
            println!(
                "{name}: {} stencil types, {:.2} MB, built in {:.2} s",
                stencils.types(),
                RowProduct::bytes(&stencils) as f64 / 1e6,
                t_stencils
            );
            let x = x_of(n);
            let (mut y0, mut y1) = (vec![0.0; n], vec![0.0; n]);
            spmv(k, &x, &mut y0);
            classes.spmv(&x, &mut y1);
            let abs = {
                let (o, c, v) = (k.row_offsets(), k.col_indices(), k.values());
                (0..n)
                    .map(|i| {
                        (o[i]..o[i + 1])
                            .map(|p| (v[p] * x[c[p]]).abs())
                            .sum::<f64>()
                    })
                    .fold(0.0_f64, f64::max)
            };
            let diff = y0
                .iter()
                .zip(&y1)
                .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
            println!(
                "{name}: n = {n}, {} classes, compact {:.0} MB ({} distinct blocks, built in {:.2} s), classes {:.1} MB (built in {:.2} s), |Δ| = {:.2e} of max Σ|K x| = {:.2e} ({:.1e})",
                classes.classes().classes(),
                compact.bytes() as f64 / 1e6,
                compact.dictionary_len(),
                t_compact,
                classes.bytes() as f64 / 1e6,
                t_classes,
                diff,
                abs,
                diff / abs
            );
            assert!(diff <= 1e-12 * abs);
            let w = |c: f64| -> Vec<f64> { x.iter().map(|v| v * c + c).collect() };
            let (r, m, v, a) = (w(1.3), w(1.2), w(1.5), w(1.6));
            let (zero, mut ln, mut rn) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let sparse = SparseLoads::new(&zero, &[]);
            for threads in [1, 2] {
                on_threads(threads, || {
                    let mut p = partials(n);
                    let (mut vn, mut an, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                    let mut t: [Vec<f64>; 6] = Default::default();
                    for _ in 0..20 {
                        let s = Instant::now();
                        compact.spmv(&x, &mut y0);
                        t[0].push(s.elapsed().as_secs_f64());
                        let s = Instant::now();
                        classes.spmv(&x, &mut y1);
                        t[1].push(s.elapsed().as_secs_f64());
                        let s = Instant::now();
                        stencils.spmv(&x, &mut y1);
                        t[4].push(s.elapsed().as_secs_f64());
                        let mut step = |q: usize, use_classes: u8| {
                            let s = Instant::now();
                            predict(
                                &sparse,
                                &[],
                                &r,
                                &v,
                                &a,
                                1e-3,
                                0.5e-6,
                                &zero,
                                &mut ln,
                                &mut rn,
                                // A run of one Δt: the sweep formed r_K.
                                false,
                                &mut p,
                            );
                            let data = lab_data(&ln, &m, &rn, &v, &a);
                            match use_classes {
                                1 => {
                                    lab_sweep(&classes, &data, [&mut vn, &mut an, &mut rx], &mut p)
                                }
                                2 => {
                                    lab_sweep(&stencils, &data, [&mut vn, &mut an, &mut rx], &mut p)
                                }
                                _ => {
                                    lab_sweep(&compact, &data, [&mut vn, &mut an, &mut rx], &mut p)
                                }
                            };
                            t[q].push(s.elapsed().as_secs_f64());
                        };
                        step(2, 0);
                        step(3, 1);
                        step(5, 2);
                    }
                    for (label, t) in [
                        "K·x compact",
                        "K·x classes",
                        "step compact",
                        "step classes",
                        "K·x stencils",
                        "step stencils",
                    ]
                    .iter()
                    .zip(&mut t)
                    {
                        t.sort_by(f64::total_cmp);
                        println!(
                            "  {threads} thread(s) {label:13}: fastest {:.3} ms, median {:.3} ms",
                            1e3 * t[0],
                            1e3 * t[10]
                        );
                    }
                });
            }
        }
    }

    /// Where the explicit step's time goes on a large structured mesh: K·x
    /// by stencil types alone, the sweep's vector work alone (K r_K handed
    /// in: 8 streams, no product) and the one sweep, with the per-row work
    /// built for SSE2 and as `fused_step` runs it (AVX where the CPU has
    /// it); 2 threads, median (fastest) of 20 interleaved rounds, ms. Run
    /// by hand:
    ///
    ///     cargo test --release -p stickslip-time --lib sweep_lab -- --ignored --nocapture
    ///
    /// (STICKSLIP_LAB_MESHES, default q1-1416x354,q2-708x177.) Measured
    /// 2026-11-24 06:05, release, this 2-core machine (AVX-512 stencil
    /// sums, 64-row batches):
    ///
    /// | mesh (free DOFs)        | K·x         | vectors     | sweep, SSE2 | sweep       |
    /// |-------------------------|-------------|-------------|-------------|-------------|
    /// | Q1 708×177 (251,517)    | 0.197       | 0.278       | 0.552       | 0.474       |
    /// | Q1 1416×354 (1,004,298) | 0.964       | 1.926       | 2.325       | 2.178       |
    /// | Q2 708×177 (1,004,298)  | 1.688       | 2.065       | 3.242       | 3.244       |
    ///
    /// 2026-11-25 01:00, with four 8-row blocks in lockstep
    /// (`stencils::avx::run_512`) and the fused sweep, two runs: Q1 1M
    /// K·x 0.89-0.93, vectors 1.77-1.78, sweep 1.95-2.01 ms; Q2 1M 1.32-1.35,
    /// 1.88-2.03, 2.41.
    ///
    /// At 1M DOFs the sweep now costs less than its parts: the product's
    /// arithmetic of one batch overlaps the vectors' traffic of the next
    /// ([`BATCH`]), in part (22:42, with fused multiply-adds: Q1 K·x 0.90,
    /// vectors 1.60, sweep 2.07 ms; Q2 1.48, 1.57, 2.79). Before (04:20-04:35, 256-row batches, 4-wide sums) it
    /// cost about their sum: Q1 1M K·x 1.92-2.47, vectors 1.72-2.79, sweep
    /// 4.24-4.87; Q2 1M 3.86, 2.64, 6.52. Tried then and not kept:
    /// prefetching the next batch's m, ṙ, r̈ (and its three output rows)
    /// one to four batches ahead (Q1 1M sweep 4.28-5.57 with against
    /// 4.62-5.29 ms without); and since, non-temporal stores for the three
    /// outputs (no faster: 3.85 against 4.08 ms at 256-row batches, 2.66
    /// against 3.32 at 64).
    /// Prefetching again (2026-11-24 22:30, 64-row batches, the whole
    /// explicit step of the Q2 1M slab, with and without alternating in
    /// one process, medians of 59 blocks of 10 steps): m, ṙ, r̈ 64 or 128
    /// rows ahead 0.7% and 2.6% slower, with the three outputs (prefetchw)
    /// 128, 256 and 512 rows ahead 0.5%, 1.6% and 2.2% slower. Sweeping
    /// each batch in pieces between the next batch's 16-row stencil sums
    /// (so that the core would hold both in flight), the same bits, this
    /// lab alternating both, 22:45: 16-row pieces 2.73 / 3.43 ms against
    /// 2.07 / 2.79 (Q1 / Q2), 32 rows 2.56 / 3.17 against 2.24 / 2.89,
    /// the whole batch one batch late 2.28 / 3.21 against 2.11 / 3.13:
    /// the calls cost more than any overlap gained.
    /// On the fused kernel (2026-11-25 00:45-01:30, its sweep of
    /// `fused_lab`'s data, each variant alternating with the kept one in
    /// one process, three runs unless said, Q1 / Q2 1M): non-temporal
    /// stores of the three outputs (by 64, 32 or 16 bytes as aligned)
    /// 0.7-3.4% / 1.6-6.3% slower; the seven vectors on transparent huge
    /// pages (madvise) 0-31% slower / 2.7-4.0% faster; prefetching m, ṙ, r̈,
    /// r_K 128 rows ahead into L1 0.6% / 2.4% slower, into L2 no change,
    /// 512 rows ahead into L1 3.3% / 4.8% slower, into L2 0.6% / 1.5%
    /// faster on a busy host (one run each); handing the rows outside the
    /// unit runs on in stretches of up to 64 rather than a node pair at a
    /// time, within 3% either way; vectors 0, 16, 32 or 48 bytes past a
    /// 64-byte line, within 6% with no order between them (two runs).
    /// In place (ṙ_K and r̈_K over ṙ and r̈, `StepData::in_place`),
    /// 2026-11-25 04:00, three runs: Q1 0.87, 0.90, 0.94 of the time
    /// apart; Q2 0.98, 1.00, 0.98. Rows by parity (a grid row's even
    /// columns, then its odd ones, so that a unit's two node pairs are
    /// alike and Q2's units lose their 20% of zero slots), the stencils of
    /// both orders alternating in one process, Q2 1M: K·x 1.27 against
    /// 1.25 ms, the sweep in place 2.27 against 2.20: the FMAs saved buy
    /// nothing, and a node row's neighbours then sit in two places of x.
    /// Non-temporal stores of r_{K+1} alone, in place (ṙ and r̈ read
    /// just before are written back from cache; r_{K+1}'s lines then
    /// skip their read for ownership), zmm where 64-byte aligned and xmm
    /// elsewhere, a fence per chunk, alternating with the kept sweep in
    /// one process, 2026-11-25 14:55, three runs: Q1 1M 1.04-1.08, Q2 1M
    /// 1.04-1.07 of its time (medians). Not kept.
    /// What did bound it (2026-11-25 17:05-17:45; each variant switched at
    /// run time and alternating with the sweep in one process, vectors 576
    /// bytes apart in their pages, medians of 20 or 29 rounds, three or
    /// four runs). A stand-in with the sweep's seven streams, the same
    /// unit runs and K·x, and 4 operations per row in place of
    /// [`batch_rows`]' arithmetic and sums, skipping the node pairs
    /// between runs, took 0.60-0.72 of the sweep's time on Q1 1M and
    /// 0.66-0.79 on Q2 1M. Of the difference: the node pairs between the
    /// unit runs (1% of the rows: a node row's ends, chunk seams), summed
    /// and swept one pair at a time through a call of [`batch_rows`], cost
    /// 12-15% (Q1: 1.35-1.41 ms without them against 1.58-1.61); a block's
    /// operands reloaded through [`SweepRows`] with its checks for load
    /// and friction rows and its bounds, 9-13%; the three sums and the
    /// finiteness check, 5-8%. Now a run with no load or friction row
    /// takes its operands once ([`Rows8`]), and the pairs between runs go
    /// 8 rows at a time ([`Rows8::some`]): against the sweep before, 0.84
    /// -0.92 of its time on Q1 1M (1.52-1.84 against 1.78-2.08 ms) and
    /// 0.84-0.91 on Q2 1M (2.07-2.11 against 2.31-2.51), three runs,
    /// 17:43. The pairs between runs still cost 5-12% (a variant skipping
    /// them), in their K·x sums (a variant with their sums and not their
    /// rows took as long as the sweep; one with their rows and zero sums
    /// as long as skipping them), though not by the sums' arithmetic
    /// (four-wide, a block's four products in one fused multiply-add: no
    /// change) nor by their stencils' blocks missing the cache (nearly
    /// every such pair has a type of its own, 2,845 types for 4,846 pairs
    /// on Q1 1M; their lines requested while the run before is summed: no
    /// change). The sums and the arithmetic stay: they give
    /// [`batch_rows`]' bits. Nor does the stencils' broadcast bound the
    /// K·x loop: the unit values stored twice over, 8 wide, so that a
    /// block's values are a plain load, took as long (Q1 1M 1.95-2.30
    /// against 1.95-2.20 ms, Q2 1M 2.27-3.62 against 2.42-3.49, three
    /// runs, 18:00). Nor did ending a run with its unit's 4 rows once more
    /// (a block of 8 with 4 lanes dropped) where the two node pairs after
    /// it are that unit (two of the five pairs between runs on a node row
    /// of the 1M slabs): Q1 1M 1.81-2.31 against 1.68-2.34 ms, Q2 1M
    /// 2.37-3.10 against 2.47-3.09, four runs, 18:25. The per-row
    /// arithmetic by fused multiply-adds (10 operations in place of 16 per
    /// 8 rows; other bits, on every explicit path) would buy little:
    /// 0.96-0.99 of the time on Q1 1M, 0.98-0.99 on Q2 1M (four runs,
    /// 18:55), so `batch_rows`' operations stay.
    /// Where the 1M step stands against its own vectors in the caches
    /// (2026-11-25 19:28-19:32, the fused sweep in place forced on every
    /// size, per million rows): with the vectors in the L2 (33k DOFs) Q1
    /// 1.08, Q2 1.72 ms; in the L3 (250k) Q1 1.41-1.44, Q2 1.90-2.06;
    /// from memory (1M) Q1 1.50-1.67, Q2 1.95-2.07. The 1M step is
    /// within 15-40% of its speed out of the L2: its arithmetic, not the
    /// memory, holds it under the triad. Nor did two ways of feeding the
    /// cores more evenly help (each switched at run time, alternating in
    /// one process, 19:26-19:33): the swap of the "other" terms applied
    /// once per block to the sums instead of per offset to x (the same
    /// bits: a lane's products move, unchanged), K·x alone 0.975-0.98 of
    /// its time, the sweep 0.98-1.03; the rows of the previous four
    /// blocks interleaved among the current four's offsets (so that the
    /// per-row arithmetic shares the window with the FMAs), Q1 1M
    /// 1.00-1.03, Q2 1M 0.97-1.05, three runs.
    /// What does not bound the fused sweep (2026-11-25 14:57-15:13, each
    /// variant switched at run time and alternating with the kept sweep
    /// in place in one process, three runs, ratios of medians; the
    /// variants give wrong numbers and were never kept): the lumped mass
    /// as a constant register instead of its stream (an eighth of the
    /// bytes) Q1 1M 0.74-0.95, Q2 1M 0.98-1.03; no finiteness check, no
    /// bound sum and the two other sums 8 wide with no reduction to 4
    /// lanes (a third of the per-row instructions) Q1 0.95-0.98, Q2
    /// 0.89-1.03; the division as a multiplication Q1 0.98-1.01, Q2
    /// 0.97-1.03. K·x alone (its unaligned loads of x, the swaps and the
    /// FMAs, about 8 cycles each per offset and 32 rows) is the larger
    /// part: at 250k DOFs, where the vectors sit in the L3, it takes the
    /// same time per row as at 1M (Q2 0.32 against 1.33 ms). Nor do
    /// K·x's loads of x from the L2 bound it (the window of ±2 grid rows
    /// is 90 KB on the Q2 708×177 slab, beyond the 32 KB L1): the same
    /// DOFs on a slab four times narrower (Q2 177×708, a 23 KB window)
    /// took K·x 1.84-2.02 against 1.48-1.69 ms, Q1 354×1416 0.87-1.02
    /// against 0.94-1.08 ms (two runs, 15:19), so tiling the sweep into
    /// strips would not pay.
    #[test]
    #[ignore = "timing; run by hand (see the doc comment)"]
    fn sweep_lab() {
        use std::time::Instant;

        let meshes = std::env::var("STICKSLIP_LAB_MESHES")
            .unwrap_or_else(|_| "q1-1416x354,q2-708x177".into());
        for name in meshes.split(',') {
            let (stencils, [rn, m, v, a]) = sweep_lab_vectors(name);
            let n = rn.len();
            let zero = vec![0.0; n];
            let mut ku = vec![0.0; n];
            let data = lab_data(&zero, &m, &rn, &v, &a);
            let labels = [
                "K·x",
                "vectors (K·x given)",
                "sweep, SSE2",
                "sweep",
                "sweep in place",
            ];
            let mut t: [Vec<f64>; 5] = Default::default();
            let in_place = StepData {
                v: &[],
                a: &[],
                in_place: true,
                ..data
            };
            on_threads(2, || {
                let mut p = partials(n);
                let (mut vn, mut an, mut rx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                for _ in 0..20 {
                    let s = Instant::now();
                    stencils.spmv(&rn, &mut ku);
                    t[0].push(s.elapsed().as_secs_f64());
                    // K r_K handed in runs the vector work on the calling
                    // thread in one chunk: split it over the pool as the
                    // sweep is.
                    let s = Instant::now();
                    each_chunk_triple([&mut vn, &mut an, &mut rx], &mut p, |c, [vn, an, rx], _| {
                        let start = c * CHUNK;
                        let mut run = Running {
                            strain: Lanes::default(),
                            kinetic: Lanes::default(),
                            bound: Lanes::default(),
                            finite: true,
                            load: 0,
                            friction: 0,
                        };
                        let ku = &ku[start..start + vn.len()];
                        batch_rows(&data, &[], start, ku, [vn, an, rx], &mut run);
                    });
                    t[1].push(s.elapsed().as_secs_f64());
                    // Both builds of the per-row work (batch_rows_avx; the
                    // second is fused_step's, AVX where the CPU has it).
                    for (slot, avx) in [(2, false), (3, avx())] {
                        let s = Instant::now();
                        let out = [&mut vn[..], &mut an[..], &mut rx[..]];
                        sweep(avx, &stencils, &data, &[], None, out, &mut p);
                        t[slot].push(s.elapsed().as_secs_f64());
                    }
                    // In place: ṙ and r̈ handed in the outputs (copied
                    // first, untimed, so that each round starts alike).
                    vn.copy_from_slice(&v);
                    an.copy_from_slice(&a);
                    let s = Instant::now();
                    let out = [&mut vn[..], &mut an[..], &mut rx[..]];
                    sweep(avx(), &stencils, &in_place, &[], None, out, &mut p);
                    t[4].push(s.elapsed().as_secs_f64());
                }
            });
            println!("{name}: n = {n}, {} stencil types", stencils.types());
            for (label, t) in labels.iter().zip(&mut t) {
                t.sort_by(f64::total_cmp);
                println!(
                    "  {label:<22} {:7.3} ({:.3}) ms",
                    1e3 * t[t.len() / 2],
                    1e3 * t[0]
                );
            }
        }
    }

    /// The sweep labs' stencils of slab `name` and their r_K, lumped mass,
    /// ṙ and r̈ (made-up values of the sizes of the slab's).
    fn sweep_lab_vectors(name: &str) -> (Stencils, [Vec<f64>; 4]) {
        let (_, _, model) = lab_slab(name);
        let n = model.stiffness.nrows();
        let stencils = Stencils::new(&model.stiffness).expect("structured");
        drop(model);
        let x = x_of(n);
        let w = |c: f64| -> Vec<f64> { x.iter().map(|v| v * c + c).collect() };
        (stencils, [w(1.3), w(1.2), w(1.5), w(1.6)])
    }

    /// A copy of `src` starting at byte `offset` of a 4 KiB page (64-byte
    /// steps), in a buffer it returns beside the slice's start.
    fn at_page_offset(src: &[f64], offset: usize) -> (Vec<f64>, usize) {
        let mut buf = vec![0.0; src.len() + 1024];
        let base = buf.as_ptr() as usize;
        let start = (0..1024)
            .find(|&k| (base + 8 * k) % 4096 == offset)
            .expect("a 4 KiB page holds every 8-byte offset");
        buf[start..start + src.len()].copy_from_slice(src);
        (buf, start)
    }

    /// Whether the page offsets of the sweep's five vectors (m, r_K, ṙ,
    /// r̈, r_{K+1}) matter: the sweep in place with all five at one
    /// offset against three spreads, alternating in one process, 2
    /// threads, median (fastest) of 29 rounds, ms. Run by hand:
    ///
    ///     cargo test --release -p stickslip-time --lib page_offset_lab -- --ignored --nocapture
    ///
    /// 2026-11-25 15:33-15:35, five runs: at one offset the fastest round
    /// took 1.04-1.12 of the best spread's on Q1 1M and 1.03-1.08 on Q2
    /// 1M; the spreads among themselves within the noise. The
    /// integrator's own vectors come from the heap at offsets already
    /// apart (the Q2 708×177 bench rung, two runs: m 3056, r_K 3072 /
    /// 960 / 2880 as the three buffers turn, ṙ 1120, r̈ 768 or 880), so
    /// there is nothing to gain by placing them.
    #[test]
    #[ignore = "timing lab"]
    fn page_offset_lab() {
        use std::time::Instant;
        let meshes = std::env::var("STICKSLIP_LAB_MESHES")
            .unwrap_or_else(|_| "q1-1416x354,q2-708x177".into());
        // Page offsets (bytes) of m, r_K, ṙ, r̈, r_{K+1}.
        let layouts: [(&str, [usize; 5]); 4] = [
            ("same", [0, 0, 0, 0, 0]),
            ("spread 576", [0, 576, 1152, 1728, 2304]),
            ("spread 832", [0, 832, 1664, 2496, 3328]),
            ("spread 320", [0, 320, 640, 960, 1280]),
        ];
        for name in meshes.split(',') {
            let (stencils, [rn0, m0, v0, a0]) = sweep_lab_vectors(name);
            let n = rn0.len();
            let zero = vec![0.0; n];
            let mut t: Vec<Vec<f64>> = vec![Vec::new(); layouts.len()];
            let mut bufs: Vec<_> = layouts
                .iter()
                .map(|(_, o)| {
                    [
                        at_page_offset(&m0, o[0]),
                        at_page_offset(&rn0, o[1]),
                        at_page_offset(&v0, o[2]),
                        at_page_offset(&a0, o[3]),
                        at_page_offset(&zero, o[4]),
                    ]
                })
                .collect();
            on_threads(2, || {
                let mut p = partials(n);
                for round in 0..30 {
                    for (l, b) in bufs.iter_mut().enumerate() {
                        let [(mb, ms), (rb, rs), (vb, vs), (ab, as_), (xb, xs)] = b;
                        vb[*vs..*vs + n].copy_from_slice(&v0);
                        ab[*as_..*as_ + n].copy_from_slice(&a0);
                        let data = StepData {
                            v: &[],
                            a: &[],
                            in_place: true,
                            ..lab_data(&zero, &mb[*ms..*ms + n], &rb[*rs..*rs + n], &[], &[])
                        };
                        let (vn, an, rx) = (
                            &mut vb[*vs..*vs + n],
                            &mut ab[*as_..*as_ + n],
                            &mut xb[*xs..*xs + n],
                        );
                        let s = Instant::now();
                        sweep(avx(), &stencils, &data, &[], None, [vn, an, rx], &mut p);
                        if round > 0 {
                            t[l].push(s.elapsed().as_secs_f64());
                        }
                    }
                }
            });
            print!("{name}:");
            for ((label, _), t) in layouts.iter().zip(&mut t) {
                t.sort_by(f64::total_cmp);
                print!("  {label} {:.3} ({:.3})", 1e3 * t[t.len() / 2], 1e3 * t[0]);
            }
            println!(" ms");
        }
    }

    /// K·x on a small mesh (one chunk, in cache: the per-step overhead
    /// the paper mesh's step is made of), CSR against [`Compact`] at each
    /// width, medians of 30 rounds of 20,000 products. `STICKSLIP_LAB_MESH`
    /// picks the slab (default q2-8x2, the paper's 148 free DOFs):
    ///
    ///     cargo test --release -p stickslip-time --lib small_lab -- --ignored --nocapture
    ///
    /// 2026-11-24, paper mesh: CSR 2.30 µs; compact in [`group_sums`]'
    /// order on 64-byte lines: scalar (SSE2 build) 1.86, AVX 0.63,
    /// AVX-512 0.64 µs (the compact in the CSR's order, two groups in
    /// lockstep, 2-wide, had 1.11 µs); Q2 64×16 (8,352 DOFs, two chunks):
    /// CSR 208, AVX 67, AVX-512 61 µs.
    #[test]
    #[ignore = "timing; run by hand (see the doc comment)"]
    fn small_lab() {
        let name = std::env::var("STICKSLIP_LAB_MESH").unwrap_or_else(|_| "q2-8x2".into());
        let (_, _, model) = lab_slab(&name);
        let k = &model.stiffness;
        let n = k.nrows();
        let compact = Compact::new(k).expect("applies");
        let x = x_of(n);
        let mut y = vec![0.0; n];
        let time = |f: &mut dyn FnMut()| median_time(20_000, f);
        println!(
            "{name}: n = {n}, nnz = {}, blocks = {}",
            k.nnz(),
            compact.blocks()
        );
        let csr = time(&mut || spmv(k, std::hint::black_box(&x), &mut y));
        println!("  CSR            {:.3} µs", 1e6 * csr);
        for c in widths(&compact) {
            let t = time(&mut || c.spmv(std::hint::black_box(&x), &mut y));
            println!("  compact {:<6} {:.3} µs", format!("{:?}", c.wide), 1e6 * t);
        }
        let dict = Compact::with_form(k, Form::Dictionary).expect("applies");
        println!(
            "  dictionary: {} distinct of {} blocks",
            dict.dictionary_len(),
            dict.blocks()
        );
        for c in widths(&dict) {
            let t = time(&mut || c.spmv(std::hint::black_box(&x), &mut y));
            println!("  dict    {:<6} {:.3} µs", format!("{:?}", c.wide), 1e6 * t);
        }
        // Newmark's two passes over K and M (linalg.rs).
        let pairs = crate::linalg::PairBlocks::new(k, &model.mass).expect("shared pattern");
        let l = x_of(n);
        let mut partials = vec![0.0; 2 * crate::linalg::row_chunks(n)];
        let t = time(&mut || pairs.load_minus_k_plus_m(&l, std::hint::black_box(&x), &x, &mut y));
        println!("  pair blocks: l − K x + M y {:.3} µs", 1e6 * t);
        let t = time(&mut || {
            std::hint::black_box(pairs.two_forms(std::hint::black_box(&x), &x, &mut partials));
        });
        println!("  pair blocks: xᵀK x, yᵀM y  {:.3} µs", 1e6 * t);
    }
}
