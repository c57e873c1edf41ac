//! What the bit-for-bit tests compare against: the plain sparse product
//! and a run on a thread pool of a chosen size.

use nalgebra_sparse::CsrMatrix;

/// Runs `f` on a rayon pool of `threads` threads (the thread-independence
/// tests run the same work on 1 and on 2).
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// A x as plain row sums in storage order: the reference the tests hold the
/// optimized products and the solves' residuals against.
pub fn plain_spmv(a: &CsrMatrix<f64>, x: &[f64]) -> Vec<f64> {
    a.row_iter()
        .map(|r| {
            r.col_indices()
                .iter()
                .zip(r.values())
                .map(|(&j, v)| v * x[j])
                .sum()
        })
        .collect()
}
