//! Convergence in h against a manufactured solution, with the measured
//! errors kept in `tests/data/convergence.csv` (fenris keeps its
//! convergence data the same way).
//!
//! Problem: the unit square, its interior nodes moved by a smooth map (so
//! Q1 cells are general quadrilaterals and Q2 cells have curved edges, while
//! the boundary stays straight); plane strain E = 1, ν = 0.3;
//!   u_x = sin(αx)·sin(βy),  u_y = sin(γx)·(1 − cos(δy)),
//! which vanishes on x = 0 and y = 0 (clamped there); on x = 1 and y = 1 the
//! traction σ(u)·n is applied, and the body force is f = −div σ(u), both by
//! hand (the derivation is checked by finite differences below). The
//! solution, the mesh and the error integrals live in
//! `stickslip_testkit::manufactured`, shared with `cargo xtask verify`.
//!
//! Expected: the theory's rates (Ciarlet; METHOD.md §2-3) — L2 error
//! O(h^(k+1)) and H1 error O(h^k) for degree k — i.e. 2 and 1 for Q1, 3 and 2
//! for Q2, each measured rate within ±0.15, on 5 meshes (4 refinements).
//! Independently, the errors must match the committed data to 1e-6
//! relative, so any change in the numbers is noticed. Regenerate the data
//! (after checking the rates) with `STICKSLIP_BLESS=1 cargo test -p
//! stickslip-fem --test convergence`.

use std::fmt::Write as _;
use std::path::PathBuf;

use stickslip_mesh::CellKind;
use stickslip_testkit::manufactured::{body_force, errors, stress};

#[test]
fn hand_derived_body_force_matches_finite_differences_of_the_stress() {
    let h = 1e-5;
    for p in [[0.3, 0.7], [0.9, 0.1], [0.55, 0.45]] {
        let s = |dx: f64, dy: f64| stress([p[0] + dx, p[1] + dy]);
        let dsx = [
            (s(h, 0.0)[0] - s(-h, 0.0)[0]) / (2.0 * h),
            (s(0.0, h)[2] - s(0.0, -h)[2]) / (2.0 * h),
        ];
        let dsy = [
            (s(h, 0.0)[2] - s(-h, 0.0)[2]) / (2.0 * h),
            (s(0.0, h)[1] - s(0.0, -h)[1]) / (2.0 * h),
        ];
        let f = body_force(p);
        assert!((f[0] + dsx[0] + dsx[1]).abs() < 1e-8 && (f[1] + dsy[0] + dsy[1]).abs() < 1e-8);
    }
}

fn data_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/convergence.csv")
}

#[test]
fn q1_and_q2_converge_at_the_theoretical_rates_and_match_the_committed_errors() {
    let ladders = [
        (CellKind::Quad4, "q1", [8, 16, 32, 64, 128], 2.0),
        (CellKind::Quad9, "q2", [4, 8, 16, 32, 64], 3.0),
    ];
    let mut csv = String::from("element,n,h,l2_error,h1_error\n");
    let mut measured = Vec::new();
    for (kind, name, ns, l2_rate) in ladders {
        let errs: Vec<(f64, f64)> = ns.iter().map(|&n| errors(kind, n).unwrap()).collect();
        for (&n, &(l2, h1)) in ns.iter().zip(&errs) {
            writeln!(
                csv,
                "{name},{n},{:.17e},{l2:.17e},{h1:.17e}",
                1.0 / n as f64
            )
            .unwrap();
            measured.push((name.to_string(), n, l2, h1));
        }
        for (i, w) in errs.windows(2).enumerate() {
            let r_l2 = (w[0].0 / w[1].0).log2();
            let r_h1 = (w[0].1 / w[1].1).log2();
            eprintln!(
                "{name} n={}→{}: L2 rate {r_l2:.3}, H1 rate {r_h1:.3}",
                ns[i],
                ns[i + 1]
            );
            assert!(
                (r_l2 - l2_rate).abs() <= 0.15,
                "{name} n={}→{}: L2 rate {r_l2:.3}, theory {l2_rate}",
                ns[i],
                ns[i + 1]
            );
            assert!(
                (r_h1 - (l2_rate - 1.0)).abs() <= 0.15,
                "{name} n={}→{}: H1 rate {r_h1:.3}, theory {}",
                ns[i],
                ns[i + 1],
                l2_rate - 1.0
            );
        }
    }
    if std::env::var_os("STICKSLIP_BLESS").is_some() {
        std::fs::write(data_path(), &csv).unwrap();
        return;
    }
    let stored = std::fs::read_to_string(data_path()).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; create it with STICKSLIP_BLESS=1",
            data_path().display()
        )
    });
    let rows: Vec<Vec<String>> = stored
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(
        rows.len(),
        measured.len(),
        "rows in {}",
        data_path().display()
    );
    for (row, (name, n, l2, h1)) in rows.iter().zip(&measured) {
        assert_eq!((&row[0], row[1].parse::<usize>().unwrap()), (name, *n));
        let (sl2, sh1): (f64, f64) = (row[3].parse().unwrap(), row[4].parse().unwrap());
        assert!(
            ((l2 - sl2) / sl2).abs() < 1e-6,
            "{name} n={n}: L2 {l2:e} vs stored {sl2:e}"
        );
        assert!(
            ((h1 - sh1) / sh1).abs() < 1e-6,
            "{name} n={n}: H1 {h1:e} vs stored {sh1:e}"
        );
    }
}
