//! Products with CSR matrices (nalgebra-sparse, both triangles stored),
//! threaded by the fixed chunks of [`crate::chunks`].

use nalgebra_sparse::CsrMatrix;

use crate::chunks::{each_chunk, sum_chunks, CHUNK};

/// Σ_k vals[k]·x[cols[k]] over one row, in four interleaved partial sums
/// (one chain of additions waits on the adder's latency).
#[inline]
pub(crate) fn row_dot(vals: &[f64], cols: &[usize], x: &[f64]) -> f64 {
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

/// Row i of A times x, by [`row_dot`].
#[inline]
pub fn row(a: &CsrMatrix<f64>, i: usize, x: &[f64]) -> f64 {
    let (p, q) = (a.row_offsets()[i], a.row_offsets()[i + 1]);
    row_dot(&a.values()[p..q], &a.col_indices()[p..q], x)
}

/// y = A x.
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    each_chunk(y, |c, y| {
        for (k, yi) in y.iter_mut().enumerate() {
            *yi = row(a, c * CHUNK + k, x);
        }
    });
}

/// Row sums of two matrices on one pattern, each with [`row_dot`]'s bits.
#[inline]
fn row_dot2(a: &[f64], x: &[f64], b: &[f64], y: &[f64], cols: &[usize]) -> (f64, f64) {
    (row_dot(a, cols, x), row_dot(b, cols, y))
}

/// True when A and B store the same pattern.
pub fn same_pattern(a: &CsrMatrix<f64>, b: &CsrMatrix<f64>) -> bool {
    a.nrows() == b.nrows()
        && a.row_offsets() == b.row_offsets()
        && a.col_indices() == b.col_indices()
}

/// out_i = l_i − (K x)_i + (M y)_i in one pass over the shared pattern of
/// K and M ([`same_pattern`]), with the bits of two [`spmv`]s.
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
    each_chunk(out, |c, out| {
        for (j, o) in out.iter_mut().enumerate() {
            let i = c * CHUNK + j;
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (kx, my) = row_dot2(&kv[p..q], x, &mv[p..q], y, &cols[p..q]);
            *o = l[i] - kx + my;
        }
    });
}

/// xᵀ A x, each row's product as in [`spmv`]; `partials` holds
/// [`crate::chunks::chunks`]`(n)` sums.
pub fn quadratic_form(a: &CsrMatrix<f64>, x: &[f64], partials: &mut [[f64; 2]]) -> f64 {
    sum_chunks(x.len(), partials, |_, rows, s| {
        s[0] = rows.map(|i| x[i] * row(a, i, x)).sum();
    })[0]
}

/// (xᵀK x, yᵀM y) in one pass over the shared pattern of K and M, each with
/// the bits of [`quadratic_form`].
pub fn two_forms(
    k: &CsrMatrix<f64>,
    x: &[f64],
    m: &CsrMatrix<f64>,
    y: &[f64],
    partials: &mut [[f64; 2]],
) -> (f64, f64) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let [s, t] = sum_chunks(x.len(), partials, |_, rows, s| {
        let (mut a, mut b) = (0.0, 0.0);
        for i in rows {
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (kx, my) = row_dot2(&kv[p..q], x, &mv[p..q], y, &cols[p..q]);
            a += x[i] * kx;
            b += y[i] * my;
        }
        *s = [a, b];
    });
    (s, t)
}

/// x · y.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Index of entry (i, j) in the CSR value array, if stored.
pub fn index(a: &CsrMatrix<f64>, i: usize, j: usize) -> Option<usize> {
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

    /// A symmetric matrix with a few entries per row, long enough for
    /// several chunks.
    fn banded(n: usize) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n, n);
        for i in 0..n {
            coo.push(i, i, 4.0 + (i % 7) as f64);
            for d in [1, 5, 93] {
                if i + d < n {
                    let v = -0.25 * d as f64;
                    coo.push(i, i + d, v);
                    coo.push(i + d, i, v);
                }
            }
        }
        CsrMatrix::from(&coo)
    }

    /// The products against a plain sum over the stored entries.
    #[test]
    fn products_and_forms_against_plain_sums() {
        let n = 3 * CHUNK + 101;
        let a = banded(n);
        let x: Vec<f64> = (0..n).map(|i| ((i * 31) % 17) as f64 - 8.0).collect();
        let y: Vec<f64> = (0..n).map(|i| ((i * 13) % 11) as f64 * 0.5).collect();
        let plain: Vec<f64> = a
            .row_iter()
            .map(|r| {
                r.col_indices()
                    .iter()
                    .zip(r.values())
                    .map(|(&j, v)| v * x[j])
                    .sum()
            })
            .collect();
        let mut ax = vec![0.0; n];
        spmv(&a, &x, &mut ax);
        for (p, q) in plain.iter().zip(&ax) {
            // Small integers and halves: every sum is exact.
            assert_eq!(p, q);
        }
        let mut partials = crate::chunks::partials(n);
        let xax: f64 = x.iter().zip(&plain).map(|(a, b)| a * b).sum();
        assert!((quadratic_form(&a, &x, &mut partials) - xax).abs() <= 1e-12 * xax.abs());
        let (f1, f2) = two_forms(&a, &x, &a, &y, &mut partials);
        assert_eq!(
            f1.to_bits(),
            quadratic_form(&a, &x, &mut partials).to_bits()
        );
        assert_eq!(
            f2.to_bits(),
            quadratic_form(&a, &y, &mut partials).to_bits()
        );
        let l = vec![1.5; n];
        let mut out = vec![0.0; n];
        load_minus_k_plus_m(&l, &a, &x, &a, &y, &mut out);
        let mut ay = vec![0.0; n];
        spmv(&a, &y, &mut ay);
        for i in 0..n {
            assert_eq!(out[i].to_bits(), (l[i] - ax[i] + ay[i]).to_bits());
        }
        assert_eq!(index(&a, 0, 5), Some(2));
        assert_eq!(index(&a, 0, 2), None);
    }
}
