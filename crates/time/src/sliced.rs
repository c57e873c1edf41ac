//! K x by slices of eight rows (the SELL-8 layout) for systems of one
//! chunk: the paper's 85-node mesh and its like.
//!
//! In [`crate::kernels::Compact`] a 64-byte line holds two 2×2 blocks of
//! one node, so each block needs its own x pair (a gather and a shuffle)
//! and each row ends in a reduction across lanes. Here a line holds one
//! column of eight rows: x_j is one broadcast, the product one multiply
//! and one add, and lane l *is* row l of the slice, so nothing is reduced.
//! The rows of a slice are chosen for alike column sets (a node's two rows
//! have the same ones), so the zeros that pad a slice's columns stay few.
//! The paper-sized Q2 8×2 slab (148 free DOFs, 3,536 entries): 19 slices,
//! 5,344 padded values (66% filled), one K x 0.47 µs against the compact
//! form's 0.63 (`tests::sliced_lab`).
//!
//! Bits: row i is Σ over its slice's columns in order, in four partial sums
//! (entry e to sum e mod 4, then (s0 + s1) + (s2 + s3)), the same on the
//! scalar path and with AVX-512. Not the bits of the CSR's or of
//! [`crate::kernels::Compact`]'s product (a different order of the same
//! terms; padded terms add +0·x).

/// Rows per slice: one AVX-512 register of f64. Slices of four rows (AVX,
/// 32-byte lines) fill more of their lines (the paper mesh 84% against
/// 66%, 33 against 41 KB) but were no faster, 0.547 against 0.557 µs for
/// one K x (`sliced_lab`, 2026-11-25): a line costs about the same few
/// cycles whatever its width, so fewer, wider lines win.
const LANES: usize = 8;

/// Independent partial sums per row, hiding the adder's latency.
const SUMS: usize = 4;

/// One column of a slice: its eight rows' values (0 where a row lacks it).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Line([f64; LANES]);

/// K in slices of eight rows (see the module documentation).
#[derive(Clone, Debug)]
pub struct Sliced {
    n: usize,
    /// Slice s holds entries starts[s]..starts[s + 1].
    starts: Vec<u32>,
    /// Per entry: its column (< n, checked at build).
    cols: Vec<u32>,
    /// Per entry: the slice's rows' values in that column.
    lines: Vec<Line>,
    /// Per slice: its rows (`NONE` in lanes past the last row).
    rows: Vec<[u32; LANES]>,
    /// Per row: slice · LANES + lane.
    place: Vec<u32>,
    /// Structural entries of K (for the padding figure).
    nnz: usize,
}

const NONE: u32 = u32::MAX;

/// Most padded values for which the explicit step takes [`Sliced`] (128
/// KB: the slices stay in L2 beside the step's vectors). `sliced_lab`,
/// one K x, medians of 30, 2026-11-24: Q2 148 DOFs 0.63 → 0.47 µs and 220
/// DOFs 1.00 → 0.69 µs (5,344 and 8,104 values); at 552 DOFs (19k-23k
/// values) Q1 1.70 → 1.63 and Q2 2.40 → 2.39, and at 2,128 DOFs slower
/// (Q1 6.2 → 8.2, Q2 9.5 → 10.0 µs).
pub const MAX_VALUES: usize = 1 << 14;

/// Least fill (K's entries over the padded values) for which the explicit
/// step takes [`Sliced`]: the Q2 meshes fill 64-68% of their slices, the
/// Q1 meshes 44-47%, where the padding eats the gain (above).
pub const MIN_FILL: f64 = 0.5;

impl Sliced {
    /// K (square CSR, columns sorted per row, as nalgebra-sparse keeps
    /// them) in slices; `None` beyond u32 indices.
    pub fn new(k: &nalgebra_sparse::CsrMatrix<f64>) -> Option<Sliced> {
        let n = k.nrows();
        if n >= NONE as usize / LANES || k.ncols() != n {
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
            place: vec![0; n],
            nnz: values.len(),
        };
        // Rows by greedy alikeness: the first free row, then the free row
        // (among those sharing a column with the slice so far) that adds
        // the fewest new columns for the most shared ones; ties to the lower
        // index, so the layout is a function of K's pattern alone.
        let mut union: Vec<usize> = Vec::new();
        let mut mark = vec![false; n];
        let mut candidates: Vec<usize> = Vec::new();
        let mut first = 0;
        while first < n {
            if taken[first] {
                first += 1;
                continue;
            }
            let mut slice = [NONE; LANES];
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
            while lanes < LANES {
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
            let e0 = s.lines.len();
            for &c in &union {
                s.cols.push(c as u32);
                s.lines.push(Line::default());
            }
            for (lane, &r) in slice.iter().enumerate().take(lanes) {
                let r = r as usize;
                s.place[r] = (s.rows.len() * LANES + lane) as u32;
                for (&c, &v) in row_cols(r).iter().zip(&values[offsets[r]..offsets[r + 1]]) {
                    let e = e0 + union.binary_search(&c).expect("in the union");
                    s.lines[e].0[lane] = v;
                }
            }
            for &c in &union {
                mark[c] = false;
            }
            union.clear();
            s.rows.push(slice);
            s.starts.push(s.lines.len() as u32);
        }
        assert!(s.cols.iter().all(|&c| (c as usize) < n));
        Some(s)
    }

    /// K in slices where the explicit step is faster for it than with
    /// [`crate::kernels::Compact`]: at most [`MAX_VALUES`] padded values,
    /// at least [`MIN_FILL`] filled.
    pub fn small(k: &nalgebra_sparse::CsrMatrix<f64>) -> Option<Sliced> {
        if k.nnz() > MAX_VALUES {
            return None;
        }
        Sliced::new(k)
            .filter(|s| s.padded() <= MAX_VALUES && s.nnz() as f64 >= MIN_FILL * s.padded() as f64)
    }

    /// Rows.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Padded entries (slices × their columns × 8).
    pub fn padded(&self) -> usize {
        self.lines.len() * LANES
    }

    /// K's structural entries.
    pub fn nnz(&self) -> usize {
        self.nnz
    }

    /// Bytes one K x reads from the operator.
    pub fn bytes(&self) -> usize {
        self.lines.len() * (64 + 4) + self.rows.len() * (4 * LANES + 4)
    }

    /// (K x)_i alone, with the bits of [`Sliced::spmv`].
    pub fn row(&self, i: usize, x: &[f64]) -> f64 {
        let p = self.place[i] as usize;
        let (s, lane) = (p / LANES, p % LANES);
        let e = self.starts[s] as usize..self.starts[s + 1] as usize;
        let mut acc = [0.0; SUMS];
        for (j, (line, &c)) in self.lines[e.clone()].iter().zip(&self.cols[e]).enumerate() {
            acc[j % SUMS] += line.0[lane] * x[c as usize];
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3])
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
        let x = &x[..self.n];
        for (s, rows) in self.rows.iter().enumerate() {
            let e = self.starts[s] as usize..self.starts[s + 1] as usize;
            let mut acc = [[0.0; LANES]; SUMS];
            for (j, (line, &c)) in self.lines[e.clone()].iter().zip(&self.cols[e]).enumerate() {
                let xc = x[c as usize];
                for (a, v) in acc[j % SUMS].iter_mut().zip(&line.0) {
                    *a += v * xc;
                }
            }
            for (lane, &r) in rows.iter().enumerate() {
                if r != NONE {
                    y[r as usize] = (acc[0][lane] + acc[1][lane]) + (acc[2][lane] + acc[3][lane]);
                }
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[allow(unsafe_code)]
    pub(crate) fn spmv_avx512(&self, x: &[f64], y: &mut [f64]) {
        use std::arch::x86_64::*;
        let x = &x[..self.n];
        let y = &mut y[..self.n];
        let xp = x.as_ptr();
        for (s, rows) in self.rows.iter().enumerate() {
            let e = self.starts[s] as usize..self.starts[s + 1] as usize;
            let (lines, cols) = (&self.lines[e.clone()], &self.cols[e]);
            let mut acc = [_mm512_setzero_pd(); SUMS];
            let whole = lines.len() / SUMS * SUMS;
            // SAFETY: every column < n = x's length (asserted at build);
            // a Line is 64 bytes, 64-aligned.
            unsafe {
                let term = |line: &Line, c: u32| {
                    _mm512_mul_pd(
                        _mm512_load_pd(line.0.as_ptr()),
                        _mm512_set1_pd(*xp.add(c as usize)),
                    )
                };
                for (l4, c4) in lines[..whole]
                    .chunks_exact(SUMS)
                    .zip(cols[..whole].chunks_exact(SUMS))
                {
                    acc[0] = _mm512_add_pd(acc[0], term(&l4[0], c4[0]));
                    acc[1] = _mm512_add_pd(acc[1], term(&l4[1], c4[1]));
                    acc[2] = _mm512_add_pd(acc[2], term(&l4[2], c4[2]));
                    acc[3] = _mm512_add_pd(acc[3], term(&l4[3], c4[3]));
                }
                for (j, (line, &c)) in lines[whole..].iter().zip(&cols[whole..]).enumerate() {
                    acc[j] = _mm512_add_pd(acc[j], term(line, c));
                }
                let sum =
                    _mm512_add_pd(_mm512_add_pd(acc[0], acc[1]), _mm512_add_pd(acc[2], acc[3]));
                let mut out = Line::default();
                _mm512_store_pd(out.0.as_mut_ptr(), sum);
                for (lane, &r) in rows.iter().enumerate() {
                    if r != NONE {
                        y[r as usize] = out.0[lane];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::tests::{lab_slab, median_time, x_of};

    /// Each row of the product is the row of K times x to rounding, the
    /// scalar and AVX-512 paths give the same bits, and `row` gives the
    /// bits of `spmv` on every row.
    #[test]
    fn products_agree() {
        let (mut partial, mut ragged) = (false, false);
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
            ragged |= s
                .starts
                .windows(2)
                .any(|w| !((w[1] - w[0]) as usize).is_multiple_of(SUMS));
            #[cfg(target_arch = "x86_64")]
            if crate::kernels::avx512() {
                let mut z = vec![f64::NAN; n];
                // SAFETY: checked above.
                #[allow(unsafe_code)]
                unsafe {
                    s.spmv_avx512(&x, &mut z)
                };
                assert!(
                    y.iter().zip(&z).all(|(p, q)| p.to_bits() == q.to_bits()),
                    "{name}"
                );
            }
        }
        assert!(
            partial && ragged,
            "a slice of fewer than 8 rows, one of entries not a multiple of 4"
        );
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
