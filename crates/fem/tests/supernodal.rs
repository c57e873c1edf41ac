//! The supernodal solves of `stickslip-linalg` on the operators of finite-element
//! models: against faer's own solve and against the matrix.
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par, Side, Spec};
use nalgebra_sparse::CsrMatrix;
use stickslip_fem::Model;
use stickslip_linalg::*;
use stickslip_mesh::CellKind;
use stickslip_testkit::{on_threads, paper_material, plain_spmv, rectangle, spread};

fn operator(kind: CellKind, nx: usize, ny: usize) -> CsrMatrix<f64> {
    let mesh = rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
    let material = paper_material();
    let model = Model::new(&mesh, &material, &[]).unwrap();
    // A₀ of the paper's Newmark step: (β/γ)Δt K + M/(γΔt), Δt = 1e-3.
    model.combined(0.5e-3, 1.0 / 0.5e-3)
}

fn as_csc(a: &CsrMatrix<f64>) -> SparseColMatRef<'_, usize, f64> {
    stickslip_linalg::csc_view(a, a.values())
}

struct Factor {
    symbolic: SymbolicCholesky<usize>,
    l: Vec<f64>,
}

fn factor(a: &CsrMatrix<f64>) -> Factor {
    let symbolic =
        stickslip_linalg::analyze_symbolic(a, &stickslip_linalg::FillOrder::default()).unwrap();
    let mut l = vec![0.0; symbolic.len_val()];
    let mut scratch =
        MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
    symbolic
        .factorize_numeric_llt(
            &mut l,
            as_csc(a),
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut scratch),
            Spec::default(),
        )
        .unwrap();
    Factor { symbolic, l }
}

fn faer_solve(f: &Factor, x: &mut [f64]) {
    let n = x.len();
    let mut scratch = MemBuffer::new(f.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
    LltRef::<'_, usize, f64>::new(&f.symbolic, &f.l).solve_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(x, n, 1),
        Par::Seq,
        MemStack::new(&mut scratch),
    );
}

fn residual(a: &CsrMatrix<f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut worst: f64 = 0.0;
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (ax, bi) in plain_spmv(a, x).iter().zip(b) {
        worst = worst.max((ax - bi).abs() / scale);
    }
    worst
}

/// The solve satisfies A x = b (residual against the matrix, not
/// against faer) and agrees with faer's solve, Q1 and Q2.
#[test]
fn solves_like_faer() {
    for (kind, nx, ny) in [(CellKind::Quad4, 24, 6), (CellKind::Quad9, 8, 2)] {
        let a = operator(kind, nx, ny);
        let f = factor(&a);
        let mut sn = Supernodal::new(&f.symbolic).expect("forced supernodal");
        let b = spread(a.nrows());
        let mut x = b.clone();
        sn.solve(&f.l, &mut x);
        assert!(residual(&a, &x, &b) < 1e-12, "{kind:?}");
        let mut y = b.clone();
        faer_solve(&f, &mut y);
        let d = x
            .iter()
            .zip(&y)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        let s = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(d <= 1e-12 * s, "{kind:?}: {d} against {s}");
    }
}

/// The split step (forward, back on the reach, forward on the reach,
/// back) gives A⁻¹b at the reach DOFs and A⁻¹(b − c) in the end.
#[test]
fn split_step_matches_two_solves() {
    let a = operator(CellKind::Quad4, 24, 6);
    let n = a.nrows();
    let f = factor(&a);
    let mut sn = Supernodal::new(&f.symbolic).unwrap();
    // The bottom edge's x DOFs (nodes 0..=24 of the rectangle): DOF 2i.
    let dofs: Vec<usize> = (0..=24).map(|i| 2 * i).collect();
    sn.set_reach(&dofs);
    assert!(sn.reach_len() < f.l.len(), "the reach is part of the tree");
    let b = spread(n);
    let perm = sn.permuted_indices();
    sn.begin_reach(&f.l, &b);
    let mut full = b.clone();
    faer_solve(&f, &mut full);
    for &d in &dofs {
        let v = sn.reach_value(perm[d]);
        assert!((v - full[d]).abs() <= 1e-12 * full[d].abs().max(1.0), "{d}");
    }
    let c: Vec<(usize, f64)> = dofs.iter().map(|&d| (perm[d], 0.1 * d as f64)).collect();
    let mut x = vec![0.0; n];
    sn.finish_reach(&f.l, &c, &mut x);
    let mut bc = b.clone();
    for &d in &dofs {
        bc[d] -= 0.1 * d as f64;
    }
    assert!(residual(&a, &x, &bc) < 1e-12);
}

/// The two-group solve (forced on a small factor) solves A x = b, and
/// gives the same bits on one thread and on two: the groups' arithmetic
/// does not depend on the thread count.
#[test]
fn split_solve_is_right_and_thread_independent() {
    let a = operator(CellKind::Quad4, 40, 10);
    let n = a.nrows();
    let f = factor(&a);
    let b = spread(n);
    let dofs: Vec<usize> = (0..=40).map(|i| 2 * i).collect();
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut sn = Supernodal::with_split_min(&f.symbolic, 0).unwrap();
            assert!(sn.is_split(), "the tree splits");
            sn.set_reach(&dofs);
            let mut x = b.clone();
            sn.solve(&f.l, &mut x);
            let perm = sn.permuted_indices();
            sn.begin_reach(&f.l, &b);
            let at: Vec<f64> = dofs.iter().map(|&d| sn.reach_value(perm[d])).collect();
            let c: Vec<(usize, f64)> = dofs.iter().map(|&d| (perm[d], 0.5)).collect();
            let mut y = vec![0.0; n];
            sn.finish_reach(&f.l, &c, &mut y);
            // The step through W: p, then the corrected solution.
            let rows: Vec<Vec<(usize, f64)>> = dofs.iter().map(|&d| vec![(perm[d], 1.0)]).collect();
            let op = sn.schur_complement(&f.l, &rows);
            let mut p = vec![0.0; rows.len()];
            sn.begin_paths(&f.l, &op, &b, &mut p);
            let mut z = vec![0.0; n];
            sn.finish_paths(&f.l, &op, &vec![0.5; rows.len()], &mut z);
            (x, at, y, (op.s, p, z))
        })
    };
    let (x1, at1, y1, w1) = run(1);
    let (x2, at2, y2, w2) = run(2);
    assert!(
        residual(&a, &w1.2, &{
            let mut bc = b.clone();
            for &d in &dofs {
                bc[d] -= 0.5;
            }
            bc
        }) < 1e-12
    );
    for (k, &d) in dofs.iter().enumerate() {
        assert!((w1.1[k] - x1[d]).abs() <= 1e-12 * x1[d].abs().max(1.0));
    }
    assert!(residual(&a, &x1, &b) < 1e-12);
    for (k, &d) in dofs.iter().enumerate() {
        assert!((at1[k] - x1[d]).abs() <= 1e-12 * x1[d].abs().max(1.0));
    }
    let mut bc = b.clone();
    for &d in &dofs {
        bc[d] -= 0.5;
    }
    assert!(residual(&a, &y1, &bc) < 1e-12);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&x1), bits(&x2));
    assert_eq!(bits(&at1), bits(&at2));
    assert_eq!(bits(&y1), bits(&y2));
    assert_eq!(bits(&w1.0), bits(&w2.0), "S");
    assert_eq!(bits(&w1.1), bits(&w2.1), "p through W");
    assert_eq!(bits(&w1.2), bits(&w2.2), "x through W");
}

/// G = P A⁻¹ Pᵀ on the reach equals P applied to full solves.
#[test]
fn schur_complement_matches_full_solves() {
    let a = operator(CellKind::Quad4, 24, 6);
    let n = a.nrows();
    let f = factor(&a);
    let mut sn = Supernodal::new(&f.symbolic).unwrap();
    let perm = sn.permuted_indices();
    // Rows of P: 11 "nodes", some with two DOFs (a tangent (0.6, 0.8)).
    let rows: Vec<Vec<(usize, f64)>> = (0..11)
        .map(|i| {
            if i % 2 == 0 {
                vec![(2 * i, 0.6), (2 * i + 1, 0.8)]
            } else {
                vec![(2 * i, 1.0)]
            }
        })
        .collect();
    let dofs: Vec<usize> = rows.iter().flatten().map(|&(d, _)| d).collect();
    sn.set_reach(&dofs);
    let permuted: Vec<Vec<(usize, f64)>> = rows
        .iter()
        .map(|r| r.iter().map(|&(d, v)| (perm[d], v)).collect())
        .collect();
    let op = sn.schur_complement(&f.l, &permuted);
    let g = &op.s;
    let p = rows.len();
    // The step through W: p = P A⁻¹ b, then x = A⁻¹(b − Pᵀf).
    let b = spread(n);
    let mut pv = vec![0.0; p];
    sn.begin_paths(&f.l, &op, &b, &mut pv);
    let mut full = b.clone();
    faer_solve(&f, &mut full);
    for (j, row) in rows.iter().enumerate() {
        let want: f64 = row.iter().map(|&(d, v)| v * full[d]).sum();
        assert!(
            (pv[j] - want).abs() <= 1e-12 * want.abs().max(1.0),
            "p[{j}]"
        );
    }
    let fv: Vec<f64> = (0..p).map(|j| 0.3 * j as f64 - 1.0).collect();
    let mut x = vec![0.0; n];
    sn.finish_paths(&f.l, &op, &fv, &mut x);
    let mut bc = b.clone();
    for (row, fj) in rows.iter().zip(&fv) {
        for &(d, v) in row {
            bc[d] -= v * fj;
        }
    }
    assert!(residual(&a, &x, &bc) < 1e-12);
    assert!(op.w_len() < sn.reach_columns() * p, "W is sparse");
    for j in 0..p {
        let mut x = vec![0.0; n];
        for &(d, v) in &rows[j] {
            x[d] = v;
        }
        faer_solve(&f, &mut x);
        for i in 0..p {
            let want: f64 = rows[i].iter().map(|&(d, v)| v * x[d]).sum();
            assert!(
                (g[j * p + i] - want).abs() <= 1e-12 * want.abs().max(1e-3),
                "G[{i}, {j}] = {} against {want}",
                g[j * p + i]
            );
        }
    }
}

/// A Schur complement large enough for its groups to go to the pool (p
/// times the reach's DOFs from 2¹⁶, `PATHS_PARALLEL_MIN`): G = WᵀW equals
/// P applied to full solves, and S and the step through W have the same
/// bits on one thread and on two.
#[test]
fn schur_complement_on_the_pool_is_right_and_thread_independent() {
    let a = operator(CellKind::Quad4, 80, 20);
    let n = a.nrows();
    let f = factor(&a);
    let b = spread(n);
    // 81 DOFs, as a contact row's (any set serves: S is P A⁻¹ Pᵀ).
    let dofs: Vec<usize> = (0..=80).map(|i| 2 * i).collect();
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut sn = Supernodal::new(&f.symbolic).unwrap();
            sn.set_reach(&dofs);
            let perm = sn.permuted_indices();
            let rows: Vec<Vec<(usize, f64)>> = dofs.iter().map(|&d| vec![(perm[d], 1.0)]).collect();
            assert!(
                rows.len() * sn.reach_columns() >= 1 << 16,
                "the groups go to the pool"
            );
            let op = sn.schur_complement(&f.l, &rows);
            let mut p = vec![0.0; rows.len()];
            sn.begin_paths(&f.l, &op, &b, &mut p);
            (op.s, p)
        })
    };
    let (s1, p1) = run(1);
    let (s2, p2) = run(2);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&s1), bits(&s2), "S");
    assert_eq!(bits(&p1), bits(&p2), "p through W");
    let p = dofs.len();
    for (j, &dj) in dofs.iter().enumerate() {
        let mut x = vec![0.0; n];
        x[dj] = 1.0;
        faer_solve(&f, &mut x);
        for (i, &di) in dofs.iter().enumerate() {
            let want = x[di];
            assert!(
                (s1[j * p + i] - want).abs() <= 1e-12 * want.abs().max(1e-3),
                "G[{i}, {j}] = {} against {want}",
                s1[j * p + i]
            );
        }
    }
}
