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

/// Runs `body(c, chunks, sums)` over the same chunks of V vectors of one
/// length, each chunk with its own `S` partial sums, and returns them
/// added in chunk order. Allocates nothing: the chunks are split off by
/// halves (on the pool, by `rayon::join`).
pub fn each_chunk_of<const V: usize, const S: usize>(
    vectors: [&mut [f64]; V],
    partials: &mut [[f64; S]],
    body: impl Fn(usize, [&mut [f64]; V], &mut [f64; S]) + Sync,
) -> [f64; S] {
    let n = vectors.first().map_or(0, |v| v.len());
    debug_assert!(vectors.iter().all(|v| v.len() == n));
    let partials = &mut partials[..chunks(n)];
    halves(0, vectors, partials, parallel(n), &body);
    add_in_order(partials)
}

/// [`each_chunk_of`] on chunks c0.. of `vectors`, one per entry of
/// `partials`.
fn halves<const V: usize, const S: usize>(
    c0: usize,
    vectors: [&mut [f64]; V],
    partials: &mut [[f64; S]],
    pool: bool,
    body: &(impl Fn(usize, [&mut [f64]; V], &mut [f64; S]) + Sync),
) {
    if let [p] = partials {
        return body(c0, vectors, p);
    }
    let mid = partials.len() / 2;
    let mut pairs = vectors.map(|v| {
        let (a, b) = v.split_at_mut((mid * CHUNK).min(v.len()));
        (Some(a), Some(b))
    });
    let left = std::array::from_fn(|i| pairs[i].0.take().expect("split above"));
    let right = std::array::from_fn(|i| pairs[i].1.take().expect("split above"));
    let (pl, pr) = partials.split_at_mut(mid);
    if pool {
        rayon::join(
            || halves(c0, left, pl, pool, body),
            || halves(c0 + mid, right, pr, pool, body),
        );
    } else {
        halves(c0, left, pl, pool, body);
        halves(c0 + mid, right, pr, pool, body);
    }
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

/// For rows in groups (group g's first row `group_rows[g]`, then the row
/// count): the first group of each chunk of n rows, then the number of
/// groups.
pub fn chunk_groups(group_rows: &[u32], n: usize) -> Vec<u32> {
    let groups = group_rows.len() - 1;
    let mut out = Vec::with_capacity(chunks(n) + 1);
    for (g, &r) in group_rows.iter().enumerate() {
        while out.len() * CHUNK <= r as usize && out.len() <= chunks(n) {
            out.push(g as u32);
        }
    }
    while out.len() <= chunks(n) {
        out.push(groups as u32);
    }
    out
}

/// Partial sums for [`sum_chunks`] over n rows.
pub fn partials<const S: usize>(n: usize) -> Vec<[f64; S]> {
    vec![[0.0; S]; chunks(n)]
}
