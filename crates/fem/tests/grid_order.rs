//! The node orders of free DOFs (dofs.rs): Gmsh's slabs are numbered as
//! the generator numbers its grid (`NodeOrder::Grid`), Gmsh's rounding of
//! the coordinates does not stop it, other meshes get reverse
//! Cuthill–McKee's band (`NodeOrder::Bandwidth`), and a model in either
//! order is the mesh-order model with its rows and columns permuted, bit
//! for bit.

use stickslip_fem::{Dirichlet, DofMap, Model, NodeOrder};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::{paper_material, read_mesh, rectangle};

/// The paper's supports: rollers on `top`, x held on `left`.
fn supports(top: &str) -> Vec<Dirichlet> {
    vec![Dirichlet::new(top, 1, 0.0), Dirichlet::new("left", 0, 0.0)]
}

fn coordinates(mesh: &Mesh, dofs: &DofMap) -> Vec<([f64; 2], usize)> {
    (0..dofs.n_free())
        .map(|i| {
            let dof = dofs.full_of_free(i);
            (mesh.nodes[dof / 2], dof % 2)
        })
        .collect()
}

#[test]
fn gmsh_slabs_in_grid_order_are_numbered_as_the_generator_numbers_them() {
    for (file, kind, nx, ny) in [
        ("slab-q2-8x2.msh", CellKind::Quad9, 8, 2),
        ("slab-q1-32x8.msh", CellKind::Quad4, 32, 8),
        ("slab-q2-32x8.msh", CellKind::Quad9, 32, 8),
    ] {
        let gmsh = read_mesh(file).unwrap();
        let made = DofMap::new(&gmsh, &supports("support")).unwrap();
        let mine = made.renumbered(&gmsh, NodeOrder::Mesh).unwrap();
        let grid = mine.renumbered(&gmsh, NodeOrder::Grid).expect("a grid");
        assert_eq!(grid.node_order(), NodeOrder::Grid);
        let rect = rectangle(kind, nx, ny, [0.0, 0.0], [8.0, 1.0]);
        let theirs = DofMap::new(&rect, &supports("top")).unwrap();
        let theirs = theirs.renumbered(&rect, NodeOrder::Mesh).unwrap();
        let (a, b) = (coordinates(&gmsh, &grid), coordinates(&rect, &theirs));
        assert_eq!(a.len(), b.len(), "{file}");
        for (i, ((p, c), (q, d))) in a.iter().zip(&b).enumerate() {
            assert_eq!(c, d, "{file}: free DOF {i} component");
            assert!(
                (p[0] - q[0]).abs() <= 1e-12 && (p[1] - q[1]).abs() <= 1e-12,
                "{file}: free DOF {i} at {p:?}, the generator's at {q:?}"
            );
        }
        // Gmsh's order is not the grid's (boundary nodes first): the two
        // numberings differ, so the tests that compare them compare
        // something.
        assert!(
            (0..grid.n_free()).any(|i| grid.full_of_free(i) != mine.full_of_free(i)),
            "{file}"
        );
        // The generator's own order is the grid order already.
        let again = theirs.renumbered(&rect, NodeOrder::Grid).unwrap();
        assert!((0..again.n_free()).all(|i| again.full_of_free(i) == theirs.full_of_free(i)));
    }
}

#[test]
fn grid_order_takes_gmsh_rounding_and_declines_meshes_that_are_no_grid() {
    // Gmsh's transfinite nodes (not snapped) sit up to about 1e-11 off their
    // grid lines on an 8 x 1 slab: the same numbering.
    let exact = read_mesh("slab-q2-32x8.msh").unwrap();
    let mut noisy = exact.clone();
    for (i, p) in noisy.nodes.iter_mut().enumerate() {
        let w = ((i as f64) * 0.618_033_988_75).fract() - 0.5;
        p[0] += 3e-11 * w;
        p[1] -= 2e-11 * w;
    }
    let conditions = supports("support");
    let a = DofMap::new(&exact, &conditions).unwrap();
    let b = DofMap::new(&noisy, &conditions).unwrap();
    let (a, b) = (
        a.renumbered(&exact, NodeOrder::Grid).unwrap(),
        b.renumbered(&noisy, NodeOrder::Grid).unwrap(),
    );
    assert!((0..a.n_free()).all(|i| a.full_of_free(i) == b.full_of_free(i)));
    // Unstructured meshes are no grid: they get the band.
    let keep = std::env::var("STICKSLIP_DOF_ORDER").as_deref() == Ok("mesh");
    for file in ["hole-q1.msh", "hole-q2.msh", "slab-unstructured-q1.msh"] {
        let mesh = read_mesh(file).unwrap();
        let d = edge_fixed(&mesh);
        let expected = if keep {
            NodeOrder::Mesh
        } else {
            NodeOrder::Bandwidth
        };
        assert_eq!(d.node_order(), expected, "{file}");
        assert!(d.renumbered(&mesh, NodeOrder::Grid).is_none(), "{file}");
    }
}

/// The DOF map of `mesh` with u_x fixed on its first boundary group.
fn edge_fixed(mesh: &Mesh) -> DofMap {
    let group = mesh.groups.iter().find(|g| g.dim == 1).unwrap();
    DofMap::new(mesh, &[Dirichlet::new(group.name.clone(), 0, 0.0)]).unwrap()
}

/// Largest |i − j| over the free DOFs of nodes that share a cell.
fn bandwidth(mesh: &Mesh, d: &DofMap) -> usize {
    let npc = mesh.kind.nodes_per_cell();
    let mut widest = 0;
    for cell in mesh.cells.chunks(npc) {
        let free: Vec<usize> = cell
            .iter()
            .flat_map(|&v| [d.free(v, 0), d.free(v, 1)])
            .flatten()
            .collect();
        if let (Some(lo), Some(hi)) = (free.iter().min(), free.iter().max()) {
            widest = widest.max(hi - lo);
        }
    }
    widest
}

#[test]
fn reverse_cuthill_mckee_narrows_gmsh_unstructured_meshes() {
    for file in [
        "hole-q1.msh",
        "hole-q2.msh",
        "slab-unstructured-q1.msh",
        "slab-unstructured-q2.msh",
    ] {
        let mesh = read_mesh(file).unwrap();
        let d = edge_fixed(&mesh);
        let (m, b) = (
            d.renumbered(&mesh, NodeOrder::Mesh).unwrap(),
            d.renumbered(&mesh, NodeOrder::Bandwidth).unwrap(),
        );
        // A numbering of the same free DOFs...
        assert_eq!(b.n_free(), m.n_free());
        let mut seen = vec![false; b.n_full()];
        for i in 0..b.n_free() {
            let dof = b.full_of_free(i);
            assert!(!seen[dof], "{file}");
            seen[dof] = true;
            assert!(m.free_of_full(dof).is_some(), "{file}");
        }
        // ... whose band is narrower than the file's.
        let (wm, wb) = (bandwidth(&mesh, &m), bandwidth(&mesh, &b));
        println!("{file}: band {wb} against the file's {wm}");
        assert!(4 * wb <= wm, "{file}: band {wb} against the file's {wm}");
    }
}

#[test]
fn a_model_in_another_order_is_the_mesh_order_model_permuted_bit_for_bit() {
    for (file, order) in [
        ("slab-q2-8x2.msh", NodeOrder::Grid),
        ("slab-unstructured-q2.msh", NodeOrder::Bandwidth),
    ] {
        permuted_model(file, order);
    }
}

fn permuted_model(file: &str, order: NodeOrder) {
    let mesh = read_mesh(file).unwrap();
    let material = paper_material();
    let dofs = DofMap::new(&mesh, &supports("support")).unwrap();
    let (dm, dg) = (
        dofs.renumbered(&mesh, NodeOrder::Mesh).unwrap(),
        dofs.renumbered(&mesh, order).unwrap(),
    );
    let m = Model::with_dofs(&mesh, &material, dm.clone()).unwrap();
    let g = Model::with_dofs(&mesh, &material, dg.clone()).unwrap();
    let n = m.dofs.n_free();
    // p: mesh-order free index → grid-order free index.
    let p: Vec<usize> = (0..n)
        .map(|i| dg.free_of_full(dm.full_of_free(i)).unwrap())
        .collect();
    let dense = |a: &nalgebra_sparse::CsrMatrix<f64>| {
        let mut d = vec![vec![0.0_f64; n]; n];
        for (i, j, v) in a.triplet_iter() {
            d[i][j] = *v;
        }
        d
    };
    for (name, a, b) in [
        ("K", &m.stiffness, &g.stiffness),
        ("M", m.mass.as_ref().unwrap(), g.mass.as_ref().unwrap()),
    ] {
        assert_eq!(a.nnz(), b.nnz(), "{name}");
        let (a, b) = (dense(a), dense(b));
        for i in 0..n {
            for j in 0..n {
                assert_eq!(
                    a[i][j].to_bits(),
                    b[p[i]][p[j]].to_bits(),
                    "{name}[{i}][{j}]"
                );
            }
        }
    }
    for i in 0..n {
        assert_eq!(m.lumped_mass[i].to_bits(), g.lumped_mass[p[i]].to_bits());
    }
    // A vector moved between the numberings and back.
    let x: Vec<f64> = (0..n).map(|i| i as f64 * 0.5 - 3.0).collect();
    let y = dg.from_numbering(&dm, &x);
    assert!((0..n).all(|i| y[p[i]] == x[i]));
    assert_eq!(dm.from_numbering(&dg, &y), x);
}

#[test]
fn every_grid_is_numbered_in_grid_order_unless_the_environment_says_mesh() {
    let keep = std::env::var("STICKSLIP_DOF_ORDER").as_deref() == Ok("mesh");
    let expected = if keep {
        NodeOrder::Mesh
    } else {
        NodeOrder::Grid
    };
    for file in ["slab-q2-8x2.msh", "slab-q1-16x4.msh", "slab-q2-64x16.msh"] {
        let mesh = read_mesh(file).unwrap();
        let d = DofMap::new(&mesh, &supports("support")).unwrap();
        assert_eq!(d.node_order(), expected, "{file}");
    }
}
