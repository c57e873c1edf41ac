//! K·x by stencil types (issue 7, the explicit step on structured meshes).
//!
//! On a structured mesh most of K's row groups (a node's two rows,
//! [`kernels::row_groups`]) are the same stencil: the same blocks at the
//! same column offsets from the group's first row, equal up to the rounding
//! of the coordinates they were assembled from (the Q1 slab of 1M DOFs has
//! 211,770 bit-distinct blocks of 4.5M, nearly all of them one of nine
//! values to 1e-13). [`Stencils`] keeps one copy of each distinct stencil
//! (a *type*: groups alike when their row count and block offsets are equal
//! and every block value is within [`TOLERANCE`] · max |K_ij| of the type's
//! first member) and per group only its type, so a product streams 8 bytes
//! per group (first row, type) instead of the blocks, and reads the blocks
//! of the few types from L1. Rows are independent and each is summed in its
//! type's block order whatever batch or thread computes it: the same bits
//! on any number of threads. Not the bits of the assembled K's product:
//! within [`TOLERANCE`] · max |K_ij| · Σ_j |x_j| over the row's columns of
//! it (tests below); the classes of `stickslip_fem::ElementClasses` make the
//! same trade on Q2 meshes.
//!
//! Declined ([`Stencils::new`] returns `None`) when the types would not
//! shrink the matrix: unstructured meshes, where nearly every group is its
//! own stencil.

use std::collections::HashMap;

use nalgebra_sparse::CsrMatrix;

use crate::kernels::{self, RowProduct, BATCH};

/// Block values within this fraction of max |K_ij| of a type's are the
/// type's (measured: the Q1 and Q2 slabs' stencils spread by up to ~1e-13
/// relative; see `stencil_types_on_the_slabs`).
pub const TOLERANCE: f64 = 1e-12;

/// The coarse grid, in tolerances, on which a stencil's values are hashed
/// (alike stencils land in one bucket unless a value straddles a grid
/// line, which costs a type, never a wrong merge: members are compared to
/// the tolerance).
const COARSE: f64 = (1u64 << 24) as f64;

/// Groups of one type summed in lockstep ([`Stencils::lockstep`]).
const LOCKSTEP: usize = 4;

/// K by stencil types (module documentation).
#[derive(Clone, Debug)]
pub struct Stencils {
    /// First row of each group, then n.
    group_rows: Vec<u32>,
    /// Type of each group.
    types: Vec<u32>,
    /// Blocks of type t: type_blocks[t]..type_blocks[t + 1].
    type_blocks: Vec<u32>,
    /// Each type block's first column minus its group's first row.
    offsets: Vec<i32>,
    /// Each type block's values, by columns (as `kernels::block` reads them).
    values: Vec<[f64; 4]>,
    /// Groups of chunk c: chunk_groups[c]..chunk_groups[c + 1].
    chunk_groups: Vec<u32>,
    /// The CPU has AVX (checked at run time): runs of four node pairs of
    /// one type are summed 4 doubles wide ([`avx::quad`]), the same bits.
    avx: bool,
}

impl Stencils {
    /// The stencil types of a square CSR matrix with sorted columns at
    /// [`TOLERANCE`], or `None` when they do not cut the bytes a product
    /// streams from the matrix by at least 4× against its blocks stored.
    pub fn new(a: &CsrMatrix<f64>) -> Option<Stencils> {
        Stencils::with_tolerance(a, TOLERANCE)
    }

    /// [`Stencils::new`] at tolerance `tol` (relative to max |K_ij|; 0:
    /// equal bits only).
    pub fn with_tolerance(a: &CsrMatrix<f64>, tol: f64) -> Option<Stencils> {
        // Types may hold at most 1/8 of the stored blocks (36 bytes each
        // with the offset): then the types and the 8 bytes per group are
        // at most about a quarter of the stored form's stream.
        Stencils::build(a, tol, (a.nnz() / 32).max(64))
    }

    /// The types at tolerance `tol`, `None` past `limit` type blocks.
    fn build(a: &CsrMatrix<f64>, tol: f64, limit: usize) -> Option<Stencils> {
        let n = a.nrows();
        if n < 2 || a.ncols() != n || n >= i32::MAX as usize {
            return None;
        }
        let max = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let tol = tol * max;
        let grid = if tol > 0.0 { COARSE * tol } else { f64::NAN };
        let mut index: HashMap<Vec<i64>, Vec<u32>> = HashMap::new();
        let mut key: Vec<i64> = Vec::new();
        let (mut types, mut type_blocks) = (Vec::with_capacity(n / 2 + 1), vec![0u32]);
        let (mut offsets, mut values): (Vec<i32>, Vec<[f64; 4]>) = (Vec::new(), Vec::new());
        let mut declined = false;
        let group_rows = kernels::row_groups(a, |r0, r1, cols, vals| {
            if declined {
                return;
            }
            key.clear();
            key.extend([(r1 - r0) as i64, cols.len() as i64]);
            for (&c, v) in cols.iter().zip(vals) {
                key.push(c as i64 - r0 as i64);
                for &x in v {
                    // Equal bits only at tol = 0 (NaN grid).
                    key.push(if grid.is_nan() {
                        x.to_bits() as i64
                    } else {
                        (x / grid).round() as i64
                    });
                }
            }
            let alike = |t: u32| {
                let b = type_blocks[t as usize] as usize..type_blocks[t as usize + 1] as usize;
                values[b]
                    .iter()
                    .zip(vals)
                    .all(|(p, q)| (0..4).all(|k| (p[k] - q[k]).abs() <= tol))
            };
            let found = index
                .get(&key)
                .and_then(|ts| ts.iter().copied().find(|&t| alike(t)));
            let t = match found {
                Some(t) => t,
                None => {
                    let t = (type_blocks.len() - 1) as u32;
                    offsets.extend(cols.iter().map(|&c| (c as i64 - r0 as i64) as i32));
                    values.extend_from_slice(vals);
                    type_blocks.push(values.len() as u32);
                    index.entry(key.clone()).or_default().push(t);
                    declined = values.len() > limit;
                    t
                }
            };
            types.push(t);
        });
        if declined {
            return None;
        }
        let chunk_groups = kernels::chunk_groups(&group_rows, n);
        types.shrink_to_fit();
        Some(Stencils {
            group_rows,
            types,
            type_blocks,
            offsets,
            values,
            chunk_groups,
            avx: avx::available(),
        })
    }

    /// Distinct stencils.
    pub fn types(&self) -> usize {
        self.type_blocks.len() - 1
    }

    /// The sums of group g's rows (the second is 0 for a single row).
    #[inline(always)]
    fn group_sums(&self, g: usize, x: &[f64]) -> [f64; 2] {
        let t = self.types[g] as usize;
        let r0 = self.group_rows[g] as isize;
        let b = self.type_blocks[t] as usize..self.type_blocks[t + 1] as usize;
        let mut s = [0.0; 2];
        for (&o, v) in self.offsets[b.clone()].iter().zip(&self.values[b]) {
            kernels::block((r0 + o as isize) as u32, *v, x, &mut s);
        }
        s
    }

    /// G groups of one type in lockstep: 2G independent chains of
    /// additions (one chain alone waits on the adder's latency), each row's
    /// order unchanged, the type's blocks loaded once for all.
    #[inline(always)]
    fn lockstep<const G: usize>(&self, g: usize, x: &[f64]) -> [[f64; 2]; G] {
        let t = self.types[g] as usize;
        let r: [isize; G] = std::array::from_fn(|q| self.group_rows[g + q] as isize);
        let b = self.type_blocks[t] as usize..self.type_blocks[t + 1] as usize;
        let mut s = [[0.0; 2]; G];
        for (&o, v) in self.offsets[b.clone()].iter().zip(&self.values[b]) {
            let o = o as isize;
            for q in 0..G {
                kernels::block((r[q] + o) as u32, *v, x, &mut s[q]);
            }
        }
        s
    }

    /// K x on the rows of groups g0..g1 into `out` (from g0's first row).
    #[inline(always)]
    fn groups_into(&self, g0: usize, g1: usize, x: &[f64], out: &mut [f64]) {
        let base = self.group_rows[g0] as usize;
        let mut put = |g: usize, s: [f64; 2]| {
            let (r0, r1) = (self.group_rows[g] as usize, self.group_rows[g + 1] as usize);
            out[r0 - base] = s[0];
            if r1 - r0 == 2 {
                out[r0 + 1 - base] = s[1];
            }
        };
        let mut g = g0;
        while g < g1 {
            let t = self.types[g];
            let alike = |k: usize| g + k <= g1 && self.types[g + 1..g + k].iter().all(|&u| u == t);
            let ty = |t: u32| {
                let b = self.type_blocks[t as usize] as usize
                    ..self.type_blocks[t as usize + 1] as usize;
                (&self.offsets[b.clone()], &self.values[b])
            };
            let pairs = |k: usize| self.group_rows[g + k] == self.group_rows[g] + 2 * k as u32;
            if self.avx && alike(4) && pairs(4) {
                // Four node pairs of one type on consecutive rows (Q1).
                let (o, v) = ty(t);
                let sums = avx::run(o, v, avx::Rows::Consecutive(self.group_rows[g] as usize), x);
                for (q, s) in sums.into_iter().enumerate() {
                    put(g + q, s);
                }
                g += 4;
            } else if self.avx
                && g + 8 <= g1
                && pairs(8)
                && (2..8).all(|k| self.types[g + k] == self.types[g + k % 2])
            {
                // Eight node pairs of two types in turn (a Q2 node row:
                // vertex and edge nodes, or edge and centre nodes).
                let r = self.group_rows[g] as usize;
                for (p, t) in [(0, t), (1, self.types[g + 1])] {
                    let (o, v) = ty(t);
                    let rows = std::array::from_fn(|q| r + 2 * p + 4 * q);
                    let sums = avx::run(o, v, avx::Rows::Any(rows), x);
                    for (q, s) in sums.into_iter().enumerate() {
                        put(g + p + 2 * q, s);
                    }
                }
                g += 8;
            } else if alike(LOCKSTEP) {
                for (q, s) in self.lockstep::<LOCKSTEP>(g, x).into_iter().enumerate() {
                    put(g + q, s);
                }
                g += LOCKSTEP;
            } else {
                put(g, self.group_sums(g, x));
                g += 1;
            }
        }
    }
}

/// The 4-wide sums of four node pairs of one type.
mod avx {
    /// The first rows of the four pairs.
    #[derive(Clone, Copy)]
    pub enum Rows {
        /// r, r + 2, r + 4, r + 6.
        Consecutive(usize),
        /// Anywhere.
        Any([usize; 4]),
    }

    /// Whether this CPU runs [`quad`].
    pub fn available() -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// [`quad`] on a CPU where [`available`] said yes.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn run(offsets: &[i32], values: &[[f64; 4]], rows: Rows, x: &[f64]) -> [[f64; 2]; 4] {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: callers hold `Stencils::avx`, set from `available()`.
            unsafe {
                match rows {
                    Rows::Consecutive(r) => quad::<true>(offsets, values, [r; 4], x),
                    Rows::Any(rows) => quad::<false>(offsets, values, rows, x),
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (offsets, values, rows, x);
            unreachable!("AVX is x86_64 only")
        }
    }

    /// The sums of four node pairs of one type (blocks at `offsets` with
    /// `values`) at `rows` (`CONSECUTIVE`: rows[0] + 2q), each row's
    /// products added in `kernels::block`'s order (column c, then c + 1),
    /// multiplications and additions separate (no fused multiply-add): the
    /// bits of the scalar sums. Two pairs per 4-wide register; consecutive
    /// pairs read x[c..c + 4] in one load.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[allow(unsafe_code)]
    fn quad<const CONSECUTIVE: bool>(
        offsets: &[i32],
        values: &[[f64; 4]],
        rows: [usize; 4],
        x: &[f64],
    ) -> [[f64; 2]; 4] {
        use std::arch::x86_64::*;
        let mut s = [_mm256_setzero_pd(); 2];
        for (&o, v) in offsets.iter().zip(values) {
            let o = o as isize;
            // [x_c, x_c+1] of pairs 2h and 2h + 1.
            let xs: [__m256d; 2] = std::array::from_fn(|h| {
                if CONSECUTIVE {
                    let c = (rows[0] as isize + o) as usize + 4 * h;
                    let xs: &[f64; 4] = x[c..c + 4].try_into().expect("4 columns");
                    // SAFETY: xs holds 4 doubles; unaligned load.
                    unsafe { _mm256_loadu_pd(xs.as_ptr()) }
                } else {
                    let col = |q: usize| (rows[q] as isize + o) as usize;
                    let (c0, c1) = (col(2 * h), col(2 * h + 1));
                    let (a, b): (&[f64; 2], &[f64; 2]) = (
                        x[c0..c0 + 2].try_into().expect("2 columns"),
                        x[c1..c1 + 2].try_into().expect("2 columns"),
                    );
                    // SAFETY: a and b hold 2 doubles each; unaligned loads.
                    unsafe {
                        _mm256_insertf128_pd(
                            _mm256_castpd128_pd256(_mm_loadu_pd(a.as_ptr())),
                            _mm_loadu_pd(b.as_ptr()),
                            1,
                        )
                    }
                }
            });
            // [v0, v1, v0, v1] and [v2, v3, v2, v3]: rows 0 and 1 of the
            // block's first and second column, for two pairs.
            let c0 = _mm256_setr_pd(v[0], v[1], v[0], v[1]);
            let c1 = _mm256_setr_pd(v[2], v[3], v[2], v[3]);
            for h in 0..2 {
                let lo = _mm256_unpacklo_pd(xs[h], xs[h]);
                s[h] = _mm256_add_pd(s[h], _mm256_mul_pd(c0, lo));
            }
            for h in 0..2 {
                let hi = _mm256_unpackhi_pd(xs[h], xs[h]);
                s[h] = _mm256_add_pd(s[h], _mm256_mul_pd(c1, hi));
            }
        }
        let mut out = [0.0; 8];
        // SAFETY: out holds 8 doubles.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), s[0]);
            _mm256_storeu_pd(out.as_mut_ptr().add(4), s[1]);
        }
        std::array::from_fn(|q| [out[2 * q], out[2 * q + 1]])
    }
}

impl RowProduct for Stencils {
    #[inline]
    fn chunk_batches(&self, c: usize, x: &[f64], mut f: impl FnMut(usize, &[f64])) {
        let (g0, g1) = (
            self.chunk_groups[c] as usize,
            self.chunk_groups[c + 1] as usize,
        );
        let mut buf = [0.0; BATCH];
        let mut g = g0;
        while g < g1 {
            let gb = (g + BATCH / 2).min(g1);
            let (ra, rb) = (self.group_rows[g] as usize, self.group_rows[gb] as usize);
            let out = &mut buf[..rb - ra];
            self.groups_into(g, gb, x, out);
            f(ra, out);
            g = gb;
        }
    }

    fn row(&self, i: usize, x: &[f64]) -> f64 {
        let g = self.group_rows.partition_point(|&r| r as usize <= i) - 1;
        let s = self.group_sums(g, x);
        if i == self.group_rows[g] as usize {
            s[0]
        } else {
            s[1]
        }
    }

    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        kernels::each_chunk(y, |c, y| {
            let (g0, g1) = (
                self.chunk_groups[c] as usize,
                self.chunk_groups[c + 1] as usize,
            );
            self.groups_into(g0, g1, x, y);
        });
    }

    fn bytes(&self) -> usize {
        4 * (self.group_rows.len() + self.types.len() + self.chunk_groups.len())
            + 4 * self.type_blocks.len()
            + 36 * self.values.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::spmv;
    use stickslip_fem::testing::on_threads;
    use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
    use stickslip_mesh::Mesh;

    fn x_of(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i as f64 * 0.618_033_988_75).fract() - 0.5) * (1.0 + i as f64 * 1e-3))
            .collect()
    }

    /// Every row within TOLERANCE · max|K| · Σ_j |x_j| (its columns) of the
    /// CSR's product, and the rows alone and on two threads the same bits.
    fn check(k: &CsrMatrix<f64>, s: &Stencils, name: &str) {
        let n = k.nrows();
        let x = x_of(n);
        let mut y0 = vec![0.0; n];
        spmv(k, &x, &mut y0);
        let max = k.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let (o, c) = (k.row_offsets(), k.col_indices());
        let mut y1 = vec![0.0; n];
        on_threads(1, || s.spmv(&x, &mut y1));
        let mut y2 = vec![0.0; n];
        on_threads(2, || s.spmv(&x, &mut y2));
        let mut y3 = vec![0.0; n];
        on_threads(2, || {
            kernels::each_chunk(&mut y3, |ch, y| {
                s.chunk_batches(ch, &x, |r0, ku| {
                    y[r0 - ch * kernels::CHUNK..][..ku.len()].copy_from_slice(ku)
                })
            })
        });
        for i in 0..n {
            // A block of a single-DOF column reads its neighbour too.
            let xs: f64 = (o[i]..o[i + 1])
                .flat_map(|p| (c[p].saturating_sub(1)..(c[p] + 2).min(n)).map(|j| x[j].abs()))
                .sum();
            // Rounding of the sums themselves: ~25 terms.
            let bound = TOLERANCE * max * xs + 64.0 * f64::EPSILON * max * xs;
            assert!(
                (y0[i] - y1[i]).abs() <= bound,
                "{name} row {i}: {} vs {} (bound {bound:.2e})",
                y1[i],
                y0[i]
            );
            assert_eq!(y1[i].to_bits(), y2[i].to_bits(), "{name} row {i} threads");
            assert_eq!(y1[i].to_bits(), y3[i].to_bits(), "{name} row {i} batches");
            assert_eq!(y1[i].to_bits(), s.row(i, &x).to_bits(), "{name} row {i}");
        }
    }

    /// The slab's supports: u_y fixed on `support`, u_x on "left".
    fn slab_model(mesh: &Mesh, support: &str) -> Model {
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let supports = [
            Dirichlet::new(support, 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        Model::new(mesh, &material, &supports).unwrap()
    }

    /// Structured slabs (the bench's numbering, row by row, and the
    /// committed Gmsh Q1 slab, boundary nodes numbered first): few types,
    /// products within the tolerance of the CSR's, the same bits on 1 and
    /// 2 threads, by batches and row by row, for K and M; with tolerance 0
    /// (equal bits only) the product is the CSR's to the last bit (the
    /// blocks' order and padding are the compact form's).
    #[test]
    fn stencil_types_on_the_slabs() {
        use stickslip_fem::testing::rectangle;
        use stickslip_mesh::CellKind;
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        let rect = |kind, nx, ny| rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
        let meshes = [
            ("q1 128x32", rect(CellKind::Quad4, 128, 32), "top"),
            ("q2 64x16", rect(CellKind::Quad9, 64, 16), "top"),
            ("q1 200x50", rect(CellKind::Quad4, 200, 50), "top"),
            (
                "slab-q1-128x32.msh",
                Mesh::from_file(dir.join("slab-q1-128x32.msh")).unwrap(),
                "support",
            ),
        ];
        for (name, mesh, support) in meshes {
            let model = slab_model(&mesh, support);
            for k in [&model.stiffness, &model.mass] {
                let s = Stencils::new(k).expect("structured: applies");
                // Types on the boundary rows (Gmsh numbers those nodes
                // first: more of them), one inside.
                let groups = s.types.len();
                assert!(6 * s.types() <= groups, "{name}: {} types", s.types());
                check(k, &s, name);
                let exact = Stencils::build(k, 0.0, usize::MAX).unwrap();
                assert!(exact.types() > s.types(), "{name}");
                let x = x_of(k.nrows());
                let (mut y0, mut y1) = (vec![0.0; k.nrows()], vec![0.0; k.nrows()]);
                spmv(k, &x, &mut y0);
                exact.spmv(&x, &mut y1);
                for i in 0..k.nrows() {
                    assert_eq!(y0[i].to_bits(), y1[i].to_bits(), "{name} row {i} exact");
                }
            }
        }
    }

    /// Unstructured meshes: nearly every group its own stencil, declined.
    #[test]
    fn stencils_decline_unstructured_meshes() {
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        for name in ["slab-unstructured-q1.msh", "slab-unstructured-q2.msh"] {
            let mesh = Mesh::from_file(dir.join(name)).unwrap();
            let model = slab_model(&mesh, "support");
            assert!(Stencils::new(&model.stiffness).is_none(), "{name}");
        }
    }
}
