//! Assembled operators: rigid-body modes, mass totals, HRZ ratios, shared
//! pattern, `combine`, and thread-count independence.

use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::{add_point_group, map_nodes, on_threads, plain_spmv, rectangle};

fn material() -> Material {
    Material::new(1000.0, 0.3, 2.5, Hypothesis::PlaneStrain).unwrap()
}

/// A 3 × 2 rectangle whose interior nodes are moved by a smooth map that
/// vanishes on the boundary: distorted Q1 cells, curved Q2 cells; the
/// domain (and so its area, 6) is unchanged.
fn distorted(kind: CellKind, nx: usize, ny: usize) -> Mesh {
    let mut m = rectangle(kind, nx, ny, [0.0, 0.0], [3.0, 2.0]);
    map_nodes(&mut m, |[x, y]| {
        let b = (std::f64::consts::PI * x / 3.0).sin() * (std::f64::consts::PI * y / 2.0).sin();
        [
            x + 0.18 * b * (1.3 * y).cos(),
            y + 0.12 * b * (0.7 * x).sin(),
        ]
    });
    m
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The rigid modes the DofMap reports are the motions the supports leave
/// free: K annihilates each (theory, as above), each vanishes where a DOF
/// is held (it is a vector on the free DOFs only), and they are, per
/// support: none held (3: x, y, rotation), rollers u_y = 0 on the top (1:
/// x), u_y = 0 at one point (2: x, and rotation about that point).
#[test]
fn the_rigid_modes_are_the_free_motions() {
    let mut mesh = distorted(CellKind::Quad9, 3, 2);
    add_point_group(&mut mesh, "corner", &[0]);
    // (A rotation with x free is about any point of the held node's
    // vertical: the one at the centre's height, y = 1, is reported.)
    let cases: [(Vec<Dirichlet>, &[&str]); 3] = [
        (
            vec![],
            &[
                "translation in x",
                "translation in y",
                "rotation about (1.500000, 1.000000)",
            ],
        ),
        (vec![Dirichlet::new("top", 1, 0.0)], &["translation in x"]),
        (
            vec![Dirichlet::new("corner", 1, 0.0)],
            &["translation in x", "rotation about (0.000000, 1.000000)"],
        ),
    ];
    for (k, (conditions, labels)) in cases.iter().enumerate() {
        let model = Model::new(&mesh, &material(), conditions).unwrap();
        let modes = model.dofs.rigid_modes();
        let got: Vec<&str> = modes.iter().map(|m| m.label.as_str()).collect();
        assert_eq!(&got[..], *labels, "case {k}");
        let k_norm = norm(model.stiffness.values());
        for m in modes {
            let kr = plain_spmv(&model.stiffness, &m.vector);
            let rel = norm(&kr) / (k_norm * norm(&m.vector));
            assert!(rel < 1e-10, "case {k} {}: {rel:e}", m.label);
        }
    }
}

/// Expected (theory): a rigid motion has zero strain, so K r = 0. With no
/// conditions all DOFs are free and K is the full stiffness. Tolerance
/// 1e-10 relative to ‖K‖_F ‖r‖ (the sums' rounding, with wide room).
#[test]
fn stiffness_annihilates_the_three_rigid_body_motions() {
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let mesh = distorted(kind, 5, 4);
        let model = Model::new(&mesh, &material(), &[]).unwrap();
        assert_eq!(model.dofs.n_free(), 2 * mesh.nodes.len());
        let k_norm = norm(model.stiffness.values());
        // x-translation, y-translation, rotation about (1.5, 1).
        let motions = [
            |_: [f64; 2]| [1.0, 0.0],
            |_: [f64; 2]| [0.0, 1.0],
            |[x, y]: [f64; 2]| [-(y - 1.0), x - 1.5],
        ];
        for (m, motion) in motions.iter().enumerate() {
            let full: Vec<f64> = mesh.nodes.iter().flat_map(|&p| motion(p)).collect();
            // (Free DOFs in the DofMap's node order.)
            let mut r = vec![0.0; model.dofs.n_free()];
            model.dofs.restrict(&full, &mut r);
            let kr = plain_spmv(&model.stiffness, &r);
            let rel = norm(&kr) / (k_norm * norm(&r));
            assert!(
                rel < 1e-10,
                "{kind:?} motion {m}: |K r| / (|K| |r|) = {rel:e}"
            );
        }
    }
}

/// Expected (closed form): Σ_ab M_ab over one direction = ∫ρ dA = ρ·area,
/// area = 3 × 2 = 6 (the map moves only interior nodes, so the domain is the
/// rectangle; det J is a polynomial the full rule integrates exactly). HRZ
/// preserves the element mass, so the lumped masses sum to the same; no
/// coupling between directions.
#[test]
fn consistent_and_lumped_mass_sum_to_rho_area_per_direction() {
    let rho = material().density;
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let mesh = distorted(kind, 5, 4);
        let model = Model::new(&mesh, &material(), &[]).unwrap();
        assert!(
            (model.area - 6.0).abs() < 1e-12,
            "{kind:?} area {}",
            model.area
        );
        for dir in 0..2 {
            let e: Vec<f64> = (0..mesh.nodes.len())
                .flat_map(|_| [(dir == 0) as u8 as f64, (dir == 1) as u8 as f64])
                .collect();
            let other: Vec<f64> = e.iter().map(|v| 1.0 - v).collect();
            let me = plain_spmv(model.mass.as_ref().unwrap(), &e);
            let total: f64 = me.iter().zip(&e).map(|(a, b)| a * b).sum();
            let cross: f64 = me.iter().zip(&other).map(|(a, b)| a * b).sum();
            assert!(
                (total - rho * 6.0).abs() < 1e-12,
                "{kind:?} dir {dir}: consistent {total}"
            );
            assert!(cross.abs() < 1e-12);
            let lumped: f64 = model.lumped_mass.iter().zip(&e).map(|(a, b)| a * b).sum();
            assert!(
                (lumped - rho * 6.0).abs() < 1e-12,
                "{kind:?} dir {dir}: lumped {lumped}"
            );
            assert!(model.lumped_mass.iter().all(|&m| m > 0.0));
        }
    }
}

/// Expected (BENCHMARK.md, closed form): HRZ on a rectangular Q2 element
/// gives corner : mid-side : centre = 1 : 4 : 16 in units of (element
/// mass)/36, for both components.
#[test]
fn hrz_lumped_mass_of_one_rectangular_q2_element_is_1_4_16() {
    let mesh = rectangle(CellKind::Quad9, 1, 1, [2.0, -1.0], [1.0, 0.5]);
    let mat = material();
    let model = Model::new(&mesh, &mat, &[]).unwrap();
    let unit = mat.density * 0.5 / 36.0;
    let cell = mesh.cell(0);
    let expected = [1.0, 1.0, 1.0, 1.0, 4.0, 4.0, 4.0, 4.0, 16.0];
    for (a, &v) in cell.iter().enumerate() {
        for comp in 0..2 {
            let m = model.lumped_mass[model.dofs.free(v, comp).unwrap()];
            assert!(
                (m / unit - expected[a]).abs() < 1e-12,
                "node {a}: {}",
                m / unit
            );
        }
    }
}

/// K and M share one pattern, K is symmetric, and `combine` gives a·K + b·M
/// entry by entry (checked against the stored values).
#[test]
fn k_and_m_share_a_pattern_and_combine_in_place() {
    let mesh = distorted(CellKind::Quad9, 3, 2);
    let model = Model::new(
        &mesh,
        &material(),
        &[stickslip_fem::Dirichlet::new("left", 0, 0.0)],
    )
    .unwrap();
    assert_eq!(
        model.stiffness.pattern(),
        model.mass.as_ref().unwrap().pattern()
    );
    let kt = model.stiffness.transpose();
    let scale = model
        .stiffness
        .values()
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in model.stiffness.values().iter().zip(kt.values()) {
        assert!((a - b).abs() <= 1e-13 * scale);
    }
    let mut out = model.stiffness.clone();
    let ptr = out.values().as_ptr();
    model.combine(0.25, 40.0, &mut out);
    assert_eq!(ptr, out.values().as_ptr(), "combine must not reallocate");
    for ((o, k), m) in out
        .values()
        .iter()
        .zip(model.stiffness.values())
        .zip(model.mass.as_ref().unwrap().values())
    {
        assert_eq!(*o, 0.25 * k + 40.0 * m);
    }
}

/// Element matrices are computed in parallel and scattered in cell order,
/// so the result must be bitwise the same on 1 and on several threads
/// (mesh large enough for several chunks of cells).
#[test]
fn assembly_is_bitwise_identical_for_any_thread_count() {
    let mesh = distorted(CellKind::Quad9, 48, 30);
    let mat = material();
    let bcs = [
        stickslip_fem::Dirichlet::new("left", 0, 0.01),
        stickslip_fem::Dirichlet::new("bottom", 1, 0.0),
    ];
    let run = |threads: usize| on_threads(threads, || Model::new(&mesh, &mat, &bcs).unwrap());
    let one = run(1);
    let many = run(4);
    assert_eq!(one.stiffness.values(), many.stiffness.values());
    assert_eq!(
        one.mass.as_ref().unwrap().values(),
        many.mass.as_ref().unwrap().values()
    );
    assert_eq!(one.lumped_mass, many.lumped_mass);
    assert_eq!(one.dirichlet_load, many.dirichlet_load);
    assert!(one.dirichlet_load.iter().any(|&v| v != 0.0));
}
