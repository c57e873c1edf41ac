//! Products with CSR matrices (nalgebra-sparse, both triangles stored),
//! threaded by the fixed chunks of [`crate::chunks`].

use nalgebra_sparse::CsrMatrix;

use crate::chunks::{each_chunk, each_chunk_of, sum_chunks, CHUNK};

/// Σ_k vals[k]·x[cols[k]] over one row, in four interleaved partial sums
/// (one chain of additions waits on the adder's latency): [`row_dots`]
/// for one pair.
#[inline(always)]
pub(crate) fn row_dot(vals: &[f64], cols: &[usize], x: &[f64]) -> f64 {
    row_dots([vals], [x], cols)[0]
}

/// Row i of A times x, in `row_dot`'s four interleaved partial sums: the
/// same bits as row i of [`spmv`].
#[inline(always)]
pub fn row(a: &CsrMatrix<f64>, i: usize, x: &[f64]) -> f64 {
    let (p, q) = (a.row_offsets()[i], a.row_offsets()[i + 1]);
    row_dot(&a.values()[p..q], &a.col_indices()[p..q], x)
}

/// y = A x.
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    each_chunk(y, |c, y| {
        crate::simd::vectorized(Rows { a, c, x, y });
    });
}

/// Rows of chunk c of A x, as a dispatched kernel.
struct Rows<'a> {
    a: &'a CsrMatrix<f64>,
    c: usize,
    x: &'a [f64],
    y: &'a mut [f64],
}

impl crate::simd::Kernel for Rows<'_> {
    type Output = ();

    #[inline(always)]
    fn run<S: crate::simd::Simd>(self, _simd: S) {
        for (k, yi) in self.y.iter_mut().enumerate() {
            *yi = row(self.a, self.c * CHUNK + k, self.x);
        }
    }
}

/// Row sums Σ_k vals[v][k]·x[v][cols[k]] for V (values, vector) pairs on
/// one pattern in one loop over it, each in four interleaved partial sums
/// (lane l takes the terms k ≡ l mod 4, the lanes added pairwise, then the
/// row's last len mod 4 terms in order): the row's indices are read once
/// for all V.
#[inline(always)]
fn row_dots<const V: usize>(vals: [&[f64]; V], x: [&[f64]; V], cols: &[usize]) -> [f64; V] {
    let len = cols.len();
    let split = len - len % 4;
    let mut acc = [[0.0; 4]; V];
    for (g, c) in cols[..split].chunks_exact(4).enumerate() {
        // Sorted distinct columns: four consecutive ones (a run of nodes
        // along a grid row) are one load of each vector.
        let run = c[3] == c[0] + 3;
        for (acc, (vals, x)) in acc.iter_mut().zip(vals.iter().zip(&x)) {
            let v = &vals[4 * g..4 * g + 4];
            let xs: [f64; 4] = if run {
                x[c[0]..c[0] + 4].try_into().expect("four values")
            } else {
                [x[c[0]], x[c[1]], x[c[2]], x[c[3]]]
            };
            for l in 0..4 {
                acc[l] += v[l] * xs[l];
            }
        }
    }
    let mut s = acc.map(|a| (a[0] + a[1]) + (a[2] + a[3]));
    for (k, &c) in cols.iter().enumerate().skip(split) {
        for (s, (vals, x)) in s.iter_mut().zip(vals.iter().zip(&x)) {
            *s += vals[k] * x[c];
        }
    }
    s
}

/// True when A and B store the same pattern.
pub fn same_pattern(a: &CsrMatrix<f64>, b: &CsrMatrix<f64>) -> bool {
    a.nrows() == b.nrows()
        && a.row_offsets() == b.row_offsets()
        && a.col_indices() == b.col_indices()
}

/// out_i = l_i − (K x)_i + (M y)_i in one pass over the shared pattern of
/// K and M ([`same_pattern`]), with the bits of two [`spmv`]s.
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
    each_chunk(out, |c, out| {
        for (j, o) in out.iter_mut().enumerate() {
            let i = c * CHUNK + j;
            let (p, q) = (offsets[i], offsets[i + 1]);
            let [kx, my] = row_dots([&kv[p..q], &mv[p..q]], [x, y], &cols[p..q]);
            *o = l[i] - kx + my;
        }
    });
}

/// xᵀ A x, each row's product as in [`spmv`]; `partials` holds
/// [`crate::chunks::chunks`]`(n)` sums.
pub fn quadratic_form(a: &CsrMatrix<f64>, x: &[f64], partials: &mut [[f64; 2]]) -> f64 {
    sum_chunks(x.len(), partials, |_, rows, s| {
        s[0] = rows.map(|i| x[i] * row(a, i, x)).sum();
    })[0]
}

/// (xᵀK x, yᵀM y) in one pass over the shared pattern of K and M, each with
/// the bits of [`quadratic_form`].
pub fn two_forms(
    k: &CsrMatrix<f64>,
    x: &[f64],
    m: &CsrMatrix<f64>,
    y: &[f64],
    partials: &mut [[f64; 2]],
) -> (f64, f64) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let [s, t] = sum_chunks(x.len(), partials, |_, rows, s| {
        let (mut a, mut b) = (0.0, 0.0);
        for i in rows {
            let (p, q) = (offsets[i], offsets[i + 1]);
            let [kx, my] = row_dots([&kv[p..q], &mv[p..q]], [x, y], &cols[p..q]);
            a += x[i] * kx;
            b += y[i] * my;
        }
        *s = [a, b];
    });
    (s, t)
}

/// (xᵀK x, yᵀM y) with the bits of [`two_forms`], and in the same pass over
/// the shared pattern K x' into `kx` and M y' into `my`, each row with the
/// bits of [`load_minus_k_plus_m`]'s: an implicit step's energies and the
/// next step's products read K and M once. `partials` as [`two_forms`]'.
pub fn two_forms_and_products(
    k: &CsrMatrix<f64>,
    [x, x2]: [&[f64]; 2],
    m: &CsrMatrix<f64>,
    [y, y2]: [&[f64]; 2],
    [kx, my]: [&mut [f64]; 2],
    partials: &mut [[f64; 2]],
) -> (f64, f64) {
    let offsets = k.row_offsets();
    let cols = k.col_indices();
    let (kv, mv) = (k.values(), m.values());
    let [s, t] = each_chunk_of([kx, my], partials, |c, [kc, mc], s| {
        *s = crate::simd::vectorized(FourRows {
            rows: c * CHUNK,
            k: (offsets, cols, kv),
            m: mv,
            x: [x, x2, y, y2],
            out: [kc, mc],
        });
    });
    (s, t)
}

/// Rows `rows..` of [`two_forms_and_products`], as a dispatched kernel:
/// (x·Kx, y·My) over them, and K x', M y' into `out`.
struct FourRows<'a> {
    rows: usize,
    k: (&'a [usize], &'a [usize], &'a [f64]),
    m: &'a [f64],
    x: [&'a [f64]; 4],
    out: [&'a mut [f64]; 2],
}

impl crate::simd::Kernel for FourRows<'_> {
    type Output = [f64; 2];

    #[inline(always)]
    fn run<S: crate::simd::Simd>(self, _simd: S) -> [f64; 2] {
        let (offsets, cols, kv) = self.k;
        let [x, x2, y, y2] = self.x;
        let [kc, mc] = self.out;
        let (mut a, mut b) = (0.0, 0.0);
        for (j, (ko, mo)) in kc.iter_mut().zip(mc.iter_mut()).enumerate() {
            let i = self.rows + j;
            let (p, q) = (offsets[i], offsets[i + 1]);
            let (k, m) = (&kv[p..q], &self.m[p..q]);
            let [kx, kx2, my, my2] = row_dots([k, k, m, m], [x, x2, y, y2], &cols[p..q]);
            a += x[i] * kx;
            b += y[i] * my;
            (*ko, *mo) = (kx2, my2);
        }
        [a, b]
    }
}

/// x · y.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// A's diagonal, 0 where a row stores none.
pub fn diagonal(a: &CsrMatrix<f64>) -> Vec<f64> {
    (0..a.nrows())
        .map(|i| index(a, i, i).map_or(0.0, |k| a.values()[k]))
        .collect()
}

/// Index of entry (i, j) in the CSR value array, if stored.
pub fn index(a: &CsrMatrix<f64>, i: usize, j: usize) -> Option<usize> {
    let start = a.row_offsets()[i];
    let end = a.row_offsets()[i + 1];
    a.col_indices()[start..end]
        .binary_search(&j)
        .ok()
        .map(|k| start + k)
}
