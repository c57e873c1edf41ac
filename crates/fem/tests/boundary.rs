//! Boundary nodal quadrature: weights, tangents, normals, chain order.

use stickslip_fem::{boundary_quadrature, FemError};
use stickslip_mesh::{CellKind, Group};
use stickslip_testkit::{map_nodes, rectangle, slab};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-13
}

/// Expected (BENCHMARK.md): Simpson weights 1/6, 2/3, 1/6 of the edge length
/// (1) per Q2 edge, so node (8, 0) has w = 1/6 and node (7, 0) w = 1/3;
/// trapezoid 1/2, 1/2 of 0.5 per Q1 edge, so (8, 0) has 1/4 and (7, 0) 1/2.
/// Tangent +x, outward normal (0, −1) on the bottom face; chain from (0, 0).
#[test]
fn slab_bottom_weights_tangents_and_normals() {
    for (kind, w_end, w_71, n_nodes) in [
        (CellKind::Quad9, 1.0 / 6.0, 1.0 / 3.0, 17),
        (CellKind::Quad4, 0.25, 0.5, 17),
    ] {
        let mesh = slab(kind, 1);
        let bq = boundary_quadrature(&mesh, "contact").unwrap();
        assert_eq!(bq.len(), n_nodes);
        let at = |x: f64| {
            bq.iter()
                .find(|b| close(mesh.nodes[b.node][0], x) && close(mesh.nodes[b.node][1], 0.0))
                .unwrap()
        };
        assert!(
            close(at(8.0).weight, w_end),
            "{kind:?} w(8,0) = {}",
            at(8.0).weight
        );
        assert!(
            close(at(7.0).weight, w_71),
            "{kind:?} w(7,0) = {}",
            at(7.0).weight
        );
        assert!(close(at(0.0).weight, w_end));
        for (i, b) in bq.iter().enumerate() {
            assert_eq!(b.tangent, [1.0, 0.0]);
            assert_eq!(b.normal, [0.0, -1.0]);
            // Ordered from (0, 0) along +x; s is the x coordinate.
            assert!(close(mesh.nodes[b.node][0], 0.5 * i as f64));
            assert!(close(b.s, mesh.nodes[b.node][0]));
        }
        let total: f64 = bq.iter().map(|b| b.weight).sum();
        assert!(close(total, 8.0));
    }
}

/// Expected (geometry): a closed loop around the 2 × 1 rectangle has total
/// weight = perimeter 6; each corner's tangent is the normalised sum of the
/// unit tangents of its two edges, e.g. (1, −1)/√2 at (0, 0) (arriving along
/// −y, leaving along +x), so its outward normal is (−1, −1)/√2.
#[test]
fn closed_loop_around_a_rectangle_averages_tangents_at_corners() {
    for kind in [CellKind::Quad4, CellKind::Quad9] {
        let mut mesh = rectangle(kind, 4, 2, [0.0, 0.0], [2.0, 1.0]);
        let edges: Vec<_> = ["bottom", "right", "top", "left"]
            .iter()
            .flat_map(|n| mesh.group(n).unwrap().edges.clone())
            .collect();
        let mut nodes: Vec<usize> = edges
            .iter()
            .flat_map(|e| [e.nodes[0], e.nodes[1]].into_iter().chain(e.mid))
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        mesh.groups.push(Group {
            name: "outer".into(),
            tag: 9,
            dim: 1,
            elements: edges.len(),
            edges,
            cells: vec![],
            points: vec![],
            nodes,
        });
        let bq = boundary_quadrature(&mesh, "outer").unwrap();
        let expected_nodes = if kind == CellKind::Quad9 {
            2 * (8 + 4)
        } else {
            2 * (4 + 2)
        };
        assert_eq!(bq.len(), expected_nodes, "closed loop lists each node once");
        assert!((bq.iter().map(|b| b.weight).sum::<f64>() - 6.0).abs() < 1e-13);
        assert_eq!(bq[0].node, 0);
        let r = 0.5f64.sqrt();
        assert!(close(bq[0].tangent[0], r) && close(bq[0].tangent[1], -r));
        assert!(close(bq[0].normal[0], -r) && close(bq[0].normal[1], -r));
        assert!(close(
            bq.last().unwrap().s,
            6.0 - bq.last().map(|b| mesh.nodes[b.node][1]).unwrap()
        ));
    }
}

/// Expected (closed form): the bottom of a Q2 mesh bent onto a circular arc
/// of radius 2 over a quarter turn: total weight and arc length → π (Simpson
/// on the isoparametric arc, error O(h⁴), here < 1e-4 with 16 edges);
/// normals point away from the body, which lies outside radius 2, i.e.
/// towards the centre: n = −x/|x| (to 1e-3, the isoparametric arc is not a
/// circle exactly).
#[test]
fn curved_q2_edge_tangents_follow_the_arc() {
    let mut mesh = rectangle(CellKind::Quad9, 16, 2, [0.0, 0.0], [1.0, 1.0]);
    // (x, y) → (r cos t, −r sin t), t = x·π/2, r = 2 + y: det J = r·π/2 > 0,
    // so cells stay counter-clockwise and the bottom (y = 0) becomes the arc
    // r = 2, with the body outside it.
    map_nodes(&mut mesh, |[x, y]| {
        let t = x * std::f64::consts::FRAC_PI_2;
        let r = 2.0 + y;
        [r * t.cos(), -r * t.sin()]
    });
    let bq = boundary_quadrature(&mesh, "bottom").unwrap();
    let total: f64 = bq.iter().map(|b| b.weight).sum();
    assert!(
        (total - std::f64::consts::PI).abs() < 1e-4,
        "total weight {total}"
    );
    assert!((bq.last().unwrap().s - std::f64::consts::PI).abs() < 1e-6);
    for b in &bq {
        let p = mesh.nodes[b.node];
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        // The body is at r > 2, so the outward normal is −p/r.
        assert!(
            (b.normal[0] + p[0] / r).abs() < 1e-3 && (b.normal[1] + p[1] / r).abs() < 1e-3,
            "node {:?} normal {:?}",
            p,
            b.normal
        );
        assert!((b.tangent[0] * b.tangent[0] + b.tangent[1] * b.tangent[1] - 1.0).abs() < 1e-14);
    }
}

#[test]
fn non_chains_and_cell_groups_are_refused_with_the_group_named() {
    let mut mesh = rectangle(CellKind::Quad9, 3, 2, [0.0, 0.0], [3.0, 2.0]);
    match boundary_quadrature(&mesh, "domain") {
        Err(e @ FemError::WrongGroupDimension { .. }) => {
            assert!(e.to_string().contains("\"domain\""), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // Bottom and top together: two separate pieces.
    let edges: Vec<_> = ["bottom", "top"]
        .iter()
        .flat_map(|n| mesh.group(n).unwrap().edges.clone())
        .collect();
    mesh.groups.push(Group {
        name: "two".into(),
        tag: 10,
        dim: 1,
        elements: edges.len(),
        edges,
        cells: vec![],
        points: vec![],
        nodes: vec![],
    });
    match boundary_quadrature(&mesh, "two") {
        Err(e @ FemError::NotAChain { .. }) => {
            assert!(e.to_string().contains("2 separate pieces"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // An edge listed twice: the line overlaps itself.
    let mut edges = mesh.group("bottom").unwrap().edges.clone();
    edges.push(edges[1]);
    mesh.groups.push(Group {
        name: "dup".into(),
        tag: 11,
        dim: 1,
        elements: edges.len(),
        edges,
        cells: vec![],
        points: vec![],
        nodes: vec![],
    });
    match boundary_quadrature(&mesh, "dup") {
        Err(e @ FemError::NotAChain { .. }) => {
            assert!(e.to_string().contains("two of its edges start at"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    match boundary_quadrature(&mesh, "nope") {
        Err(e @ FemError::UnknownGroup { .. }) => {
            let s = e.to_string();
            assert!(
                s.contains("\"nope\"") && s.contains("bottom, right, top, left, domain"),
                "{s}"
            );
        }
        other => panic!("{other:?}"),
    }
}
