//! The fill-reducing ordering of the Cholesky factors (the static solve,
//! Newmark's A₀, the consistent mass): faer's AMD on small systems, a
//! nested dissection by cells from [`DISSECTION_MIN_DOFS`] unless AMD's
//! factor is clearly smaller ([`FillOrder`]).
//!
//! Nested dissection: the cells are split at the median of their centroids
//! across the longer side of their bounding box, the nodes the two halves
//! share are the separator and are numbered after both halves, and each
//! half is split again down to single cells. The separator is the line of
//! nodes between two rows of cells, one node wide for Q1 and Q2 alike.
//! Measured against AMD (faer's symbolic and numeric factorization of K,
//! `Par::Seq`, 2026-11-26; `cases/hole.geo` meshed by Gmsh with lc_hole =
//! lc/2, the slabs built in code):
//!
//! | mesh                   | DOFs  | factor values, ND / AMD | numeric factorization | ordering + symbolic |
//! |------------------------|-------|-------------------------|-----------------------|---------------------|
//! | hole Q1, lc 0.0196     | 61k   | 6.11M / 6.25M           | 0.061 / 0.065 s       | 0.028 / 0.039 s     |
//! | hole Q1, lc 0.0098     | 238k  | 28.7M / 32.6M           | 0.46 / 0.61 s         | 0.13 / 0.27 s       |
//! | hole Q2, lc 0.0196     | 243k  | 29.5M / 35.9M           | 0.52 / 0.71 s         | 0.15 / 0.31 s       |
//! | hole Q1, lc 0.0045     | 1.12M | 164M / 196M             | 3.55 / 5.26 s         | 0.91 / 1.64 s       |
//! | hole Q2, lc 0.009      | 1.13M | 165M / 233M             | 3.67 / 6.90 s         | 0.72 / 1.78 s       |
//! | slab Q2, row by row    | 62k   | 5.21M / 5.08M           | 0.052 / 0.051 s       | 0.020 / 0.045 s     |
//! | slab Q1, row by row    | 249k  | 25.1M / 24.6M           | 0.38 / 0.37 s         | 0.10 / 0.20 s       |
//! | slab Q2, row by row    | 993k  | 115M / 121M             | 2.24 / 2.41 s         | 0.52 / 1.40 s       |
//!
//! On unstructured meshes from 238k DOFs the dissection has 12-29% fewer
//! values and factorizes 1.3-1.9× faster; on grids numbered row by row its
//! fill is within 5% of AMD's either way. Its supernodes are larger, and
//! the Newmark step is as fast or faster even on the grids (`bench_step
//! --case newmark MESH 10 3`, `STICKSLIP_FILL_ORDER` = nd against amd, two
//! alternating runs each): slab Q2 352×88 (249k DOFs) 43.6-46.1 against
//! 50.9-51.7 ms, slab Q1 708×177 (251k) 45.8-49.0 against 49.1-50.1 ms,
//! Gmsh's `hole.geo` Q1 at 238k 44.0-45.8 against 49.7-50.3 ms and Q2 at
//! 243k 51.3-51.8 against 57.5-59.9 ms, with setups of 2.7-3.0 against
//! 3.7-4.4 s on those two (the dissection alone; with AMD's analysis
//! beside it, below, the Q2 mesh's setup read 3.44-3.52 against 4.71-4.83
//! s and its step 51.8-56.7 against 61.8-62.0 ms, two alternating runs on
//! a busier host). Below [`DISSECTION_MIN_DOFS`] AMD stays (the
//! slab Q2 16×4, 552 DOFs: 18.1k factor values against AMD's 16.0k; the
//! paper's Q2 8×2, 148 DOFs: 3.3k against 3.5k).
//!
//! Not every mesh above [`DISSECTION_MIN_DOFS`] gains: on non-convex
//! domains and long thin strips the dissection's factor is larger than
//! AMD's (a comb of 114k DOFs 1.28-1.37×, strips of 500:1 1.23-1.28×,
//! 200:1 1.11×: `cargo run --release -p stickslip-fem --example
//! fill_order_shapes`). So from [`DISSECTION_MIN_DOFS`] the first
//! factorization of a run analyses its pattern in both orders and keeps
//! the dissection unless AMD's factor has [`stickslip_linalg::AMD_MARGIN`] fewer values
//! ([`choose`]); K, A₀ and M share the pattern, and the later
//! factorizations reuse the choice. The price is AMD's analysis beside the
//! dissection's (1.5 s at 1.12M DOFs, where the dissection saves 1.7 s of
//! factorization; 0.3 s at 250k).
//!
//! Tried and not kept: leaves of 2, 4 or 16 cells in any order (up to 31%
//! more fill than AMD on the Q2 slab of 249k DOFs with 16; 2 and 4 never
//! better than single cells); separators of nodes (one side's nodes
//! touching the other, by the node graph): equal on Q1, 10% more fill
//! than AMD on the Q2 mesh of 1.13M DOFs, where the median cuts through
//! cells whose nodes couple two node rows apart.

use stickslip_linalg::FillOrder;
use stickslip_mesh::Mesh;

use crate::dofs::DofMap;

/// Free DOFs from which the factors are ordered by nested dissection (the
/// table above: at 61-62k the two are within 3% either way).
pub const DISSECTION_MIN_DOFS: usize = 100_000;

/// Environment variable that overrides the choice, for comparisons:
/// `amd` or `nd` (as [`crate::dofs::ORDER_ENV`] keeps the file's node
/// order); any other value, or none, chooses by size.
pub const FILL_ORDER_ENV: &str = "STICKSLIP_FILL_ORDER";

/// The ordering of the model's factors: AMD below [`DISSECTION_MIN_DOFS`]
/// free DOFs, else the dissection or AMD by their factors
/// ([`stickslip_linalg::AMD_MARGIN`]), unless [`FILL_ORDER_ENV`] says which.
pub fn choose(mesh: &Mesh, dofs: &DofMap) -> FillOrder {
    match std::env::var(FILL_ORDER_ENV).as_deref() {
        Ok("amd") => FillOrder::amd(),
        Ok("nd") => FillOrder::dissection(nested_dissection(mesh, dofs)),
        _ if dofs.n_free() < DISSECTION_MIN_DOFS => FillOrder::amd(),
        _ => FillOrder::dissection_unless_amd(nested_dissection(mesh, dofs)),
    }
}

/// The free DOFs of `dofs` in nested-dissection order (module
/// documentation), each node's DOFs together, x before y. Deterministic:
/// the same mesh gives the same order.
pub fn nested_dissection(mesh: &Mesh, dofs: &DofMap) -> Vec<usize> {
    let n_nodes = mesh.nodes.len();
    let centroid: Vec<[f64; 2]> = (0..mesh.n_cells())
        .map(|c| {
            // Corners first in both cell kinds.
            let corners = &mesh.cell(c)[..4];
            let mut x = [0.0; 2];
            for &v in corners {
                x[0] += 0.25 * mesh.nodes[v][0];
                x[1] += 0.25 * mesh.nodes[v][1];
            }
            x
        })
        .collect();
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        Open,
        Separator,
        Numbered,
    }
    let mut state = vec![State::Open; n_nodes];
    let mut in_first = vec![u32::MAX; n_nodes];
    let mut nodes = Vec::with_capacity(n_nodes);
    enum Job {
        Split(Vec<u32>),
        Number(Vec<usize>),
    }
    let mut jobs = vec![Job::Split((0..mesh.n_cells() as u32).collect())];
    let mut split = 0u32;
    while let Some(job) = jobs.pop() {
        let mut cells = match job {
            Job::Number(separator) => {
                for v in separator {
                    state[v] = State::Numbered;
                    nodes.push(v);
                }
                continue;
            }
            Job::Split(cells) => cells,
        };
        if cells.len() <= 1 {
            for &c in &cells {
                for &v in mesh.cell(c as usize) {
                    if state[v] == State::Open {
                        state[v] = State::Numbered;
                        nodes.push(v);
                    }
                }
            }
            continue;
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &c in &cells {
            for d in 0..2 {
                lo[d] = lo[d].min(centroid[c as usize][d]);
                hi[d] = hi[d].max(centroid[c as usize][d]);
            }
        }
        let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
        let key = |c: &u32| centroid[*c as usize][axis];
        let mid = cells.len() / 2;
        cells.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        // Split at a coordinate, so that cells of one row or column (equal
        // centroids on a grid) stay on one side and the separator is a
        // straight line; by position when none lies below the median.
        let at = key(&cells[mid]);
        let (first, second): (Vec<u32>, Vec<u32>) = if cells[..mid].iter().any(|c| key(c) < at) {
            cells.iter().partition(|c| key(c) < at)
        } else {
            (cells[..mid].to_vec(), cells[mid..].to_vec())
        };
        for &c in &first {
            for &v in mesh.cell(c as usize) {
                in_first[v] = split;
            }
        }
        let mut separator = Vec::new();
        for &c in &second {
            for &v in mesh.cell(c as usize) {
                if in_first[v] == split && state[v] == State::Open {
                    state[v] = State::Separator;
                    separator.push(v);
                }
            }
        }
        split += 1;
        jobs.push(Job::Number(separator));
        jobs.push(Job::Split(second));
        jobs.push(Job::Split(first));
    }
    // Nodes in no cell (a mesh may carry them) last.
    nodes.extend((0..n_nodes).filter(|&v| state[v] == State::Open));
    nodes
        .iter()
        .flat_map(|&v| (0..2).filter_map(move |k| dofs.free(v, k)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{rectangle, slab};
    use crate::Dirichlet;
    use stickslip_mesh::CellKind;

    fn slab_dofs(kind: CellKind, refine: usize) -> (Mesh, DofMap) {
        let mesh = slab(kind, refine);
        let dofs = DofMap::new(
            &mesh,
            &[
                Dirichlet::new("support", 1, 0.0),
                Dirichlet::new("left", 0, 0.0),
            ],
        )
        .unwrap();
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
        use crate::testing::{add_point_group, rectangle};
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

    /// The dissection's quality where AMD is at its best, a grid numbered
    /// row by row: within 5% of AMD's factor values (1.003 for Q1 and 1.028
    /// for Q2 at 101k DOFs, 2026-11-26), and the same factor whatever the
    /// numbering of the DOFs (reverse Cuthill–McKee's here).
    #[test]
    fn dissection_fill_is_amd_s_on_a_grid_whatever_the_numbering() {
        use crate::{Hypothesis, Material, Model, NodeOrder};
        use stickslip_linalg::analyze_symbolic;
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
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

    #[test]
    fn amd_on_small_meshes_the_smaller_factor_on_large_ones() {
        use crate::{Hypothesis, Material, Model};
        use stickslip_linalg::analyze_symbolic;
        if std::env::var_os(FILL_ORDER_ENV).is_some() {
            return;
        }
        let (mesh, dofs) = slab_dofs(CellKind::Quad4, 4);
        let small = choose(&mesh, &dofs);
        assert!(small.dissection_order().is_none());
        assert_eq!(small.name(), "AMD");
        assert_eq!(small.decided_name(), Some("AMD"));
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
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        for (mesh, dofs, amd_wins) in [(slab, slab_dofs, false), (strip, strip_dofs, true)] {
            assert!(dofs.n_free() >= DISSECTION_MIN_DOFS);
            let order = choose(&mesh, &dofs);
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
        }
    }
}
