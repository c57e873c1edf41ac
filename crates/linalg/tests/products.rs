//! The products and sums of the fixed chunks (chunks.rs, csr.rs,
//! stencils.rs, paired.rs) against the plain sums over the stored entries, and the
//! same bits on one thread and on two.

use nalgebra_sparse::{CooMatrix, CsrMatrix};
use stickslip_linalg::chunks::{chunks, partials, sum_chunks, CHUNK};
use stickslip_linalg::csr::{index, quadratic_form, spmv};
use stickslip_linalg::{PairedKm, Product, Stencils, Symmetric, TOLERANCE};
use stickslip_testkit::{on_threads, plain_spmv, spread};

/// The chunked sum of a long vector is the same on one thread and on
/// two, and within rounding of the plain sum.
#[test]
fn sums_do_not_depend_on_the_threads() {
    let n = 5 * CHUNK + 17;
    let x: Vec<f64> = (0..n)
        .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.4)
        .collect();
    let sum = |threads: usize| {
        on_threads(threads, || {
            let mut p = partials::<1>(n);
            sum_chunks(n, &mut p, |_, rows, s| s[0] = rows.map(|i| x[i]).sum())[0]
        })
    };
    let (one, two) = (sum(1), sum(2));
    assert_eq!(one.to_bits(), two.to_bits());
    let plain: f64 = x.iter().sum();
    assert!((one - plain).abs() <= 1e-12 * n as f64);
}

/// A symmetric matrix with a few entries per row, long enough for
/// several chunks.
fn banded(n: usize) -> CsrMatrix<f64> {
    let mut coo = CooMatrix::new(n, n);
    for i in 0..n {
        coo.push(i, i, 4.0 + (i % 7) as f64);
        for d in [1, 5, 93] {
            if i + d < n {
                let v = -0.25 * d as f64;
                coo.push(i, i + d, v);
                coo.push(i + d, i, v);
            }
        }
    }
    CsrMatrix::from(&coo)
}

/// The products against a plain sum over the stored entries.
#[test]
fn products_and_forms_against_plain_sums() {
    let n = 3 * CHUNK + 101;
    let a = banded(n);
    let x: Vec<f64> = (0..n).map(|i| ((i * 31) % 17) as f64 - 8.0).collect();
    let y: Vec<f64> = (0..n).map(|i| ((i * 13) % 11) as f64 * 0.5).collect();
    let plain = plain_spmv(&a, &x);
    let mut ax = vec![0.0; n];
    spmv(&a, &x, &mut ax);
    for (p, q) in plain.iter().zip(&ax) {
        // Small integers and halves: every sum is exact.
        assert_eq!(p, q);
    }
    let mut partials = partials(n);
    let xax: f64 = x.iter().zip(&plain).map(|(a, b)| a * b).sum();
    assert!((quadratic_form(&a, &x, &mut partials) - xax).abs() <= 1e-12 * xax.abs());
    // No two rows share their columns: the paired passes sum every row
    // from the rest's CSR, in storage order, exactly here.
    let mut m = a.clone();
    for v in m.values_mut() {
        *v *= 0.75;
    }
    let km = PairedKm::new(&a, &m).expect("one pattern");
    assert_eq!(km.counts(), (0, a.nnz()));
    let my = plain_spmv(&m, &y);
    let (f1, f2) = km.two_forms(&x, &y, &mut partials);
    let ymy: f64 = y.iter().zip(&my).map(|(a, b)| a * b).sum();
    assert!((f1 - xax).abs() <= 1e-12 * xax.abs());
    assert!((f2 - ymy).abs() <= 1e-12 * ymy.abs());
    let l = vec![1.5; n];
    let mut out = vec![0.0; n];
    km.load_minus_k_plus_m(&l, &x, &y, &mut out);
    for i in 0..n {
        assert_eq!(out[i], l[i] - plain[i] + my[i]);
    }
    assert_eq!(index(&a, 0, 5), Some(2));
    assert_eq!(index(&a, 0, 2), None);
}

/// A grid of nx × ny nodes, two DOFs each, numbered node by node, row
/// by row, coupled to their 8 neighbours by 2×2 blocks as a Q1
/// stiffness couples them; `wobble` perturbs every value by up to that
/// relative amount (the rounding of a mesh's coordinates), `fixed`
/// removes the x DOF of the first node (a support: single DOFs).
fn grid(nx: usize, ny: usize, wobble: f64, fixed: bool) -> CsrMatrix<f64> {
    let node = |i: usize, j: usize| j * nx + i;
    let all = 2 * nx * ny;
    let skip = usize::from(fixed);
    let mut coo = CooMatrix::new(all - skip, all - skip);
    let mut k = 0u64;
    let mut jitter = || {
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        1.0 + wobble * ((k >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    };
    for j in 0..ny {
        for i in 0..nx {
            for dj in -1i64..=1 {
                for di in -1i64..=1 {
                    let (ii, jj) = (i as i64 + di, j as i64 + dj);
                    if ii < 0 || jj < 0 || ii >= nx as i64 || jj >= ny as i64 {
                        continue;
                    }
                    let (a, b) = (node(i, j), node(ii as usize, jj as usize));
                    for p in 0..2 {
                        for q in 0..2 {
                            let (r, c) = (2 * a + p, 2 * b + q);
                            if r < skip || c < skip {
                                continue;
                            }
                            let base = if a == b {
                                if p == q {
                                    8.0
                                } else {
                                    0.5
                                }
                            } else {
                                -1.0 - 0.25 * (p + q) as f64 - 0.1 * (di + 2 * dj) as f64
                            };
                            coo.push(r - skip, c - skip, base * jitter());
                        }
                    }
                }
            }
        }
    }
    CsrMatrix::from(&coo)
}

/// [`PairedKm::two_forms_and_products`] on `threads` threads: K x', M y'
/// and the forms (xᵀK x, yᵀM y).
fn fused(
    threads: usize,
    km: &PairedKm,
    x: [&[f64]; 2],
    y: [&[f64]; 2],
) -> (Vec<f64>, Vec<f64>, (f64, f64)) {
    let n = km.n();
    on_threads(threads, || {
        let (mut kx, mut my) = (vec![0.0; n], vec![0.0; n]);
        let mut sums = vec![[0.0; 2]; chunks(n)];
        let f = km.two_forms_and_products(x, y, [&mut kx, &mut my], &mut sums);
        (kx, my, f)
    })
}

/// A mass on `k`'s pattern: m_ab·I₂ between the DOFs of nodes a and b
/// (DOF i is node (i + skip) / 2's component (i + skip) % 2), and with
/// `skew`, every 37th node block's off-diagonal entries made non-zero.
fn node_mass(k: &CsrMatrix<f64>, skip: usize, skew: bool) -> CsrMatrix<f64> {
    let mut m = k.clone();
    let offsets = m.row_offsets().to_vec();
    let cols = m.col_indices().to_vec();
    for (i, vals) in offsets.windows(2).enumerate() {
        for p in vals[0]..vals[1] {
            let (r, c) = (i + skip, cols[p] + skip);
            let (a, b) = (r / 2, c / 2);
            let value = 1.0 + 0.125 * ((a + b) % 5) as f64 + 1e-3 * (a * b % 7) as f64;
            m.values_mut()[p] = if r % 2 == c % 2 {
                value
            } else if skew && (a + b) % 37 == 0 {
                0.01 * value
            } else {
                0.0
            };
        }
    }
    m
}

/// On a grid's pattern with a support's single DOF, and chunk seams: the
/// paired passes agree with the plain row sums within rounding, and with
/// each other in every bit (the forms of [`PairedKm::two_forms`] and of
/// the fused pass; K x' and M y' of the fused pass and of
/// [`PairedKm::load_minus_k_plus_m`]), on one thread and on two. M's
/// blocks of another shape than m·I₂ go to the rest and still agree.
#[test]
fn paired_passes_agree_with_the_row_sums_and_each_other() {
    let k = grid(300, 40, 1e-6, true);
    let n = k.nrows();
    assert!(chunks(n) > 2);
    let x = spread(n);
    let y: Vec<f64> = x.iter().map(|v| 1.0 - 0.3 * v).collect();
    let l: Vec<f64> = (0..n).map(|i| (i % 5) as f64 - 2.0).collect();
    for skew in [false, true] {
        let m = node_mass(&k, 1, skew);
        let km = PairedKm::new(&k, &m).expect("one pattern");
        let (blocks, rest) = km.counts();
        // Both paths run: most entries in blocks, the single DOF's row and
        // column (and the skewed blocks) in the rest.
        assert!(4 * blocks > k.nnz() * 9 / 10, "{blocks} blocks");
        assert!(rest > 0);
        let (kx, my) = (plain_spmv(&k, &y), plain_spmv(&m, &x));
        let scale = |a: &CsrMatrix<f64>, v: &[f64], i: usize| {
            let r = a.row(i);
            r.col_indices()
                .iter()
                .zip(r.values())
                .map(|(&j, w)| (w * v[j]).abs())
                .sum::<f64>()
        };
        let mut sums = partials(n);
        let forms = km.two_forms(&y, &x, &mut sums);
        let want_k: f64 = y.iter().zip(&kx).map(|(a, b)| a * b).sum();
        let want_m: f64 = x.iter().zip(&my).map(|(a, b)| a * b).sum();
        assert!((forms.0 - want_k).abs() <= 1e-12 * want_k.abs());
        assert!((forms.1 - want_m).abs() <= 1e-12 * want_m.abs());
        let mut b = vec![0.0; n];
        km.load_minus_k_plus_m(&l, &x, &y, &mut b);
        for threads in [1, 2] {
            let (fk, fm, f) = fused(threads, &km, [&y, &x], [&x, &y]);
            assert_eq!(f.0.to_bits(), forms.0.to_bits());
            assert_eq!(f.1.to_bits(), forms.1.to_bits());
            let (kx2, my2) = (plain_spmv(&k, &x), plain_spmv(&m, &y));
            for i in 0..n {
                assert!(
                    (fk[i] - kx2[i]).abs() <= 1e-14 * scale(&k, &x, i),
                    "row {i}"
                );
                assert!(
                    (fm[i] - my2[i]).abs() <= 1e-14 * scale(&m, &y, i),
                    "row {i}"
                );
                assert_eq!(b[i].to_bits(), (l[i] - fk[i] + fm[i]).to_bits(), "row {i}");
            }
        }
    }
}

/// Within TOLERANCE · max|K| · Σ|x| of the assembled product, row by
/// row, on a grid with rounding-sized wobble and a fixed DOF; few types.
#[test]
fn product_within_the_tolerance_of_the_assembled_one() {
    for fixed in [false, true] {
        let a = grid(300, 40, 1e-13, fixed);
        let s = Stencils::new(&a).expect("a structured grid has few stencils");
        assert!(s.types() < 40, "{} types", s.types());
        let n = a.nrows();
        let x = spread(n);
        let mut y = vec![0.0; n];
        s.spmv(&x, &mut y);
        let max = a.values().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let want = plain_spmv(&a, &x);
        for (i, r) in a.row_iter().enumerate() {
            let scale: f64 = r.col_indices().iter().map(|&j| x[j].abs()).sum();
            assert!(
                (y[i] - want[i]).abs() <= 2.0 * TOLERANCE * max * scale,
                "row {i}: {} against {}",
                y[i],
                want[i]
            );
        }
    }
}

/// Batches (here by the scalar path), single rows, one thread and two (by
/// the CPU's vectors): the same bits.
#[test]
fn rows_have_the_same_bits_every_way() {
    let a = grid(200, 60, 1e-13, true);
    let s = Stencils::new(&a).unwrap();
    let n = a.nrows();
    assert!(chunks(n) > 2);
    let x = spread(n);
    let on = |threads: usize| {
        on_threads(threads, || {
            let mut y = vec![0.0; n];
            s.spmv(&x, &mut y);
            y
        })
    };
    let (one, two) = (on(1), on(2));
    let mut batched = vec![f64::NAN; n];
    for c in 0..chunks(n) {
        s.batches(pulp::Scalar::new(), c, &x, &mut |r0: usize, ku: &[f64]| {
            batched[r0..r0 + ku.len()].copy_from_slice(ku)
        });
    }
    for i in 0..n {
        assert_eq!(one[i].to_bits(), two[i].to_bits(), "row {i}");
        assert_eq!(one[i].to_bits(), batched[i].to_bits(), "row {i}");
        assert_eq!(one[i].to_bits(), s.row(i, &x).to_bits(), "row {i}");
    }
}

/// Values that differ by more than the tolerance make types of their
/// own: a wobble of 1e-6 leaves too many for the types to pay.
#[test]
fn declines_what_has_no_structure() {
    assert!(Stencils::new(&grid(100, 20, 1e-6, false)).is_none());
}

/// On the structured Q1 and Q2 slabs (Q2's corner and mid-side node rows
/// alternate stencils), the product by the CPU's vectors (units of node
/// pairs where it has AVX or AVX-512) has the bits of the scalar path, on
/// every row, chunk seams and boundary rows included.
#[test]
fn vectors_have_the_scalar_bits_on_the_slabs() {
    use stickslip_testkit::{structured_slab, Slab};
    use stickslip_time::History;
    for (nx, ny, q2) in [(128, 32, false), (64, 16, true), (96, 24, true)] {
        let slab = Slab::paper(structured_slab(nx, ny, q2), 1e-4, History::Step, true).unwrap();
        let k = &slab.model.stiffness;
        let s = Stencils::new(k).expect("a structured slab has stencil types");
        let n = k.nrows();
        let x = spread(n);
        let mut vectors = vec![0.0; n];
        s.spmv(&x, &mut vectors);
        let mut scalar = vec![f64::NAN; n];
        for c in 0..chunks(n) {
            s.batches(pulp::Scalar::new(), c, &x, &mut |r0: usize, ku: &[f64]| {
                scalar[r0..r0 + ku.len()].copy_from_slice(ku)
            });
        }
        let all: Vec<usize> = (0..n).collect();
        let mut rows = vec![0.0; n];
        s.rows(&all, &x, &mut rows);
        for i in 0..n {
            assert_eq!(
                vectors[i].to_bits(),
                scalar[i].to_bits(),
                "q2 {q2}, row {i}"
            );
            assert_eq!(vectors[i].to_bits(), rows[i].to_bits(), "q2 {q2}, row {i}");
        }
        // Rows picked as a contact face's are (a node's x rows, runs of
        // consecutive groups, in both directions, duplicates allowed).
        for picked in [
            (0..n).step_by(2).collect::<Vec<usize>>(),
            (0..n).rev().step_by(3).collect(),
            vec![5, 5, 6, 0, n - 1, 7, 8, 9, 200, 3],
        ] {
            let mut out = vec![f64::NAN; picked.len()];
            s.rows(&picked, &x, &mut out);
            for (&i, o) in picked.iter().zip(&out) {
                assert_eq!(vectors[i].to_bits(), o.to_bits(), "q2 {q2}, picked row {i}");
            }
        }
    }
}

/// `grid`'s matrix made symmetric ((A + Aᵀ)/2: both triangles the same
/// bits) without the DOFs `drop` names: single rows among the node pairs.
fn symmetric_grid(nx: usize, ny: usize, drop: impl Fn(usize) -> bool) -> CsrMatrix<f64> {
    let a = grid(nx, ny, 1e-6, false);
    let t = a.transpose();
    let n = a.nrows();
    let mut index = vec![usize::MAX; n];
    let mut kept = 0;
    for (i, slot) in index.iter_mut().enumerate() {
        if !drop(i) {
            *slot = kept;
            kept += 1;
        }
    }
    let mut coo = CooMatrix::new(kept, kept);
    for (m, factor) in [(&a, 0.5), (&t, 0.5)] {
        for (i, j, v) in m.triplet_iter() {
            if index[i] != usize::MAX && index[j] != usize::MAX {
                coo.push(index[i], index[j], factor * v);
            }
        }
    }
    CsrMatrix::from(&coo)
}

/// The upper node blocks give the assembled product to rounding, with the
/// same bits on one thread and on two, and by the formed product's
/// batches and rows; on a narrow band and on one wider than a chunk (its
/// halos reach past the next chunk), with single rows among the pairs.
#[test]
fn symmetric_blocks_are_the_assembled_product() {
    for (nx, ny) in [(300, 60), (5000, 4)] {
        let a = symmetric_grid(nx, ny, |i| (i % 2 == 1 && i % 74 == 37) || i == 0);
        let n = a.nrows();
        assert!(n > 2 * CHUNK);
        let x = spread(n);
        let want = plain_spmv(&a, &x);
        let form = |threads: usize| {
            on_threads(threads, || {
                let mut p = Product::new(a.clone());
                assert_eq!(p.name(), "symmetric node blocks");
                let mut y = vec![0.0; n];
                p.spmv(&x, &mut y);
                let formed = p.form(&x);
                let mut whole = vec![f64::NAN; n];
                formed.spmv(&mut whole);
                let mut batches = vec![f64::NAN; n];
                for c in 0..chunks(n) {
                    formed.batches(pulp::Scalar::new(), c, &mut |r0: usize, ku: &[f64]| {
                        batches[r0..r0 + ku.len()].copy_from_slice(ku)
                    });
                }
                let all: Vec<usize> = (0..n).rev().collect();
                let mut rows = vec![f64::NAN; n];
                formed.rows(&all, &mut rows);
                rows.reverse();
                for i in 0..n {
                    for (way, v) in [
                        ("formed", whole[i]),
                        ("batches", batches[i]),
                        ("rows", rows[i]),
                    ] {
                        assert_eq!(y[i].to_bits(), v.to_bits(), "row {i} by {way}");
                    }
                }
                y
            })
        };
        let (one, two) = (form(1), form(2));
        for (i, r) in a.row_iter().enumerate() {
            // The same products summed in another order: well within
            // 1e-13 of Σ|K_ij x_j|.
            let scale: f64 = r
                .col_indices()
                .iter()
                .zip(r.values())
                .map(|(&j, v)| (v * x[j]).abs())
                .sum();
            assert!(
                (one[i] - want[i]).abs() <= 1e-13 * scale,
                "row {i}: {} against {}",
                one[i],
                want[i]
            );
            assert_eq!(one[i].to_bits(), two[i].to_bits(), "row {i}");
        }
    }
}

/// An unsymmetric matrix is not taken for a symmetric one: its product
/// is then the CSR.
#[test]
fn unsymmetric_matrices_keep_the_csr() {
    let a = grid(300, 40, 1e-6, false);
    assert!(Symmetric::new(&a).is_none());
    assert_eq!(Product::new(a).name(), "assembled CSR");
}
