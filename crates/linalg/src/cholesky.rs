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
use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::linalg::cholesky::llt::factor::LltParams;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::{amd, SupernodalThreshold};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side, Spec};

use crate::{FillOrder, Supernodal};
use faer::perm::PermRef;

/// faer's dense kernels run on the calling thread. Given the pool, they
/// split each supernode's products among its threads and wait for them
/// supernode by supernode; the fronts of 2-D meshes are small, and that
/// waiting made the factorizations slower than one thread
/// (docs/performance.md). A run's cores go to independent work instead.
const KERNELS: Par = Par::Seq;
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
    /// Shared with the other factorizations of the pattern (a run's
    /// preload, A₀ and M: [`SparseCholesky::analysis`]).
    analysis: Analysis,
    l_values: Vec<f64>,
    factorized: bool,
    factor_scratch: MemBuffer,
    solver: RefCell<Supernodal>,
    /// The factor in single precision ([`SparseCholesky::factorize_single`]),
    /// of A scaled by `single_scale`; empty until then.
    single: Vec<f32>,
    single_scale: f64,
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.analysis.n)
            .field("nnz", &self.analysis.nnz)
            .field("factor_nnz", &self.l_values.len())
            .field("factorized", &self.factorized)
            .field("single", &!self.single.is_empty())
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
        // The two analyses at once, each on its own thread (AMD's is the
        // longer: docs/performance.md).
        None => {
            let (dissected, amd) =
                rayon::join(|| symbolic_in(a, Some(forward)), || symbolic_in(a, None));
            let (dissected, amd) = (dissected?, amd?);
            let dissection_won =
                dissected.len_val() as f64 <= crate::AMD_MARGIN * amd.len_val() as f64;
            let _ = chosen.set(dissection_won);
            Ok(if dissection_won { dissected } else { amd })
        }
    }
}

/// faer's AMD order of `a`'s pattern: `amd::order` on the pattern as it
/// is, whose columns are sorted and without duplicates (nalgebra-sparse
/// keeps them so) and whose transpose is itself (symmetric). The order
/// `SymmetricOrdering::Amd` gives, without the sorted, deduplicated copy
/// of the pattern it makes first for an input that may be neither: its
/// time and its pages (docs/performance.md, "One analysis a run").
fn amd_order(a: &CsrMatrix<f64>) -> Result<Vec<usize>, SolverError> {
    let n = a.nrows();
    let (mut forward, mut inverse) = (vec![0; n], vec![0; n]);
    let mut scratch = MemBuffer::try_new(amd::order_scratch::<usize>(n, a.nnz()))
        .map_err(|e| SolverError::Analysis(format!("{e:?}")))?;
    amd::order(
        &mut forward,
        &mut inverse,
        as_csc(a).symbolic(),
        amd::Control::default(),
        MemStack::new(&mut scratch),
    )
    .map_err(|e| SolverError::Analysis(format!("{e:?}")))?;
    Ok(forward)
}

/// The symbolic analysis in the elimination order `forward` (AMD's when
/// `None`).
fn symbolic_in(
    a: &CsrMatrix<f64>,
    forward: Option<&[usize]>,
) -> Result<SymbolicCholesky<usize>, SolverError> {
    let amd;
    let forward = match forward {
        None => {
            amd = amd_order(a)?;
            amd.as_slice()
        }
        Some(forward) => forward,
    };
    if forward.len() != a.nrows() {
        return Err(SolverError::Analysis(format!(
            "an ordering of {} rows for a matrix of {}",
            forward.len(),
            a.nrows()
        )));
    }
    symbolic_in_order(as_csc(a).symbolic(), forward)
}

/// The supernodal symbolic factor of the pattern `a` (both triangles, a
/// CSR pattern read as its own CSC transpose) in the elimination order
/// `forward`.
pub(crate) fn symbolic_in_order(
    a: SymbolicSparseColMatRef<'_, usize>,
    forward: &[usize],
) -> Result<SymbolicCholesky<usize>, SolverError> {
    let mut inverse = vec![0; forward.len()];
    for (i, &row) in forward.iter().enumerate() {
        inverse[row] = i;
    }
    let ordering = SymmetricOrdering::Custom(PermRef::new_checked(forward, &inverse, a.nrows()));
    factorize_symbolic_cholesky(
        a,
        Side::Lower,
        ordering,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        },
    )
    .map_err(|e| SolverError::Analysis(format!("{e:?}")))
}

/// The symbolic analysis of one sparsity pattern (its ordering and
/// symbolic factor), shared by the factorizations of the matrices that
/// have it (a run's K, M and A₀): cloning it shares, not copies.
#[derive(Clone)]
pub struct Analysis {
    symbolic: Arc<SymbolicCholesky<usize>>,
    /// The analysed matrix's size and number of stored values, which a
    /// matrix given later must have (its pattern itself is not kept: at
    /// 500k DOFs it is 9M indices).
    n: usize,
    nnz: usize,
}

impl std::fmt::Debug for Analysis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Analysis")
            .field("n", &self.n)
            .field("nnz", &self.nnz)
            .field("factor_nnz", &self.symbolic.len_val())
            .finish()
    }
}

impl Analysis {
    /// The analysis of `a`'s pattern in `order` ([`analyze_symbolic`]).
    ///
    /// # Errors
    /// [`SolverError::NotSquare`], or [`SolverError::Analysis`] if faer
    /// fails.
    pub fn of(a: &CsrMatrix<f64>, order: &FillOrder) -> Result<Analysis, SolverError> {
        if a.nrows() != a.ncols() {
            return Err(SolverError::NotSquare {
                rows: a.nrows(),
                cols: a.ncols(),
            });
        }
        Ok(Analysis {
            symbolic: Arc::new(analyze_symbolic(a, order)?),
            n: a.nrows(),
            nnz: a.nnz(),
        })
    }

    /// `shared` where it is given (made of `a`'s pattern already, by
    /// another matrix of the model), else the analysis of `a` in `order`.
    ///
    /// # Errors
    /// As [`Analysis::of`] (where `shared` is given: a non-square `a`);
    /// [`SolverError::Analysis`] where `shared` is of another size,
    /// [`SolverError::PatternChanged`] of another number of values.
    pub fn shared_or_of(
        shared: Option<Analysis>,
        a: &CsrMatrix<f64>,
        order: &FillOrder,
    ) -> Result<Analysis, SolverError> {
        match shared {
            Some(analysis) => analysis.check(a).map(|()| analysis),
            None => Analysis::of(a, order),
        }
    }

    /// faer's symbolic factor.
    pub fn symbolic(&self) -> &SymbolicCholesky<usize> {
        &self.symbolic
    }

    /// Whether `other` is this very analysis (shared, not recomputed).
    pub fn is(&self, other: &Analysis) -> bool {
        Arc::ptr_eq(&self.symbolic, &other.symbolic)
    }

    /// `a` has the analysed size and number of values (the same check as
    /// a refactorization's: comparing the patterns would read them).
    fn check(&self, a: &CsrMatrix<f64>) -> Result<(), SolverError> {
        if a.nrows() != a.ncols() {
            return Err(SolverError::NotSquare {
                rows: a.nrows(),
                cols: a.ncols(),
            });
        }
        if a.nrows() != self.n {
            return Err(SolverError::Analysis(format!(
                "an analysis of {} rows for a matrix of {}",
                self.n,
                a.nrows()
            )));
        }
        if a.nnz() != self.nnz {
            return Err(SolverError::PatternChanged {
                analysed: self.nnz,
                given: a.nnz(),
            });
        }
        Ok(())
    }
}

impl SparseCholesky {
    /// The symbolic factor of `a`'s pattern in `order` (AMD or a given
    /// permutation: [`FillOrder`]). Values are not read.
    ///
    /// # Errors
    /// [`SolverError::NotSquare`], or [`SolverError::Analysis`] if faer fails.
    pub fn analyze(a: &CsrMatrix<f64>, order: &FillOrder) -> Result<SparseCholesky, SolverError> {
        SparseCholesky::on(Analysis::of(a, order)?)
    }

    /// A factorization on `analysis`, made already of the pattern of the
    /// matrices it will factorize (by [`Analysis::of`], or another
    /// factorization's [`SparseCholesky::analysis`]): the matrices of one
    /// model share one pattern, so one analysis serves them all.
    ///
    /// # Errors
    /// [`SolverError::Analysis`] for a layout [`Supernodal`] does not know.
    pub fn on(analysis: Analysis) -> Result<SparseCholesky, SolverError> {
        let symbolic = &analysis.symbolic;
        let factor_scratch = MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(KERNELS, Default::default()),
        );
        let solver = RefCell::new(Supernodal::new(symbolic).ok_or_else(|| {
            SolverError::Analysis("faer returned a factor layout this solver does not know".into())
        })?);
        Ok(SparseCholesky {
            l_values: vec![0.0; symbolic.len_val()],
            analysis,
            factorized: false,
            factor_scratch,
            solver,
            single: Vec::new(),
            single_scale: 1.0,
        })
    }

    /// The analysis this factorization runs on, for another matrix of the
    /// same pattern ([`SparseCholesky::on`]).
    pub fn analysis(&self) -> &Analysis {
        &self.analysis
    }

    /// Matrix size.
    pub fn n(&self) -> usize {
        self.analysis.n
    }

    /// Number of stored values of the factor L (fill included).
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    /// Numeric factorization of `a`, which must have the analysed pattern.
    /// Allocates nothing: the factor and the scratch space are reused (a
    /// single factor, if any, is dropped).
    ///
    /// # Errors
    /// [`SolverError::NotPositiveDefinite`] for a singular or indefinite
    /// matrix, [`SolverError::PatternChanged`] for another pattern
    /// ([`SolverError::Analysis`] for another size).
    pub fn factorize(&mut self, a: &CsrMatrix<f64>) -> Result<(), SolverError> {
        self.analysis.check(a)?;
        self.factorized = false;
        self.single = Vec::new();
        let result = self.analysis.symbolic.factorize_numeric_llt(
            &mut self.l_values,
            as_csc(a),
            Side::Lower,
            Default::default(),
            KERNELS,
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
                n: self.n(),
            }),
        }
    }

    /// Numeric factorization of `a` in single precision, on the analysed
    /// structure, for a solve refined to double's accuracy
    /// ([`SparseCholesky::solve_refined`]): half the bytes of the double
    /// factor and twice the values a vector register holds. `a` is scaled
    /// by the power of two that brings its largest value (a diagonal one,
    /// A being positive definite) into [1/2, 1], so that f32's range holds
    /// every value of any units; values below f32's smallest become zero
    /// or subnormal, a perturbation the refinement corrects like the
    /// rounding. The double factor, if any, is kept.
    ///
    /// # Errors
    /// [`SolverError::NotPositiveDefinite`] where a pivot fails in single
    /// precision (A singular, or too ill-conditioned for f32: the double
    /// factor may still succeed), [`SolverError::PatternChanged`] for
    /// another pattern ([`SolverError::Analysis`] for another size).
    pub fn factorize_single(&mut self, a: &CsrMatrix<f64>) -> Result<(), SolverError> {
        self.analysis.check(a)?;
        self.single.clear();
        let largest = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        if !(largest.is_finite() && largest > 0.0) {
            return Err(SolverError::NotPositiveDefinite {
                pivot: 0,
                n: self.n(),
            });
        }
        // A power of two: the scaling itself rounds nothing.
        let scale = 2.0_f64.powi(-(largest.log2().ceil() as i32));
        let values: Vec<f32> = a.values().iter().map(|v| (v * scale) as f32).collect();
        let sym = SymbolicSparseColMatRef::new_checked(
            a.nrows(),
            a.ncols(),
            a.row_offsets(),
            None,
            a.col_indices(),
        );
        let mut l = vec![0.0_f32; self.analysis.symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            self.analysis
                .symbolic
                .factorize_numeric_llt_scratch::<f32>(KERNELS, Default::default()),
        );
        let result = self.analysis.symbolic.factorize_numeric_llt(
            &mut l,
            SparseColMatRef::new(sym, &values),
            Side::Lower,
            Default::default(),
            KERNELS,
            MemStack::new(&mut scratch),
            Spec::<LltParams, f32>::default(),
        );
        match result {
            Ok(_) => {
                self.single = l;
                self.single_scale = scale;
                Ok(())
            }
            Err(LltError::NonPositivePivot { index }) => Err(SolverError::NotPositiveDefinite {
                pivot: index,
                n: self.n(),
            }),
        }
    }

    /// x ← A⁻¹x approximately, by the single factor (read in double:
    /// [`crate::FactorValue`]), its scaling undone (exactly: a power of
    /// two).
    ///
    /// # Panics
    /// Before a successful [`SparseCholesky::factorize_single`], or with
    /// `x.len() != n`.
    pub(crate) fn solve_single_in_place(&self, x: &mut [f64]) {
        assert!(
            !self.single.is_empty() || self.n() == 0,
            "SparseCholesky::solve_single_in_place before factorize_single"
        );
        assert_eq!(x.len(), self.n(), "right-hand side length");
        self.solver.borrow_mut().solve(&self.single, x);
        for v in x.iter_mut() {
            *v *= self.single_scale;
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
        assert_eq!(x.len(), self.n(), "right-hand side length");
        self.solver.borrow_mut().solve(&self.l_values, x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 5-point Laplacian of an n×n grid plus the identity.
    fn grid(n: usize) -> CsrMatrix<f64> {
        crate::refine::tests::grid(n, 1.0)
    }

    /// One analysis serves another matrix of the pattern (a run's K, M
    /// and A₀): its factor has the bits of the matrix's own analysis, and
    /// its solve is the closed form's.
    #[test]
    fn a_shared_analysis_factorizes_another_matrix_of_the_pattern() {
        let (n, shift) = (20, 3.0);
        let (k, m) = (grid(n), crate::refine::tests::grid(n, shift));
        let mut own = SparseCholesky::analyze(&m, &FillOrder::amd()).unwrap();
        own.factorize(&m).unwrap();
        let first = SparseCholesky::analyze(&k, &FillOrder::amd()).unwrap();
        let analysis =
            Analysis::shared_or_of(Some(first.analysis().clone()), &m, &FillOrder::amd());
        let mut shared = SparseCholesky::on(analysis.unwrap()).unwrap();
        shared.factorize(&m).unwrap();
        assert!(first.analysis().is(shared.analysis()));
        let same = own
            .l_values
            .iter()
            .zip(&shared.l_values)
            .all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same, "the shared analysis's factor differs");
        // The grid's lowest mode v: M v = λ v in closed form
        // (`refine.rs`), so M⁻¹v = v/λ, to a few ulps of κ ≈ 3.
        let (v, lambda) = crate::refine::tests::lowest_mode(n, shift);
        let mut x = v.clone();
        shared.solve_in_place(&mut x);
        for (x, v) in x.iter().zip(&v) {
            assert!(
                (x - v / lambda).abs() <= 1e-14,
                "{x} against {}",
                v / lambda
            );
        }
    }

    /// Our AMD order is faer's (`SymmetricOrdering::Amd`), without its
    /// copy of the pattern: the same permutation, the same factor.
    #[test]
    fn the_amd_order_is_faers() {
        for a in [
            grid(1),
            grid(7),
            grid(40),
            crate::refine::tests::grid(25, 0.5),
        ] {
            let faers = factorize_symbolic_cholesky(
                as_csc(&a).symbolic(),
                Side::Lower,
                SymmetricOrdering::Amd,
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                    ..Default::default()
                },
            )
            .unwrap();
            let ours = symbolic_in(&a, None).unwrap();
            let (faers_fwd, _) = faers.perm().unwrap().arrays();
            let (ours_fwd, _) = ours.perm().unwrap().arrays();
            assert_eq!(faers_fwd, ours_fwd);
            assert_eq!(faers.len_val(), ours.len_val());
        }
    }

    #[test]
    fn an_analysis_of_another_pattern_is_refused() {
        let first = SparseCholesky::analyze(&grid(4), &FillOrder::amd()).unwrap();
        let shared = || Some(first.analysis().clone());
        let larger = Analysis::shared_or_of(shared(), &grid(5), &FillOrder::amd());
        assert!(
            matches!(larger, Err(SolverError::Analysis(_))),
            "{:?}",
            larger.err()
        );
        // Of the size, with another number of values (one coupling less).
        let mut coo = nalgebra_sparse::CooMatrix::new(16, 16);
        for (i, j, &v) in nalgebra_sparse::CooMatrix::from(&grid(4)).triplet_iter() {
            if i.min(j) != 0 || i.max(j) != 1 {
                coo.push(i, j, v);
            }
        }
        let fewer = CsrMatrix::from(&coo);
        let other = Analysis::shared_or_of(shared(), &fewer, &FillOrder::amd());
        assert!(
            matches!(other, Err(SolverError::PatternChanged { .. })),
            "{:?}",
            other.err()
        );
    }
}
