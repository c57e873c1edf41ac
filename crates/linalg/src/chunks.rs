//! Work on free-DOF vectors in fixed chunks of rows.
//!
//! Every pass splits its rows into chunks of [`CHUNK`] whatever the number
//! of threads, forms each chunk's sums on its own and adds the chunks' sums
//! in chunk order, so a run gives the same bits on one thread and on many.
//! Below [`PARALLEL_MIN`] whole chunks a pass stays on the calling thread:
//! a dispatch to the pool costs more than a pass over a small system.

use rayon::prelude::*;

/// Rows per chunk of work.
pub const CHUNK: usize = 8192;

/// Whole chunks from which the passes use the thread pool (a partial second
/// chunk leaves the other thread little to do for its wake-up and join).
pub const PARALLEL_MIN: usize = 2;

/// Number of chunks of a vector of length n (at least one).
pub fn chunks(n: usize) -> usize {
    n.div_ceil(CHUNK).max(1)
}

/// True when a pass over n rows should use the thread pool.
pub fn parallel(n: usize) -> bool {
    n / CHUNK >= PARALLEL_MIN && rayon::current_num_threads() > 1
}

/// Runs `body(c, chunk)` over the chunks of `y`.
pub fn each_chunk(y: &mut [f64], body: impl Fn(usize, &mut [f64]) + Sync) {
    if parallel(y.len()) {
        y.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, y)| body(c, y));
    } else {
        y.chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, y)| body(c, y));
    }
}

/// Runs `body(c, rows, sums)` over the chunks of n rows, each with its own
/// `S` partial sums (`partials` holds [`chunks`]`(n)` of them), and returns
/// the partial sums added in chunk order.
pub fn sum_chunks<const S: usize>(
    n: usize,
    partials: &mut [[f64; S]],
    body: impl Fn(usize, std::ops::Range<usize>, &mut [f64; S]) + Sync,
) -> [f64; S] {
    let partials = &mut partials[..chunks(n)];
    let rows = |c: usize| c * CHUNK..((c + 1) * CHUNK).min(n);
    if parallel(n) {
        partials
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, p)| body(c, rows(c), p));
    } else {
        for (c, p) in partials.iter_mut().enumerate() {
            body(c, rows(c), p);
        }
    }
    add_in_order(partials)
}

/// Runs `body(c, y chunk, sums)` over the chunks of `y`, each with its own
/// `S` partial sums, and returns them added in chunk order.
pub fn each_chunk_summed<const S: usize>(
    y: &mut [f64],
    partials: &mut [[f64; S]],
    body: impl Fn(usize, &mut [f64], &mut [f64; S]) + Sync,
) -> [f64; S] {
    let n = y.len();
    let partials = &mut partials[..chunks(n)];
    if parallel(n) {
        y.par_chunks_mut(CHUNK)
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, (y, p))| body(c, y, p));
    } else {
        for (c, (y, p)) in y.chunks_mut(CHUNK).zip(partials.iter_mut()).enumerate() {
            body(c, y, p);
        }
    }
    add_in_order(partials)
}

/// Runs `body(c, y chunk, z chunk, sums)` over the same chunks of two
/// vectors, each chunk with its own `S` partial sums, and returns them
/// added in chunk order.
pub fn each_chunk_pair<const S: usize>(
    y: &mut [f64],
    z: &mut [f64],
    partials: &mut [[f64; S]],
    body: impl Fn(usize, &mut [f64], &mut [f64], &mut [f64; S]) + Sync,
) -> [f64; S] {
    let n = y.len();
    let partials = &mut partials[..chunks(n)];
    if parallel(n) {
        y.par_chunks_mut(CHUNK)
            .zip(z.par_chunks_mut(CHUNK))
            .zip(partials.par_iter_mut())
            .enumerate()
            .for_each(|(c, ((y, z), p))| body(c, y, z, p));
    } else {
        for (c, ((y, z), p)) in y
            .chunks_mut(CHUNK)
            .zip(z.chunks_mut(CHUNK))
            .zip(partials.iter_mut())
            .enumerate()
        {
            body(c, y, z, p);
        }
    }
    add_in_order(partials)
}

/// The chunks' partial sums added in chunk order.
fn add_in_order<const S: usize>(partials: &[[f64; S]]) -> [f64; S] {
    let mut total = [0.0; S];
    for p in partials {
        for (t, v) in total.iter_mut().zip(p) {
            *t += v;
        }
    }
    total
}

/// Partial sums for [`sum_chunks`] over n rows.
pub fn partials<const S: usize>(n: usize) -> Vec<[f64; S]> {
    vec![[0.0; S]; chunks(n)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunked sum of a long vector is the same on one thread and on
    /// two, and within rounding of the plain sum.
    #[test]
    fn sums_do_not_depend_on_the_threads() {
        let n = 5 * CHUNK + 17;
        let x: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.4)
            .collect();
        let sum = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut p = partials::<1>(n);
                sum_chunks(n, &mut p, |_, rows, s| s[0] = rows.map(|i| x[i]).sum())[0]
            })
        };
        let (one, two) = (sum(1), sum(2));
        assert_eq!(one.to_bits(), two.to_bits());
        let plain: f64 = x.iter().sum();
        assert!((one - plain).abs() <= 1e-12 * n as f64);
    }
}
