//! The sparse Cholesky factorization (cholesky.rs): solves against a
//! closed-form inverse and by residual after a refactorization, and a
//! singular matrix refused.

use nalgebra_sparse::{CooMatrix, CsrMatrix};
use stickslip_linalg::{FillOrder, SolverError, SparseCholesky};
use stickslip_testkit::plain_spmv;

/// The 1-D Laplacian with Dirichlet ends: tridiag(−1, 2, −1), whose
/// inverse is known in closed form, A⁻¹ᵢⱼ = min(i,j)(n+1−max(i,j))/(n+1)
/// (1-based indices).
fn laplacian(n: usize, shift: f64) -> CsrMatrix<f64> {
    let mut coo = CooMatrix::new(n, n);
    for i in 0..n {
        coo.push(i, i, 2.0 + shift);
        if i > 0 {
            coo.push(i, i - 1, -1.0);
            coo.push(i - 1, i, -1.0);
        }
    }
    CsrMatrix::from(&coo)
}

#[test]
fn solves_against_the_closed_form_inverse() {
    let n = 50;
    let a = laplacian(n, 0.0);
    let mut chol = SparseCholesky::analyze(&a, &FillOrder::default()).unwrap();
    chol.factorize(&a).unwrap();
    // x = A⁻¹ e_k is column k of the closed-form inverse.
    let k = 17;
    let mut x = vec![0.0; n];
    x[k] = 1.0;
    chol.solve_in_place(&mut x);
    for (i, xi) in x.iter().enumerate() {
        let (i1, k1) = ((i + 1) as f64, (k + 1) as f64);
        let exact = i1.min(k1) * ((n + 1) as f64 - i1.max(k1)) / (n + 1) as f64;
        assert!(
            (xi - exact).abs() < 1e-12,
            "x[{i}] = {xi}, closed form {exact}"
        );
    }
}

#[test]
fn refactorizes_with_new_values_on_the_same_pattern() {
    let n = 30;
    let mut a = laplacian(n, 0.0);
    let mut chol = SparseCholesky::analyze(&a, &FillOrder::default()).unwrap();
    chol.factorize(&a).unwrap();
    // Shift the diagonal: same pattern, new values; check A x = b by residual.
    let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
    let shifted = laplacian(n, 0.5);
    a.values_mut().copy_from_slice(shifted.values());
    chol.factorize(&a).unwrap();
    let mut x = b.clone();
    chol.solve_in_place(&mut x);
    for (i, ax) in plain_spmv(&a, &x).iter().enumerate() {
        assert!((ax - b[i]).abs() < 1e-12, "residual at row {i}");
    }
}

#[test]
fn singular_matrix_is_reported_not_positive_definite() {
    // Free-free 1-D Laplacian: rows sum to zero, the constant vector is
    // in the kernel (a rigid-body translation).
    let n = 10;
    let mut coo = CooMatrix::new(n, n);
    for i in 0..n {
        let d = if i == 0 || i == n - 1 { 1.0 } else { 2.0 };
        coo.push(i, i, d);
        if i > 0 {
            coo.push(i, i - 1, -1.0);
            coo.push(i - 1, i, -1.0);
        }
    }
    let a = CsrMatrix::from(&coo);
    let mut chol = SparseCholesky::analyze(&a, &FillOrder::default()).unwrap();
    match chol.factorize(&a) {
        Err(SolverError::NotPositiveDefinite { .. }) => {}
        other => panic!("expected NotPositiveDefinite, got {other:?}"),
    }
}
