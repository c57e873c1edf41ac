//! K·x for the explicit step: by stencil types where the matrix has them
//! (structured meshes), else by its upper node blocks, else from the
//! assembled CSR.

use nalgebra_sparse::CsrMatrix;

use crate::chunks::CHUNK;
use crate::csr;
use crate::simd::Batches;
use crate::stencils::{Stencils, BATCH};
use crate::symmetric::Symmetric;

/// Rows from which [`Product::without_csr`] makes the stencil types and
/// the node blocks side by side rather than the blocks only where the
/// types are declined: an unstructured mesh's types are declined only
/// after a pass over K, as long as the blocks take (docs/performance.md).
const BOTH_MIN_ROWS: usize = 100_000;

/// The product a step streams K from: every row's value is the same
/// whichever batch, chunk or thread computes it.
#[derive(Clone, Debug)]
pub enum Product {
    /// Stencil types ([`Stencils`]): within 1e-10 · max |K_ij| · Σ|x_j| of
    /// the assembled product, not its bits.
    Stencils(Stencils),
    /// The upper triangle of K's node blocks ([`Symmetric`]): the assembled
    /// product to rounding, formed whole before its rows are read.
    Symmetric(Symmetric),
    /// The assembled matrix.
    Csr(CsrMatrix<f64>),
}

/// No rows (the empty CSR), so that a step can move its product out while
/// it reads a formed one.
impl Default for Product {
    fn default() -> Product {
        Product::Csr(CsrMatrix::zeros(0, 0))
    }
}

impl Product {
    /// The fastest form `k` allows: stencil types, else the upper node
    /// blocks, else the CSR itself.
    pub fn new(k: CsrMatrix<f64>) -> Product {
        Product::without_csr(&k, true).unwrap_or(Product::Csr(k))
    }

    /// Stencil types where `stencils` is asked and `k` has them, else the
    /// upper node blocks: `None` where only `k` itself serves (then
    /// `Product::Csr(k)`), so that `k` stays the caller's until then.
    pub fn without_csr(k: &CsrMatrix<f64>, stencils: bool) -> Option<Product> {
        let (types, symmetric) = if stencils && k.nrows() >= BOTH_MIN_ROWS {
            // The types on one thread, the blocks beside them (their
            // symmetry check on the pool); the blocks are dropped where
            // the types serve.
            let (t, s) = rayon::join(|| Stencils::new(k), || Symmetric::new(k));
            (t, Some(s))
        } else {
            (stencils.then(|| Stencils::new(k)).flatten(), None)
        };
        match types {
            Some(t) => Some(Product::Stencils(t)),
            None => symmetric
                .unwrap_or_else(|| Symmetric::new(k))
                .map(Product::Symmetric),
        }
    }

    /// Rows.
    pub fn n(&self) -> usize {
        match self {
            Product::Stencils(s) => s.n(),
            Product::Symmetric(s) => s.n(),
            Product::Csr(k) => k.nrows(),
        }
    }

    /// y = K x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Product::Stencils(s) => s.spmv(x, y),
            Product::Symmetric(s) => s.spmv(x, y),
            Product::Csr(k) => csr::spmv(k, x, y),
        }
    }

    /// K x ready to be read by batches or rows: the upper node blocks'
    /// product is formed whole here (a row is final only once every row
    /// before it scattered), the others' rows as they are read.
    pub fn form<'a>(&'a mut self, x: &'a [f64]) -> Formed<'a> {
        if let Product::Symmetric(s) = self {
            s.form(x);
        }
        let k: &'a Product = self;
        let whole = match k {
            Product::Symmetric(s) => Some(s.formed()),
            Product::Stencils(_) | Product::Csr(_) => None,
        };
        Formed { k, x, whole }
    }

    /// Bytes one product streams from the operator's data (and, for the
    /// upper node blocks, the formed product written and read back).
    pub fn bytes(&self) -> usize {
        match self {
            Product::Stencils(s) => s.bytes(),
            Product::Symmetric(s) => s.bytes() + 16 * s.n(),
            Product::Csr(k) => 16 * k.nnz() + 8 * (k.nrows() + 1),
        }
    }

    /// "stencil types", "symmetric node blocks" or "assembled CSR", for
    /// messages and the results.
    pub fn name(&self) -> &'static str {
        match self {
            Product::Stencils(_) => "stencil types",
            Product::Symmetric(_) => "symmetric node blocks",
            Product::Csr(_) => "assembled CSR",
        }
    }
}

/// K x for one x ([`Product::form`]): its rows by batches or by index,
/// with the same bits either way.
#[derive(Clone, Copy, Debug)]
pub struct Formed<'a> {
    k: &'a Product,
    x: &'a [f64],
    /// The whole product, where it was formed at once.
    whole: Option<&'a [f64]>,
}

impl Formed<'_> {
    /// y = K x.
    pub fn spmv(&self, y: &mut [f64]) {
        match self.whole {
            Some(w) => y.copy_from_slice(w),
            None => self.k.spmv(self.x, y),
        }
    }

    /// Hands `to` K x on consecutive batches of at most [`BATCH`] rows
    /// covering chunk `c` (of [`crate::chunks::CHUNK`] rows), in order
    /// (call inside a [`crate::simd::Kernel`]).
    #[inline(always)]
    pub fn batches<S: crate::simd::Simd>(&self, simd: S, c: usize, to: &mut impl Batches) {
        let x = self.x;
        let end = ((c + 1) * CHUNK).min(self.k.n());
        let mut r0 = c * CHUNK;
        if let Some(w) = self.whole {
            while r0 < end {
                let r1 = (r0 + BATCH).min(end);
                to.batch(r0, &w[r0..r1]);
                r0 = r1;
            }
            return;
        }
        match self.k {
            Product::Stencils(s) => s.batches(simd, c, x, to),
            Product::Symmetric(_) => unreachable!("formed whole"),
            Product::Csr(k) => {
                let mut buf = [0.0; BATCH];
                while r0 < end {
                    let r1 = (r0 + BATCH).min(end);
                    for (o, i) in buf.iter_mut().zip(r0..r1) {
                        *o = csr::row(k, i, x);
                    }
                    to.batch(r0, &buf[..r1 - r0]);
                    r0 = r1;
                }
            }
        }
    }

    /// (K x)_i, with the bits the batches give it.
    pub fn row(&self, i: usize) -> f64 {
        let mut out = [0.0];
        self.rows(&[i], &mut out);
        out[0]
    }

    /// (K x)_i for each i of `rows` into `out`, with the bits the batches
    /// give them.
    pub fn rows(&self, rows: &[usize], out: &mut [f64]) {
        if let Some(w) = self.whole {
            for (o, &i) in out.iter_mut().zip(rows) {
                *o = w[i];
            }
            return;
        }
        match self.k {
            Product::Stencils(s) => s.rows(rows, self.x, out),
            Product::Symmetric(_) => unreachable!("formed whole"),
            Product::Csr(k) => {
                for (o, &i) in out.iter_mut().zip(rows) {
                    *o = csr::row(k, i, self.x);
                }
            }
        }
    }
}
