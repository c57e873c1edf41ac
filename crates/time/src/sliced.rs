//! K x by slices of four rows and column pairs for systems of one chunk:
//! the paper's 85-node mesh and its like.
//!
//! In [`crate::kernels::Compact`] a 64-byte line holds two 2×2 blocks of
//! one node, so each block needs its own x pair (a gather and a shuffle)
//! and each row ends in a reduction across lanes. Here a line holds two
//! columns (c, c + 1: a node's two DOFs) of four rows, lane 2k + h row k
//! in column c + h: the x pair is one 16-byte broadcast, the product one
//! multiply and one add, and a row's two lanes are added once at the end
//! of its slice. The rows of a slice are chosen for alike column sets (a
//! node's two rows have the same ones), so the zeros that pad its lines
//! stay few. A line costs about the same whatever it holds (0.65-0.7 ns
//! here), so the layout is chosen for the fewest lines: on the paper-sized
//! Q2 8×2 slab (148 free DOFs, 3,536 entries), `tests::sliced_lab`,
//! 2026-11-26:
//!
//! | layout                                   | lines | fill | one K x  |
//! |------------------------------------------|-------|------|----------|
//! | 8 rows × 1 column (until 2026-11-26)     | 668   | 66%  | 0.45 µs  |
//! | 4 rows × 2 columns, four partial sums    | 624   | 71%  | 0.41 µs  |
//! | 4 rows × 2 columns, two partial sums     | 580   | 76%  | 0.38 µs  |
//!
//! (Slices are padded with zero lines to a multiple of the partial sums,
//! so fewer sums pad less.) The paper mesh's explicit step, `bench_step
//! --case cd gen-q2-8x2 200000 5`, five alternating runs each, medians:
//! 1.097 µs (8 × 1), 0.968 (four sums), 0.955 (two sums).
//!
//! Bits: row k of a slice is, per column half h, Σ over its lines in
//! order in two partial sums (line j to sum j mod 2, then s0 + s1), and
//! then half 0 + half 1; the same on the scalar path and with AVX-512. Not
//! the bits of the CSR's or of [`crate::kernels::Compact`]'s product (a
//! different order of the same terms; padded terms add +0·x).

/// Rows per slice. A line holds four rows in two columns (a pair of
/// x entries, one 16-byte broadcast), so a slice is two nodes' rows and
/// its lines are its union of node columns.
const ROWS: usize = 4;

/// Values per line (one AVX-512 register of f64): ROWS rows × 2 columns.
const LANES: usize = 2 * ROWS;

/// Independent partial sums per row and column half (two: see the
/// module documentation).
const SUMS: usize = 2;

/// One column pair of a slice: lane 2k + h is row k's value in column
/// p + h (0 where the row lacks it).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Line([f64; LANES]);

/// K in slices of four rows (see the module documentation).
#[derive(Clone, Debug)]
pub struct Sliced {
    n: usize,
    /// Slice s holds entries starts[s]..starts[s + 1], a multiple of SUMS.
    starts: Vec<u32>,
    /// Per entry: its column pair's first column p (p + 1 < n, checked at
    /// build).
    cols: Vec<u32>,
    /// Per entry: the slice's rows' values in columns p and p + 1.
    lines: Vec<Line>,
    /// Per slice: its rows (`NONE` in lanes past the last row).
    rows: Vec<[u32; ROWS]>,
    /// Per slice: how many of `rows` are rows.
    lanes: Vec<u8>,
    /// Per row: slice · ROWS + its place in the slice.
    place: Vec<u32>,
    /// Structural entries of K (for the padding figure).
    nnz: usize,
}

const NONE: u32 = u32::MAX;

/// Most padded values for which the explicit step takes [`Sliced`] (1 MB
/// of lines, about 3,000 DOFs; within one chunk, where the step forms K x
/// whole). `bench_step --case cd MESH 20000 5`, three alternating runs
/// each, 2026-11-26, against [`crate::kernels::Compact`]: Q2 148 DOFs 1.10
/// → 0.96 µs; Q1 552 DOFs (66% filled, below the 8-row layout's 50%
/// floor before) 2.92 → 2.46 µs; Q2 2,128 DOFs (83k values) 13.6 → 12.1
/// µs; Q1 2,128 DOFs (59k values) 7.7 both. With 8-row slices it had
/// been slower from 2,128 DOFs (`sliced_lab`, 2026-11-24).
pub const MAX_VALUES: usize = 1 << 17;

/// Least fill (K's entries over the padded values) for which the explicit
/// step takes [`Sliced`]: the slabs' Q2 meshes fill 76% of their lines,
/// their Q1 meshes 59-66%.
pub const MIN_FILL: f64 = 0.5;

impl Sliced {
    /// K (square CSR, columns sorted per row, as nalgebra-sparse keeps
    /// them) in slices; `None` beyond u32 indices or below two rows.
    pub fn new(k: &nalgebra_sparse::CsrMatrix<f64>) -> Option<Sliced> {
        let n = k.nrows();
        if n < 2 || n >= NONE as usize / LANES || k.ncols() != n {
            return None;
        }
        let (offsets, cols, values) = (k.row_offsets(), k.col_indices(), k.values());
        let row_cols = |i: usize| &cols[offsets[i]..offsets[i + 1]];
        let mut taken = vec![false; n];
        let mut s = Sliced {
            n,
            starts: vec![0],
            cols: Vec::new(),
            lines: Vec::new(),
            rows: Vec::new(),
            lanes: Vec::new(),
            place: vec![0; n],
            nnz: values.len(),
        };
        // Rows by greedy alikeness: the first free row, then the free row
        // (among those sharing a column with the slice so far) that adds
        // the fewest new columns for the most shared ones; ties to the lower
        // index, so the layout is a function of K's pattern alone.
        let mut union: Vec<usize> = Vec::new();
        let mut mark = vec![false; n];
        // Per column of the slice: its line · 2 + its half (NONE: none).
        let mut slot = vec![NONE; n];
        let mut candidates: Vec<usize> = Vec::new();
        let mut first = 0;
        while first < n {
            if taken[first] {
                first += 1;
                continue;
            }
            let mut slice = [NONE; ROWS];
            let mut lanes = 0;
            let add = |r: usize, union: &mut Vec<usize>, mark: &mut [bool]| {
                for &c in row_cols(r) {
                    if !mark[c] {
                        mark[c] = true;
                        union.push(c);
                    }
                }
            };
            taken[first] = true;
            slice[0] = first as u32;
            lanes += 1;
            add(first, &mut union, &mut mark);
            while lanes < ROWS {
                // K's pattern is symmetric: the rows with a column in the
                // union are the rows of the union's columns.
                candidates.clear();
                for &c in &union {
                    candidates.extend(row_cols(c).iter().copied().filter(|&r| !taken[r]));
                }
                candidates.sort_unstable();
                candidates.dedup();
                let best = candidates
                    .iter()
                    .map(|&r| {
                        let shared = row_cols(r).iter().filter(|&&c| mark[c]).count() as i64;
                        let new = row_cols(r).len() as i64 - shared;
                        (shared - new, r)
                    })
                    .max_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)));
                let Some((_, r)) = best else { break };
                taken[r] = true;
                slice[lanes] = r as u32;
                lanes += 1;
                add(r, &mut union, &mut mark);
            }
            union.sort_unstable();
            // Column pairs over the union: c with c + 1 (a node's two
            // DOFs, where both are free), the last column with the one
            // before it; each column of the union in exactly one pair.
            let e0 = s.lines.len();
            for &c in &union {
                if slot[c] != NONE {
                    continue;
                }
                let p = if c + 1 < n { c } else { c - 1 };
                let line = (s.lines.len() - e0) as u32;
                s.cols.push(p as u32);
                s.lines.push(Line::default());
                slot[c] = 2 * line + (c - p) as u32;
                if p == c && mark[c + 1] && slot[c + 1] == NONE {
                    slot[c + 1] = 2 * line + 1;
                }
            }
            // Zero lines up to a multiple of SUMS (at the slice's first
            // pair, in cache): line j still goes to sum j mod SUMS, and +0
            // added to a sum that never holds −0 keeps its bits, so the
            // kernel has no remainder loop.
            while !(s.lines.len() - e0).is_multiple_of(SUMS) {
                s.cols.push(s.cols[e0]);
                s.lines.push(Line::default());
            }
            for (k, &r) in slice.iter().enumerate().take(lanes) {
                let r = r as usize;
                s.place[r] = (s.rows.len() * ROWS + k) as u32;
                for (&c, &v) in row_cols(r).iter().zip(&values[offsets[r]..offsets[r + 1]]) {
                    let at = slot[c] as usize;
                    s.lines[e0 + at / 2].0[2 * k + at % 2] = v;
                }
            }
            for &c in &union {
                mark[c] = false;
                slot[c] = NONE;
            }
            union.clear();
            s.rows.push(slice);
            s.lanes.push(lanes as u8);
            s.starts.push(s.lines.len() as u32);
        }
        assert!(s.cols.iter().all(|&p| (p as usize) + 1 < n));
        Some(s)
    }

    /// K in slices where the explicit step is faster for it than with
    /// [`crate::kernels::Compact`]: one chunk (its rows one by one are
    /// slow: the step must form K x whole), at most [`MAX_VALUES`] padded
    /// values, at least [`MIN_FILL`] filled.
    pub fn small(k: &nalgebra_sparse::CsrMatrix<f64>) -> Option<Sliced> {
        if k.nnz() > MAX_VALUES || crate::kernels::chunks(k.nrows()) > 1 {
            return None;
        }
        Sliced::new(k)
            .filter(|s| s.padded() <= MAX_VALUES && s.nnz() as f64 >= MIN_FILL * s.padded() as f64)
    }

    /// Rows.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Padded entries (lines × 8).
    pub fn padded(&self) -> usize {
        self.lines.len() * LANES
    }

    /// K's structural entries.
    pub fn nnz(&self) -> usize {
        self.nnz
    }

    /// Bytes one K x reads from the operator.
    pub fn bytes(&self) -> usize {
        self.lines.len() * (64 + 4) + self.rows.len() * (4 * ROWS + 4 + 1)
    }

    /// (K x)_i alone, with the bits of [`Sliced::spmv`].
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        let p = self.place[i] as usize;
        let (s, k) = (p / ROWS, p % ROWS);
        let e = self.starts[s] as usize..self.starts[s + 1] as usize;
        let mut acc = [[0.0; 2]; SUMS];
        for (j, (line, &c)) in self.lines[e.clone()].iter().zip(&self.cols[e]).enumerate() {
            let c = c as usize;
            acc[j % SUMS][0] += line.0[2 * k] * x[c];
            acc[j % SUMS][1] += line.0[2 * k + 1] * x[c + 1];
        }
        let half = |h: usize| acc[0][h] + acc[1][h];
        half(0) + half(1)
    }

    /// y = K x.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if crate::kernels::avx512() {
            // SAFETY: the CPU has AVX-512F (checked).
            #[allow(unsafe_code)]
            unsafe {
                self.spmv_avx512(x, y)
            };
            return;
        }
        self.spmv_scalar(x, y)
    }

    /// [`Sliced::spmv`] without SIMD (the reference for the bits).
    pub(crate) fn spmv_scalar(&self, x: &[f64], y: &mut [f64]) {
        for (s, rows) in self.rows.iter().enumerate() {
            for &r in &rows[..self.lanes[s] as usize] {
                y[r as usize] = self.row(r as usize, x);
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[allow(unsafe_code)]
    pub(crate) fn spmv_avx512(&self, x: &[f64], y: &mut [f64]) {
        use std::arch::x86_64::*;
        assert!(x.len() >= self.n && y.len() >= self.n);
        let (xp, yp) = (x.as_ptr(), y.as_mut_ptr());
        let (lines, cols) = (self.lines.as_ptr(), self.cols.as_ptr());
        let mut e = 0usize;
        for s in 0..self.rows.len() {
            // SAFETY: starts, rows and lanes have an entry per slice; a
            // slice's entries are a multiple of SUMS (built so); each pair
            // p, p + 1 < n ≤ x's length and each row < n ≤ y's length
            // (both asserted); a Line is 64 bytes, 64-aligned.
            unsafe {
                let end = *self.starts.get_unchecked(s + 1) as usize;
                let mut acc = [_mm512_setzero_pd(); SUMS];
                while e < end {
                    for (j, a) in acc.iter_mut().enumerate() {
                        // x_p, x_{p+1} in every 128-bit lane (the f32x4
                        // broadcast moves the same 16 bytes; AVX-512F).
                        let pair = _mm_loadu_ps(xp.add(*cols.add(e + j) as usize).cast());
                        let t = _mm512_mul_pd(
                            _mm512_load_pd((*lines.add(e + j)).0.as_ptr()),
                            _mm512_castps_pd(_mm512_broadcast_f32x4(pair)),
                        );
                        *a = _mm512_add_pd(*a, t);
                    }
                    e += SUMS;
                }
                let sum = _mm512_add_pd(acc[0], acc[1]);
                // Lane 2k: s[2k] + s[2k + 1], row k's two halves.
                let both = _mm512_add_pd(sum, _mm512_permute_pd::<0x55>(sum));
                let mut out = Line::default();
                _mm512_store_pd(out.0.as_mut_ptr(), both);
                let rows = self.rows.get_unchecked(s);
                for k in 0..*self.lanes.get_unchecked(s) as usize {
                    *yp.add(*rows.get_unchecked(k) as usize) = out.0[2 * k];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::tests::{lab_slab, median_time, x_of};

    /// K x by the AVX-512 kernel, where the CPU has it.
    fn avx512_product(s: &Sliced, x: &[f64]) -> Option<Vec<f64>> {
        #[cfg(target_arch = "x86_64")]
        if crate::kernels::avx512() {
            let mut z = vec![f64::NAN; s.n];
            // SAFETY: the CPU has AVX-512F (checked).
            #[allow(unsafe_code)]
            unsafe {
                s.spmv_avx512(x, &mut z)
            };
            return Some(z);
        }
        None
    }

    /// Each row of the product is the row of K times x to rounding, the
    /// scalar and AVX-512 paths give the same bits, and `row` gives the
    /// bits of `spmv` on every row.
    #[test]
    fn products_agree() {
        let mut partial = false;
        for name in ["q2-8x2", "q1-12x3", "q2-5x3"] {
            let (_, _, model) = lab_slab(name);
            let k = &model.stiffness;
            let n = k.nrows();
            let s = Sliced::new(k).expect("applies");
            let x = x_of(n);
            let mut y = vec![f64::NAN; n];
            s.spmv_scalar(&x, &mut y);
            for i in 0..n {
                let (mut exact, mut size) = (0.0, 0.0f64);
                let row = k.row(i);
                for (&c, &v) in row.col_indices().iter().zip(row.values()) {
                    exact += v * x[c];
                    size = size.max((v * x[c]).abs());
                }
                assert!(
                    (y[i] - exact).abs() <= 1e-13 * size.max(1e-300),
                    "{name} row {i}"
                );
                assert_eq!(s.row(i, &x).to_bits(), y[i].to_bits(), "{name} row {i}");
            }
            partial |= s.rows.iter().any(|r| r.contains(&NONE));
            assert!(
                s.starts
                    .windows(2)
                    .all(|w| ((w[1] - w[0]) as usize).is_multiple_of(SUMS)),
                "{name}: a slice's lines a multiple of the sums"
            );
            if let Some(z) = avx512_product(&s, &x) {
                assert!(
                    y.iter().zip(&z).all(|(p, q)| p.to_bits() == q.to_bits()),
                    "{name}"
                );
            }
        }
        assert!(partial, "a slice of fewer than 4 rows");
    }

    /// Column pairs where a column's partner is not in its slice: the last
    /// column paired with the one before it, a lone column with the next
    /// one; every product still exact on small integers, in both paths.
    #[test]
    fn lone_columns_pair_up() {
        use nalgebra_sparse::{CooMatrix, CsrMatrix};
        // Rows 0 and 2 coupled, 1 and 3 alone: slice {0, 2} has columns
        // 0 and 2, the last paired as (1, 2); slice {1} pairs (1, 2) and
        // {3} pairs (2, 3) with zeros.
        let mut coo = CooMatrix::new(4, 4);
        for (i, j, v) in [
            (0, 0, 4.0),
            (0, 2, -1.0),
            (2, 0, -1.0),
            (2, 2, 5.0),
            (1, 1, 3.0),
            (3, 3, 2.0),
        ] {
            coo.push(i, j, v);
        }
        let k = CsrMatrix::from(&coo);
        let s = Sliced::new(&k).expect("applies");
        let x = [1.0, 2.0, 3.0, 4.0];
        let want = [1.0, 6.0, 14.0, 8.0];
        let mut y = [f64::NAN; 4];
        s.spmv_scalar(&x, &mut y);
        assert_eq!(y, want);
        for (i, w) in want.iter().enumerate() {
            assert_eq!(s.row(i, &x), *w);
        }
        if let Some(z) = avx512_product(&s, &x) {
            assert_eq!(z, want);
        }
        assert!(
            s.cols.contains(&1),
            "the last column paired with the one before"
        );
    }

    /// A small deterministic generator (xorshift64).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }

        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    /// Random sparse patterns, symmetric and not, n from 2 up, with empty
    /// rows and lone columns: every structural entry of K lands in exactly
    /// one lane (the lines rebuilt into K give K, and hold no more nonzero
    /// lanes than K has entries), every row's place points back at it, and
    /// the products are exact on small integers and the same bits by `row`,
    /// the scalar path and AVX-512 on real values.
    #[test]
    fn random_patterns_cover_every_entry_once() {
        use nalgebra_sparse::{CooMatrix, CsrMatrix};
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for trial in 0..600 {
            let n = 2 + trial % 41;
            let symmetric = trial % 3 != 0;
            let mut dense = vec![0.0f64; n * n];
            // Some rows (and, if symmetric, their columns) left empty.
            let empty: Vec<bool> = (0..n).map(|_| rng.below(6) == 0).collect();
            let per_row = 1 + rng.below(6);
            for i in 0..n {
                if empty[i] {
                    continue;
                }
                if rng.below(4) != 0 {
                    dense[i * n + i] = 1.0 + rng.below(9) as f64;
                }
                for _ in 0..rng.below(per_row + 1) {
                    let j = rng.below(n);
                    if (symmetric && empty[j]) || dense[i * n + j] != 0.0 {
                        continue;
                    }
                    let v = rng.below(17) as f64 - 8.0;
                    let v = if v == 0.0 { 3.0 } else { v };
                    dense[i * n + j] = v;
                    if symmetric {
                        dense[j * n + i] = v;
                    }
                }
            }
            let mut coo = CooMatrix::new(n, n);
            for i in 0..n {
                for j in 0..n {
                    if dense[i * n + j] != 0.0 {
                        coo.push(i, j, dense[i * n + j]);
                    }
                }
            }
            let k = CsrMatrix::from(&coo);
            let s = Sliced::new(&k).expect("applies");
            let mut rebuilt = vec![0.0f64; n * n];
            let mut lanes_set = 0;
            for (sl, rows) in s.rows.iter().enumerate() {
                let e = s.starts[sl] as usize..s.starts[sl + 1] as usize;
                assert!(e.len().is_multiple_of(SUMS), "trial {trial}");
                for (line, &p) in s.lines[e.clone()].iter().zip(&s.cols[e]) {
                    assert!((p as usize) + 1 < n, "trial {trial}");
                    for (kk, &r) in rows.iter().enumerate().take(s.lanes[sl] as usize) {
                        for h in 0..2 {
                            let v = line.0[2 * kk + h];
                            if v != 0.0 {
                                lanes_set += 1;
                                rebuilt[r as usize * n + p as usize + h] += v;
                            }
                        }
                    }
                }
            }
            assert_eq!(lanes_set, k.nnz(), "trial {trial}: lanes holding entries");
            assert_eq!(rebuilt, dense, "trial {trial}: K rebuilt from the lines");
            for i in 0..n {
                let p = s.place[i] as usize;
                assert_eq!(s.rows[p / ROWS][p % ROWS] as usize, i, "trial {trial}");
                assert!(p % ROWS < s.lanes[p / ROWS] as usize, "trial {trial}");
            }
            let ints: Vec<f64> = (0..n).map(|_| rng.below(21) as f64 - 10.0).collect();
            for (x, exact) in [(ints, true), (x_of(n), false)] {
                let mut y = vec![f64::NAN; n];
                s.spmv_scalar(&x, &mut y);
                for i in 0..n {
                    if exact {
                        let want: f64 = (0..n).map(|j| dense[i * n + j] * x[j]).sum();
                        assert_eq!(y[i], want, "trial {trial} row {i}");
                    }
                    assert_eq!(
                        s.row(i, &x).to_bits(),
                        y[i].to_bits(),
                        "trial {trial} row {i}"
                    );
                }
                if let Some(z) = avx512_product(&s, &x) {
                    for i in 0..n {
                        assert_eq!(z[i].to_bits(), y[i].to_bits(), "trial {trial} row {i}");
                    }
                }
            }
        }
    }

    /// Timing lab (run by hand): one K x by [`Sliced`] against
    /// [`crate::kernels::Compact`], same run.
    ///
    ///     cargo test --release -p stickslip-time --lib sliced_lab -- --ignored --nocapture
    #[test]
    #[ignore = "timing lab, run by hand"]
    fn sliced_lab() {
        for name in [
            "q2-8x2",
            "q2-12x2",
            "q1-32x8",
            "q2-16x4",
            "q1-64x16",
            "q2-32x8",
            "q2-64x16",
            "q1-128x32",
        ] {
            let (_, _, model) = lab_slab(name);
            let k = &model.stiffness;
            let n = k.nrows();
            let s = Sliced::new(k).expect("applies");
            let c = crate::kernels::Compact::new(k).expect("applies");
            let x = x_of(n);
            let mut y = vec![0.0; n];
            let time = |f: &mut dyn FnMut()| median_time(20_000, f);
            let tc = time(&mut || c.spmv(std::hint::black_box(&x), &mut y));
            let ts = time(&mut || s.spmv(std::hint::black_box(&x), &mut y));
            println!(
                "{name}: n = {n}, nnz = {}, slices = {}, padded = {} ({:.0}% fill, {} KB); compact {:.3} µs, sliced {:.3} µs, {:.2} ns per line",
                s.nnz(),
                s.rows.len(),
                s.padded(),
                100.0 * s.nnz() as f64 / s.padded() as f64,
                s.padded() / 128,
                tc * 1e6,
                ts * 1e6,
                ts * 1e9 / (s.padded() / 8) as f64
            );
        }
    }
}
