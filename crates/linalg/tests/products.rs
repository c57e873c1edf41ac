//! The products and sums of the fixed chunks (chunks.rs, csr.rs,
//! stencils.rs) against the plain sums over the stored entries, and the
//! same bits on one thread and on two.

use nalgebra_sparse::{CooMatrix, CsrMatrix};
use stickslip_linalg::chunks::{chunks, partials, sum_chunks, CHUNK};
use stickslip_linalg::csr::{
    index, load_minus_k_plus_m, quadratic_form, spmv, two_forms, two_forms_and_products,
};
use stickslip_linalg::{Product, Stencils, Symmetric, TOLERANCE};
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
    let (f1, f2) = two_forms(&a, &x, &a, &y, &mut partials);
    assert_eq!(
        f1.to_bits(),
        quadratic_form(&a, &x, &mut partials).to_bits()
    );
    assert_eq!(
        f2.to_bits(),
        quadratic_form(&a, &y, &mut partials).to_bits()
    );
    let l = vec![1.5; n];
    let mut out = vec![0.0; n];
    load_minus_k_plus_m(&l, &a, &x, &a, &y, &mut out);
    let mut ay = vec![0.0; n];
    spmv(&a, &y, &mut ay);
    for i in 0..n {
        assert_eq!(out[i].to_bits(), (l[i] - ax[i] + ay[i]).to_bits());
    }
    // The fused pass: the forms of (x, y) and the products of (y, x), each
    // with the bits of the passes it replaces, on one thread and on two.
    let mut m = a.clone();
    for v in m.values_mut() {
        *v *= 0.75;
    }
    let l0 = vec![0.0; n];
    let mut want = vec![0.0; n];
    load_minus_k_plus_m(&l0, &a, &y, &m, &x, &mut want);
    let forms = two_forms(&a, &x, &m, &y, &mut partials);
    for threads in [1, 2] {
        let (kx, mx, f) = fused(threads, &a, [&x, &y], &m, [&y, &x]);
        assert_eq!(f.0.to_bits(), forms.0.to_bits());
        assert_eq!(f.1.to_bits(), forms.1.to_bits());
        for i in 0..n {
            assert_eq!(want[i].to_bits(), (l0[i] - kx[i] + mx[i]).to_bits());
        }
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

/// [`two_forms_and_products`] on `threads` threads: K x', M y' and the
/// forms (xᵀK x, yᵀM y).
fn fused(
    threads: usize,
    k: &CsrMatrix<f64>,
    x: [&[f64]; 2],
    m: &CsrMatrix<f64>,
    y: [&[f64]; 2],
) -> (Vec<f64>, Vec<f64>, (f64, f64)) {
    let n = k.nrows();
    on_threads(threads, || {
        let (mut kx, mut my) = (vec![0.0; n], vec![0.0; n]);
        let mut sums = vec![[0.0; 2]; chunks(n)];
        let f = two_forms_and_products(k, x, m, y, [&mut kx, &mut my], &mut sums);
        (kx, my, f)
    })
}

/// On a grid's pattern, where most groups of four columns are consecutive
/// (runs of nodes along a row, read as one load), the fused rows keep the
/// bits of the plain row sums (`spmv`, `quadratic_form`), on one thread
/// and on two.
#[test]
fn fused_rows_keep_the_row_sums_bits_on_runs_of_columns() {
    let k = grid(300, 40, 1e-6, true);
    let mut m = k.clone();
    for (i, v) in m.values_mut().iter_mut().enumerate() {
        *v *= 0.5 + (i % 3) as f64 * 0.125;
    }
    let n = k.nrows();
    assert!(chunks(n) > 2);
    // The case the loads serve must occur: groups of four consecutive
    // columns at a row's start.
    let runs = (0..n)
        .filter(|&i| {
            let c = &k.col_indices()[k.row_offsets()[i]..k.row_offsets()[i + 1]];
            c.len() >= 4 && c[3] == c[0] + 3
        })
        .count();
    assert!(runs > n / 2, "{runs} of {n} rows");
    let x = spread(n);
    let y: Vec<f64> = x.iter().map(|v| 1.0 - 0.3 * v).collect();
    let (mut kx, mut my) = (vec![0.0; n], vec![0.0; n]);
    spmv(&k, &x, &mut kx);
    spmv(&m, &y, &mut my);
    let mut sums = partials(n);
    let forms = (
        quadratic_form(&k, &y, &mut sums),
        quadratic_form(&m, &x, &mut sums),
    );
    let l: Vec<f64> = (0..n).map(|i| (i % 5) as f64 - 2.0).collect();
    let mut b = vec![0.0; n];
    load_minus_k_plus_m(&l, &k, &x, &m, &y, &mut b);
    for i in 0..n {
        assert_eq!(b[i].to_bits(), (l[i] - kx[i] + my[i]).to_bits(), "row {i}");
    }
    for threads in [1, 2] {
        let (fk, fm, f) = fused(threads, &k, [&y, &x], &m, [&x, &y]);
        assert_eq!(f.0.to_bits(), forms.0.to_bits());
        assert_eq!(f.1.to_bits(), forms.1.to_bits());
        for i in 0..n {
            assert_eq!(fk[i].to_bits(), kx[i].to_bits(), "row {i}");
            assert_eq!(fm[i].to_bits(), my[i].to_bits(), "row {i}");
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
