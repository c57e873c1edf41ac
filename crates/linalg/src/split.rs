//! The single-precision factor of a matrix ordered by nested dissection,
//! factorized as its two first halves at once, one a thread (the
//! preconditioner of a refined solve, `refine.rs`).
//!
//! faer's supernodal factorization runs on one thread (`cholesky.rs`);
//! the dissection's first separator S splits the other unknowns into two
//! halves that A does not couple:
//!
//! ```text
//!     A = [A₁ 0 C₁ᵀ; 0 A₂ C₂ᵀ; C₁ C₂ A_S]
//! ```
//!
//! Each B_h = [A_h C_hᵀ; C_h A_S], a principal submatrix of A and so
//! positive definite, is factorized on its own thread in the dissection's
//! order, the separator last: B_h = L_h L_hᵀ, whose trailing block T_h has
//! T_h T_hᵀ = A_S − C_h A_h⁻¹ C_hᵀ. A's Schur complement on the separator is
//! then S = T₁T₁ᵀ + T₂T₂ᵀ − A_S, dense (the separator is a line of nodes: a
//! few hundred to a thousand unknowns), factorized by faer's dense LLᵀ.
//!
//! A solve is that of A's factor in the order [half 1, half 2, S]: each
//! half's forward solve of [b_h; 0] gives y_h and, in its trailing part z_h,
//! the separator's coupling C_h A_h⁻¹ b_h = −T_h z_h; then x_S = S⁻¹(b_S +
//! T₁z₁ + T₂z₂), and each half's back solve of [y_h; T_hᵀx_S] gives x_h.
//! The two halves' solves run at once too.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::cholesky::llt::factor::LltParams;
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, Par, Side, Spec};
use nalgebra_sparse::CsrMatrix;

use crate::cholesky::symbolic_in_order;
use crate::refine::{refine, MAX_ITERATIONS};
use crate::{Refined, SolverError, Supernodal};

/// One half with the separator: B_h, its factor, and T_h.
struct Half {
    /// A's index of each of B_h's unknowns: the half's, then the
    /// separator's.
    dofs: Vec<usize>,
    /// The half's unknowns (B_h's first).
    inner: usize,
    /// B_h's pattern (both triangles, columns sorted) and, for each of its
    /// values, where it is among A's.
    offsets: Vec<usize>,
    columns: Vec<usize>,
    source: Vec<u32>,
    symbolic: SymbolicCholesky<usize>,
    solver: Supernodal,
    /// L_h in single precision, of B_h scaled as [`SplitSingle`] says.
    l: Vec<f32>,
    /// T_h of the unscaled B_h (the f32 factor's block over √scale), its
    /// rows in the separator's order ([`SplitSingle`]'s
    /// `separator`), its columns in the factor's.
    t: Mat<f64>,
    /// The permuted right-hand side and solution.
    y: Vec<f64>,
}

/// A's factor in single precision by its two halves ([`crate::split`]'s
/// documentation), for [`SplitSingle::solve_refined`].
pub struct SplitSingle {
    halves: [Half; 2],
    /// A's index of each separator unknown.
    separator: Vec<usize>,
    /// The factor of S = T₁T₁ᵀ + T₂T₂ᵀ − A_S in its lower triangle.
    schur: Option<Mat<f64>>,
    /// The power of two that scales A's values into f32's range (as
    /// [`crate::SparseCholesky::factorize_single`]), and its square root.
    scale: f64,
    root: f64,
}

impl std::fmt::Debug for SplitSingle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SplitSingle")
            .field("halves", &[self.halves[0].inner, self.halves[1].inner])
            .field("separator", &self.separator.len())
            .finish()
    }
}

impl SplitSingle {
    /// The analysis of `a`'s two halves: `order` is the dissection's (A's
    /// indices in elimination order), its first `halves[0]` unknowns the
    /// first half, the next `halves[1]` the second, the rest the separator.
    /// `None` where the split does not serve: an entry of `a` couples the
    /// two halves, there is no separator, or a half's factor would not
    /// eliminate the separator last.
    ///
    /// # Errors
    /// [`SolverError::Analysis`] for an order of another length, or where
    /// faer fails.
    pub fn analyze(
        a: &CsrMatrix<f64>,
        order: &[usize],
        halves: [usize; 2],
    ) -> Result<Option<SplitSingle>, SolverError> {
        let n = a.nrows();
        if u32::try_from(a.nnz()).is_err() {
            return Ok(None);
        }
        if order.len() != n || a.ncols() != n {
            return Err(SolverError::Analysis(format!(
                "an ordering of {} for a matrix of {}×{}",
                order.len(),
                n,
                a.ncols()
            )));
        }
        let [n1, n2] = halves;
        if n1 == 0 || n2 == 0 || n1 + n2 >= n {
            return Ok(None);
        }
        // Which part each unknown is in (0, 1, the separator 2) and its
        // index there.
        let mut part = vec![2u8; n];
        let mut local = vec![0usize; n];
        for (k, &i) in order.iter().enumerate() {
            let (p, l) = match k {
                k if k < n1 => (0, k),
                k if k < n1 + n2 => (1, k - n1),
                k => (2, k - n1 - n2),
            };
            part[i] = p;
            local[i] = l;
        }
        let coupled = (0..n).any(|i| {
            part[i] < 2
                && a.row(i)
                    .col_indices()
                    .iter()
                    .any(|&j| part[j] == 1 - part[i])
        });
        if coupled {
            return Ok(None);
        }
        let separator = order[n1 + n2..].to_vec();
        let half = |h: usize| -> Result<Option<Half>, SolverError> {
            let range = if h == 0 { 0..n1 } else { n1..n1 + n2 };
            let inner = range.len();
            let dofs: Vec<usize> = order[range].iter().chain(&separator).copied().collect();
            let at = |j: usize| -> Option<usize> {
                match part[j] {
                    2 => Some(inner + local[j]),
                    p if usize::from(p) == h => Some(local[j]),
                    _ => None,
                }
            };
            let (mut offsets, mut columns, mut source) = (vec![0], Vec::new(), Vec::new());
            let mut row: Vec<(usize, usize)> = Vec::new();
            let a_offsets = a.row_offsets();
            for &i in &dofs {
                row.clear();
                let start = a_offsets[i];
                for (e, &j) in a.row(i).col_indices().iter().enumerate() {
                    if let Some(c) = at(j) {
                        row.push((c, start + e));
                    }
                }
                row.sort_unstable();
                columns.extend(row.iter().map(|r| r.0));
                source.extend(row.iter().map(|r| r.1 as u32));
                offsets.push(columns.len());
            }
            let m = dofs.len();
            // B_h's unknowns are in the dissection's order already.
            let identity: Vec<usize> = (0..m).collect();
            let symbolic = symbolic_in_order(
                SymbolicSparseColMatRef::new_checked(m, m, &offsets, None, &columns),
                &identity,
            )?;
            let solver = Supernodal::with_split_min(&symbolic, usize::MAX).ok_or_else(|| {
                SolverError::Analysis(
                    "faer returned a factor layout this solver does not know".into(),
                )
            })?;
            // The separator last: every permuted position from `inner` on
            // holds a separator unknown.
            if solver.forward_permutation()[inner..]
                .iter()
                .any(|&f| (f as usize) < inner)
            {
                return Ok(None);
            }
            let ns = m - inner;
            Ok(Some(Half {
                dofs,
                inner,
                offsets,
                columns,
                source,
                symbolic,
                solver,
                l: Vec::new(),
                t: Mat::zeros(ns, ns),
                y: vec![0.0; m],
            }))
        };
        let (first, second) = rayon::join(|| half(0), || half(1));
        let (Some(first), Some(second)) = (first?, second?) else {
            return Ok(None);
        };
        Ok(Some(SplitSingle {
            halves: [first, second],
            separator,
            schur: None,
            scale: 1.0,
            root: 1.0,
        }))
    }

    /// The factor of `a` (the analysed matrix): both halves in single
    /// precision at once, then S in double. Once: the halves' patterns are
    /// dropped after it (a preload's factor serves one solve).
    ///
    /// # Errors
    /// [`SolverError::Analysis`] when called again;
    /// [`SolverError::NotPositiveDefinite`] where a half's pivot fails in
    /// single precision or S is not positive definite (the pivot is a
    /// half's, or S's row after both halves).
    pub fn factorize(&mut self, a: &CsrMatrix<f64>) -> Result<(), SolverError> {
        self.schur = None;
        if self.halves.iter().any(|h| h.source.is_empty()) {
            return Err(SolverError::Analysis(
                "a split factor is factorized once".into(),
            ));
        }
        let largest = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        if !(largest.is_finite() && largest > 0.0) {
            return Err(SolverError::NotPositiveDefinite {
                pivot: 0,
                n: a.nrows(),
            });
        }
        // A power of two: the scaling itself rounds nothing.
        self.scale = 2.0_f64.powi(-(largest.log2().ceil() as i32));
        self.root = self.scale.sqrt();
        let (scale, root) = (self.scale, self.root);
        let values = a.values();
        let [first, second] = &mut self.halves;
        let (p1, p2) = rayon::join(
            || first.factorize(values, scale, root),
            || second.factorize(values, scale, root),
        );
        let (mut s, p2) = (p1?, p2?);
        // S = T₁T₁ᵀ + T₂T₂ᵀ − A_S.
        let ns = self.separator.len();
        let mut at = vec![usize::MAX; a.nrows()];
        for (k, &i) in self.separator.iter().enumerate() {
            at[i] = k;
        }
        for (k, &i) in self.separator.iter().enumerate() {
            let row = a.row(i);
            for (&j, &v) in row.col_indices().iter().zip(row.values()) {
                if at[j] != usize::MAX {
                    s[(k, at[j])] -= v;
                }
            }
        }
        for j in 0..ns {
            for i in 0..ns {
                s[(i, j)] += p2[(i, j)];
            }
        }
        // On this thread, as every factorization (the bits do not depend
        // on the pool's size).
        let mut scratch = MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
            ns,
            Par::Seq,
            Default::default(),
        ));
        llt::factor::cholesky_in_place(
            s.as_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .map_err(|_| SolverError::NotPositiveDefinite {
            pivot: a.nrows() - ns,
            n: a.nrows(),
        })?;
        self.schur = Some(s);
        Ok(())
    }

    /// x ← A⁻¹x approximately, by the halves' single factors (read in
    /// double: [`crate::FactorValue`]) and S's.
    ///
    /// # Panics
    /// Before a successful [`SplitSingle::factorize`], or with `x` of
    /// another length than A's.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        let schur = self
            .schur
            .as_ref()
            .expect("SplitSingle::solve_in_place before factorize");
        let root = self.root;
        let [first, second] = &mut self.halves;
        let shared = &*x;
        let (c1, c2) = rayon::join(
            || first.forward(shared, root),
            || second.forward(shared, root),
        );
        let mut xs = Mat::<f64>::zeros(self.separator.len(), 1);
        for (k, &i) in self.separator.iter().enumerate() {
            xs[(k, 0)] = x[i] + c1[k] + c2[k];
        }
        llt::solve::solve_in_place_with_conj(
            schur.as_ref(),
            Conj::No,
            xs.as_mut(),
            Par::Seq,
            MemStack::new(&mut MemBuffer::new(
                llt::solve::solve_in_place_scratch::<f64>(schur.nrows(), 1, Par::Seq),
            )),
        );
        let xs = xs.col(0);
        rayon::join(|| first.backward(xs, root), || second.backward(xs, root));
        for half in &self.halves {
            let fwd = half.solver.forward_permutation();
            for (p, &f) in fwd.iter().enumerate() {
                let f = f as usize;
                if f < half.inner {
                    x[half.dofs[f]] = half.y[p];
                }
            }
        }
        for (k, &i) in self.separator.iter().enumerate() {
            x[i] = xs[k];
        }
    }

    /// A x = b by CG preconditioned with this factor, as
    /// [`crate::SparseCholesky::solve_refined`] with its single factor.
    ///
    /// # Errors
    /// As [`crate::SparseCholesky::solve_refined`].
    ///
    /// # Panics
    /// Before a successful [`SplitSingle::factorize`].
    pub fn solve_refined(
        &mut self,
        a: &CsrMatrix<f64>,
        x: &mut [f64],
        tolerance: f64,
    ) -> Result<Refined, Refined> {
        refine(a, x, tolerance, MAX_ITERATIONS, |z| self.solve_in_place(z))
    }
}

impl Half {
    /// L_h of A's `values` scaled by `scale`, in single precision, then
    /// T_h of the unscaled B_h and its T_hT_hᵀ (the separator's order).
    fn factorize(
        &mut self,
        values: &[f64],
        scale: f64,
        root: f64,
    ) -> Result<Mat<f64>, SolverError> {
        let m = self.dofs.len();
        let b: Vec<f32> = self
            .source
            .iter()
            .map(|&e| (values[e as usize] * scale) as f32)
            .collect();
        let sym = SymbolicSparseColMatRef::new_checked(m, m, &self.offsets, None, &self.columns);
        self.l = vec![0.0_f32; self.symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f32>(Par::Seq, Default::default()),
        );
        let factored = self
            .symbolic
            .factorize_numeric_llt(
                &mut self.l,
                SparseColMatRef::new(sym, &b),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Spec::<LltParams, f32>::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    SolverError::NotPositiveDefinite { pivot: index, n: m }
                }
            });
        drop(b);
        self.offsets = Vec::new();
        self.columns = Vec::new();
        self.source = Vec::new();
        factored?;
        // T_h: the factor's columns from `inner` on (the separator's, in
        // the factor's order), rows mapped to the separator's order.
        let inner = self.inner;
        let fwd = self.solver.forward_permutation();
        self.t.fill(0.0);
        for s in (0..self.solver.supernodes()).rev() {
            let c0 = self.solver.first_column(s);
            let (k, _) = self.solver.block_shape(s);
            if c0 + k <= inner {
                break;
            }
            let pattern = self.solver.pattern(s);
            let block = &self.l[self.solver.value_range(s)];
            let ld = k + pattern.len();
            for c in c0.max(inner)..c0 + k {
                let col = &block[(c - c0) * ld..(c - c0 + 1) * ld];
                let j = c - inner;
                for r in c..c0 + k {
                    self.t[(fwd[r] as usize - inner, j)] = f64::from(col[r - c0]) / root;
                }
                for (t, &r) in pattern.iter().enumerate() {
                    self.t[(fwd[r as usize] as usize - inner, j)] = f64::from(col[k + t]) / root;
                }
            }
        }
        let ns = m - inner;
        let mut p = Mat::<f64>::zeros(ns, ns);
        faer::linalg::matmul::matmul(
            p.as_mut(),
            Accum::Replace,
            self.t.as_ref(),
            self.t.transpose(),
            1.0,
            Par::Seq,
        );
        Ok(p)
    }

    /// The forward solve of [b_h; 0] (b in A's indices) into `y`, and
    /// T_h z_h in the separator's order.
    fn forward(&mut self, b: &[f64], root: f64) -> Vec<f64> {
        let inner = self.inner;
        let fwd = self.solver.forward_permutation();
        for (y, &f) in self.y.iter_mut().zip(fwd) {
            let f = f as usize;
            *y = if f < inner {
                root * b[self.dofs[f]]
            } else {
                0.0
            };
        }
        self.solver.forward_permuted(&self.l, &mut self.y);
        let ns = self.y.len() - inner;
        let z = &self.y[inner..];
        let mut c = vec![0.0; ns];
        for (j, &zj) in z.iter().enumerate() {
            for (ci, t) in c.iter_mut().zip(self.t.col(j).iter()) {
                *ci += t * zj;
            }
        }
        c
    }

    /// The back solve of [y_h; T_hᵀ x_S] in `y` (permuted).
    fn backward(&mut self, xs: faer::ColRef<'_, f64>, root: f64) {
        let inner = self.inner;
        for (j, y) in self.y[inner..].iter_mut().enumerate() {
            let col = self.t.col(j);
            *y = col.iter().zip(xs.iter()).map(|(t, x)| t * x).sum();
        }
        for y in &mut self.y {
            *y *= root;
        }
        self.solver.backward_permuted(&self.l, &mut self.y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// The 5-point Laplacian of a w × h grid plus `shift` on the diagonal,
    /// and its dissection at the middle column: the left columns, the
    /// right ones, then the middle.
    fn grid(w: usize, h: usize, shift: f64) -> (CsrMatrix<f64>, Vec<usize>, [usize; 2]) {
        let id = |x: usize, y: usize| y * w + x;
        let mut coo = CooMatrix::new(w * h, w * h);
        for y in 0..h {
            for x in 0..w {
                let i = id(x, y);
                coo.push(i, i, 4.0 + shift);
                if x + 1 < w {
                    coo.push(i, id(x + 1, y), -1.0);
                    coo.push(id(x + 1, y), i, -1.0);
                }
                if y + 1 < h {
                    coo.push(i, id(x, y + 1), -1.0);
                    coo.push(id(x, y + 1), i, -1.0);
                }
            }
        }
        let mid = w / 2;
        let column = |x: usize| (0..h).map(move |y| id(x, y));
        let order: Vec<usize> = (0..mid)
            .flat_map(column)
            .chain((mid + 1..w).flat_map(column))
            .chain(column(mid))
            .collect();
        (CsrMatrix::from(&coo), order, [mid * h, (w - mid - 1) * h])
    }

    #[test]
    fn the_split_factor_solves_as_one_factor_to_single_precision() {
        let (a, order, halves) = grid(9, 6, 0.01);
        let mut split = SplitSingle::analyze(&a, &order, halves)
            .unwrap()
            .expect("the middle column separates");
        split.factorize(&a).unwrap();
        let n = a.nrows();
        let want: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        let mut b = vec![0.0; n];
        crate::csr::spmv(&a, &want, &mut b);
        let mut x = b.clone();
        split.solve_in_place(&mut x);
        let err = x
            .iter()
            .zip(&want)
            .map(|(x, w)| (x - w).abs())
            .fold(0.0, f64::max);
        // f32's factor: κ(A) u₃₂ relative.
        assert!(err < 1e-3, "largest error {err}");
        let mut x = b.clone();
        let refined = split
            .solve_refined(&a, &mut x, crate::BACKWARD_ERROR)
            .unwrap();
        assert!(refined.iterations <= 6, "{refined:?}");
        let err = x
            .iter()
            .zip(&want)
            .map(|(x, w)| (x - w).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-11, "largest error {err} after refinement");
    }

    #[test]
    fn a_split_whose_halves_touch_is_refused() {
        let (a, mut order, halves) = grid(9, 6, 0.01);
        // The first unknown of the separator into the second half.
        let (n1, n2) = (halves[0], halves[1]);
        order.swap(n1 + n2, n1);
        assert!(SplitSingle::analyze(&a, &order, halves).unwrap().is_none());
    }
}
