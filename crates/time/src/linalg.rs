//! Small vector kernels on free-DOF vectors and CSR matrices.

use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

/// Rows per chunk of work: sums are formed per chunk and added in chunk
/// order, so the threaded and the sequential products agree bit for bit.
const ROWS: usize = 4096;

/// Σ_k vals[k]·x[cols[k]] over one row, in four interleaved partial sums
/// (a single chain is bound by the adder's latency: the implicit step's
/// products on the paper's mesh spent half their time waiting on it).
#[inline]
fn row_dot(vals: &[f64], cols: &[usize], x: &[f64]) -> f64 {
    let split = vals.len() - vals.len() % 4;
    let mut acc = [0.0; 4];
    for (v, c) in vals[..split]
        .chunks_exact(4)
        .zip(cols[..split].chunks_exact(4))
    {
        acc[0] += v[0] * x[c[0]];
        acc[1] += v[1] * x[c[1]];
        acc[2] += v[2] * x[c[2]];
        acc[3] += v[3] * x[c[3]];
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (v, &c) in vals[split..].iter().zip(&cols[split..]) {
        s += v * x[c];
    }
    s
}

/// y = A x, rows in chunks on the thread pool when there are several.
/// (`kernels::spmv` keeps one chain per row instead: the explicit step's
/// compact K must reproduce its bits.)
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let body = |c: usize, y: &mut [f64]| {
        for (k, yi) in y.iter_mut().enumerate() {
            let i = c * ROWS + k;
            let (p, q) = (offsets[i], offsets[i + 1]);
            *yi = row_dot(&vals[p..q], &cols[p..q], x);
        }
    };
    if y.len() > ROWS {
        y.par_chunks_mut(ROWS)
            .enumerate()
            .for_each(|(c, y)| body(c, y));
    } else {
        body(0, y);
    }
}

/// Row sums of two matrices on one pattern: (Σ a_k x[c_k], Σ b_k y[c_k]),
/// each in the order of [`row_dot`] (so each equals [`row_dot`]'s bits).
#[inline]
fn row_dot2(a: &[f64], x: &[f64], b: &[f64], y: &[f64], cols: &[usize]) -> (f64, f64) {
    let split = cols.len() - cols.len() % 4;
    let (mut p, mut q) = ([0.0; 4], [0.0; 4]);
    for ((u, v), c) in a[..split]
        .chunks_exact(4)
        .zip(b[..split].chunks_exact(4))
        .zip(cols[..split].chunks_exact(4))
    {
        for j in 0..4 {
            p[j] += u[j] * x[c[j]];
            q[j] += v[j] * y[c[j]];
        }
    }
    let mut s = (p[0] + p[1]) + (p[2] + p[3]);
    let mut t = (q[0] + q[1]) + (q[2] + q[3]);
    for ((u, v), &c) in a[split..].iter().zip(&b[split..]).zip(&cols[split..]) {
        s += u * x[c];
        t += v * y[c];
    }
    (s, t)
}

/// True when `a` and `b` store the same pattern (K and M as assembled).
pub fn same_pattern(a: &CsrMatrix<f64>, b: &CsrMatrix<f64>) -> bool {
    a.nrows() == b.nrows()
        && a.row_offsets() == b.row_offsets()
        && a.col_indices() == b.col_indices()
}

/// out_i = l_i − (K x)_i + (M y)_i in one pass over the shared pattern of
/// K and M (see [`same_pattern`]): the implicit step's R̂_K with the
/// consistent mass, the bits of two [`spmv`]s and the same combination.
pub fn load_minus_k_plus_m(
    l: &[f64],
    k: &CsrMatrix<f64>,
    x: &[f64],
    m: &CsrMatrix<f64>,
    y: &[f64],
    out: &mut [f64],
) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let body = |c: usize, out: &mut [f64]| {
        for (j, o) in out.iter_mut().enumerate() {
            let i = c * ROWS + j;
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (kx, my) = row_dot2(&kv[p..q], x, &mv[p..q], y, &cols[p..q]);
            *o = l[i] - kx + my;
        }
    };
    if out.len() > ROWS {
        out.par_chunks_mut(ROWS)
            .enumerate()
            .for_each(|(c, o)| body(c, o));
    } else {
        body(0, out);
    }
}

/// (xᵀK x, yᵀM y) in one pass over the shared pattern of K and M, each
/// with the bits of [`quadratic_form`]; `partials` is 2·[`row_chunks`] long.
pub fn two_forms(
    k: &CsrMatrix<f64>,
    x: &[f64],
    m: &CsrMatrix<f64>,
    y: &[f64],
    partials: &mut [f64],
) -> (f64, f64) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let chunk = |c: usize| -> (f64, f64) {
        let rows = c * ROWS..((c + 1) * ROWS).min(x.len());
        let (mut s, mut t) = (0.0, 0.0);
        for i in rows {
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (kx, my) = row_dot2(&kv[p..q], x, &mv[p..q], y, &cols[p..q]);
            s += x[i] * kx;
            t += y[i] * my;
        }
        (s, t)
    };
    pair_sums(x.len(), partials, chunk)
}

/// Two sums over the row chunks of a length-n vector: `chunk(c)` per
/// chunk into `partials` (2·[`row_chunks`] long), on the pool when there
/// are several, the chunks' sums added in order (the same bits either way).
fn pair_sums(
    n: usize,
    partials: &mut [f64],
    chunk: impl Fn(usize) -> (f64, f64) + Sync,
) -> (f64, f64) {
    let chunks = row_chunks(n);
    let partials = &mut partials[..2 * chunks];
    if chunks > 1 {
        partials
            .par_chunks_mut(2)
            .enumerate()
            .for_each(|(c, p)| (p[0], p[1]) = chunk(c));
        let s = partials.iter().step_by(2).sum();
        let t = partials.iter().skip(1).step_by(2).sum();
        (s, t)
    } else {
        chunk(0)
    }
}

/// Chunks of rows of a vector of length n (the length of the `partials`
/// buffer [`quadratic_form`] needs).
pub fn row_chunks(n: usize) -> usize {
    n.div_ceil(ROWS).max(1)
}

/// xᵀ A x: per-row products as in [`spmv`], summed per chunk of rows into
/// `partials` (at least [`row_chunks`] long), the chunks' sums added in
/// order.
pub fn quadratic_form(a: &CsrMatrix<f64>, x: &[f64], partials: &mut [f64]) -> f64 {
    let offsets = a.row_offsets();
    let cols = a.col_indices();
    let vals = a.values();
    let chunk = |c: usize| -> f64 {
        let rows = c * ROWS..((c + 1) * ROWS).min(x.len());
        let mut total = 0.0;
        for i in rows {
            let (p, q) = (offsets[i], offsets[i + 1]);
            total += x[i] * row_dot(&vals[p..q], &cols[p..q], x);
        }
        total
    };
    let chunks = row_chunks(x.len());
    let partials = &mut partials[..chunks];
    if chunks > 1 {
        partials
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, p)| *p = chunk(c));
        partials.iter().sum()
    } else {
        chunk(0)
    }
}

/// x · y.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Index of entry (i, j) in the CSR value array, if stored.
pub fn csr_index(a: &CsrMatrix<f64>, i: usize, j: usize) -> Option<usize> {
    let start = a.row_offsets()[i];
    let end = a.row_offsets()[i + 1];
    a.col_indices()[start..end]
        .binary_search(&j)
        .ok()
        .map(|k| start + k)
}

/// The size up to which the implicit step keeps K and M as
/// [`PairBlocks`] (about 17 bytes per entry of K).
pub const PAIR_BLOCKS_MAX_BYTES: usize = 8 << 20;

/// K and M on their shared pattern as 2×2 blocks: rows in pairs (2p,
/// 2p + 1), each pair's entries in blocks of two adjacent columns with a
/// u32 first column, K's four values and M's side by side. The implicit
/// step's two products per step ([`PairBlocks::load_minus_k_plus_m`],
/// [`PairBlocks::two_forms`]) then read a column index per four entries
/// instead of one per entry, and a block's eight values are summed in
/// eight lanes: on the paper's mesh the CSR products were 43% of a
/// Newmark step, bound by the instructions per entry (index load, bounds
/// check, gather).
///
/// An entry missing from a block is a stored zero (rows of a pair that
/// belong to different nodes have different columns). With n odd the last
/// column shares a block starting one column earlier, and the last row is
/// a pair's first row whose second sums are not written. Each pair sums
/// its blocks in storage order in two interleaved sets of partial sums
/// (even and odd blocks), each set one per matrix, row and column of the
/// block (the eight values of a block against [x_c, x_c, x_c+1, x_c+1,
/// y_c, y_c, y_c+1, y_c+1]: one 8-wide multiplication and addition per
/// block with AVX-512, blocks on 64-byte lines); then even + odd, then per
/// row its first column's terms + its second's. So the bits depend on the
/// pattern alone, not on threads or the CPU's width. The paper mesh's
/// Newmark step (bench_step, three runs each, 2026-11-24): 10.7-10.9 µs
/// with 2-wide sums of each column in turn, 9.4-9.6 µs 8 wide; with the
/// whole pass (its loop over pairs, the rows' sums and the pass's own
/// arithmetic) in one AVX-512 function rather than a call per pair,
/// 6.3-6.9 → 5.4-5.7 µs (four runs each, against the build before, the
/// small solve in both). Each pass is now about 1.0 µs (`small_lab`),
/// about 3.6 cycles a block: K's and M's 57 KB do not fit the 32 KB L1.
#[derive(Clone, Debug)]
pub struct PairBlocks {
    n: usize,
    /// Blocks of pair p: starts[p]..starts[p + 1].
    starts: Vec<u32>,
    /// First column of each block.
    cols: Vec<u32>,
    /// [K by columns: (r0, c0), (r1, c0), (r0, c1), (r1, c1); then M].
    vals: Vec<Line>,
    /// Where K and M are symmetric and n even: the index of pair p's
    /// diagonal block (its blocks before it lie below the diagonal, those
    /// after above), for the quadratic forms on the upper half.
    upper: Vec<u32>,
    /// The sums run 8 wide ([`PairBlocks::pair_avx512`]; the same bits).
    wide: bool,
}

/// A block's eight values on one 64-byte line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Line([f64; 8]);

impl PairBlocks {
    /// The block form of K and M, which must share their pattern
    /// ([`same_pattern`]); `None` below 2 rows or beyond u32 indices.
    pub fn new(k: &CsrMatrix<f64>, m: &CsrMatrix<f64>) -> Option<PairBlocks> {
        let n = k.nrows();
        if n < 2 || !same_pattern(k, m) || k.nnz() >= u32::MAX as usize {
            return None;
        }
        let offsets = k.row_offsets();
        let cols = k.col_indices();
        let (kv, mv) = (k.values(), m.values());
        let start_of = |c: usize| if (c | 1) < n { c & !1 } else { n - 2 };
        let mut starts = Vec::with_capacity(n / 2 + 2);
        let mut bcols: Vec<u32> = Vec::with_capacity(k.nnz() / 3);
        let mut vals: Vec<Line> = Vec::with_capacity(k.nnz() / 3);
        let mut entries: Vec<(usize, usize, usize)> = Vec::new();
        starts.push(0u32);
        for p in 0..n.div_ceil(2) {
            entries.clear();
            for r in 0..2 {
                let i = 2 * p + r;
                if i >= n {
                    break;
                }
                for e in offsets[i]..offsets[i + 1] {
                    let c = cols[e];
                    let s = start_of(c);
                    entries.push((s, 2 * (c - s) + r, e));
                }
            }
            entries.sort_unstable();
            for &(s, slot, e) in &entries {
                if bcols.last().map(|&b| b as usize) != Some(s) || bcols.len() == starts[p] as usize
                {
                    bcols.push(s as u32);
                    vals.push(Line([0.0; 8]));
                }
                let Line(v) = vals.last_mut().expect("pushed above");
                v[slot] = kv[e];
                v[4 + slot] = mv[e];
            }
            if bcols.len() >= u32::MAX as usize {
                return None;
            }
            starts.push(bcols.len() as u32);
        }
        // pass_avx512 reads x[c], x[c + 1] unchecked.
        assert!(bcols.iter().all(|&c| (c as usize) + 1 < n));
        let symmetric = |a: &CsrMatrix<f64>| {
            a.triplet_iter()
                .all(|(i, j, v)| csr_index(a, j, i).map(|e| a.values()[e]) == Some(*v))
        };
        let upper = if n.is_multiple_of(2) && symmetric(k) && symmetric(m) {
            (0..n / 2)
                .map(|p| {
                    let blocks = starts[p] as usize..starts[p + 1] as usize;
                    let d = bcols[blocks.clone()]
                        .iter()
                        .position(|&c| c as usize == 2 * p);
                    (blocks.start + d.expect("a symmetric pattern holds the diagonal")) as u32
                })
                .collect()
        } else {
            Vec::new()
        };
        Some(PairBlocks {
            n,
            starts,
            cols: bcols,
            vals,
            upper,
            wide: crate::kernels::avx512(),
        })
    }

    /// Bytes held (and streamed per product).
    pub fn bytes(&self) -> usize {
        4 * (self.starts.len() + self.cols.len() + self.upper.len()) + 64 * self.vals.len()
    }

    /// One pass over `pairs`: with FORMS, returns (Σ x_i (K x)_i, Σ y_i
    /// (M y)_i) over their rows, each sum row by row in order; without,
    /// writes l_i − (K x)_i + (M y)_i into `out` (its row 0 is the first
    /// pair's first row).
    #[inline(always)]
    #[allow(unsafe_code)]
    fn pass<const FORMS: bool, const UPPER: bool>(
        &self,
        pairs: std::ops::Range<usize>,
        x: &[f64],
        y: &[f64],
        l: &[f64],
        out: &mut [f64],
    ) -> (f64, f64) {
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: `wide` only where the CPU has AVX-512 (new).
            return unsafe { self.pass_avx512::<FORMS, UPPER>(pairs, x, y, l, out) };
        }
        let (n, first) = (self.n, pairs.start);
        let (mut s, mut t) = (0.0, 0.0);
        for p in pairs {
            let (kx, my) = self.pair::<UPPER>(p, x, y);
            let i = 2 * p;
            for r in 0..2.min(n - i) {
                if FORMS {
                    s += x[i + r] * kx[r];
                    t += y[i + r] * my[r];
                } else {
                    out[i - 2 * first + r] = l[i + r] - kx[r] + my[r];
                }
            }
        }
        (s, t)
    }

    /// ((K x) on rows 2p, 2p + 1; (M y) on the same rows), scalar.
    #[inline(always)]
    /// With UPPER, the pair's upper half (see [`PairBlocks::two_forms`]).
    fn pair<const UPPER: bool>(&self, p: usize, x: &[f64], y: &[f64]) -> ([f64; 2], [f64; 2]) {
        let start = if UPPER { self.upper[p] } else { self.starts[p] };
        let blocks = start as usize..self.starts[p + 1] as usize;
        let (cols, vals) = (&self.cols[blocks.clone()], &self.vals[blocks]);
        // One length for both vectors: one bounds check covers both reads.
        let (x, y) = (&x[..self.n], &y[..self.n]);
        let product = |c: u32, v: &[f64; 8]| -> [f64; 8] {
            let c = c as usize;
            let (xs, ys) = (&x[c..c + 2], &y[c..c + 2]);
            let z = [xs[0], xs[0], xs[1], xs[1], ys[0], ys[0], ys[1], ys[1]];
            std::array::from_fn(|l| v[l] * z[l])
        };
        let skip = usize::from(UPPER);
        let mut acc = [[0.0; 8]; 2];
        for (j, (&c, Line(v))) in cols[skip..].iter().zip(&vals[skip..]).enumerate() {
            let t = product(c, v);
            for l in 0..8 {
                acc[j % 2][l] += t[l];
            }
        }
        if UPPER {
            let mut d = [0.0; 8];
            for (d, t) in d.iter_mut().zip(product(cols[0], &vals[0].0)) {
                *d += t;
            }
            Self::rows(std::array::from_fn(|l| {
                d[l] + 2.0 * (acc[0][l] + acc[1][l])
            }))
        } else {
            Self::rows(std::array::from_fn(|l| acc[0][l] + acc[1][l]))
        }
    }

    /// The pair's two rows of K x and M y from the lanes' sums (even +
    /// odd blocks): per row its first column's terms + its second's.
    #[inline(always)]
    fn rows(t: [f64; 8]) -> ([f64; 2], [f64; 2]) {
        ([t[0] + t[2], t[1] + t[3]], [t[4] + t[6], t[5] + t[7]])
    }

    /// [`PairBlocks::pass`] 8 wide: a block's values against x_c, x_c,
    /// x_c+1, x_c+1, y_c, y_c, y_c+1, y_c+1 (one two-source permutation
    /// of the two pairs); per lane the scalar operations in their order
    /// (multiplications and additions separate), then the rows' sums and
    /// the pass's own arithmetic on two lanes, so the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[allow(unsafe_code)]
    fn pass_avx512<const FORMS: bool, const UPPER: bool>(
        &self,
        pairs: std::ops::Range<usize>,
        x: &[f64],
        y: &[f64],
        l: &[f64],
        out: &mut [f64],
    ) -> (f64, f64) {
        use std::arch::x86_64::*;
        let (n, first) = (self.n, pairs.start);
        // Every block's c + 1 < n (new): with x and y this long the reads
        // need no check per block.
        let (xp, yp) = (x[..n].as_ptr(), y[..n].as_ptr());
        // [x_c, x_c, x_c+1, x_c+1, y_c, y_c, y_c+1, y_c+1] from the two
        // pairs in one two-source permutation.
        let spread = _mm512_set_epi64(9, 9, 8, 8, 1, 1, 0, 0);
        let add = |c: u32, v: &Line, acc: __m512d| -> __m512d {
            // SAFETY: c + 1 < n (above): two doubles read unaligned from
            // each vector; a line is 8 doubles, 64-byte aligned.
            unsafe {
                let c = c as usize;
                let xv = (xp.add(c) as *const __m128d).read_unaligned();
                let yv = (yp.add(c) as *const __m128d).read_unaligned();
                let z = _mm512_permutex2var_pd(
                    _mm512_castpd128_pd512(xv),
                    spread,
                    _mm512_castpd128_pd512(yv),
                );
                _mm512_add_pd(acc, _mm512_mul_pd(_mm512_load_pd(v.0.as_ptr()), z))
            }
        };
        let two = |v: &[f64]| -> __m128d {
            // SAFETY: v holds two doubles.
            unsafe { _mm_loadu_pd(v[..2].as_ptr()) }
        };
        let lanes =
            |v: __m128d| -> [f64; 2] { [_mm_cvtsd_f64(v), _mm_cvtsd_f64(_mm_unpackhi_pd(v, v))] };
        let (mut s, mut t) = (0.0, 0.0);
        for p in pairs {
            let start = if UPPER { self.upper[p] } else { self.starts[p] };
            let blocks = start as usize..self.starts[p + 1] as usize;
            let (cols, vals) = (&self.cols[blocks.clone()], &self.vals[blocks]);
            let diagonal = UPPER.then(|| add(cols[0], &vals[0], _mm512_setzero_pd()));
            let skip = usize::from(UPPER);
            let (cols, vals) = (&cols[skip..], &vals[skip..]);
            let (mut even, mut odd) = (_mm512_setzero_pd(), _mm512_setzero_pd());
            let split = cols.len() & !1;
            for (c, v) in cols[..split]
                .chunks_exact(2)
                .zip(vals[..split].chunks_exact(2))
            {
                even = add(c[0], &v[0], even);
                odd = add(c[1], &v[1], odd);
            }
            if split < cols.len() {
                even = add(cols[split], &vals[split], even);
            }
            // Lanes [K: (r0, c0), (r1, c0), (r0, c1), (r1, c1), then M]:
            // each row's first column + its second, in lanes 0, 1 (K) and
            // 4, 5 (M).
            let mut sum = _mm512_add_pd(even, odd);
            if let Some(d) = diagonal {
                sum = _mm512_add_pd(d, _mm512_mul_pd(_mm512_set1_pd(2.0), sum));
            }
            let rows = _mm512_add_pd(sum, _mm512_permutex_pd::<0b01_00_11_10>(sum));
            let kx = _mm512_castpd512_pd128(rows);
            let my = _mm256_castpd256_pd128(_mm512_extractf64x4_pd::<1>(rows));
            let i = 2 * p;
            if i + 1 < n {
                if FORMS {
                    let (px, py) = (
                        lanes(_mm_mul_pd(two(&x[i..]), kx)),
                        lanes(_mm_mul_pd(two(&y[i..]), my)),
                    );
                    s = s + px[0] + px[1];
                    t = t + py[0] + py[1];
                } else {
                    let o = _mm_add_pd(_mm_sub_pd(two(&l[i..]), kx), my);
                    // SAFETY: rows i, i + 1 of out exist (i + 1 < n).
                    unsafe { _mm_storeu_pd(out[i - 2 * first..][..2].as_mut_ptr(), o) };
                }
            } else {
                let (kx, my) = (_mm_cvtsd_f64(kx), _mm_cvtsd_f64(my));
                if FORMS {
                    s += x[i] * kx;
                    t += y[i] * my;
                } else {
                    out[i - 2 * first] = l[i] - kx + my;
                }
            }
        }
        (s, t)
    }

    /// out_i = l_i − (K x)_i + (M y)_i, rows in chunks on the pool.
    pub fn load_minus_k_plus_m(&self, l: &[f64], x: &[f64], y: &[f64], out: &mut [f64]) {
        let body = |c: usize, out: &mut [f64]| {
            let first = c * ROWS / 2;
            self.pass::<false, false>(first..first + out.len().div_ceil(2), x, y, l, out);
        };
        if out.len() > ROWS {
            out.par_chunks_mut(ROWS)
                .enumerate()
                .for_each(|(c, o)| body(c, o));
        } else {
            body(0, out);
        }
    }

    /// (xᵀK x, yᵀM y), per chunk of rows into `partials` (2·[`row_chunks`]
    /// long), the chunks' sums added in order.
    ///
    /// Where K and M are symmetric (bit for bit) and n even, each pair's
    /// rows take their diagonal block once and the blocks right of it
    /// twice (x_Iᵀ(D_I x_I + 2 Σ_{J>I} B_IJ x_J)), so the pass reads half
    /// the blocks: per lane the diagonal block's product + 2·(even + odd
    /// sums of the others), then the rows' sums as in the products.
    pub fn two_forms(&self, x: &[f64], y: &[f64], partials: &mut [f64]) -> (f64, f64) {
        let n = self.n;
        let chunk = |c: usize| -> (f64, f64) {
            let rows = c * ROWS..((c + 1) * ROWS).min(n);
            let pairs = rows.start / 2..rows.end.div_ceil(2);
            if self.upper.is_empty() {
                self.pass::<true, false>(pairs, x, y, &[], &mut [])
            } else {
                self.pass::<true, true>(pairs, x, y, &[], &mut [])
            }
        };
        pair_sums(n, partials, chunk)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;
    use stickslip_fem::testing::{on_threads, plain_spmv};

    /// A banded symmetric pattern over `n` rows (rows of 5-11 entries, so
    /// the four-way split and the remainder both occur) and two value sets.
    fn pair(n: usize) -> (CsrMatrix<f64>, CsrMatrix<f64>) {
        let (mut k, mut m) = (CooMatrix::new(n, n), CooMatrix::new(n, n));
        for i in 0..n {
            for j in i.saturating_sub(5)..(i + 6).min(n) {
                let h = ((i * 31 + j * 17) % 97) as f64 / 97.0;
                k.push(i, j, if i == j { 10.0 } else { -h });
                m.push(i, j, if i == j { 2.0 } else { 0.1 * h });
            }
        }
        (CsrMatrix::from(&k), CsrMatrix::from(&m))
    }

    fn vector(n: usize, seed: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919 + seed) % 1009) as f64 / 1009.0 - 0.5)
            .collect()
    }

    /// The fused products have the bits of the separate ones, and the
    /// threaded runs (several chunks) the bits of one thread.
    #[test]
    fn fused_products_have_the_bits_of_the_separate_ones() {
        for n in [37, 3 * ROWS + 11] {
            let (k, m) = pair(n);
            assert!(same_pattern(&k, &m));
            let (x, y, l) = (vector(n, 1), vector(n, 2), vector(n, 3));
            let run = |threads: usize| {
                on_threads(threads, || {
                    let mut partials = vec![0.0; 2 * row_chunks(n)];
                    let (mut kx, mut my, mut fused) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                    spmv(&k, &x, &mut kx);
                    spmv(&m, &y, &mut my);
                    load_minus_k_plus_m(&l, &k, &x, &m, &y, &mut fused);
                    let separate: Vec<f64> = (0..n).map(|i| l[i] - kx[i] + my[i]).collect();
                    let qk = quadratic_form(&k, &x, &mut partials);
                    let qm = quadratic_form(&m, &y, &mut partials);
                    let both = two_forms(&k, &x, &m, &y, &mut partials);
                    (fused, separate, (qk, qm), both, kx)
                })
            };
            let one = run(1);
            let two = run(2);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&one.0), bits(&one.1), "n = {n}: fused R̂");
            assert_eq!(one.2 .0.to_bits(), one.3 .0.to_bits(), "n = {n}: xᵀKx");
            assert_eq!(one.2 .1.to_bits(), one.3 .1.to_bits(), "n = {n}: yᵀMy");
            assert_eq!(bits(&one.0), bits(&two.0), "n = {n}: threads");
            assert_eq!(one.3 .0.to_bits(), two.3 .0.to_bits(), "n = {n}: threads");
            // And the product is right: against a plain row loop to 1e-13.
            for (plain, kx) in plain_spmv(&k, &x).iter().zip(&one.4) {
                assert!((plain - kx).abs() <= 1e-13 * plain.abs().max(1.0));
            }
        }
    }

    /// A symmetric pattern whose paired rows differ (as when a node has
    /// one DOF constrained), n odd and even.
    fn ragged(n: usize) -> (CsrMatrix<f64>, CsrMatrix<f64>) {
        let (mut k, mut m) = (CooMatrix::new(n, n), CooMatrix::new(n, n));
        for i in 0..n {
            for j in 0..=i {
                let h = (i * 31 + j * 17) % 97;
                if i == j || (i - j < 9 && h % 3 != 0) {
                    let v = h as f64 / 97.0;
                    for (a, b) in [(i, j), (j, i)] {
                        if a != b || i == j {
                            k.push(a, b, if i == j { 20.0 } else { -v });
                            m.push(a, b, if i == j { 2.0 } else { 0.1 * v });
                        }
                        if i == j {
                            break;
                        }
                    }
                }
            }
        }
        (CsrMatrix::from(&k), CsrMatrix::from(&m))
    }

    /// The block products equal plain row sums to rounding, on one thread
    /// and on two with the same bits, scalar and 8 wide; the forms too, on
    /// the upper half (symmetric, n even) and on whole rows.
    #[test]
    fn pair_blocks_agree_with_the_csr_products() {
        for n in [2, 3, 37, 38, 2 * ROWS + 1, 3 * ROWS + 10] {
            for (symmetric, (k, m)) in [(false, pair(n)), (true, ragged(n))] {
                let blocks = PairBlocks::new(&k, &m).expect("shared pattern");
                // The forms on the upper half where K and M are symmetric.
                assert_eq!(!blocks.upper.is_empty(), symmetric && n % 2 == 0, "n = {n}");
                let (x, y, l) = (vector(n, 4), vector(n, 5), vector(n, 6));
                let run = |threads: usize| {
                    on_threads(threads, || {
                        let mut out = vec![0.0; n];
                        let mut partials = vec![0.0; 2 * row_chunks(n)];
                        blocks.load_minus_k_plus_m(&l, &x, &y, &mut out);
                        (out, blocks.two_forms(&x, &y, &mut partials))
                    })
                };
                let (one, two) = (run(1), run(2));
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&one.0), bits(&two.0), "n = {n}: threads");
                // The scalar sums where the CPU runs them 8 wide: the same bits.
                if blocks.wide {
                    let scalar = PairBlocks {
                        wide: false,
                        ..blocks.clone()
                    };
                    let mut out = vec![0.0; n];
                    let mut partials = vec![0.0; 2 * row_chunks(n)];
                    scalar.load_minus_k_plus_m(&l, &x, &y, &mut out);
                    assert_eq!(bits(&one.0), bits(&out), "n = {n}: width");
                    let forms = scalar.two_forms(&x, &y, &mut partials);
                    assert_eq!(one.1 .0.to_bits(), forms.0.to_bits(), "n = {n}: width");
                    assert_eq!(one.1 .1.to_bits(), forms.1.to_bits(), "n = {n}: width");
                }
                assert_eq!(one.1 .0.to_bits(), two.1 .0.to_bits(), "n = {n}");
                assert_eq!(one.1 .1.to_bits(), two.1 .1.to_bits(), "n = {n}");
                let plain = |a: &CsrMatrix<f64>, v: &[f64], i: usize| -> (f64, f64) {
                    let row = a.row(i);
                    let terms = row.col_indices().iter().zip(row.values());
                    let s = terms.clone().map(|(&j, w)| w * v[j]).sum();
                    (s, terms.map(|(&j, w)| (w * v[j]).abs()).sum())
                };
                let (mut xkx, mut ymy, mut scale) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    let (kx, ka) = plain(&k, &x, i);
                    let (my, ma) = plain(&m, &y, i);
                    let want = l[i] - kx + my;
                    let err = (one.0[i] - want).abs();
                    assert!(err <= 1e-14 * (l[i].abs() + ka + ma), "n = {n}, row {i}");
                    xkx += x[i] * kx;
                    ymy += y[i] * my;
                    scale += (x[i] * ka).abs() + (y[i] * ma).abs();
                }
                assert!((one.1 .0 - xkx).abs() <= 1e-13 * scale, "n = {n}: xᵀKx");
                assert!((one.1 .1 - ymy).abs() <= 1e-13 * scale, "n = {n}: yᵀMy");
            }
        }
    }
}
