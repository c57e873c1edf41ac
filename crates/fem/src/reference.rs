//! Reference elements: Q1 (4-node bilinear) and Q2 (9-node biquadratic
//! Lagrange) on [-1, 1]², line2 and line3 on [-1, 1]. Shape functions and
//! their reference gradients are written into buffers the caller owns, so a
//! hot loop evaluates them without allocating.
//!
//! Node orders follow the mesh crate: quad corners counter-clockwise from
//! (-1, -1), then the mid-sides of edges (0,1), (1,2), (2,3), (3,0), then the
//! centre ([`stickslip_mesh::GMSH_TO_FEM_QUAD9`]); a line3 is (start, end, mid)
//! as Gmsh writes it.

use stickslip_mesh::CellKind;

/// Reference coordinates of the Q1 nodes.
pub const Q1_NODES: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Reference coordinates of the Q2 nodes.
pub const Q2_NODES: [[f64; 2]; 9] = [
    [-1.0, -1.0],
    [1.0, -1.0],
    [1.0, 1.0],
    [-1.0, 1.0],
    [0.0, -1.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [-1.0, 0.0],
    [0.0, 0.0],
];

/// For each Q2 node, the indices (i, j) of its 1-D quadratic factors in ξ and
/// η; factor 0 is the node at -1, 1 at 0, 2 at +1.
const Q2_FACTORS: [(usize, usize); 9] = [
    (0, 0),
    (2, 0),
    (2, 2),
    (0, 2),
    (1, 0),
    (2, 1),
    (1, 2),
    (0, 1),
    (1, 1),
];

/// The 1-D quadratic Lagrange basis on nodes (-1, 0, 1) and its derivative.
#[inline]
fn quadratic_1d(x: f64) -> ([f64; 3], [f64; 3]) {
    (
        [0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)],
        [x - 0.5, -2.0 * x, x + 0.5],
    )
}

/// Q1 shape functions at `xi` into `n[0..4]`.
#[inline]
pub fn q1_values(xi: [f64; 2], n: &mut [f64]) {
    for (a, p) in Q1_NODES.iter().enumerate() {
        n[a] = 0.25 * (1.0 + p[0] * xi[0]) * (1.0 + p[1] * xi[1]);
    }
}

/// Q1 reference gradients (∂/∂ξ, ∂/∂η) at `xi` into `g[0..4]`.
#[inline]
pub fn q1_gradients(xi: [f64; 2], g: &mut [[f64; 2]]) {
    for (a, p) in Q1_NODES.iter().enumerate() {
        g[a] = [
            0.25 * p[0] * (1.0 + p[1] * xi[1]),
            0.25 * p[1] * (1.0 + p[0] * xi[0]),
        ];
    }
}

/// Q2 shape functions at `xi` into `n[0..9]`.
#[inline]
pub fn q2_values(xi: [f64; 2], n: &mut [f64]) {
    let (lx, _) = quadratic_1d(xi[0]);
    let (ly, _) = quadratic_1d(xi[1]);
    for (a, &(i, j)) in Q2_FACTORS.iter().enumerate() {
        n[a] = lx[i] * ly[j];
    }
}

/// Q2 reference gradients at `xi` into `g[0..9]`.
#[inline]
pub fn q2_gradients(xi: [f64; 2], g: &mut [[f64; 2]]) {
    let (lx, dx) = quadratic_1d(xi[0]);
    let (ly, dy) = quadratic_1d(xi[1]);
    for (a, &(i, j)) in Q2_FACTORS.iter().enumerate() {
        g[a] = [dx[i] * ly[j], lx[i] * dy[j]];
    }
}

/// Shape functions of a cell kind at `xi` into `n[0..kind.nodes_per_cell()]`.
#[inline]
pub fn cell_values(kind: CellKind, xi: [f64; 2], n: &mut [f64]) {
    match kind {
        CellKind::Quad4 => q1_values(xi, n),
        CellKind::Quad9 => q2_values(xi, n),
    }
}

/// Reference gradients of a cell kind at `xi` into `g[0..kind.nodes_per_cell()]`.
#[inline]
pub fn cell_gradients(kind: CellKind, xi: [f64; 2], g: &mut [[f64; 2]]) {
    match kind {
        CellKind::Quad4 => q1_gradients(xi, g),
        CellKind::Quad9 => q2_gradients(xi, g),
    }
}

/// Reference coordinates of a cell kind's nodes.
pub fn cell_nodes(kind: CellKind) -> &'static [[f64; 2]] {
    match kind {
        CellKind::Quad4 => &Q1_NODES,
        CellKind::Quad9 => &Q2_NODES,
    }
}

/// Line2 shape functions (start, end) and derivatives at `s` in [-1, 1].
#[inline]
pub fn line2(s: f64, n: &mut [f64], dn: &mut [f64]) {
    n[0] = 0.5 * (1.0 - s);
    n[1] = 0.5 * (1.0 + s);
    dn[0] = -0.5;
    dn[1] = 0.5;
}

/// Line3 shape functions in Gmsh order (start at -1, end at +1, mid at 0)
/// and derivatives at `s` in [-1, 1].
#[inline]
pub fn line3(s: f64, n: &mut [f64], dn: &mut [f64]) {
    let (l, d) = quadratic_1d(s);
    n[0] = l[0];
    n[1] = l[2];
    n[2] = l[1];
    dn[0] = d[0];
    dn[1] = d[2];
    dn[2] = d[1];
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lagrange property (N_a(x_b) = δ_ab) and partition of unity (Σ N_a = 1,
    /// Σ ∇N_a = 0) hold by construction of a Lagrange basis; gradients are
    /// checked against central differences of the values.
    #[test]
    fn cell_shape_functions_are_lagrange_and_gradients_match_differences() {
        for kind in [CellKind::Quad4, CellKind::Quad9] {
            let nn = kind.nodes_per_cell();
            let mut n = [0.0; 9];
            for (b, &xb) in cell_nodes(kind).iter().enumerate() {
                cell_values(kind, xb, &mut n);
                for a in 0..nn {
                    let expected = if a == b { 1.0 } else { 0.0 };
                    assert!((n[a] - expected).abs() < 1e-15);
                }
            }
            let xi = [0.31, -0.47];
            let mut g = [[0.0; 2]; 9];
            cell_values(kind, xi, &mut n);
            cell_gradients(kind, xi, &mut g);
            assert!((n[..nn].iter().sum::<f64>() - 1.0).abs() < 1e-15);
            let h = 1e-6;
            let (mut np, mut nm) = ([0.0; 9], [0.0; 9]);
            for d in 0..2 {
                let mut xp = xi;
                let mut xm = xi;
                xp[d] += h;
                xm[d] -= h;
                cell_values(kind, xp, &mut np);
                cell_values(kind, xm, &mut nm);
                let sum: f64 = g[..nn].iter().map(|v| v[d]).sum();
                assert!(sum.abs() < 1e-14);
                for a in 0..nn {
                    assert!(((np[a] - nm[a]) / (2.0 * h) - g[a][d]).abs() < 1e-8);
                }
            }
        }
    }

    #[test]
    fn line_shape_functions_are_lagrange() {
        let (mut n, mut dn) = ([0.0; 3], [0.0; 3]);
        for (b, s) in [-1.0, 1.0, 0.0].into_iter().enumerate() {
            line3(s, &mut n, &mut dn);
            for (a, &v) in n.iter().enumerate() {
                assert_eq!(v, if a == b { 1.0 } else { 0.0 });
            }
            assert!(dn.iter().sum::<f64>().abs() < 1e-15);
        }
        for (b, s) in [-1.0, 1.0].into_iter().enumerate() {
            line2(s, &mut n, &mut dn);
            for a in 0..2 {
                assert_eq!(n[a], if a == b { 1.0 } else { 0.0 });
            }
        }
    }
}
