//! The implicit step's passes over K and M by 2×2 blocks of row pairs.
//!
//! Rows i and i + 1 with the same columns (a node's two DOFs) form a pair,
//! as in [`crate::Symmetric`]; a pair row meets a pair column in a 2×2
//! block. K keeps every such block (four values, one 32-bit column); M
//! keeps one value where its block is m·I₂, as an isotropic mass's are:
//! a term's two x values and one M value are loaded once for both rows,
//! where the CSR loads them per row with 64-bit columns. Entries outside
//! these blocks (single rows, single columns, M blocks of another shape)
//! stay in a small CSR, summed after the blocks.
//!
//! Each row's sums are formed by one function ([`unit_sums`]) for every
//! pass, so the forms, the next step's products and R̂'s products agree
//! in every bit (a restarted run and a run to a later t_end keep the
//! bits of the run they continue), on any number of threads (the fixed
//! chunks of [`crate::chunks`]; a pair never spans a chunk seam).

use nalgebra_sparse::CsrMatrix;

use crate::chunks::{chunk_groups, each_chunk, each_chunk_of, sum_chunks, CHUNK};
use crate::csr::same_pattern;
use crate::simd::Kernel;

/// K and M (one pattern) by row pairs' blocks (module documentation).
#[derive(Clone, Debug)]
pub struct PairedKm {
    n: usize,
    /// First row of each unit (a pair or a single row), then n.
    unit_rows: Vec<u32>,
    /// Blocks of unit u: unit_blocks[u]..unit_blocks[u + 1] (none for a
    /// single row).
    unit_blocks: Vec<usize>,
    /// Each block's first column.
    block_cols: Vec<u32>,
    /// Each block's K values, column by column: [K00, K10, K01, K11].
    block_k: Vec<[f64; 4]>,
    /// Each block's m (M's block is m·I₂).
    block_m: Vec<f64>,
    /// The entries outside the blocks, by rows: rest_rows[i]..rest_rows[i + 1].
    rest_rows: Vec<usize>,
    rest_cols: Vec<u32>,
    rest_k: Vec<f64>,
    rest_m: Vec<f64>,
    /// Units of chunk c: chunk_units[c]..chunk_units[c + 1].
    chunk_units: Vec<u32>,
}

impl PairedKm {
    /// K and M by blocks; `None` unless they are square and share one
    /// pattern ([`same_pattern`]).
    pub fn new(k: &CsrMatrix<f64>, m: &CsrMatrix<f64>) -> Option<PairedKm> {
        let n = k.nrows();
        if k.ncols() != n || !same_pattern(k, m) || n >= u32::MAX as usize - 2 {
            return None;
        }
        let offsets = k.row_offsets();
        let cols = k.col_indices();
        let (kv, mv) = (k.values(), m.values());
        let row = |i: usize| &cols[offsets[i]..offsets[i + 1]];
        let mut unit_rows = Vec::with_capacity(n / 2 + 2);
        let mut pair_first = vec![false; n + 1];
        let mut i = 0;
        while i < n {
            unit_rows.push(i as u32);
            if i + 1 < n && (i + 1) % CHUNK != 0 && row(i) == row(i + 1) {
                pair_first[i] = true;
                i += 2;
            } else {
                i += 1;
            }
        }
        unit_rows.push(n as u32);
        let units = unit_rows.len() - 1;
        let mut this = PairedKm {
            n,
            unit_blocks: Vec::with_capacity(units + 1),
            block_cols: Vec::with_capacity(cols.len() / 4),
            block_k: Vec::with_capacity(cols.len() / 4),
            block_m: Vec::with_capacity(cols.len() / 4),
            rest_rows: Vec::with_capacity(n + 1),
            rest_cols: Vec::new(),
            rest_k: Vec::new(),
            rest_m: Vec::new(),
            chunk_units: chunk_groups(&unit_rows, n),
            unit_rows,
        };
        this.unit_blocks.push(0);
        this.rest_rows.push(0);
        // Positions of a pair's second row's rest entries, in its row order.
        let mut second = Vec::new();
        for u in 0..units {
            let r0 = this.unit_rows[u] as usize;
            if !pair_first[r0] {
                for p in offsets[r0]..offsets[r0 + 1] {
                    this.push_rest(cols[p], kv[p], mv[p]);
                }
                this.rest_rows.push(this.rest_cols.len());
                this.unit_blocks.push(this.block_cols.len());
                continue;
            }
            // The two rows' entries align: the same columns.
            let (p0, len) = (offsets[r0], offsets[r0 + 1] - offsets[r0]);
            let q0 = offsets[r0 + 1];
            second.clear();
            let mut j = 0;
            while j < len {
                let (p, q) = (p0 + j, q0 + j);
                let c = cols[p];
                let block = pair_first[c]
                    && j + 1 < len
                    && cols[p + 1] == c + 1
                    && mv[p + 1] == 0.0
                    && mv[q] == 0.0
                    && mv[p].to_bits() == mv[q + 1].to_bits();
                if block {
                    this.block_cols.push(c as u32);
                    this.block_k.push([kv[p], kv[q], kv[p + 1], kv[q + 1]]);
                    this.block_m.push(mv[p]);
                    j += 2;
                } else {
                    this.push_rest(c, kv[p], mv[p]);
                    second.push(q);
                    j += 1;
                }
            }
            this.rest_rows.push(this.rest_cols.len());
            for &q in &second {
                this.push_rest(cols[q], kv[q], mv[q]);
            }
            this.rest_rows.push(this.rest_cols.len());
            this.unit_blocks.push(this.block_cols.len());
        }
        Some(this)
    }

    fn push_rest(&mut self, c: usize, k: f64, m: f64) {
        self.rest_cols.push(c as u32);
        self.rest_k.push(k);
        self.rest_m.push(m);
    }

    /// Unit u's first row and its rows (1 or 2).
    #[inline(always)]
    fn unit(&self, u: usize) -> (usize, usize) {
        let r0 = self.unit_rows[u] as usize;
        (r0, self.unit_rows[u + 1] as usize - r0)
    }

    /// Rows.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Stored 2×2 blocks and entries outside them.
    pub fn counts(&self) -> (usize, usize) {
        (self.block_cols.len(), self.rest_cols.len())
    }

    /// (xᵀK x, yᵀM y). `partials` holds [`crate::chunks::chunks`]`(n)`
    /// sums.
    pub fn two_forms(&self, x: &[f64], y: &[f64], partials: &mut [[f64; 2]]) -> (f64, f64) {
        let [s, t] = sum_chunks(self.n, partials, |c, _, s| {
            *s = crate::simd::vectorized(Pass {
                km: self,
                chunk: c,
                x: [x],
                y: [y],
                out: Out::Forms,
            });
        });
        (s, t)
    }

    /// (xᵀK x, yᵀM y) with the bits of [`PairedKm::two_forms`], and in the
    /// same pass K x' into `kx` and M y' into `my`, each row with the bits
    /// of [`PairedKm::load_minus_k_plus_m`]'s: an implicit step's energies
    /// and the next step's products read K and M once.
    pub fn two_forms_and_products(
        &self,
        [x, x2]: [&[f64]; 2],
        [y, y2]: [&[f64]; 2],
        out: [&mut [f64]; 2],
        partials: &mut [[f64; 2]],
    ) -> (f64, f64) {
        let [s, t] = each_chunk_of(out, partials, |c, [kx, my], s| {
            *s = crate::simd::vectorized(Pass {
                km: self,
                chunk: c,
                x: [x, x2],
                y: [y, y2],
                out: Out::FormsAndProducts(kx, my),
            });
        });
        (s, t)
    }

    /// out_i = l_i − (K x)_i + (M y)_i.
    pub fn load_minus_k_plus_m(&self, l: &[f64], x: &[f64], y: &[f64], out: &mut [f64]) {
        each_chunk(out, |c, out| {
            crate::simd::vectorized(Pass {
                km: self,
                chunk: c,
                x: [x],
                y: [y],
                out: Out::Load(l, out),
            });
        });
    }
}

/// What a chunk's pass yields besides the forms of its first vectors.
enum Out<'a> {
    /// The forms only.
    Forms,
    /// K x' and M y' of the second vectors, this chunk's rows.
    FormsAndProducts(&'a mut [f64], &'a mut [f64]),
    /// l − K x + M y, this chunk's rows (no forms).
    Load(&'a [f64], &'a mut [f64]),
}

/// One chunk of a pass with A vectors for K and B for M.
struct Pass<'a, const A: usize, const B: usize> {
    km: &'a PairedKm,
    chunk: usize,
    x: [&'a [f64]; A],
    y: [&'a [f64]; B],
    out: Out<'a>,
}

impl<const A: usize, const B: usize> Kernel for Pass<'_, A, B> {
    type Output = [f64; 2];

    #[inline(always)]
    fn run<S: crate::simd::Simd>(self, _simd: S) -> [f64; 2] {
        let km = self.km;
        let first = (self.chunk * CHUNK).min(km.n);
        let units = km.chunk_units[self.chunk] as usize..km.chunk_units[self.chunk + 1] as usize;
        let [mut a, mut b] = [0.0, 0.0];
        let (x, y) = (self.x, self.y);
        match self.out {
            Out::Forms => each_row(km, units, (x, y), |i, kx, my| {
                a += x[0][i] * kx[0];
                b += y[0][i] * my[0];
            }),
            Out::FormsAndProducts(ko, mo) => each_row(km, units, (x, y), |i, kx, my| {
                a += x[0][i] * kx[0];
                b += y[0][i] * my[0];
                ko[i - first] = kx[A - 1];
                mo[i - first] = my[B - 1];
            }),
            Out::Load(l, o) => each_row(km, units, (x, y), |i, kx, my| {
                o[i - first] = l[i] - kx[0] + my[0];
            }),
        }
        [a, b]
    }
}

/// `row(i, K x's row i, M y's row i)` for the rows of `units`, in order.
#[inline(always)]
fn each_row<const A: usize, const B: usize>(
    km: &PairedKm,
    units: std::ops::Range<usize>,
    (x, y): ([&[f64]; A], [&[f64]; B]),
    mut row: impl FnMut(usize, [f64; A], [f64; B]),
) {
    for u in units {
        let (r0, rows) = km.unit(u);
        let (kx, my) = unit_sums(km, u, r0, rows, x, y);
        for r in 0..rows {
            row(r0 + r, kx[r], my[r]);
        }
    }
}

/// One block's terms into one set of partial sums: per vector, K's two
/// columns times x's two values, each column's two rows in one sum pair.
#[inline(always)]
fn block_term<const A: usize, const B: usize>(
    (ka, ma): (&mut [[[f64; 2]; 2]; A], &mut [[f64; 2]; B]),
    (k, m, c): (&[f64; 4], f64, u32),
    x: &[&[f64]; A],
    y: &[&[f64]; B],
) {
    let c = c as usize;
    for (acc, x) in ka.iter_mut().zip(x) {
        let &[x0, x1] = &x[c..c + 2] else {
            unreachable!("a slice of two")
        };
        acc[0][0] += k[0] * x0;
        acc[0][1] += k[1] * x0;
        acc[1][0] += k[2] * x1;
        acc[1][1] += k[3] * x1;
    }
    for (acc, y) in ma.iter_mut().zip(y) {
        let &[y0, y1] = &y[c..c + 2] else {
            unreachable!("a slice of two")
        };
        acc[0] += m * y0;
        acc[1] += m * y1;
    }
}

/// Unit u's rows (r0, and r0 + 1 for a pair) of K·x for each x and M·y for
/// each y, by rows: the blocks' terms in two alternating sets of partial
/// sums, each block column in its own sums, then the rest in row order.
#[inline(always)]
fn unit_sums<const A: usize, const B: usize>(
    km: &PairedKm,
    u: usize,
    r0: usize,
    rows: usize,
    x: [&[f64]; A],
    y: [&[f64]; B],
) -> ([[f64; A]; 2], [[f64; B]; 2]) {
    let mut kx = [[0.0; A]; 2];
    let mut my = [[0.0; B]; 2];
    let blocks = km.unit_blocks[u]..km.unit_blocks[u + 1];
    if !blocks.is_empty() {
        let cols = &km.block_cols[blocks.clone()];
        let kb = &km.block_k[blocks.clone()];
        let mb = &km.block_m[blocks];
        // Per set and vector: [[K00 x0, K10 x0], [K01 x1, K11 x1]] and
        // [m y0, m y1].
        let (mut k0, mut k1) = ([[[0.0; 2]; 2]; A], [[[0.0; 2]; 2]; A]);
        let (mut m0, mut m1) = ([[0.0; 2]; B], [[0.0; 2]; B]);
        let pairs = cols
            .chunks_exact(2)
            .zip(kb.chunks_exact(2))
            .zip(mb.chunks_exact(2));
        for ((c, k), m) in pairs {
            block_term((&mut k0, &mut m0), (&k[0], m[0], c[0]), &x, &y);
            block_term((&mut k1, &mut m1), (&k[1], m[1], c[1]), &x, &y);
        }
        if cols.len() % 2 == 1 {
            let j = cols.len() - 1;
            block_term((&mut k0, &mut m0), (&kb[j], mb[j], cols[j]), &x, &y);
        }
        for r in 0..2 {
            for v in 0..A {
                let (p, q) = (&k0[v], &k1[v]);
                kx[r][v] = (p[0][r] + p[1][r]) + (q[0][r] + q[1][r]);
            }
            for v in 0..B {
                my[r][v] = m0[v][r] + m1[v][r];
            }
        }
    }
    for r in 0..rows {
        let i = r0 + r;
        let (mut sk, mut sm) = (kx[r], my[r]);
        for p in km.rest_rows[i]..km.rest_rows[i + 1] {
            let c = km.rest_cols[p] as usize;
            for (s, x) in sk.iter_mut().zip(&x) {
                *s += km.rest_k[p] * x[c];
            }
            for (s, y) in sm.iter_mut().zip(&y) {
                *s += km.rest_m[p] * y[c];
            }
        }
        kx[r] = sk;
        my[r] = sm;
    }
    (kx, my)
}
