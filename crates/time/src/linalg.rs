//! Small vector kernels on free-DOF vectors and CSR matrices.

use nalgebra_sparse::CsrMatrix;

/// y = A x.
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    for (i, yi) in y.iter_mut().enumerate() {
        let mut s = 0.0;
        for k in offsets[i]..offsets[i + 1] {
            s += vals[k] * x[cols[k]];
        }
        *yi = s;
    }
}

/// xᵀ A x.
pub fn quadratic_form(a: &CsrMatrix<f64>, x: &[f64]) -> f64 {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let mut total = 0.0;
    for (i, xi) in x.iter().enumerate() {
        let mut s = 0.0;
        for k in offsets[i]..offsets[i + 1] {
            s += vals[k] * x[cols[k]];
        }
        total += xi * s;
    }
    total
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
