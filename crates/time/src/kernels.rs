//! The explicit step's vector passes, fused and threaded (issue 7,
//! deliverable 2).
//!
//! An explicit step is bound by memory traffic, so it makes as few passes
//! over the free-DOF vectors as the data dependencies allow: (A) load and
//! predictor, (B) K·r by CSR SpMV fused with the right-hand side, the
//! lumped-mass division and the strain energy, then friction at the contact
//! nodes, (C) acceleration, work, kinetic energy and the finiteness check.
//!
//! Work is split into fixed chunks of [`CHUNK`] DOFs whatever the number of
//! threads, and sums are formed per chunk and added in chunk order, so a
//! run is bit-identical on one thread and on many. Below [`PARALLEL_MIN`]
//! chunks the passes run on the calling thread (a rayon dispatch costs
//! microseconds, more than a pass over the paper's 170 DOFs).
//!
//! K·r by CSR SpMV rather than element by element: per Q1 DOF the CSR row
//! reads 18 values and 18 column indices (288 bytes with usize indices),
//! while stored element matrices read 64 values per element, one element
//! per node, i.e. 256 bytes per DOF plus the connectivity, and scatter
//! their results, which in parallel needs colouring or atomics to stay
//! deterministic; for Q2 the element matrices (18×18 per 4 nodes, 324
//! bytes per DOF) lose more. The gather-free CSR row is the cheaper
//! memory stream, and its rows are independent, so threads never share an
//! output. (`examples/bench_step.rs` prints the SpMV's bandwidth.)

use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

use crate::integrator::Load;

/// DOFs per chunk of work.
pub const CHUNK: usize = 8192;
/// Chunks from which the passes go parallel.
pub const PARALLEL_MIN: usize = 2;

/// Number of chunks of a vector of length n.
pub fn chunks(n: usize) -> usize {
    n.div_ceil(CHUNK).max(1)
}

/// True when the passes should use the thread pool.
fn parallel(n: usize) -> bool {
    chunks(n) >= PARALLEL_MIN && rayon::current_num_threads() > 1
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

/// Per-chunk partial sums, added in chunk order.
pub type Partials = Vec<[f64; 4]>;

fn total(partials: &[[f64; 4]], k: usize) -> f64 {
    partials.iter().map(|p| p[k]).sum()
}

/// Pass A: R_K = constant + Σ θ_l load_l into `load_new`, and the
/// predictor r_K = r + c1 ṙ + c2 r̈ into `r_new`.
#[allow(clippy::too_many_arguments)]
pub fn load_and_predict(
    constant: &[f64],
    loads: &[Load],
    thetas: &[f64],
    r: &[f64],
    v: &[f64],
    a: &[f64],
    c1: f64,
    c2: f64,
    load_new: &mut [f64],
    r_new: &mut [f64],
) {
    let body = |c: usize, l: &mut [f64], rn: &mut [f64]| {
        let range = c * CHUNK..c * CHUNK + l.len();
        l.copy_from_slice(&constant[range.clone()]);
        for (load, theta) in loads.iter().zip(thetas) {
            if *theta != 0.0 {
                for (o, f) in l.iter_mut().zip(&load.vector[range.clone()]) {
                    *o += theta * f;
                }
            }
        }
        let (r, v, a) = (&r[range.clone()], &v[range.clone()], &a[range]);
        for i in 0..rn.len() {
            rn[i] = r[i] + c1 * v[i] + c2 * a[i];
        }
    };
    if parallel(r.len()) {
        load_new
            .par_chunks_mut(CHUNK)
            .zip(r_new.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (l, rn))| body(c, l, rn));
    } else {
        load_new
            .chunks_mut(CHUNK)
            .zip(r_new.chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (l, rn))| body(c, l, rn));
    }
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
    let body = |c: usize, b: &mut [f64], vn: &mut [f64], partial: &mut [f64; 4]| {
        let range = c * CHUNK..c * CHUNK + b.len();
        let (l, m, rn) = (
            &load_new[range.clone()],
            &mass[range.clone()],
            &r_new[range.clone()],
        );
        let (v, a) = (&v[range.clone()], &a[range]);
        let mut strain = 0.0;
        for i in 0..b.len() {
            let ku = b[i];
            strain += rn[i] * ku;
            let bi = l[i] - ku + m[i] * (cv * v[i] + ca * a[i]);
            b[i] = bi;
            vn[i] = bi / (m[i] * scale);
        }
        partial[0] = strain;
    };
    if parallel(r_new.len()) {
        b.par_chunks_mut(CHUNK)
            .zip(v_new.par_chunks_mut(CHUNK))
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, ((b, vn), p))| body(c, b, vn, p));
    } else {
        b.chunks_mut(CHUNK)
            .zip(v_new.chunks_mut(CHUNK))
            .zip(partials.iter_mut())
            .enumerate()
            .for_each(|(c, ((b, vn), p))| body(c, b, vn, p));
    }
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
}

/// Pass C: r̈_K = (ṙ_K − ṙ)/(γΔt) − (1−γ)/γ r̈ into `a_new`, and the sums.
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
    gamma_dt: f64,
    ratio: f64,
    a_new: &mut [f64],
    partials: &mut Partials,
) -> Sums {
    let body = |c: usize, an: &mut [f64], partial: &mut [f64; 4]| {
        let range = c * CHUNK..c * CHUNK + an.len();
        let (m, l, ln) = (
            &mass[range.clone()],
            &load[range.clone()],
            &load_new[range.clone()],
        );
        let (r, rn, v) = (&r[range.clone()], &r_new[range.clone()], &v[range.clone()]);
        let (vn, a) = (&v_new[range.clone()], &a[range]);
        let (mut work, mut kinetic, mut load_dot) = (0.0, 0.0, 0.0);
        let mut finite = true;
        for i in 0..an.len() {
            an[i] = (vn[i] - v[i]) / gamma_dt - ratio * a[i];
            work += 0.5 * (ln[i] + l[i]) * (rn[i] - r[i]);
            kinetic += m[i] * vn[i] * vn[i];
            load_dot += rn[i] * ln[i];
            finite &= rn[i].is_finite() && vn[i].is_finite();
        }
        *partial = [work, kinetic, load_dot, if finite { 0.0 } else { 1.0 }];
    };
    if parallel(r.len()) {
        a_new
            .par_chunks_mut(CHUNK)
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, (an, p))| body(c, an, p));
    } else {
        a_new
            .chunks_mut(CHUNK)
            .zip(partials.iter_mut())
            .enumerate()
            .for_each(|(c, (an, p))| body(c, an, p));
    }
    Sums {
        work: total(partials, 0),
        kinetic: 0.5 * total(partials, 1),
        load_dot: total(partials, 2),
        finite: total(partials, 3) == 0.0,
    }
}
