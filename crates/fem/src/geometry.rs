//! Isoparametric geometry: the map x(ξ) = Σ_a N_a(ξ) x_a of a cell, its
//! Jacobian, determinant and inverse. The same map serves Q1 (straight
//! edges) and Q2 (edges curved through their mid-side nodes).

use stickslip_mesh::CellKind;

use crate::reference::{cell_gradients, cell_values};

/// The Jacobian of the isoparametric map at one reference point:
/// `matrix[i][k] = ∂x_i/∂ξ_k`, `inverse[k][i] = ∂ξ_k/∂x_i`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jacobian {
    /// ∂x_i/∂ξ_k.
    pub matrix: [[f64; 2]; 2],
    /// det J (positive for a valid counter-clockwise cell).
    pub det: f64,
    /// J⁻¹ (meaningless when `det` is 0).
    pub inverse: [[f64; 2]; 2],
}

impl Jacobian {
    /// From the cell's node coordinates and the reference gradients of its
    /// shape functions at the point (both of the cell's node count).
    #[inline]
    pub fn from_gradients(coords: &[[f64; 2]], ref_grads: &[[f64; 2]]) -> Self {
        let mut m = [[0.0; 2]; 2];
        for (x, g) in coords.iter().zip(ref_grads) {
            m[0][0] += x[0] * g[0];
            m[0][1] += x[0] * g[1];
            m[1][0] += x[1] * g[0];
            m[1][1] += x[1] * g[1];
        }
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let r = 1.0 / det;
        let inverse = [[m[1][1] * r, -m[0][1] * r], [-m[1][0] * r, m[0][0] * r]];
        Jacobian {
            matrix: m,
            det,
            inverse,
        }
    }

    /// At reference point `xi` of a cell of `kind` with node coordinates `coords`.
    pub fn at(kind: CellKind, coords: &[[f64; 2]], xi: [f64; 2]) -> Self {
        let mut g = [[0.0; 2]; 9];
        let n = kind.nodes_per_cell();
        cell_gradients(kind, xi, &mut g[..n]);
        Jacobian::from_gradients(coords, &g[..n])
    }

    /// Physical gradients ∇_x N_a = J⁻ᵀ ∇_ξ N_a into `out`.
    #[inline]
    pub fn physical_gradients(&self, ref_grads: &[[f64; 2]], out: &mut [[f64; 2]]) {
        let v = &self.inverse;
        for (o, g) in out.iter_mut().zip(ref_grads) {
            *o = [
                g[0] * v[0][0] + g[1] * v[1][0],
                g[0] * v[0][1] + g[1] * v[1][1],
            ];
        }
    }
}

/// The physical point x(ξ) of a cell.
pub fn map_point(kind: CellKind, coords: &[[f64; 2]], xi: [f64; 2]) -> [f64; 2] {
    let mut n = [0.0; 9];
    cell_values(kind, xi, &mut n);
    let mut x = [0.0; 2];
    for (na, c) in n.iter().zip(coords) {
        x[0] += na * c[0];
        x[1] += na * c[1];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An affine map x = A ξ + b has J = A everywhere (closed form).
    #[test]
    fn affine_cell_jacobian_is_the_affine_matrix() {
        let a = [[2.0, 0.5], [-0.3, 1.5]];
        let b = [0.7, -1.1];
        let map = |p: [f64; 2]| {
            [
                a[0][0] * p[0] + a[0][1] * p[1] + b[0],
                a[1][0] * p[0] + a[1][1] * p[1] + b[1],
            ]
        };
        for kind in [CellKind::Quad4, CellKind::Quad9] {
            let coords: Vec<[f64; 2]> = crate::reference::cell_nodes(kind)
                .iter()
                .map(|&p| map(p))
                .collect();
            let j = Jacobian::at(kind, &coords, [0.2, -0.6]);
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            for i in 0..2 {
                for k in 0..2 {
                    assert!((j.matrix[i][k] - a[i][k]).abs() < 1e-14);
                }
            }
            assert!((j.det - det).abs() < 1e-14);
            // J J⁻¹ = I.
            for i in 0..2 {
                for k in 0..2 {
                    let p: f64 = (0..2).map(|m| j.matrix[i][m] * j.inverse[m][k]).sum();
                    assert!((p - if i == k { 1.0 } else { 0.0 }).abs() < 1e-14);
                }
            }
            let x = map_point(kind, &coords, [0.2, -0.6]);
            let e = map([0.2, -0.6]);
            assert!((x[0] - e[0]).abs() < 1e-14 && (x[1] - e[1]).abs() < 1e-14);
        }
    }

    /// A Q2 cell whose nodes sit on a quadratic map reproduces that map
    /// exactly, so J equals the map's analytic derivative (curved edges).
    #[test]
    fn curved_q2_cell_jacobian_matches_the_quadratic_map() {
        let map = |p: [f64; 2]| {
            [
                p[0] + 0.1 * p[1] * p[1],
                p[1] + 0.15 * p[0] * p[0] - 0.05 * p[0] * p[1],
            ]
        };
        let dmap = |p: [f64; 2]| {
            [
                [1.0, 0.2 * p[1]],
                [0.3 * p[0] - 0.05 * p[1], 1.0 - 0.05 * p[0]],
            ]
        };
        let coords: Vec<[f64; 2]> = crate::reference::Q2_NODES.iter().map(|&p| map(p)).collect();
        let xi = [0.37, -0.81];
        let j = Jacobian::at(CellKind::Quad9, &coords, xi);
        let e = dmap(xi);
        for i in 0..2 {
            for k in 0..2 {
                assert!((j.matrix[i][k] - e[i][k]).abs() < 1e-14);
            }
        }
    }
}
