//! Patch tests: any linear displacement field is reproduced exactly by Q1 on
//! distorted meshes and by Q2 on meshes with curved edges, with constant
//! stress (the isoparametric space contains the linear fields, and the full
//! Gauss rule integrates ∫∇N_a dA exactly because adj(J)·∇̂N is polynomial).

use stickslip_fem::{
    gauss_point_stresses, nodal_stresses, static_solve, stress_at_node, traction_load_with,
    von_mises, Dirichlet, Hypothesis, Material, Model,
};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::{add_point_group, map_nodes, rectangle};

/// The linear field u = a + B x (a generic choice, all entries non-zero).
fn linear(p: [f64; 2]) -> [f64; 2] {
    [
        0.01 + 0.02 * p[0] - 0.015 * p[1],
        -0.02 + 0.005 * p[0] + 0.03 * p[1],
    ]
}
/// Its strain (ε_xx, ε_yy, γ_xy).
const STRAIN: [f64; 3] = [0.02, 0.03, -0.015 + 0.005];

fn material() -> Material {
    Material::new(200.0, 0.27, 1.0, Hypothesis::PlaneStress).unwrap()
}

fn exact_stress() -> [f64; 3] {
    let d = material().elasticity();
    [0, 1, 2].map(|i| (0..3).map(|j| d[i][j] * STRAIN[j]).sum())
}

/// Deterministic pseudo-random numbers in [−1, 1] (no dependency).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// Q1 on a 5 × 4 grid over [0, 2.5] × [0, 2] with every interior node moved
/// randomly by up to 30 % of the spacing: general convex quadrilaterals.
fn distorted_q1() -> Mesh {
    let mut m = rectangle(CellKind::Quad4, 5, 4, [0.0, 0.0], [2.5, 2.0]);
    let mut s = 7u64;
    for p in &mut m.nodes {
        if p[0] > 1e-12 && p[0] < 2.5 - 1e-12 && p[1] > 1e-12 && p[1] < 2.0 - 1e-12 {
            p[0] += 0.3 * 0.5 * lcg(&mut s);
            p[1] += 0.3 * 0.5 * lcg(&mut s);
        }
    }
    m
}

/// Q2 on a 4 × 3 grid bent by a smooth non-affine map: every edge, the
/// outer ones included, is a curved (parabolic) line3.
fn curved_q2() -> Mesh {
    let mut m = rectangle(CellKind::Quad9, 4, 3, [0.0, 0.0], [2.0, 1.5]);
    map_nodes(&mut m, |[x, y]| {
        [
            x + 0.08 * (1.7 * y).sin() + 0.05 * x * y,
            y + 0.1 * (1.3 * x).cos() - 0.04 * x * x,
        ]
    });
    m
}

/// Interior-node error and worst Gauss/nodal stress error of the linear field
/// imposed on every boundary node.
fn displacement_patch(mut mesh: Mesh) -> (f64, f64) {
    let boundary: Vec<usize> = {
        let mut b: Vec<usize> = ["bottom", "right", "top", "left"]
            .iter()
            .flat_map(|g| mesh.group(g).unwrap().nodes.clone())
            .collect();
        b.sort_unstable();
        b.dedup();
        b
    };
    let mut bcs = Vec::new();
    for &v in &boundary {
        let name = format!("p{v}");
        add_point_group(&mut mesh, &name, &[v]);
        let u = linear(mesh.nodes[v]);
        bcs.push(Dirichlet::new(name.clone(), 0, u[0]));
        bcs.push(Dirichlet::new(name, 1, u[1]));
    }
    let model = Model::new(&mesh, &material(), &bcs).unwrap();
    assert!(model.dofs.n_free() > 0 && model.dofs.n_free() < 2 * mesh.nodes.len());
    let u = static_solve(&model, &vec![0.0; model.dofs.n_free()]).unwrap();
    let mut worst_u = 0.0f64;
    for (v, p) in mesh.nodes.iter().enumerate() {
        let e = linear(*p);
        worst_u = worst_u
            .max((u[2 * v] - e[0]).abs())
            .max((u[2 * v + 1] - e[1]).abs());
    }
    (worst_u, stress_error(&mesh, &u))
}

fn stress_error(mesh: &Mesh, u: &[f64]) -> f64 {
    let s0 = exact_stress();
    let scale = s0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for g in gauss_point_stresses(mesh, &material(), u) {
        for k in 0..3 {
            worst = worst.max((g.stress[k] - s0[k]).abs() / scale);
        }
    }
    for s in nodal_stresses(mesh, &material(), u) {
        for k in 0..3 {
            worst = worst.max((s[k] - s0[k]).abs() / scale);
        }
    }
    worst
}

/// Expected: the imposed linear field itself at every interior node (1e-12:
/// rounding, displacements are O(0.1)), and σ = D ε of that field at every
/// Gauss point and node (relative 1e-11: stresses are derivatives, so the
/// nodal rounding is amplified by 1/h).
#[test]
fn displacement_patch_test_on_distorted_q1_and_curved_q2() {
    for (name, mesh) in [("distorted Q1", distorted_q1()), ("curved Q2", curved_q2())] {
        let (eu, es) = displacement_patch(mesh);
        assert!(eu < 1e-12, "{name}: displacement error {eu:e}");
        assert!(es < 1e-11, "{name}: relative stress error {es:e}");
    }
}

/// Traction form: the constant stress σ⁰ = D ε applied as the traction σ⁰·n
/// on all four (curved) sides, with only rigid motions removed (node (0, 0)
/// fixed to the linear field, node (2, 0)'s image fixed in y). The consistent
/// edge loads ∫N_a σ⁰n ds are exact (n ds is polynomial on a line3), so the
/// linear field must come back everywhere. Expected as above.
#[test]
fn traction_patch_test_on_curved_q2_and_distorted_q1() {
    for (name, mut mesh) in [("distorted Q1", distorted_q1()), ("curved Q2", curved_q2())] {
        let s0 = exact_stress();
        let mut full = vec![0.0; 2 * mesh.nodes.len()];
        for g in ["bottom", "right", "top", "left"] {
            traction_load_with(
                &mesh,
                g,
                |_, n| [s0[0] * n[0] + s0[2] * n[1], s0[2] * n[0] + s0[1] * n[1]],
                &mut full,
            )
            .unwrap();
        }
        let origin = 0;
        let far = mesh.group("bottom").unwrap().edges.last().unwrap().nodes[1];
        add_point_group(&mut mesh, "origin", &[origin]);
        add_point_group(&mut mesh, "far", &[far]);
        let (u0, uf) = (linear(mesh.nodes[origin]), linear(mesh.nodes[far]));
        let bcs = [
            Dirichlet::new("origin", 0, u0[0]),
            Dirichlet::new("origin", 1, u0[1]),
            Dirichlet::new("far", 1, uf[1]),
        ];
        let model = Model::new(&mesh, &material(), &bcs).unwrap();
        let mut free = vec![0.0; model.dofs.n_free()];
        model.dofs.restrict(&full, &mut free);
        let u = static_solve(&model, &free).unwrap();
        let mut worst = 0.0f64;
        for (v, p) in mesh.nodes.iter().enumerate() {
            let e = linear(*p);
            worst = worst
                .max((u[2 * v] - e[0]).abs())
                .max((u[2 * v + 1] - e[1]).abs());
        }
        assert!(worst < 1e-12, "{name}: displacement error {worst:e}");
        let es = stress_error(&mesh, &u);
        assert!(es < 1e-11, "{name}: relative stress error {es:e}");
    }
}

/// One node's stress from its cells alone (what `stickslip probe` reads
/// over a history) has the bits of the whole mesh's nodal stresses, on the
/// distorted Q1 and curved Q2 meshes with a pseudo-random displacement.
#[test]
fn stress_at_one_node_is_the_nodal_stress() {
    for mesh in [distorted_q1(), curved_q2()] {
        let mut state = 7u64;
        let u: Vec<f64> = (0..2 * mesh.nodes.len()).map(|_| lcg(&mut state)).collect();
        let all = nodal_stresses(&mesh, &material(), &u);
        for (v, expected) in all.iter().enumerate() {
            let cells: Vec<usize> = (0..mesh.n_cells())
                .filter(|&c| mesh.cell(c).contains(&v))
                .collect();
            let s = stress_at_node(&mesh, &material(), v, &cells, |w| [u[2 * w], u[2 * w + 1]]);
            assert_eq!(s.map(f64::to_bits), expected.map(f64::to_bits), "node {v}");
        }
    }
}

/// Von Mises by hand: uniaxial σ in plane stress is σ; pure shear τ is
/// √3 τ; plane strain's σzz = ν(σxx + σyy) enters (equibiaxial σ, ν = 0.3:
/// σzz = 0.6σ, von Mises |σ − 0.6σ| = 0.4σ).
#[test]
fn von_mises_by_hand() {
    let stress = Material::new(1.0, 0.3, 1.0, Hypothesis::PlaneStress).unwrap();
    let strain = Material::new(1.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
    assert!((von_mises(&stress, [5.0, 0.0, 0.0]) - 5.0).abs() < 1e-14);
    assert!((von_mises(&stress, [0.0, 0.0, 2.0]) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
    assert!((von_mises(&strain, [1.0, 1.0, 0.0]) - 0.4).abs() < 1e-14);
}
