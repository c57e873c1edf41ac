//! Nodal quadrature on a named boundary line (METHOD.md §3): per-node
//! weights w_J from the trapezoid rule (line2) or Simpson's rule (line3),
//! summed over the group's edges, with unit tangents counter-clockwise along
//! the boundary (body on the left) and outward normals, ordered along the
//! chain. The `contact` crate builds the friction surface on this.

use std::collections::HashMap;

use stickslip_mesh::Mesh;

use crate::error::FemError;
use crate::loads::{line_group, EdgeGeometry};
use crate::quadrature::GaussLegendre;

/// One node of a boundary line with its nodal quadrature data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundaryNode {
    /// Mesh node index.
    pub node: usize,
    /// Nodal weight w_J: trapezoid (line2) or Simpson (line3) weights of
    /// each adjacent edge, summed. On a straight edge of length L these are
    /// L/2, L/2 and L/6, 2L/3, L/6; on a curved line3 edge Simpson's rule is
    /// applied to ∫|x'(s)| ds on the reference edge, so the weights still
    /// integrate the arc length.
    pub weight: f64,
    /// Unit tangent, counter-clockwise along the boundary (body on the
    /// left); the normalised sum of the adjacent edges' unit tangents where
    /// the line bends.
    pub tangent: [f64; 2],
    /// Unit outward normal = (tangent.y, −tangent.x).
    pub normal: [f64; 2],
    /// Arc length from the first node of the chain.
    pub s: f64,
}

/// The nodes of boundary group `group` in chain order (the first node is
/// the start of an open chain; for a closed loop, the start of the group's
/// first edge), with weights, tangents and normals.
///
/// # Errors
/// Unknown group; a group of dimension ≠ 1; a group that is empty, branches,
/// or is not one connected open or closed chain.
pub fn boundary_quadrature(mesh: &Mesh, group: &str) -> Result<Vec<BoundaryNode>, FemError> {
    let g = line_group(mesh, group, "a boundary quadrature (contact surface)")?;
    let not_chain = |reason: String| FemError::NotAChain {
        name: group.to_string(),
        reason,
    };
    let at = |v: usize| format!("node {v} at ({}, {})", mesh.nodes[v][0], mesh.nodes[v][1]);
    if g.edges.is_empty() {
        return Err(not_chain("it has no edges".to_string()));
    }
    let mut by_start: HashMap<usize, usize> = HashMap::with_capacity(g.edges.len());
    let mut by_end: HashMap<usize, usize> = HashMap::with_capacity(g.edges.len());
    for (k, e) in g.edges.iter().enumerate() {
        if by_start.insert(e.nodes[0], k).is_some() {
            return Err(not_chain(format!(
                "two of its edges start at {} (the line branches or overlaps itself)",
                at(e.nodes[0])
            )));
        }
        if by_end.insert(e.nodes[1], k).is_some() {
            return Err(not_chain(format!(
                "two of its edges end at {} (the line branches or overlaps itself)",
                at(e.nodes[1])
            )));
        }
    }
    let starts: Vec<usize> = (0..g.edges.len())
        .filter(|&k| !by_end.contains_key(&g.edges[k].nodes[0]))
        .collect();
    let (first, closed) = match starts.len() {
        0 => (0, true),
        1 => (starts[0], false),
        n => {
            return Err(not_chain(format!(
                "it has {n} separate pieces (starting at {} and {})",
                at(g.edges[starts[0]].nodes[0]),
                at(g.edges[starts[1]].nodes[0])
            )))
        }
    };
    let mut order = Vec::with_capacity(g.edges.len());
    let mut k = first;
    loop {
        order.push(k);
        match by_start.get(&g.edges[k].nodes[1]) {
            Some(&next) if next != first => k = next,
            _ => break,
        }
        if order.len() > g.edges.len() {
            break;
        }
    }
    if order.len() != g.edges.len() {
        return Err(not_chain(format!(
            "the chain from {} covers {} of its {} edges; the rest form another piece",
            at(g.edges[first].nodes[0]),
            order.len(),
            g.edges.len()
        )));
    }

    let rule = GaussLegendre::new(5);
    let mut nv = [0.0; 3];
    let mut out: Vec<BoundaryNode> = Vec::with_capacity(2 * order.len() + 1);
    // Tangent sums, normalised at the end.
    let push =
        |out: &mut Vec<BoundaryNode>, node: usize, weight: f64, tangent: [f64; 2], s: f64| {
            out.push(BoundaryNode {
                node,
                weight,
                tangent,
                normal: [0.0; 2],
                s,
            });
        };
    let unit = |d: [f64; 2]| {
        let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
        [d[0] / l, d[1] / l]
    };
    let mut s0 = 0.0;
    for (i, &k) in order.iter().enumerate() {
        let eg = EdgeGeometry::of(&g.edges[k]);
        // Arc length of the edge and of its first half: 5-point Gauss on
        // |x'(s)| (exact enough for any smooth line3).
        let (mut len, mut half) = (0.0, 0.0);
        for (&p, &w) in rule.points().iter().zip(rule.weights()) {
            let (_, d) = eg.eval(mesh, p, &mut nv);
            len += w * (d[0] * d[0] + d[1] * d[1]).sqrt();
            let (_, dh) = eg.eval(mesh, 0.5 * (p - 1.0), &mut nv);
            half += 0.5 * w * (dh[0] * dh[0] + dh[1] * dh[1]).sqrt();
        }
        let speed = |s: f64, nv: &mut [f64; 3]| {
            let (_, d) = eg.eval(mesh, s, nv);
            ((d[0] * d[0] + d[1] * d[1]).sqrt(), unit(d))
        };
        let (j0, t0) = speed(-1.0, &mut nv);
        let (j1, t1) = speed(1.0, &mut nv);
        let (w0, w1) = if eg.n == 3 {
            (j0 / 3.0, j1 / 3.0)
        } else {
            (0.5 * len, 0.5 * len)
        };
        if i == 0 {
            push(&mut out, eg.nodes[0], 0.0, [0.0; 2], 0.0);
        }
        let last = out.last_mut().expect("pushed above");
        last.weight += w0;
        last.tangent = [last.tangent[0] + t0[0], last.tangent[1] + t0[1]];
        if eg.n == 3 {
            let (jm, tm) = speed(0.0, &mut nv);
            push(&mut out, eg.nodes[2], 4.0 * jm / 3.0, tm, s0 + half);
        }
        s0 += len;
        if closed && i + 1 == order.len() {
            out[0].weight += w1;
            out[0].tangent = [out[0].tangent[0] + t1[0], out[0].tangent[1] + t1[1]];
        } else {
            push(&mut out, eg.nodes[1], w1, t1, s0);
        }
    }
    for b in &mut out {
        b.tangent = unit(b.tangent);
        b.normal = [b.tangent[1], -b.tangent[0]];
    }
    Ok(out)
}
