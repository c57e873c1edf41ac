//! The fill-reducing ordering (ordering.rs): the nested dissection numbers
//! every free DOF once on any mesh, splits the slab at its middle line, is
//! as good as AMD on a grid, and `choose` keeps the smaller factor.

use stickslip_fem::ordering::{
    choose, dissection_with_halves, nested_dissection, wanted, DISSECTION_MIN_DOFS, FILL_ORDER_ENV,
};
use stickslip_fem::{Dirichlet, DofMap, Model, NodeOrder};
use stickslip_linalg::{analyze_symbolic, FillOrder};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::{
    add_point_group, map_nodes, paper_material, paper_supports, read_mesh, rectangle, slab,
};

fn slab_dofs(kind: CellKind, refine: usize) -> (Mesh, DofMap) {
    let mesh = slab(kind, refine);
    let dofs = DofMap::new(&mesh, &paper_supports()).unwrap();
    (mesh, dofs)
}

#[test]
fn every_free_dof_once() {
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let (mesh, dofs) = slab_dofs(kind, 4);
        let order = nested_dissection(&mesh, &dofs);
        let mut seen = vec![false; dofs.n_free()];
        for &d in &order {
            assert!(!seen[d], "{kind:?}: DOF {d} twice");
            seen[d] = true;
        }
        assert_eq!(order.len(), dofs.n_free(), "{kind:?}");
    }
}

/// Meshes the slabs are not: two disjoint parts, two parts on top of
/// each other (equal centroids in pairs), one part all clamped, a
/// single row and a single column of cells, a third of the nodes
/// clamped, nodes in no cell (free or clamped): each free DOF once.
#[test]
fn every_free_dof_once_on_odd_meshes() {
    fn merge(a: &Mesh, b: &Mesh) -> Mesh {
        let mut m = a.clone();
        let off = a.nodes.len();
        m.nodes.extend(&b.nodes);
        m.node_tags = (1..=m.nodes.len() as u64).collect();
        m.cells.extend(b.cells.iter().map(|v| v + off));
        m.cell_tags = (1..=(m.cells.len() / m.kind.nodes_per_cell()) as u64).collect();
        m
    }
    let clamp = |group: &str| [Dirichlet::new(group, 0, 0.0), Dirichlet::new(group, 1, 0.0)];
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let a = rectangle(kind, 12, 7, [0.0, 0.0], [3.0, 2.0]);
        let mut meshes = Vec::new();
        for (origin, fixed) in [([5.0, 0.5], false), ([0.0, 0.0], false), ([5.0, 0.0], true)] {
            let b = rectangle(kind, 6, 9, origin, [1.0, 2.0]);
            let mut m = merge(&a, &b);
            let off = a.nodes.len();
            let held: Vec<usize> = if fixed {
                (off..m.nodes.len()).collect()
            } else {
                b.groups[0].nodes.iter().map(|v| v + off).collect()
            };
            add_point_group(&mut m, "held", &held);
            meshes.push(m);
        }
        for (nx, ny) in [(40, 1), (1, 40)] {
            let mut m = rectangle(kind, nx, ny, [0.0, 0.0], [nx as f64, ny as f64]);
            add_point_group(&mut m, "held", &[0]);
            meshes.push(m);
        }
        let mut m = a.clone();
        let third: Vec<usize> = (0..m.nodes.len()).step_by(3).collect();
        add_point_group(&mut m, "held", &third);
        meshes.push(m);
        let mut m = a.clone();
        let n = m.nodes.len();
        m.nodes.extend([[9.0, 9.0], [9.0, 1.0]]);
        m.node_tags.extend([n as u64 + 1, n as u64 + 2]);
        add_point_group(&mut m, "held", &[n]);
        meshes.push(m);
        for (i, mesh) in meshes.iter().enumerate() {
            let conditions: Vec<Dirichlet> =
                clamp("bottom").into_iter().chain(clamp("held")).collect();
            let dofs = DofMap::new(mesh, &conditions).unwrap();
            let order = nested_dissection(mesh, &dofs);
            let mut seen = vec![false; dofs.n_free()];
            for &d in &order {
                assert!(!seen[d], "{kind:?} mesh {i}: DOF {d} twice");
                seen[d] = true;
            }
            assert_eq!(order.len(), dofs.n_free(), "{kind:?} mesh {i}");
            assert_eq!(order, nested_dissection(mesh, &dofs), "{kind:?} mesh {i}");
        }
    }
}

/// The first split of the 64×16 Q1 slab (8 × 1) is across x at the
/// median cell column: its separator, numbered last, is the 17 nodes of
/// the line x = 4 (less the support's y, fixed: 33 free DOFs).
#[test]
fn the_last_dofs_are_the_middle_line() {
    let (mesh, dofs) = slab_dofs(CellKind::Quad4, 4);
    let order = nested_dissection(&mesh, &dofs);
    let dofs = &dofs;
    let line: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&v| (mesh.nodes[v][0] - 4.0).abs() < 1e-12)
        .flat_map(|v| (0..2).filter_map(move |k| dofs.free(v, k)))
        .collect();
    assert_eq!(line.len(), 33);
    let mut last: Vec<usize> = order[order.len() - line.len()..].to_vec();
    last.sort_unstable();
    let mut want = line.clone();
    want.sort_unstable();
    assert_eq!(last, want);
}

/// The first split's halves: the DOFs left and right of the middle line,
/// numbered first (the left's, then the right's), and no entry of K
/// couples them (a factorization may split there).
#[test]
fn the_halves_are_the_two_sides_of_the_middle_line() {
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let mesh = slab(kind, 4);
        let model = Model::new(&mesh, &paper_material(), &paper_supports()).unwrap();
        let (order, halves) = dissection_with_halves(&mesh, &model.dofs);
        let [n1, n2] = halves.expect("two halves");
        let side = |d: usize| {
            let v = model.dofs.full_of_free(d) / 2;
            mesh.nodes[v][0] - 4.0
        };
        assert!(order[..n1].iter().all(|&d| side(d) < -1e-12), "{kind:?}");
        assert!(
            order[n1..n1 + n2].iter().all(|&d| side(d) > 1e-12),
            "{kind:?}"
        );
        assert!(
            order[n1 + n2..].iter().all(|&d| side(d).abs() < 1e-12),
            "{kind:?}"
        );
        let k = &model.stiffness;
        let left: Vec<bool> = {
            let mut l = vec![false; k.nrows()];
            order[..n1].iter().for_each(|&d| l[d] = true);
            l
        };
        for &d in &order[n1..n1 + n2] {
            assert!(k.row(d).col_indices().iter().all(|&j| !left[j]), "{kind:?}");
        }
    }
}

/// A split reads its separator only from the cells near it (within three
/// times the farthest any node lies from its cell's centroid, `reach`):
/// on meshes whose cells differ in size by far the first split still
/// leaves two halves that K does not couple, so no node the halves share
/// was missed. The graded slabs have their widest cells (29.5 times the
/// narrowest) at the middle line, where the first split falls: there the
/// centroids across it lie 2·reach apart, so a band below that fails.
/// The committed unstructured slabs too.
#[test]
fn the_halves_are_uncoupled_on_graded_and_unstructured_meshes() {
    let mut meshes = Vec::new();
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let mut mesh = slab(kind, 4);
        // x = 8 (1/2 + g(s)), s = x/8 − 1/2, g(s) = 1.475 s − 1.9 s³: g'
        // is 1.475 at the middle and 0.05 at the ends.
        map_nodes(&mut mesh, |[x, y]| {
            let s = x / 8.0 - 0.5;
            [8.0 * (0.5 + 1.475 * s - 1.9 * s.powi(3)), y]
        });
        meshes.push((format!("graded {kind:?}"), mesh));
    }
    for file in ["slab-unstructured-q1.msh", "slab-unstructured-q2.msh"] {
        meshes.push((file.to_string(), read_mesh(file).unwrap()));
    }
    for (name, mesh) in meshes {
        let model = Model::new(&mesh, &paper_material(), &paper_supports()).unwrap();
        let (order, halves) = dissection_with_halves(&mesh, &model.dofs);
        let [n1, n2] = halves.expect("two halves");
        assert!(n1 > 0 && n2 > 0 && n1 + n2 < order.len(), "{name}");
        let k = &model.stiffness;
        let mut first = vec![false; k.nrows()];
        order[..n1].iter().for_each(|&d| first[d] = true);
        for &d in &order[n1..n1 + n2] {
            assert!(
                k.row(d).col_indices().iter().all(|&j| !first[j]),
                "{name}: DOF {d}"
            );
        }
    }
}

/// The dissection's quality where AMD is at its best, a grid numbered
/// row by row: within 5% of AMD's factor values (1.003 for Q1 and 1.028
/// for Q2 at these 101k DOFs), and the same factor whatever the
/// numbering of the DOFs (reverse Cuthill–McKee's here).
#[test]
fn dissection_fill_is_amd_s_on_a_grid_whatever_the_numbering() {
    let material = paper_material();
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let (mesh, grid) = slab_dofs(kind, 28);
        assert_eq!(grid.node_order(), NodeOrder::Grid);
        let band = grid.renumbered(&mesh, NodeOrder::Bandwidth).unwrap();
        let mut values = Vec::new();
        for dofs in [grid, band] {
            let nd = FillOrder::dissection(nested_dissection(&mesh, &dofs));
            let model = Model::with_dofs(&mesh, &material, dofs).unwrap();
            let count = |order: &FillOrder| {
                analyze_symbolic(&model.stiffness, order).unwrap().len_val() as f64
            };
            values.push((count(&nd), count(&FillOrder::amd())));
        }
        let ((nd_grid, amd_grid), (nd_band, _)) = (values[0], values[1]);
        assert!(
            nd_grid <= 1.05 * amd_grid,
            "{kind:?}: {nd_grid} factor values against AMD's {amd_grid}"
        );
        assert_eq!(
            nd_grid, nd_band,
            "{kind:?}: the numbering changed the factor"
        );
    }
}

/// From 10,000 nodes `Model::new` makes the nodes' dissection beside the
/// DOF map: its factors' order is the one made from the finished DOF map.
#[test]
fn the_dissection_made_beside_the_dof_map_is_the_same() {
    if std::env::var_os(FILL_ORDER_ENV).is_some() {
        return;
    }
    assert!(!wanted(DISSECTION_MIN_DOFS / 2 - 1));
    let mesh = slab(CellKind::Quad4, 28);
    assert!(mesh.nodes.len() >= 10_000 && wanted(mesh.nodes.len()));
    let model = Model::new(&mesh, &paper_material(), &paper_supports()).unwrap();
    model.fill_order.keep_dissection();
    assert_eq!(
        model.fill_order.dissection_order(),
        Some(&nested_dissection(&mesh, &model.dofs)[..])
    );
    let (_, halves) = dissection_with_halves(&mesh, &model.dofs);
    assert_eq!(model.fill_order.halves(), halves);
}

#[test]
fn amd_on_small_meshes_the_smaller_factor_on_large_ones() {
    if std::env::var_os(FILL_ORDER_ENV).is_some() {
        return;
    }
    // The 16 × 4 slab: AMD; the 32 × 8 (552 free DOFs): the dissection.
    let (mesh, dofs) = slab_dofs(CellKind::Quad4, 1);
    assert!(dofs.n_free() < DISSECTION_MIN_DOFS);
    let small = choose(&mesh, &dofs, None);
    assert!(small.dissection_order().is_none());
    assert_eq!(small.name(), "AMD");
    assert_eq!(small.decided_name(), Some("AMD"));
    let (mesh, dofs) = slab_dofs(CellKind::Quad4, 2);
    assert!(dofs.n_free() >= DISSECTION_MIN_DOFS);
    assert!(choose(&mesh, &dofs, None).dissection_order().is_some());
    // 28 × (16×4) cells: 100,912 free DOFs, the dissection a
    // candidate, kept; and a strip of 5000 × 10 cells (110k DOFs),
    // where AMD's factor is the smaller by more than the margin (1.23×,
    // fill_order_shapes).
    let (slab, slab_dofs) = slab_dofs(CellKind::Quad4, 28);
    let strip = rectangle(CellKind::Quad4, 5000, 10, [0.0, 0.0], [5000.0, 10.0]);
    let strip_dofs = DofMap::new(
        &strip,
        &[
            Dirichlet::new("left", 0, 0.0),
            Dirichlet::new("left", 1, 0.0),
        ],
    )
    .unwrap();
    let material = paper_material();
    for (mesh, dofs, amd_wins) in [(slab, slab_dofs, false), (strip, strip_dofs, true)] {
        assert!(dofs.n_free() >= DISSECTION_MIN_DOFS);
        let order = choose(&mesh, &dofs, None);
        assert_eq!(
            order.dissection_order(),
            Some(&nested_dissection(&mesh, &dofs)[..])
        );
        assert!(order.name().contains("clearly"), "{}", order.name());
        assert_eq!(order.decided_name(), None);
        let model = Model::with_dofs(&mesh, &material, dofs).unwrap();
        let k = &model.stiffness;
        let values = |order: &FillOrder| analyze_symbolic(k, order).unwrap().len_val();
        let (nd, amd) = (
            values(&FillOrder::dissection(
                order.dissection_order().unwrap().to_vec(),
            )),
            values(&FillOrder::amd()),
        );
        let dissection_kept = nd as f64 <= stickslip_linalg::AMD_MARGIN * amd as f64;
        assert_eq!(!dissection_kept, amd_wins, "AMD {amd}, the dissection {nd}");
        let kept = if dissection_kept { nd } else { amd };
        // A clone shares the decision.
        let copy = order.clone();
        assert_eq!(values(&order), kept);
        let want = if dissection_kept {
            "nested dissection"
        } else {
            "AMD"
        };
        assert_eq!(copy.name(), want, "{nd} against AMD's {amd}");
        assert_eq!(copy.decided_name(), Some(want));
        assert_eq!(values(&copy), kept);
        // A run that factorizes once (the explicit preload) keeps the
        // dissection without analysing AMD's order, where AMD wins too.
        let once = choose(&mesh, &model.dofs, None);
        once.keep_dissection();
        assert_eq!(once.decided_name(), Some("nested dissection"));
        assert_eq!(values(&once), nd);
        // AMD by size stays AMD.
        let amd_order = FillOrder::amd();
        amd_order.keep_dissection();
        assert_eq!(values(&amd_order), amd);
    }
}

/// On an unstructured mesh the cells' centroids put a staircase between
/// the halves; from `CUT_MIN_CELLS` cells a split takes the shortest path
/// of cell sides across a band instead. A 256 × 64 grid on [0, 8] × [0, 1]
/// whose rows of nodes are moved along x by up to 1.5 cells (less within
/// 16 cells of the ends), each row its own way (deterministically): its
/// columns of nodes are still paths of cell sides, 65 nodes, which no
/// path across the slab beats, while the rows' centroids move the
/// centroid split's staircase by a cell here and there. The first
/// separator is a column (65 nodes, 129 free DOFs: the top node's y is
/// held), and the halves it leaves are uncoupled.
#[test]
fn a_large_split_takes_the_shortest_path_across() {
    let mut mesh = slab(CellKind::Quad4, 16);
    assert_eq!(mesh.n_cells(), 256 * 64);
    let (lo, hi) = mesh
        .nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[0]), hi.max(p[0]))
        });
    let h = (hi - lo) / 256.0;
    map_nodes(&mut mesh, |[x, y]| {
        let i = ((x - lo) / h).round() as u64;
        if i == 0 || i == 256 {
            return [x, y];
        }
        // Rows are 1/64 apart.
        let j = (y * 64.0).round() as u64;
        let mut s = (j * 7_919 + 13) | 1;
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let r = (s % 1_000) as f64 / 1_000.0 - 0.5;
        // Tapered over 16 cells from the ends, whose nodes stay.
        let taper = (i.min(256 - i) as f64 / 16.0).min(1.0);
        [x + 3.0 * r * taper * h, y]
    });
    let model = Model::new(&mesh, &paper_material(), &paper_supports()).unwrap();
    let (order, halves) = dissection_with_halves(&mesh, &model.dofs);
    let [n1, n2] = halves.expect("two halves");
    assert_eq!(
        order.len() - n1 - n2,
        2 * 65 - 1,
        "the first separator's DOFs"
    );
    let k = &model.stiffness;
    let mut first = vec![false; k.nrows()];
    order[..n1].iter().for_each(|&d| first[d] = true);
    for &d in &order[n1..n1 + n2] {
        assert!(k.row(d).col_indices().iter().all(|&j| !first[j]), "DOF {d}");
    }
}
