//! Products with CSR matrices (nalgebra-sparse, both triangles stored),
//! threaded by the fixed chunks of [`crate::chunks`].

use nalgebra_sparse::CsrMatrix;

use crate::chunks::{each_chunk, sum_chunks, CHUNK};

/// Σ_k vals[k]·x[cols[k]] over one row in four interleaved partial sums
/// (one chain of additions waits on the adder's latency): lane l takes
/// the terms k ≡ l mod 4, the lanes are added pairwise, then the row's
/// last len mod 4 terms in order.
#[inline(always)]
pub(crate) fn row_dot(vals: &[f64], cols: &[usize], x: &[f64]) -> f64 {
    let len = cols.len();
    let split = len - len % 4;
    let mut acc = [0.0; 4];
    for (g, c) in cols[..split].chunks_exact(4).enumerate() {
        let v = &vals[4 * g..4 * g + 4];
        // Sorted distinct columns: four consecutive ones (a run of nodes
        // along a grid row) are one load of x.
        let xs: [f64; 4] = if c[3] == c[0] + 3 {
            x[c[0]..c[0] + 4].try_into().expect("four values")
        } else {
            [x[c[0]], x[c[1]], x[c[2]], x[c[3]]]
        };
        for l in 0..4 {
            acc[l] += v[l] * xs[l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (k, &c) in cols.iter().enumerate().skip(split) {
        s += vals[k] * x[c];
    }
    s
}

/// Row i of A times x, in `row_dot`'s four interleaved partial sums: the
/// same bits as row i of [`spmv`].
#[inline(always)]
pub fn row(a: &CsrMatrix<f64>, i: usize, x: &[f64]) -> f64 {
    let (p, q) = (a.row_offsets()[i], a.row_offsets()[i + 1]);
    row_dot(&a.values()[p..q], &a.col_indices()[p..q], x)
}

/// y = A x.
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    each_chunk(y, |c, y| {
        crate::simd::vectorized(Rows { a, c, x, y });
    });
}

/// Rows of chunk c of A x, as a dispatched kernel.
struct Rows<'a> {
    a: &'a CsrMatrix<f64>,
    c: usize,
    x: &'a [f64],
    y: &'a mut [f64],
}

impl crate::simd::Kernel for Rows<'_> {
    type Output = ();

    #[inline(always)]
    fn run<S: crate::simd::Simd>(self, _simd: S) {
        for (k, yi) in self.y.iter_mut().enumerate() {
            *yi = row(self.a, self.c * CHUNK + k, self.x);
        }
    }
}

/// True when A and B store the same pattern.
pub fn same_pattern(a: &CsrMatrix<f64>, b: &CsrMatrix<f64>) -> bool {
    a.nrows() == b.nrows()
        && a.row_offsets() == b.row_offsets()
        && a.col_indices() == b.col_indices()
}

/// xᵀ A x, each row's product as in [`spmv`]; `partials` holds
/// [`crate::chunks::chunks`]`(n)` sums.
pub fn quadratic_form(a: &CsrMatrix<f64>, x: &[f64], partials: &mut [[f64; 2]]) -> f64 {
    sum_chunks(x.len(), partials, |_, rows, s| {
        s[0] = rows.map(|i| x[i] * row(a, i, x)).sum();
    })[0]
}

/// x · y.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// A's diagonal, 0 where a row stores none.
pub fn diagonal(a: &CsrMatrix<f64>) -> Vec<f64> {
    (0..a.nrows())
        .map(|i| index(a, i, i).map_or(0.0, |k| a.values()[k]))
        .collect()
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
