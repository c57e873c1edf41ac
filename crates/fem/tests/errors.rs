//! User-facing errors: singular supports, invalid materials, unknown
//! groups, bad Dirichlet conditions. Each message must name the problem and
//! what to do.

use stickslip_fem::{
    static_solve, traction_load, Dirichlet, DofMap, FemError, Hypothesis, Material, Model, Traction,
};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::{add_point_group, paper_material, paper_supports, rectangle, slab};

fn solve_err(mesh: &Mesh, bcs: &[Dirichlet]) -> FemError {
    let model = Model::new(mesh, &paper_material(), bcs).unwrap();
    static_solve(&model, &vec![0.0; model.dofs.n_free()]).unwrap_err()
}

/// Expected (kinematics): with no support all three rigid motions are free;
/// rollers u_x = 0 on the vertical left end hold x-translation and rotation
/// but not y-translation; a single pinned node holds both translations but
/// not the rotation about itself; the slab's own supports hold all three.
#[test]
fn singular_supports_name_the_free_rigid_body_motions() {
    let mut mesh = slab(CellKind::Quad9, 1);
    let cases: [(&[Dirichlet], &str); 2] = [
        (&[], "translation in x, translation in y, rotation"),
        (&[Dirichlet::new("left", 0, 0.0)], "translation in y"),
    ];
    for (bcs, motions) in cases {
        let e = solve_err(&mesh, bcs);
        let msg = e.to_string();
        assert!(
            msg.starts_with("the supports leave a rigid-body motion free: "),
            "{msg}"
        );
        assert_eq!(
            e,
            FemError::RigidBodyMotion {
                motions: motions.to_string()
            },
            "{msg}"
        );
    }
    // A pin at (8, 1): the rotation about that point stays free.
    let corner = mesh.nodes.iter().position(|p| *p == [8.0, 1.0]).unwrap();
    add_point_group(&mut mesh, "pin", &[corner]);
    let e = solve_err(
        &mesh,
        &[Dirichlet::new("pin", 0, 0.0), Dirichlet::new("pin", 1, 0.0)],
    );
    assert_eq!(
        e,
        FemError::RigidBodyMotion {
            motions: "rotation about (8.000000, 1.000000)".to_string()
        }
    );
    // Rollers u_y = 0 on the top face only: x-translation free, and the
    // rotation is held (two y-constraints at different x).
    let e = solve_err(&mesh, &[Dirichlet::new("support", 1, 0.0)]);
    assert_eq!(
        e,
        FemError::RigidBodyMotion {
            motions: "translation in x".to_string()
        }
    );
    // The paper's supports are enough.
    let model = Model::new(&mesh, &paper_material(), &paper_supports()).unwrap();
    assert!(model.dofs.free_rigid_motions().is_empty());
}

/// A second, unsupported body in the same mesh: every rigid motion of the
/// mesh as a whole is held, and with zero load the Cholesky (rounding leaves
/// a tiny positive pivot) returns a harmless-looking zero solution; the
/// part-by-part check must still name the free motions of the loose part.
#[test]
fn an_unsupported_separate_part_is_reported_as_a_free_rigid_motion() {
    let mut mesh = rectangle(CellKind::Quad4, 2, 2, [0.0, 0.0], [1.0, 1.0]);
    let other = rectangle(CellKind::Quad4, 2, 2, [3.0, 0.0], [1.0, 1.0]);
    let offset = mesh.nodes.len();
    mesh.nodes.extend(&other.nodes);
    mesh.node_tags
        .extend(other.node_tags.iter().map(|t| t + offset as u64));
    mesh.cells.extend(other.cells.iter().map(|v| v + offset));
    mesh.cell_tags
        .extend(other.cell_tags.iter().map(|t| t + 100));
    let e = solve_err(
        &mesh,
        &[
            Dirichlet::new("left", 0, 0.0),
            Dirichlet::new("left", 1, 0.0),
        ],
    );
    let expected =
        "translation in x of the separate part of the mesh containing node 9 at (3, 0), \
                    translation in y of the separate part of the mesh containing node 9 at (3, 0), \
                    rotation of the separate part of the mesh containing node 9 at (3, 0)";
    assert_eq!(
        e,
        FemError::RigidBodyMotion {
            motions: expected.to_string()
        }
    );
}

#[test]
fn invalid_materials_are_refused_naming_the_parameter() {
    for (e, nu, rho, what) in [
        (-1.0, 0.3, 1.0, "Young's modulus E = -1"),
        (1.0, 0.5, 1.0, "Poisson's ratio nu = 0.5"),
        (1.0, 0.3, 0.0, "density rho = 0"),
    ] {
        let msg = Material::new(e, nu, rho, Hypothesis::PlaneStrain)
            .unwrap_err()
            .to_string();
        assert!(msg.contains(what), "{msg}");
    }
}

#[test]
fn unknown_groups_are_refused_listing_the_mesh_groups() {
    let mesh = slab(CellKind::Quad4, 1);
    let expect = |e: FemError, purpose: &str| {
        let msg = e.to_string();
        assert!(msg.contains("\"suport\"") && msg.contains(purpose), "{msg}");
        assert!(msg.contains("contact, load, support, left, body"), "{msg}");
    };
    expect(
        DofMap::new(&mesh, &[Dirichlet::new("suport", 1, 0.0)]).unwrap_err(),
        "a Dirichlet condition",
    );
    expect(
        Model::new(
            &mesh,
            &paper_material(),
            &[Dirichlet::new("suport", 1, 0.0)],
        )
        .unwrap_err(),
        "a Dirichlet condition",
    );
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    expect(
        traction_load(&mesh, "suport", Traction::Pressure(1.0), &mut full).unwrap_err(),
        "a traction",
    );
    let e = traction_load(&mesh, "body", Traction::Pressure(1.0), &mut full).unwrap_err();
    assert!(
        matches!(e, FemError::WrongGroupDimension { dim: 2, .. }),
        "{e}"
    );
}

#[test]
fn bad_dirichlet_conditions_are_refused() {
    let mesh = slab(CellKind::Quad4, 1);
    let e = DofMap::new(&mesh, &[Dirichlet::new("left", 2, 0.0)]).unwrap_err();
    assert!(e.to_string().contains("use 0 for x or 1 for y"), "{e}");
    let e = DofMap::new(&mesh, &[Dirichlet::new("left", 0, f64::NAN)]).unwrap_err();
    assert!(matches!(e, FemError::NonFiniteDirichlet { .. }), "{e}");
    // (0, 0) is on both `left` and `contact`: two values for u_x there.
    let e = DofMap::new(
        &mesh,
        &[
            Dirichlet::new("left", 0, 0.0),
            Dirichlet::new("contact", 0, 0.5),
        ],
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("\"left\"") && msg.contains("\"contact\"") && msg.contains("(0, 0)"),
        "{msg}"
    );
    // The same value twice is fine.
    assert!(DofMap::new(
        &mesh,
        &[
            Dirichlet::new("left", 0, 0.0),
            Dirichlet::new("contact", 0, 0.0)
        ]
    )
    .is_ok());
}

#[test]
fn prescribed_values_are_expanded_and_restricted() {
    let mesh = slab(CellKind::Quad4, 1);
    let dofs = DofMap::new(&mesh, &[Dirichlet::new("left", 0, 0.25)]).unwrap();
    assert_eq!(dofs.n_free(), 2 * 85 - 5);
    let free: Vec<f64> = (0..dofs.n_free()).map(|i| i as f64).collect();
    let mut full = vec![0.0; 170];
    dofs.expand(&free, &mut full);
    let mut back = vec![0.0; dofs.n_free()];
    dofs.restrict(&full, &mut back);
    assert_eq!(back, free);
    for v in &mesh.group("left").unwrap().nodes {
        assert_eq!(full[2 * v], 0.25);
        assert_eq!(dofs.prescribed(*v, 0), Some(0.25));
        assert_eq!(dofs.free(*v, 0), None);
    }
    dofs.expand_homogeneous(&free, &mut full);
    assert!(mesh
        .group("left")
        .unwrap()
        .nodes
        .iter()
        .all(|v| full[2 * v] == 0.0));
}
