//! Solves with a small factor through inverted supernode blocks (issue 7:
//! the paper mesh's Newmark step).
//!
//! On small meshes the supernodal solve (`supernodal.rs` in `fem`) is bound
//! by latency, not by its 2·|L| multiplications: within a supernode each
//! column's division and update wait for the previous column's, and its
//! loops run a handful of times each. The paper's mesh (148 DOFs, a factor
//! of 3,462 values in 16 supernodes of 4-18 columns) took 4.5 µs a solve,
//! about 16,000 cycles.
//!
//! Here the supernodes are taken in panels of consecutive ones (up to
//! [`PANEL`] columns, their columns of L made dense), and each panel's
//! triangle is inverted once per factorization,
//! T = L_kk⁻¹, and F = [T; −L_b T] ((k + m) × k, L_b the m rows below the
//! triangle) is stored column-major, and so is Fᵀ, both on 64-byte lines
//! (columns padded with zeros to a multiple of 8). Then
//!
//! * the forward step of a panel is one dense product: [y; δ] = F x_s,
//!   x_s ← y, x_pattern += δ (L_kk y = x_s, δ = −L_b y);
//! * its back step is one product with Fᵀ: x_s ← Tᵀ x_s − (L_b T)ᵀ
//!   x_pattern = Fᵀ [x_s; x_pattern] (the pattern rows already final).
//!
//! Nothing inside a panel waits on anything else, and both products
//! are sums of columns scaled by one entry each ([`Wide::product`]), 8
//! wide. The price is memory: 2.3× the factor on the slabs (whole
//! triangles, both layouts, padding), so the step uses it only for small
//! factors ([`MAX_VALUES`]); beyond half the L2 ([`TRANSPOSED_MAX_VALUES`])
//! only F is stored (1.15× the factor) and the back step takes dot
//! products with its columns ([`Wide::dots`]). The arithmetic per lane is fixed, so the bits
//! do not depend on the CPU's width; they are not the supernodal solve's
//! bits (T is an explicit inverse), which is why the tests compare with
//! the matrix and with that solve to a tolerance.

use stickslip_linalg::Supernodal;

/// Factors up to this many values stored (2 MB; F and Fᵀ, or F alone
/// beyond [`TRANSPOSED_MAX_VALUES`]) are solved by inverted blocks.
/// `block_inverse_lab` (2026-11-24), one solve against the supernodal
/// loops: 3.8× faster on the paper's Q2 8×2 mesh (170 DOFs), 3.2-3.3× at
/// 350 and 594 DOFs, 2.9× (Q1 48×12) and 2.6× (Q2 32×8, 0.9 MB of F
/// alone); still 2.3× at 8.5k DOFs (4.5 MB of F alone), but that is 1.15×
/// the factor's memory again, which the large meshes cannot spare.
const MAX_VALUES: usize = 1 << 18;

/// Eight doubles on one 64-byte line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Line([f64; 8]);

/// One supernode: its first permuted column, k columns, m pattern rows,
/// the offset of its index (columns, then pattern), and F (lines per column, offset) and Fᵀ
/// (likewise).
#[derive(Clone, Copy, Debug)]
struct Block {
    c0: usize,
    k: usize,
    m: usize,
    index: usize,
    f_lines: usize,
    f_at: usize,
    g_lines: usize,
    g_at: usize,
}

impl Block {
    /// Lines of F (k columns of k + m rows) and of Fᵀ (k + m columns of k
    /// rows), rows padded to 8.
    fn lines(k: usize, m: usize) -> (usize, usize) {
        ((k + m).div_ceil(8), k.div_ceil(8))
    }
}

/// A factor's solve through inverted supernode blocks.
#[derive(Clone, Debug)]
pub(crate) struct BlockInverse {
    data: Data,
    /// The permuted vector, a block's product and a block's gathered x.
    xp: Vec<f64>,
    out: Vec<f64>,
    z: Vec<f64>,
    /// A block's gathered x on lines (the back step by dot products).
    lines: Vec<Line>,
    wide: Wide,
}

/// The blocks.
#[derive(Clone, Debug)]
struct Data {
    /// x_perm[i] = x[fwd[i]].
    fwd: Vec<u32>,
    blocks: Vec<Block>,
    /// Per block its columns c0..c0 + k, then its pattern.
    index: Vec<u32>,
    /// F of every block (column-major), then Fᵀ of every block where
    /// `transposed`.
    values: Vec<Line>,
    /// Fᵀ is stored and the back step is its products (small factors);
    /// else the back step takes dot products with F's columns.
    transposed: bool,
}

/// Factors whose F and Fᵀ together hold at most this many values (512 KB,
/// half the 1 MB L2) store both; larger ones store F alone and run the back
/// step as dot products with its columns, each summed by a three-round
/// reduction across lanes. On small factors that reduction sits on the
/// chain from block to block, where beyond the L2 half the values read
/// cost more: `block_inverse_lab`, 2026-11-24, one run, F and Fᵀ / F
/// alone: Q2 8×2 1.34 / 1.41 µs, Q1 24×6 3.28 / 3.64, Q2 16×4 (343 KB of
/// both) 6.07 / 6.75; Q1 48×12 (0.9 MB) 17.2 / 16.1, Q2 32×8 (1.9 MB)
/// 36.4 / 33.9, Q2 64×16 (9.3 MB) 204 / 182 µs.
const TRANSPOSED_MAX_VALUES: usize = 1 << 16;

/// Consecutive supernodes merged into one block while its columns stay
/// at most this many: fewer blocks mean fewer passes of the per-block work
/// (index moves, loop set-up), at the price of the zeros the merged
/// triangle and pattern hold, and the time follows the values stored
/// (about 0.14 ns a value). `block_inverse_lab`, 2026-11-24, one solve,
/// panels of ≤ 0 (none) / 8 / 24 / 32 columns: Q2 8×2 1.39 / 1.36 / 1.51
/// / 1.72 µs; Q1 24×6 3.72 / 3.35 / 3.97 / 4.41 µs; Q2 16×4 7.12 / 6.44 /
/// 7.39 / 7.79 µs; Q1 48×12 18.6 / 18.0 / 22.4 / 25.5 µs.
const PANEL: usize = 8;

/// Consecutive supernodes solved as one block: columns c0..c0 + k, the
/// rows below them with a nonzero in any of their columns.
struct Panel {
    supernodes: std::ops::Range<usize>,
    c0: usize,
    k: usize,
    pattern: Vec<u32>,
}

/// `sn`'s supernodes merged greedily in order into panels of at most
/// `kmax` columns (a wider supernode is a panel of its own).
fn panels(sn: &Supernodal, kmax: usize) -> Vec<Panel> {
    let mut out: Vec<Panel> = Vec::new();
    let mut s = 0;
    while s < sn.supernodes() {
        let (k0, _) = sn.block_shape(s);
        let mut e = s + 1;
        let mut k = k0;
        while e < sn.supernodes() && k + sn.block_shape(e).0 <= kmax {
            k += sn.block_shape(e).0;
            e += 1;
        }
        let c0 = sn.first_column(s);
        let mut pattern: Vec<u32> = (s..e)
            .flat_map(|q| sn.pattern(q).iter().copied())
            .filter(|&r| r as usize >= c0 + k)
            .collect();
        pattern.sort_unstable();
        pattern.dedup();
        out.push(Panel {
            supernodes: s..e,
            c0,
            k,
            pattern,
        });
        s = e;
    }
    out
}

/// The solve's width: scalar, or AVX-512 with the same bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wide {
    No,
    Avx512,
}

impl BlockInverse {
    /// Values of F and of Fᵀ on `panels`.
    fn counts(panels: &[Panel]) -> (usize, usize) {
        panels.iter().fold((0, 0), |(f_sum, g_sum), p| {
            let (k, m) = (p.k, p.pattern.len());
            let (f, g) = Block::lines(k, m);
            (f_sum + 8 * f * k, g_sum + 8 * g * (k + m))
        })
    }

    /// Whether Fᵀ is stored beside F for these counts of their values
    /// ([`TRANSPOSED_MAX_VALUES`]).
    fn keeps_transposed((f, g): (usize, usize)) -> bool {
        f + g <= TRANSPOSED_MAX_VALUES
    }

    /// Values stored for `sn`'s layout: F and Fᵀ up to
    /// [`TRANSPOSED_MAX_VALUES`] of both, else F.
    pub fn values_for(sn: &Supernodal) -> usize {
        let (f, g) = Self::counts(&panels(sn, PANEL));
        if Self::keeps_transposed((f, g)) {
            f + g
        } else {
            f
        }
    }

    /// True when `sn`'s factors are small enough for the inverted blocks
    /// (at most [`MAX_VALUES`]).
    pub fn worth_it(sn: &Supernodal) -> bool {
        Self::values_for(sn) <= MAX_VALUES
    }

    /// The inverted blocks of the factor with values `l` on `sn`'s layout
    /// (a factor of an SPD matrix: positive diagonal).
    pub fn new(sn: &Supernodal, l: &[f64]) -> BlockInverse {
        Self::with_panel(sn, l, PANEL, None)
    }

    /// [`BlockInverse::new`] with panels of up to `kmax` columns, and Fᵀ
    /// stored or not as `transposed` says (None: by
    /// [`TRANSPOSED_MAX_VALUES`]).
    fn with_panel(
        sn: &Supernodal,
        l: &[f64],
        kmax: usize,
        transposed: Option<bool>,
    ) -> BlockInverse {
        let panels = panels(sn, kmax);
        let transposed =
            transposed.unwrap_or_else(|| Self::keeps_transposed(Self::counts(&panels)));
        let mut blocks = Vec::with_capacity(panels.len());
        let mut index = Vec::new();
        let mut f_values: Vec<Line> = Vec::new();
        let mut g_values: Vec<Line> = Vec::new();
        let (mut max_out, mut max_z, mut max_lines) = (0, 0, 0);
        let mut t = Vec::new();
        let mut f = Vec::new();
        let mut block = Vec::new();
        let to_lines = |v: &[f64], into: &mut Vec<Line>| {
            into.extend(v.chunks_exact(8).map(|c| {
                let mut line = Line::default();
                line.0.copy_from_slice(c);
                line
            }))
        };
        let mut local = vec![u32::MAX; sn.forward_permutation().len()];
        for panel in &panels {
            let (c0, k, pattern) = (panel.c0, panel.k, &panel.pattern[..]);
            let m = pattern.len();
            let ld = k + m;
            // The panel's columns of L, dense (k + m) × k column-major:
            // rows c0..c0 + k, then the pattern.
            for (i, &r) in pattern.iter().enumerate() {
                local[r as usize] = (k + i) as u32;
            }
            block.clear();
            block.resize(ld * k, 0.0);
            for s in panel.supernodes.clone() {
                let (a, ks, sp, values) = sn.block(l, s);
                let lds = ks + sp.len();
                for j in 0..ks {
                    let col = &mut block[(a - c0 + j) * ld..(a - c0 + j + 1) * ld];
                    let src = &values[j * lds..(j + 1) * lds];
                    // Its triangle's rows j.., then its pattern rows.
                    for i in j..ks {
                        col[a - c0 + i] = src[i];
                    }
                    for (&r, v) in sp.iter().zip(&src[ks..]) {
                        let r = r as usize;
                        let at = if r < c0 + k {
                            r - c0
                        } else {
                            local[r] as usize
                        };
                        col[at] = *v;
                    }
                }
            }
            let (f_lines, g_lines) = Block::lines(k, m);
            max_out = max_out.max(8 * f_lines.max(g_lines));
            max_z = max_z.max(ld);
            max_lines = max_lines.max(f_lines);
            // T = L_kk⁻¹, column-major k × k, by forward substitution on
            // the unit vectors.
            t.clear();
            t.resize(k * k, 0.0);
            for j in 0..k {
                t[j * k + j] = 1.0 / block[j * ld + j];
                for i in j + 1..k {
                    let mut sum = 0.0;
                    for p in j..i {
                        sum += block[p * ld + i] * t[j * k + p];
                    }
                    t[j * k + i] = -sum / block[i * ld + i];
                }
            }
            // F = [T; −L_b T], column-major, columns padded to f_lines·8.
            let rows = 8 * f_lines;
            f.clear();
            f.resize(rows * k, 0.0);
            for j in 0..k {
                let col = &mut f[j * rows..(j + 1) * rows];
                col[..k].copy_from_slice(&t[j * k..(j + 1) * k]);
                for r in 0..m {
                    let mut sum = 0.0;
                    for p in j..k {
                        sum += block[p * ld + k + r] * t[j * k + p];
                    }
                    col[k + r] = -sum;
                }
            }
            let f_at = f_values.len();
            to_lines(&f, &mut f_values);
            // Fᵀ, column-major (k + m columns of k rows, padded).
            let g_at = g_values.len();
            if transposed {
                let mut g = vec![0.0; 8 * g_lines * ld];
                for i in 0..ld {
                    for j in 0..k {
                        g[i * 8 * g_lines + j] = f[j * rows + i];
                    }
                }
                to_lines(&g, &mut g_values);
            }
            blocks.push(Block {
                c0,
                k,
                m,
                index: index.len(),
                f_lines,
                f_at,
                g_lines,
                g_at,
            });
            index.extend(c0 as u32..(c0 + k) as u32);
            index.extend_from_slice(pattern);
        }
        let g_base = f_values.len();
        for b in &mut blocks {
            b.g_at += g_base;
        }
        f_values.extend(g_values);
        let n = sn.forward_permutation().len();
        // `solve` moves values through the indices unchecked.
        assert!(index.iter().all(|&r| (r as usize) < n));
        BlockInverse {
            data: Data {
                fwd: sn.forward_permutation().to_vec(),
                blocks,
                index,
                values: f_values,
                transposed,
            },
            xp: vec![0.0; n],
            out: vec![0.0; max_out],
            z: vec![0.0; max_z],
            lines: vec![Line::default(); max_lines],
            wide: if crate::kernels::avx512() {
                Wide::Avx512
            } else {
                Wide::No
            },
        }
    }

    /// Values held (F and Fᵀ; for the memory figures).
    pub fn len(&self) -> usize {
        8 * self.data.values.len()
    }

    /// x ← A⁻¹x.
    #[allow(unsafe_code)]
    pub fn solve(&mut self, x: &mut [f64]) {
        let d = &self.data;
        let (xp, out, z, lines) = (&mut self.xp, &mut self.out, &mut self.z, &mut self.lines);
        d.permute_in(x, xp);
        // The block's columns go through their indices like its pattern
        // rows: copies of a few doubles by `copy_from_slice` were calls to
        // memcpy, 5% of the paper mesh's Newmark step.
        for blk in &d.blocks {
            // [y; δ] = F x_s; x_s ← y, x_pattern += δ.
            let (c0, k) = (blk.c0, blk.k);
            let out = &mut out[..8 * blk.f_lines];
            self.wide
                .product(d.f(blk), &xp[c0..c0 + k], blk.f_lines, out);
            let (cols, pattern) = d.index(blk).split_at(k);
            // SAFETY (here and below): every index is below n = xp.len()
            // (asserted in `with_panel`): the checks were a compare and a
            // branch per value moved, in loops of nothing but moves.
            for (&c, v) in cols.iter().zip(&out[..k]) {
                unsafe { *xp.get_unchecked_mut(c as usize) = *v };
            }
            for (&r, v) in pattern.iter().zip(&out[k..]) {
                unsafe { *xp.get_unchecked_mut(r as usize) += v };
            }
        }
        for blk in d.blocks.iter().rev() {
            // x_s ← Fᵀ [x_s; x_pattern].
            let k = blk.k;
            let index = d.index(blk);
            let out = if d.transposed {
                // By columns of the stored Fᵀ.
                let z = &mut z[..index.len()];
                for (zi, &r) in z.iter_mut().zip(index) {
                    *zi = unsafe { *xp.get_unchecked(r as usize) };
                }
                let out = &mut out[..8 * blk.g_lines];
                self.wide.product(d.g(blk), z, blk.g_lines, out);
                out
            } else {
                // As dot products with F's columns (F alone stored).
                let z = &mut lines[..blk.f_lines];
                for (line, rows) in z.iter_mut().zip(index.chunks(8)) {
                    line.0 = [0.0; 8];
                    for (zi, &r) in line.0.iter_mut().zip(rows) {
                        *zi = unsafe { *xp.get_unchecked(r as usize) };
                    }
                }
                let out = &mut out[..k];
                self.wide.dots(d.f(blk), z, blk.f_lines, k, out);
                out
            };
            for (&c, v) in index[..k].iter().zip(&out[..k]) {
                unsafe { *xp.get_unchecked_mut(c as usize) = *v };
            }
        }
        d.permute_out(xp, x);
    }

    /// Solves as [`BlockInverse::solve`] on the given width (tests).
    #[cfg(test)]
    fn solve_on(&mut self, wide: Wide, x: &mut [f64]) {
        let best = self.wide;
        self.wide = wide;
        self.solve(x);
        self.wide = best;
    }
}

impl Data {
    fn f(&self, blk: &Block) -> &[Line] {
        &self.values[blk.f_at..blk.f_at + blk.f_lines * blk.k]
    }

    fn g(&self, blk: &Block) -> &[Line] {
        &self.values[blk.g_at..blk.g_at + blk.g_lines * (blk.k + blk.m)]
    }

    /// The block's columns, then its pattern rows.
    fn index(&self, blk: &Block) -> &[u32] {
        &self.index[blk.index..blk.index + blk.k + blk.m]
    }

    fn permute_in(&self, x: &[f64], xp: &mut [f64]) {
        for (y, &f) in xp.iter_mut().zip(&self.fwd) {
            *y = x[f as usize];
        }
    }

    fn permute_out(&self, xp: &[f64], x: &mut [f64]) {
        for (y, &f) in xp.iter().zip(&self.fwd) {
            x[f as usize] = *y;
        }
    }
}

impl Wide {
    /// out = A v for A column-major on `lines` lines per column (v.len()
    /// columns): per lane the terms of the even columns summed in order,
    /// those of the odd columns likewise, then even + odd. Lines in
    /// groups of up to four, held in registers across the columns.
    #[inline(always)]
    #[allow(unsafe_code)]
    fn product(self, a: &[Line], v: &[f64], lines: usize, out: &mut [f64]) {
        let mut g = 0;
        while g < lines {
            macro_rules! group {
                ($n:literal) => {{
                    #[cfg(target_arch = "x86_64")]
                    if self == Wide::Avx512 {
                        // SAFETY: Avx512 only where the CPU has it (new).
                        unsafe { group_avx512::<$n>(a, v, lines, g, out) };
                        g += $n;
                        continue;
                    }
                    group_product::<$n>(a, v, lines, g, out);
                    g += $n;
                }};
            }
            match lines - g {
                1 => group!(1),
                2 => group!(2),
                3 => group!(3),
                _ => group!(4),
            }
        }
    }
}

impl Wide {
    /// out[j] = Σ_r A[r, j] z[r] for the `k` columns of A (column-major on
    /// `lines` lines per column, z on as many lines, zero where A's
    /// columns are padded): per column, lane l sums the terms of rows
    /// 8q + l in order of q, then the lanes pairwise, ((l0 + l1) + (l2 +
    /// l3)) + ((l4 + l5) + (l6 + l7)). Columns in groups of eight.
    #[inline(always)]
    #[allow(unsafe_code)]
    fn dots(self, a: &[Line], z: &[Line], lines: usize, k: usize, out: &mut [f64]) {
        let mut j = 0;
        while j < k {
            let cols = (k - j).min(8);
            #[cfg(target_arch = "x86_64")]
            if self == Wide::Avx512 {
                // SAFETY: Avx512 only where the CPU has it (new).
                unsafe { dots_avx512(&a[j * lines..(j + cols) * lines], z, lines, &mut out[j..]) };
                j += cols;
                continue;
            }
            dots_scalar(&a[j * lines..(j + cols) * lines], z, lines, &mut out[j..]);
            j += cols;
        }
    }
}

/// [`Wide::dots`] for up to eight columns (a.len() / lines of them).
fn dots_scalar(a: &[Line], z: &[Line], lines: usize, out: &mut [f64]) {
    for (col, o) in a.chunks_exact(lines).zip(out.iter_mut()) {
        let mut acc = [0.0f64; 8];
        for (line, zq) in col.iter().zip(z) {
            for l in 0..8 {
                acc[l] += line.0[l] * zq.0[l];
            }
        }
        *o = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
    }
}

/// [`dots_scalar`] with AVX-512: a register per column, the lanes summed
/// by three rounds of pairing across the eight registers, lane by lane
/// the same operations, so the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn dots_avx512(a: &[Line], z: &[Line], lines: usize, out: &mut [f64]) {
    use std::arch::x86_64::*;
    // SAFETY: lines are 64-byte aligned 8-double arrays.
    let load = |line: &Line| unsafe { _mm512_load_pd(line.0.as_ptr()) };
    let cols = a.len() / lines;
    let mut acc = [_mm512_setzero_pd(); 8];
    for q in 0..lines {
        let zq = load(&z[q]);
        for c in 0..8 {
            if c < cols {
                acc[c] = _mm512_add_pd(acc[c], _mm512_mul_pd(load(&a[c * lines + q]), zq));
            }
        }
    }
    // Round 1: [c0 (l0+l1), c1 (l0+l1), c0 (l2+l3), c1 (l2+l3), ...].
    let pair =
        |x: __m512d, y: __m512d| _mm512_add_pd(_mm512_unpacklo_pd(x, y), _mm512_unpackhi_pd(x, y));
    let (t01, t23, t45, t67) = (
        pair(acc[0], acc[1]),
        pair(acc[2], acc[3]),
        pair(acc[4], acc[5]),
        pair(acc[6], acc[7]),
    );
    // Round 2: 128-bit lanes 0, 2 of both plus lanes 1, 3 of both:
    // [c0 (0..3), c1 (0..3), c2 (0..3), c3 (0..3), c0 (4..7), c1 (4..7), ...].
    let quad = |x: __m512d, y: __m512d| {
        _mm512_add_pd(
            _mm512_shuffle_f64x2::<0b10_00_10_00>(x, y),
            _mm512_shuffle_f64x2::<0b11_01_11_01>(x, y),
        )
    };
    let (u0, u1) = (quad(t01, t23), quad(t45, t67));
    // Round 3: the low halves (rows 0..3) plus the high halves (rows 4..7):
    // [c0, c1, c2, c3, c4, c5, c6, c7].
    let total = _mm512_add_pd(
        _mm512_shuffle_f64x2::<0b10_00_10_00>(u0, u1),
        _mm512_shuffle_f64x2::<0b11_01_11_01>(u0, u1),
    );
    let mut sums = [0.0f64; 8];
    // SAFETY: sums holds 8 doubles.
    unsafe { _mm512_storeu_pd(sums.as_mut_ptr(), total) };
    out[..cols].copy_from_slice(&sums[..cols]);
}

/// Lines g..g + G of A v into out (see [`Wide::product`]).
#[inline(always)]
fn group_product<const G: usize>(a: &[Line], v: &[f64], lines: usize, g: usize, out: &mut [f64]) {
    let mut even = [[0.0f64; 8]; G];
    let mut odd = [[0.0f64; 8]; G];
    let pairs = a.chunks_exact(2 * lines);
    let last = pairs.remainder();
    let vj = v.chunks_exact(2);
    let v_last = vj.remainder();
    for (pair, ab) in vj.zip(pairs) {
        let (p, q): (&[Line; G], &[Line; G]) = (
            ab[g..g + G].try_into().expect("G lines"),
            ab[lines + g..lines + g + G].try_into().expect("G lines"),
        );
        for c in 0..G {
            for l in 0..8 {
                even[c][l] += p[c].0[l] * pair[0];
                odd[c][l] += q[c].0[l] * pair[1];
            }
        }
    }
    if let [v_last] = v_last {
        let p: &[Line; G] = last[g..g + G].try_into().expect("G lines");
        for c in 0..G {
            for l in 0..8 {
                even[c][l] += p[c].0[l] * v_last;
            }
        }
    }
    for c in 0..G {
        for l in 0..8 {
            out[8 * (g + c) + l] = even[c][l] + odd[c][l];
        }
    }
}

/// [`group_product`] with AVX-512: one register per line and sum, lane by
/// lane the same operations in the same order (multiplications and
/// additions separate), so the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
#[allow(unsafe_code)]
fn group_avx512<const G: usize>(a: &[Line], v: &[f64], lines: usize, g: usize, out: &mut [f64]) {
    use std::arch::x86_64::*;
    // SAFETY: lines are 64-byte aligned 8-double arrays.
    let load = |line: &Line| unsafe { _mm512_load_pd(line.0.as_ptr()) };
    let mut even = [_mm512_setzero_pd(); G];
    let mut odd = [_mm512_setzero_pd(); G];
    let pairs = a.chunks_exact(2 * lines);
    let last = pairs.remainder();
    let vj = v.chunks_exact(2);
    let v_last = vj.remainder();
    for (pair, ab) in vj.zip(pairs) {
        let (p, q): (&[Line; G], &[Line; G]) = (
            ab[g..g + G].try_into().expect("G lines"),
            ab[lines + g..lines + g + G].try_into().expect("G lines"),
        );
        let (x0, x1) = (_mm512_set1_pd(pair[0]), _mm512_set1_pd(pair[1]));
        for c in 0..G {
            even[c] = _mm512_add_pd(even[c], _mm512_mul_pd(load(&p[c]), x0));
            odd[c] = _mm512_add_pd(odd[c], _mm512_mul_pd(load(&q[c]), x1));
        }
    }
    if let [v_last] = v_last {
        let p: &[Line; G] = last[g..g + G].try_into().expect("G lines");
        let x0 = _mm512_set1_pd(*v_last);
        for c in 0..G {
            even[c] = _mm512_add_pd(even[c], _mm512_mul_pd(load(&p[c]), x0));
        }
    }
    let out = &mut out[8 * g..8 * (g + G)];
    for c in 0..G {
        // SAFETY: out holds 8·G doubles from 8·g (the slice above).
        unsafe { _mm512_storeu_pd(out[8 * c..].as_mut_ptr(), _mm512_add_pd(even[c], odd[c])) };
    }
}

/// v ← v − Σ_j f_j z_j over the columns of z (column-major, v.len() rows)
/// whose f_j ≠ 0: per entry the columns in order, each a multiplication
/// and a subtraction, so the AVX-512 path (32 rows at a time held in
/// registers across the columns) has the scalar bits. The stored-Z
/// correction of the Schur step (`schur.rs`).
#[allow(unsafe_code)]
pub(crate) fn minus_columns(v: &mut [f64], z: &[f64], f: &[f64]) {
    let n = v.len();
    assert_eq!(
        z.len(),
        n * f.len(),
        "z holds f.len() columns of v's length"
    );
    #[cfg(target_arch = "x86_64")]
    if crate::kernels::avx512() {
        // SAFETY: the CPU has AVX-512 (checked).
        let done = unsafe { minus_columns_avx512(v, z, f) };
        return minus_columns_from(done, v, z, f);
    }
    minus_columns_from(0, v, z, f);
}

/// [`minus_columns`] on rows `first..`.
fn minus_columns_from(first: usize, v: &mut [f64], z: &[f64], f: &[f64]) {
    let n = v.len();
    for (j, &fj) in f.iter().enumerate() {
        if fj != 0.0 {
            for (vi, zi) in v[first..].iter_mut().zip(&z[j * n + first..(j + 1) * n]) {
                *vi -= fj * zi;
            }
        }
    }
}

/// [`minus_columns`] on the rows in whole groups of 32, then of 8;
/// returns how many.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn minus_columns_avx512(v: &mut [f64], z: &[f64], f: &[f64]) -> usize {
    use std::arch::x86_64::*;
    let n = v.len();
    let whole = n / 32 * 32;
    for g in (0..whole).step_by(32) {
        let at = |s: &[f64], i: usize| -> __m512d {
            // SAFETY: i + 8 ≤ s.len() (a group of 32 within n rows).
            unsafe { _mm512_loadu_pd(s[i..i + 8].as_ptr()) }
        };
        let mut acc = [0, 8, 16, 24].map(|o| at(v, g + o));
        for (j, &fj) in f.iter().enumerate() {
            if fj != 0.0 {
                let fv = _mm512_set1_pd(fj);
                for (q, a) in acc.iter_mut().enumerate() {
                    *a = _mm512_sub_pd(*a, _mm512_mul_pd(fv, at(z, j * n + g + 8 * q)));
                }
            }
        }
        for (q, a) in acc.iter().enumerate() {
            // SAFETY: as the loads.
            unsafe { _mm512_storeu_pd(v[g + 8 * q..g + 8 * q + 8].as_mut_ptr(), *a) };
        }
    }
    // The rest by 8 rows (the paper mesh's 148: 20 rows, 12% of the
    // correction when they ran scalar).
    let eights = n / 8 * 8;
    for g in (whole..eights).step_by(8) {
        // SAFETY: g + 8 ≤ n, and z's column j holds n rows.
        let at = |s: &[f64], i: usize| unsafe { _mm512_loadu_pd(s[i..i + 8].as_ptr()) };
        let mut a = at(v, g);
        for (j, &fj) in f.iter().enumerate() {
            if fj != 0.0 {
                a = _mm512_sub_pd(a, _mm512_mul_pd(_mm512_set1_pd(fj), at(z, j * n + g)));
            }
        }
        // SAFETY: as the loads.
        unsafe { _mm512_storeu_pd(v[g..g + 8].as_mut_ptr(), a) };
    }
    eights
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::{Par, Side, Spec};
    use nalgebra_sparse::CsrMatrix;
    use stickslip_fem::testing::{plain_spmv, rectangle};
    use stickslip_fem::{Hypothesis, Material, Model};
    use stickslip_linalg::{analyze_symbolic, csc_view};
    use stickslip_mesh::CellKind;

    /// A₀ of the paper's Newmark step on a slab without every `drop`-th
    /// DOF (as if held; supernodes of odd width), with its factor.
    fn factored(
        kind: CellKind,
        nx: usize,
        ny: usize,
        drop: usize,
    ) -> (CsrMatrix<f64>, Supernodal, Vec<f64>) {
        let mesh = rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let model = Model::new(&mesh, &material, &[]).unwrap();
        let full = model.combined(0.5e-3, 1.0 / 0.5e-3);
        let kept: Vec<usize> = (0..full.nrows())
            .filter(|i| drop == usize::MAX || i % drop != 1)
            .collect();
        let mut index = vec![usize::MAX; full.nrows()];
        for (new, &old) in kept.iter().enumerate() {
            index[old] = new;
        }
        let mut coo = nalgebra_sparse::CooMatrix::new(kept.len(), kept.len());
        for (i, j, v) in full.triplet_iter() {
            if index[i] != usize::MAX && index[j] != usize::MAX {
                coo.push(index[i], index[j], *v);
            }
        }
        let a = CsrMatrix::from(&coo);
        let symbolic = analyze_symbolic(&a, &Default::default()).unwrap();
        let mut l = vec![0.0; symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_llt(
                &mut l,
                csc_view(&a, a.values()),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Spec::default(),
            )
            .unwrap();
        let sn = Supernodal::new(&symbolic).unwrap();
        (a, sn, l)
    }

    fn rhs(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0)
            .collect()
    }

    fn widths() -> Vec<Wide> {
        let mut w = vec![Wide::No];
        if crate::kernels::avx512() {
            w.push(Wide::Avx512);
        }
        w
    }

    /// A x = b to rounding (the residual against the matrix, relative to
    /// b), the same bits on every width, and the same x as the supernodal
    /// solve to 1e-12; Q1 and Q2, blocks of odd width (DOFs dropped), of
    /// more than 32 rows (more than one group of lines) and of several
    /// supernodes ([`PANEL`]).
    #[test]
    fn solves_the_system_on_every_width() {
        let (mut odd, mut long, mut merged) = (false, false, false);
        let (mut transposed, mut dots) = (false, false);
        for (kind, nx, ny, drop) in [
            (CellKind::Quad9, 8, 2, usize::MAX),
            (CellKind::Quad9, 8, 2, 7),
            (CellKind::Quad4, 24, 6, 5),
            (CellKind::Quad9, 32, 8, usize::MAX),
        ] {
            let (a, mut sn, l) = factored(kind, nx, ny, drop);
            let n = a.nrows();
            let mut inv = BlockInverse::new(&sn, &l);
            odd |= inv.data.blocks.iter().any(|b| b.k % 2 == 1);
            long |= inv.data.blocks.iter().any(|b| b.f_lines > 4);
            merged |= inv.data.blocks.len() < sn.supernodes();
            transposed |= inv.data.transposed;
            dots |= !inv.data.transposed;
            let b = rhs(n);
            let mut reference = b.clone();
            sn.solve(&l, &mut reference);
            let mut first: Option<Vec<f64>> = None;
            for w in widths() {
                let mut x = b.clone();
                inv.solve_on(w, &mut x);
                let ax = plain_spmv(&a, &x);
                let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let worst = ax
                    .iter()
                    .zip(&b)
                    .map(|(p, q)| (p - q).abs() / scale)
                    .fold(0.0, f64::max);
                assert!(worst < 1e-13, "{kind:?} {w:?}: residual {worst:e}");
                let xs = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (p, q) in x.iter().zip(&reference) {
                    assert!((p - q).abs() <= 1e-12 * xs, "{kind:?} {w:?}: {p} vs {q}");
                }
                match &first {
                    None => first = Some(x),
                    Some(f) => assert!(
                        f.iter().zip(&x).all(|(p, q)| p.to_bits() == q.to_bits()),
                        "{kind:?}: {w:?} differs from the scalar bits"
                    ),
                }
            }
        }
        assert!(
            odd && long && merged,
            "a block of odd width, one of more than 4 lines, one of several supernodes"
        );
        assert!(
            transposed && dots,
            "a factor with Fᵀ stored and one without"
        );
    }

    /// Timing lab (run by hand): one solve by the supernodal loops and by
    /// the inverted blocks, per mesh, with F's size, with Fᵀ stored and
    /// without ([`TRANSPOSED_MAX_VALUES`]), and by panels of other widths
    /// ([`PANEL`]).
    ///
    ///     cargo test --release -p stickslip-time --lib block_inverse_lab -- --ignored --nocapture
    #[test]
    #[ignore = "timing lab, run by hand"]
    fn block_inverse_lab() {
        for (kind, nx, ny) in [
            (CellKind::Quad9, 8, 2),
            (CellKind::Quad4, 24, 6),
            (CellKind::Quad9, 16, 4),
            (CellKind::Quad4, 48, 12),
            (CellKind::Quad9, 32, 8),
            (CellKind::Quad4, 96, 24),
            (CellKind::Quad9, 64, 16),
        ] {
            let (a, mut sn, l) = factored(kind, nx, ny, usize::MAX);
            let n = a.nrows();
            let mut inv = BlockInverse::new(&sn, &l);
            let b = rhs(n);
            let mut x = b.clone();
            let reps = (20_000_000 / l.len()).max(10);
            let mut time = |f: &mut dyn FnMut(&mut [f64])| {
                let mut t = Vec::new();
                for _ in 0..7 {
                    let s = std::time::Instant::now();
                    for _ in 0..reps {
                        x.copy_from_slice(&b);
                        f(&mut x);
                    }
                    t.push(s.elapsed().as_secs_f64() / reps as f64);
                }
                t.sort_by(f64::total_cmp);
                t[3]
            };
            let t_sn = time(&mut |x| sn.solve(&l, x));
            let t_inv = time(&mut |x| inv.solve(x));
            for stored in [true, false] {
                let mut other = BlockInverse::with_panel(&sn, &l, PANEL, Some(stored));
                let t = time(&mut |x| other.solve(x));
                println!(
                    "    {}: {} values, {:.2} us",
                    if stored { "F and Fᵀ" } else { "F alone " },
                    other.len(),
                    t * 1e6
                );
            }
            for kmax in [0, 8, 24, 32] {
                let mut other = BlockInverse::with_panel(&sn, &l, kmax, None);
                let t = time(&mut |x| other.solve(x));
                println!(
                    "    panels of ≤ {kmax} columns: {} blocks, {} values, {:.2} us",
                    other.data.blocks.len(),
                    other.len(),
                    t * 1e6
                );
            }
            println!(
                "{kind:?} {nx}x{ny}: n={n} L={} F={} ({:.0} KB): supernodal {:.2} us, inverted blocks {:.2} us ({:.2}x)",
                l.len(),
                inv.len(),
                inv.len() as f64 * 8e-3,
                t_sn * 1e6,
                t_inv * 1e6,
                t_sn / t_inv
            );
        }
    }

    /// The stored-Z correction: the same bits by 32-row groups and by
    /// scalar columns (rows not a multiple of 32, a zero f skipped), and
    /// v − Z f to rounding.
    #[test]
    fn minus_columns_has_the_scalar_bits() {
        for n in [5, 32, 70, 148] {
            let cols = 5;
            let z: Vec<f64> = (0..n * cols)
                .map(|i| ((i * 37) % 101) as f64 / 7.0 - 6.0)
                .collect();
            let f = [0.5, 0.0, -1.25, 3.0e-3, 7.0];
            let v0: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
            let mut fast = v0.clone();
            minus_columns(&mut fast, &z, &f);
            let mut plain = v0.clone();
            minus_columns_from(0, &mut plain, &z, &f);
            for i in 0..n {
                assert_eq!(fast[i].to_bits(), plain[i].to_bits(), "n = {n}, row {i}");
                let want: f64 = v0[i] - (0..cols).map(|j| f[j] * z[j * n + i]).sum::<f64>();
                assert!((fast[i] - want).abs() < 1e-12, "n = {n}, row {i}");
            }
        }
    }
}
