//! The paper's slab (BENCHMARK.md) on the committed Gmsh meshes: the static
//! state under F_n = 300 alone, and the contact-face nodal quadrature.

use stickslip_fem::{
    boundary_quadrature, gauss_point_stresses, nodal_stresses, static_solve, traction_load, Model,
    Traction,
};
use stickslip_mesh::Mesh;
use stickslip_testkit::{paper_material, paper_supports, read_mesh};

/// Supports of BENCHMARK.md: rollers u_y = 0 on `support` (top), u_x = 0 on
/// `left`; pressure 300 on `contact` (bottom) pushing up.
fn static_state(mesh: &Mesh) -> Vec<f64> {
    let model = Model::new(mesh, &paper_material(), &paper_supports()).unwrap();
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    traction_load(mesh, "contact", Traction::Pressure(300.0), &mut full).unwrap();
    let mut free = vec![0.0; model.dofs.n_free()];
    model.dofs.restrict(&full, &mut free);
    static_solve(&model, &free).unwrap()
}

/// Expected (closed form, BENCHMARK.md "Initial state"): σ_yy = −300,
/// σ_xx = σ_xy = 0 everywhere, so in plane strain ε_xx = −ν(1+ν)σ_yy/E =
/// 0.117 and ε_yy = (1−ν²)σ_yy/E = −0.273, i.e. u_x = 0.117·x (u_x = 0 at
/// x = 0) and u_y = 0.273·(1 − y) (u_y = 0 at y = 1). Linear fields are in
/// the Q1/Q2 spaces, so the FE solution is exact to rounding: 1e-10 at every
/// node. The unstructured meshes are included: exactness does not
/// need a regular grid.
#[test]
fn slab_static_state_is_the_closed_form_uniform_state_on_committed_meshes() {
    for name in [
        "slab-q2-8x2.msh",
        "slab-q2-8x2-v22.msh",
        "slab-q1-16x4.msh",
        "slab-unstructured-q1.msh",
        "slab-unstructured-q2.msh",
    ] {
        let mesh = read_mesh(name).unwrap_or_else(|e| panic!("{e}"));
        let u = static_state(&mesh);
        let mut worst = 0.0f64;
        for (v, p) in mesh.nodes.iter().enumerate() {
            let (ex, ey) = (0.117 * p[0], 0.273 * (1.0 - p[1]));
            worst = worst
                .max((u[2 * v] - ex).abs())
                .max((u[2 * v + 1] - ey).abs());
        }
        assert!(worst < 1e-10, "{name}: max nodal error {worst:e}");
        // The right end starts at u_x = 0.936 (BENCHMARK.md).
        let corner = mesh
            .nodes
            .iter()
            .position(|p| (p[0] - 8.0).abs() < 1e-12 && p[1].abs() < 1e-12)
            .unwrap();
        assert!((u[2 * corner] - 0.936).abs() < 1e-10);
        let mat = paper_material();
        for s in gauss_point_stresses(&mesh, &mat, &u) {
            let e = [s.stress[0], s.stress[1] + 300.0, s.stress[2]];
            assert!(
                e.iter().all(|v| v.abs() < 1e-9),
                "{name}: Gauss stress {:?} at {:?}",
                s.stress,
                s.position
            );
        }
        for s in nodal_stresses(&mesh, &mat, &u) {
            assert!(
                s[0].abs() < 1e-9 && (s[1] + 300.0).abs() < 1e-9 && s[2].abs() < 1e-9,
                "{name}: nodal {s:?}"
            );
        }
        // Plane strain: σ_zz = ν(σ_xx + σ_yy) = −90.
        assert!((mat.out_of_plane_stress([0.0, -300.0, 0.0]) + 90.0).abs() < 1e-12);
    }
}

/// Expected (BENCHMARK.md "Conventions"): on the paper's Q2 8 × 2 mesh the
/// Simpson weights give node 81 = (8, 0) w = 1/6 and node 71 = (7, 0)
/// w = 1/3; τ = +x and n = (0, −1) along the whole bottom; on the Q1 16 × 4
/// mesh (trapezoid, edges 0.5 long) w = 1/4 and 1/2.
#[test]
fn contact_face_nodal_quadrature_on_committed_meshes() {
    for (name, w81, w71) in [
        ("slab-q2-8x2.msh", 1.0 / 6.0, 1.0 / 3.0),
        ("slab-q1-16x4.msh", 0.25, 0.5),
    ] {
        let mesh = read_mesh(name).unwrap();
        let bq = boundary_quadrature(&mesh, "contact").unwrap();
        assert_eq!(bq.len(), 17, "{name}");
        let find = |x: f64| {
            bq.iter()
                .find(|b| (mesh.nodes[b.node][0] - x).abs() < 1e-12)
                .unwrap()
        };
        assert!(
            (find(8.0).weight - w81).abs() < 1e-13,
            "{name}: w81 = {}",
            find(8.0).weight
        );
        assert!(
            (find(7.0).weight - w71).abs() < 1e-13,
            "{name}: w71 = {}",
            find(7.0).weight
        );
        assert_eq!(
            mesh.nodes[bq[0].node],
            [0.0, 0.0],
            "{name}: the chain starts at (0, 0)"
        );
        for (b, next) in bq.iter().zip(bq.iter().skip(1)) {
            assert!(
                mesh.nodes[next.node][0] > mesh.nodes[b.node][0],
                "{name}: ordered along +x"
            );
            assert!(next.s > b.s);
        }
        for b in &bq {
            assert!((b.tangent[0] - 1.0).abs() < 1e-14 && b.tangent[1].abs() < 1e-14);
            assert!(b.normal[0].abs() < 1e-14 && (b.normal[1] + 1.0).abs() < 1e-14);
            assert!(mesh.nodes[b.node][1].abs() < 1e-14);
        }
    }
}
