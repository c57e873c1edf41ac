//! K·x for the explicit step: by stencil types where the matrix has them
//! (structured meshes), else from the assembled CSR.

use nalgebra_sparse::CsrMatrix;

use crate::chunks::CHUNK;
use crate::csr;
use crate::simd::Batches;
use crate::stencils::{Stencils, BATCH};

/// The product a step streams K from: every row's value is the same
/// whichever batch, chunk or thread computes it.
#[derive(Clone, Debug)]
pub enum Product {
    /// Stencil types ([`Stencils`]): within 1e-10 · max |K_ij| · Σ|x_j| of
    /// the assembled product, not its bits.
    Stencils(Stencils),
    /// Every node row its own stencil ([`Stencils::node_blocks`]): 2×2 blocks
    /// with 32-bit offsets, summed as the types are.
    Blocks(Stencils),
    /// The assembled matrix.
    Csr(CsrMatrix<f64>),
}

impl Product {
    /// The fastest form `k` allows: stencil types, else node blocks, else
    /// the CSR itself.
    pub fn new(k: CsrMatrix<f64>) -> Product {
        Product::with_types(Stencils::new(&k), k)
    }

    /// As [`Product::new`], with `k`'s stencil types formed already.
    pub fn with_types(types: Option<Stencils>, k: CsrMatrix<f64>) -> Product {
        match types {
            Some(s) => Product::Stencils(s),
            None => match Stencils::node_blocks(&k) {
                Some(b) => Product::Blocks(b),
                None => Product::Csr(k),
            },
        }
    }

    /// Rows.
    pub fn n(&self) -> usize {
        match self {
            Product::Stencils(s) | Product::Blocks(s) => s.n(),
            Product::Csr(k) => k.nrows(),
        }
    }

    /// y = K x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Product::Stencils(s) | Product::Blocks(s) => s.spmv(x, y),
            Product::Csr(k) => csr::spmv(k, x, y),
        }
    }

    /// Hands `to` K x on consecutive batches of at most [`BATCH`] rows
    /// covering chunk `c` (of [`crate::chunks::CHUNK`] rows), in order
    /// (call inside a [`crate::simd::Kernel`]).
    #[inline(always)]
    pub fn batches<S: crate::simd::Simd>(
        &self,
        simd: S,
        c: usize,
        x: &[f64],
        to: &mut impl Batches,
    ) {
        match self {
            Product::Stencils(s) | Product::Blocks(s) => s.batches(simd, c, x, to),
            Product::Csr(k) => {
                let end = ((c + 1) * CHUNK).min(k.nrows());
                let mut buf = [0.0; BATCH];
                let mut r0 = c * CHUNK;
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
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        match self {
            Product::Stencils(s) | Product::Blocks(s) => s.row(i, x),
            Product::Csr(k) => csr::row(k, i, x),
        }
    }

    /// (K x)_i for each i of `rows` into `out`, with the bits the batches
    /// give them.
    pub fn rows(&self, rows: &[usize], x: &[f64], out: &mut [f64]) {
        match self {
            Product::Stencils(s) | Product::Blocks(s) => s.rows(rows, x, out),
            Product::Csr(k) => {
                for (o, &i) in out.iter_mut().zip(rows) {
                    *o = csr::row(k, i, x);
                }
            }
        }
    }

    /// Bytes one product streams from the operator's data.
    pub fn bytes(&self) -> usize {
        match self {
            Product::Stencils(s) | Product::Blocks(s) => s.bytes(),
            Product::Csr(k) => 16 * k.nnz() + 8 * (k.nrows() + 1),
        }
    }

    /// "stencil types", "node blocks" or "assembled CSR", for messages and
    /// the results.
    pub fn name(&self) -> &'static str {
        match self {
            Product::Stencils(_) => "stencil types",
            Product::Blocks(_) => "node blocks",
            Product::Csr(_) => "assembled CSR",
        }
    }
}
