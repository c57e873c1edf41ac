//! What the bit-for-bit tests compare against: the plain sparse product
//! and a run on a thread pool of a chosen size; and the vector they
//! multiply.

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

/// n values in [−1, 1), the same on every run, with no pattern along the
/// rows (7919 is prime): a vector for products and solves to act on.
pub fn spread(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0)
        .collect()
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
