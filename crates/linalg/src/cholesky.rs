//! Sparse symmetric positive definite solves with faer's Cholesky.
//!
//! The operators factorized here keep one sparsity pattern over many
//! factorizations (a run's K, its A₀ for every Δt), so the fill-reducing
//! ordering and the symbolic factorization are computed once
//! ([`SparseCholesky::analyze`]) and a change of values only redoes the
//! numeric part ([`SparseCholesky::factorize`]). AMD and supernodal (the
//! measured choice: DEPENDENCIES.md §3), or the caller's nested dissection
//! ([`crate::FillOrder`]). The factor is always supernodal and solved by
//! [`Supernodal`]'s loops.

use std::cell::RefCell;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::linalg::cholesky::llt::factor::LltParams;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side, Spec};

use crate::{FillOrder, Supernodal};
use faer::perm::PermRef;
use nalgebra_sparse::CsrMatrix;

/// Why a factorization failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolverError {
    /// The matrix is not square.
    #[error("the matrix is {rows}×{cols}, not square")]
    NotSquare {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
    /// A pivot was zero or negative: the matrix is singular or indefinite.
    #[error("the matrix is not positive definite (pivot {pivot} of {n} failed)")]
    NotPositiveDefinite {
        /// Index (in the permuted order) of the failed pivot.
        pivot: usize,
        /// Matrix size.
        n: usize,
    },
    /// The matrix has a different sparsity pattern than the analysed one.
    #[error("the matrix pattern changed after the symbolic analysis (nnz {analysed} → {given})")]
    PatternChanged {
        /// Non-zeros at analysis.
        analysed: usize,
        /// Non-zeros now.
        given: usize,
    },
    /// faer could not allocate or analyse.
    #[error("sparse Cholesky analysis failed: {0}")]
    Analysis(String),
}

/// A sparse Cholesky factorization A = LLᵀ of a symmetric positive definite
/// CSR matrix (both triangles stored, columns sorted, as nalgebra-sparse
/// keeps them), with the symbolic analysis kept for refactorization.
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    factorized: bool,
    n: usize,
    nnz: usize,
    factor_scratch: MemBuffer,
    solver: RefCell<Supernodal>,
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.n)
            .field("nnz", &self.nnz)
            .field("factor_nnz", &self.l_values.len())
            .field("factorized", &self.factorized)
            .finish()
    }
}

/// `values` on `a`'s pattern as a faer CSC matrix: a symmetric CSR matrix
/// is its own CSC transpose (its row offsets and column indices read as
/// column pointers and row indices of the same matrix), and K, M and
/// a·K + b·M share one pattern, so one pattern serves every combination.
pub fn csc_view<'a>(a: &'a CsrMatrix<f64>, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
    let sym = SymbolicSparseColMatRef::new_checked(
        a.nrows(),
        a.ncols(),
        a.row_offsets(),
        None,
        a.col_indices(),
    );
    SparseColMatRef::new(sym, values)
}

fn as_csc(a: &CsrMatrix<f64>) -> SparseColMatRef<'_, usize, f64> {
    csc_view(a, a.values())
}

/// The symbolic analysis of `a`'s pattern in `order` (AMD, the model's
/// nested dissection, or the dissection unless AMD's factor is clearly
/// smaller, decided here on the first call and kept in `order`:
/// `ordering.rs`), always supernodal so that [`Supernodal`] solves on its
/// layout.
///
/// # Errors
/// [`SolverError::Analysis`] if faer fails.
pub fn analyze_symbolic(
    a: &CsrMatrix<f64>,
    order: &FillOrder,
) -> Result<SymbolicCholesky<usize>, SolverError> {
    let Some(forward) = order.dissection_order() else {
        return symbolic_in(a, None);
    };
    let Some(chosen) = order.comparison() else {
        return symbolic_in(a, Some(forward));
    };
    match chosen.get() {
        Some(true) => symbolic_in(a, Some(forward)),
        Some(false) => symbolic_in(a, None),
        // The first analysis of the run: both, AMD's kept only where its
        // factor is clearly the smaller (`fill_order.rs`, AMD_MARGIN).
        None => {
            let dissected = symbolic_in(a, Some(forward))?;
            let amd = symbolic_in(a, None)?;
            let dissection_won =
                dissected.len_val() as f64 <= crate::AMD_MARGIN * amd.len_val() as f64;
            let _ = chosen.set(dissection_won);
            Ok(if dissection_won { dissected } else { amd })
        }
    }
}

/// The symbolic analysis in the elimination order `forward` (AMD's when
/// `None`).
fn symbolic_in(
    a: &CsrMatrix<f64>,
    forward: Option<&[usize]>,
) -> Result<SymbolicCholesky<usize>, SolverError> {
    let inverse;
    let ordering = match forward {
        None => SymmetricOrdering::Amd,
        Some(forward) => {
            if forward.len() != a.nrows() {
                return Err(SolverError::Analysis(format!(
                    "an ordering of {} rows for a matrix of {}",
                    forward.len(),
                    a.nrows()
                )));
            }
            let mut inv = vec![0; forward.len()];
            for (i, &row) in forward.iter().enumerate() {
                inv[row] = i;
            }
            inverse = inv;
            SymmetricOrdering::Custom(PermRef::new_checked(forward, &inverse, a.nrows()))
        }
    };
    factorize_symbolic_cholesky(
        as_csc(a).symbolic(),
        Side::Lower,
        ordering,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        },
    )
    .map_err(|e| SolverError::Analysis(format!("{e:?}")))
}

impl SparseCholesky {
    /// The symbolic factor of `a`'s pattern in `order` (AMD or a given
    /// permutation: [`FillOrder`]). Values are not read.
    ///
    /// # Errors
    /// [`SolverError::NotSquare`], or [`SolverError::Analysis`] if faer fails.
    pub fn analyze(a: &CsrMatrix<f64>, order: &FillOrder) -> Result<SparseCholesky, SolverError> {
        if a.nrows() != a.ncols() {
            return Err(SolverError::NotSquare {
                rows: a.nrows(),
                cols: a.ncols(),
            });
        }
        let symbolic = analyze_symbolic(a, order)?;
        let factor_scratch = MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        let solver = RefCell::new(Supernodal::new(&symbolic).ok_or_else(|| {
            SolverError::Analysis("faer returned a factor layout this solver does not know".into())
        })?);
        Ok(SparseCholesky {
            l_values: vec![0.0; symbolic.len_val()],
            symbolic,
            factorized: false,
            n: a.nrows(),
            nnz: a.nnz(),
            factor_scratch,
            solver,
        })
    }

    /// Matrix size.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored values of the factor L (fill included).
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    /// Numeric factorization of `a`, which must have the analysed pattern.
    /// Allocates nothing: the factor and the scratch space are reused.
    ///
    /// # Errors
    /// [`SolverError::NotPositiveDefinite`] for a singular or indefinite
    /// matrix, [`SolverError::PatternChanged`] for another pattern.
    pub fn factorize(&mut self, a: &CsrMatrix<f64>) -> Result<(), SolverError> {
        if a.nrows() != self.n || a.nnz() != self.nnz {
            return Err(SolverError::PatternChanged {
                analysed: self.nnz,
                given: a.nnz(),
            });
        }
        self.factorized = false;
        let result = self.symbolic.factorize_numeric_llt(
            &mut self.l_values,
            as_csc(a),
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut self.factor_scratch),
            Spec::<LltParams, f64>::default(),
        );
        match result {
            Ok(_) => {
                self.factorized = true;
                Ok(())
            }
            Err(LltError::NonPositivePivot { index }) => Err(SolverError::NotPositiveDefinite {
                pivot: index,
                n: self.n,
            }),
        }
    }

    /// Solves A x = b in place (`x` holds b on entry).
    ///
    /// # Panics
    /// If called before a successful [`SparseCholesky::factorize`] or with
    /// `x.len() != n` (programming errors, not input errors).
    pub fn solve_in_place(&self, x: &mut [f64]) {
        assert!(
            self.factorized,
            "SparseCholesky::solve_in_place before factorize"
        );
        assert_eq!(x.len(), self.n, "right-hand side length");
        self.solver.borrow_mut().solve(&self.l_values, x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

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
        for (i, row) in a.row_iter().enumerate() {
            let ax: f64 = row
                .col_indices()
                .iter()
                .zip(row.values())
                .map(|(&j, v)| v * x[j])
                .sum();
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
}
