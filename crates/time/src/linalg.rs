//! Small vector kernels on free-DOF vectors and CSR matrices.

use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

/// Rows per chunk of work: sums are formed per chunk and added in chunk
/// order, so the threaded and the sequential products agree bit for bit.
const ROWS: usize = 4096;

/// Σ_k vals[k]·x[cols[k]] over one row, in four interleaved partial sums
/// (a single chain is bound by the adder's latency: the implicit step's
/// products on the paper's mesh spent half their time waiting on it).
#[inline]
fn row_dot(vals: &[f64], cols: &[usize], x: &[f64]) -> f64 {
    let split = vals.len() - vals.len() % 4;
    let mut acc = [0.0; 4];
    for (v, c) in vals[..split]
        .chunks_exact(4)
        .zip(cols[..split].chunks_exact(4))
    {
        acc[0] += v[0] * x[c[0]];
        acc[1] += v[1] * x[c[1]];
        acc[2] += v[2] * x[c[2]];
        acc[3] += v[3] * x[c[3]];
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (v, &c) in vals[split..].iter().zip(&cols[split..]) {
        s += v * x[c];
    }
    s
}

/// y = A x, rows in chunks on the thread pool when there are several.
/// (`kernels::spmv` keeps one chain per row instead: the explicit step's
/// compact K must reproduce its bits.)
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let body = |c: usize, y: &mut [f64]| {
        for (k, yi) in y.iter_mut().enumerate() {
            let i = c * ROWS + k;
            let (p, q) = (offsets[i], offsets[i + 1]);
            *yi = row_dot(&vals[p..q], &cols[p..q], x);
        }
    };
    if y.len() > ROWS {
        y.par_chunks_mut(ROWS)
            .enumerate()
            .for_each(|(c, y)| body(c, y));
    } else {
        body(0, y);
    }
}

/// Row sums of two matrices on one pattern: (Σ a_k x[c_k], Σ b_k y[c_k]),
/// each in the order of [`row_dot`] (so each equals [`row_dot`]'s bits).
#[inline]
fn row_dot2(a: &[f64], x: &[f64], b: &[f64], y: &[f64], cols: &[usize]) -> (f64, f64) {
    let split = cols.len() - cols.len() % 4;
    let (mut p, mut q) = ([0.0; 4], [0.0; 4]);
    for ((u, v), c) in a[..split]
        .chunks_exact(4)
        .zip(b[..split].chunks_exact(4))
        .zip(cols[..split].chunks_exact(4))
    {
        for j in 0..4 {
            p[j] += u[j] * x[c[j]];
            q[j] += v[j] * y[c[j]];
        }
    }
    let mut s = (p[0] + p[1]) + (p[2] + p[3]);
    let mut t = (q[0] + q[1]) + (q[2] + q[3]);
    for ((u, v), &c) in a[split..].iter().zip(&b[split..]).zip(&cols[split..]) {
        s += u * x[c];
        t += v * y[c];
    }
    (s, t)
}

/// True when `a` and `b` store the same pattern (K and M as assembled).
pub fn same_pattern(a: &CsrMatrix<f64>, b: &CsrMatrix<f64>) -> bool {
    a.nrows() == b.nrows()
        && a.row_offsets() == b.row_offsets()
        && a.col_indices() == b.col_indices()
}

/// out_i = l_i − (K x)_i + (M y)_i in one pass over the shared pattern of
/// K and M (see [`same_pattern`]): the implicit step's R̂_K with the
/// consistent mass, the bits of two [`spmv`]s and the same combination.
pub fn load_minus_k_plus_m(
    l: &[f64],
    k: &CsrMatrix<f64>,
    x: &[f64],
    m: &CsrMatrix<f64>,
    y: &[f64],
    out: &mut [f64],
) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let body = |c: usize, out: &mut [f64]| {
        for (j, o) in out.iter_mut().enumerate() {
            let i = c * ROWS + j;
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (kx, my) = row_dot2(&kv[p..q], x, &mv[p..q], y, &cols[p..q]);
            *o = l[i] - kx + my;
        }
    };
    if out.len() > ROWS {
        out.par_chunks_mut(ROWS)
            .enumerate()
            .for_each(|(c, o)| body(c, o));
    } else {
        body(0, out);
    }
}

/// (xᵀK x, yᵀM y) in one pass over the shared pattern of K and M, each
/// with the bits of [`quadratic_form`]; `partials` is 2·[`row_chunks`] long.
pub fn two_forms(
    k: &CsrMatrix<f64>,
    x: &[f64],
    m: &CsrMatrix<f64>,
    y: &[f64],
    partials: &mut [f64],
) -> (f64, f64) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let chunk = |c: usize| -> (f64, f64) {
        let rows = c * ROWS..((c + 1) * ROWS).min(x.len());
        let (mut s, mut t) = (0.0, 0.0);
        for i in rows {
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (kx, my) = row_dot2(&kv[p..q], x, &mv[p..q], y, &cols[p..q]);
            s += x[i] * kx;
            t += y[i] * my;
        }
        (s, t)
    };
    let chunks = row_chunks(x.len());
    let partials = &mut partials[..2 * chunks];
    if chunks > 1 {
        partials
            .par_chunks_mut(2)
            .enumerate()
            .for_each(|(c, p)| (p[0], p[1]) = chunk(c));
        let s = partials.iter().step_by(2).sum();
        let t = partials.iter().skip(1).step_by(2).sum();
        (s, t)
    } else {
        chunk(0)
    }
}

/// Chunks of rows of a vector of length n (the length of the `partials`
/// buffer [`quadratic_form`] needs).
pub fn row_chunks(n: usize) -> usize {
    n.div_ceil(ROWS).max(1)
}

/// xᵀ A x: per-row products as in [`spmv`], summed per chunk of rows into
/// `partials` (at least [`row_chunks`] long), the chunks' sums added in
/// order.
pub fn quadratic_form(a: &CsrMatrix<f64>, x: &[f64], partials: &mut [f64]) -> f64 {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let chunk = |c: usize| -> f64 {
        let rows = c * ROWS..((c + 1) * ROWS).min(x.len());
        let mut total = 0.0;
        for i in rows {
            let (p, q) = (offsets[i], offsets[i + 1]);
            total += x[i] * row_dot(&vals[p..q], &cols[p..q], x);
        }
        total
    };
    let chunks = row_chunks(x.len());
    let partials = &mut partials[..chunks];
    if chunks > 1 {
        partials
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, p)| *p = chunk(c));
        partials.iter().sum()
    } else {
        chunk(0)
    }
}

/// x · y.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Index of entry (i, j) in the CSR value array, if stored.
pub fn csr_index(a: &CsrMatrix<f64>, i: usize, j: usize) -> Option<usize> {
    let start = a.row_offsets()[i];
    let end = a.row_offsets()[i + 1];
    a.col_indices()[start..end]
        .binary_search(&j)
        .ok()
        .map(|k| start + k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// A banded symmetric pattern over `n` rows (rows of 5-11 entries, so
    /// the four-way split and the remainder both occur) and two value sets.
    fn pair(n: usize) -> (CsrMatrix<f64>, CsrMatrix<f64>) {
        let (mut k, mut m) = (CooMatrix::new(n, n), CooMatrix::new(n, n));
        for i in 0..n {
            for j in i.saturating_sub(5)..(i + 6).min(n) {
                let h = ((i * 31 + j * 17) % 97) as f64 / 97.0;
                k.push(i, j, if i == j { 10.0 } else { -h });
                m.push(i, j, if i == j { 2.0 } else { 0.1 * h });
            }
        }
        (CsrMatrix::from(&k), CsrMatrix::from(&m))
    }

    fn vector(n: usize, seed: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919 + seed) % 1009) as f64 / 1009.0 - 0.5)
            .collect()
    }

    /// The fused products have the bits of the separate ones, and the
    /// threaded runs (several chunks) the bits of one thread.
    #[test]
    fn fused_products_have_the_bits_of_the_separate_ones() {
        for n in [37, 3 * ROWS + 11] {
            let (k, m) = pair(n);
            assert!(same_pattern(&k, &m));
            let (x, y, l) = (vector(n, 1), vector(n, 2), vector(n, 3));
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let mut partials = vec![0.0; 2 * row_chunks(n)];
                    let (mut kx, mut my, mut fused) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                    spmv(&k, &x, &mut kx);
                    spmv(&m, &y, &mut my);
                    load_minus_k_plus_m(&l, &k, &x, &m, &y, &mut fused);
                    let separate: Vec<f64> = (0..n).map(|i| l[i] - kx[i] + my[i]).collect();
                    let qk = quadratic_form(&k, &x, &mut partials);
                    let qm = quadratic_form(&m, &y, &mut partials);
                    let both = two_forms(&k, &x, &m, &y, &mut partials);
                    (fused, separate, (qk, qm), both, kx)
                })
            };
            let one = run(1);
            let two = run(2);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&one.0), bits(&one.1), "n = {n}: fused R̂");
            assert_eq!(one.2 .0.to_bits(), one.3 .0.to_bits(), "n = {n}: xᵀKx");
            assert_eq!(one.2 .1.to_bits(), one.3 .1.to_bits(), "n = {n}: yᵀMy");
            assert_eq!(bits(&one.0), bits(&two.0), "n = {n}: threads");
            assert_eq!(one.3 .0.to_bits(), two.3 .0.to_bits(), "n = {n}: threads");
            // And the product is right: against a plain row loop to 1e-13.
            for (i, row) in k.row_iter().enumerate() {
                let plain: f64 = row
                    .col_indices()
                    .iter()
                    .zip(row.values())
                    .map(|(&j, v)| v * x[j])
                    .sum();
                assert!((plain - one.4[i]).abs() <= 1e-13 * plain.abs().max(1.0));
            }
        }
    }
}
