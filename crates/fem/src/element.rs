//! Element operators (METHOD.md §3): stiffness, consistent mass, HRZ-lumped
//! mass, body force, and strains/stresses, on shape data tabulated once per
//! cell kind at the quadrature points ([`CellBasis`]). Every routine writes
//! into buffers the caller owns and allocates nothing.
//!
//! Element DOFs are interleaved by node: local DOF `2a + i` is component `i`
//! of node `a`. The consistent mass is returned per node pair (an `n × n`
//! scalar matrix `∫ρ N_a N_b`), since it is the same for both components.

use stickslip_mesh::CellKind;

use crate::geometry::Jacobian;
use crate::quadrature::square_rule;
use crate::reference::{cell_gradients, cell_values};

/// Largest node count of a cell (Q2).
pub const MAX_NODES: usize = 9;
/// Largest number of element DOFs.
pub const MAX_DOFS: usize = 2 * MAX_NODES;

/// The isoparametric map folds over at a quadrature point: det J ≤ 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonPositiveJacobian {
    /// The determinant found.
    pub det: f64,
}

/// Shape functions and reference gradients of one cell kind, tabulated at
/// the points of a tensor Gauss rule.
#[derive(Clone, Debug)]
pub struct CellBasis {
    kind: CellKind,
    n: usize,
    points: Vec<[f64; 2]>,
    weights: Vec<f64>,
    values: Vec<f64>,
    gradients: Vec<[f64; 2]>,
}

impl CellBasis {
    /// Tabulation on an `points_per_direction²` Gauss rule (1 to 5).
    ///
    /// # Panics
    /// If `points_per_direction` is not in 1..=5.
    pub fn new(kind: CellKind, points_per_direction: usize) -> Self {
        let n = kind.nodes_per_cell();
        let rule = square_rule(points_per_direction);
        let mut values = vec![0.0; rule.len() * n];
        let mut gradients = vec![[0.0; 2]; rule.len() * n];
        for (q, (xi, _)) in rule.iter().enumerate() {
            cell_values(kind, *xi, &mut values[q * n..(q + 1) * n]);
            cell_gradients(kind, *xi, &mut gradients[q * n..(q + 1) * n]);
        }
        CellBasis {
            kind,
            n,
            points: rule.iter().map(|p| p.0).collect(),
            weights: rule.iter().map(|p| p.1).collect(),
            values,
            gradients,
        }
    }

    /// The "full" rule of METHOD.md §3: 2×2 for Q1, 3×3 for Q2 (exact for
    /// the mass of affine cells and the stiffness of parallelograms).
    pub fn full(kind: CellKind) -> Self {
        CellBasis::new(kind, full_rule(kind))
    }

    /// The cell kind.
    pub fn kind(&self) -> CellKind {
        self.kind
    }
    /// Nodes per cell.
    pub fn n_nodes(&self) -> usize {
        self.n
    }
    /// Number of quadrature points.
    pub fn n_points(&self) -> usize {
        self.weights.len()
    }
    /// Reference coordinates of quadrature point `q`.
    pub fn point(&self, q: usize) -> [f64; 2] {
        self.points[q]
    }
    /// Weight of quadrature point `q`.
    pub fn weight(&self, q: usize) -> f64 {
        self.weights[q]
    }
    /// Shape function values at point `q`.
    #[inline]
    pub fn values(&self, q: usize) -> &[f64] {
        &self.values[q * self.n..(q + 1) * self.n]
    }
    /// Reference gradients at point `q`.
    #[inline]
    pub fn gradients(&self, q: usize) -> &[[f64; 2]] {
        &self.gradients[q * self.n..(q + 1) * self.n]
    }

    /// Jacobian at point `q`, refusing a folded map.
    #[inline]
    fn jacobian(&self, coords: &[[f64; 2]], q: usize) -> Result<Jacobian, NonPositiveJacobian> {
        let j = Jacobian::from_gradients(coords, self.gradients(q));
        // Not `<= 0.0` alone: NaN coordinates must be refused too.
        if j.det > 0.0 && j.det.is_finite() {
            Ok(j)
        } else {
            Err(NonPositiveJacobian { det: j.det })
        }
    }

    /// Element stiffness `K_e = ∫ Bᵀ D B dA` into `ke` ((2n)², row-major) and
    /// node-pair consistent mass `M_ab = ∫ ρ N_a N_b dA` into `me` (n², or
    /// skipped when `me` is empty). Returns the cell area.
    ///
    /// # Errors
    /// [`NonPositiveJacobian`] when det J ≤ 0 at a quadrature point.
    pub fn stiffness_and_mass(
        &self,
        coords: &[[f64; 2]],
        d: &[[f64; 3]; 3],
        density: f64,
        ke: &mut [f64],
        me: &mut [f64],
    ) -> Result<f64, NonPositiveJacobian> {
        let n = self.n;
        let nd = 2 * n;
        let ke = &mut ke[..nd * nd];
        ke.fill(0.0);
        let with_mass = !me.is_empty();
        if with_mass {
            me[..n * n].fill(0.0);
        }
        let mut area = 0.0;
        let mut g = [[0.0; 2]; MAX_NODES];
        let isotropic = d[0][2] == 0.0 && d[1][2] == 0.0 && d[2][0] == 0.0 && d[2][1] == 0.0;
        for q in 0..self.n_points() {
            let j = self.jacobian(coords, q)?;
            let w = self.weights[q] * j.det;
            area += w;
            j.physical_gradients(self.gradients(q), &mut g[..n]);
            // Upper triangle of node-pair blocks: B_aᵀ D B_b with
            // B_b = [[bx, 0], [0, by], [by, bx]]. Isotropic D (no normal-shear
            // coupling, the only kind `Material` makes) takes the short path.
            if isotropic {
                let (d00, d01, d11, d22) = (d[0][0], d[0][1], d[1][1], d[2][2]);
                for a in 0..n {
                    let ax = w * g[a][0];
                    let ay = w * g[a][1];
                    let row0 = &mut ke[2 * a * nd..(2 * a + 1) * nd];
                    for b in a..n {
                        let (bx, by) = (g[b][0], g[b][1]);
                        row0[2 * b] += d00 * ax * bx + d22 * ay * by;
                        row0[2 * b + 1] += d01 * ax * by + d22 * ay * bx;
                    }
                    let row1 = &mut ke[(2 * a + 1) * nd..(2 * a + 2) * nd];
                    for b in a..n {
                        let (bx, by) = (g[b][0], g[b][1]);
                        row1[2 * b] += d01 * ay * bx + d22 * ax * by;
                        row1[2 * b + 1] += d11 * ay * by + d22 * ax * bx;
                    }
                }
            } else {
                for a in 0..n {
                    let ax = w * g[a][0];
                    let ay = w * g[a][1];
                    for b in a..n {
                        let (bx, by) = (g[b][0], g[b][1]);
                        let c0 = [
                            d[0][0] * bx + d[0][2] * by,
                            d[1][0] * bx + d[1][2] * by,
                            d[2][0] * bx + d[2][2] * by,
                        ];
                        let c1 = [
                            d[0][1] * by + d[0][2] * bx,
                            d[1][1] * by + d[1][2] * bx,
                            d[2][1] * by + d[2][2] * bx,
                        ];
                        let r0 = 2 * a * nd + 2 * b;
                        let r1 = r0 + nd;
                        ke[r0] += ax * c0[0] + ay * c0[2];
                        ke[r0 + 1] += ax * c1[0] + ay * c1[2];
                        ke[r1] += ay * c0[1] + ax * c0[2];
                        ke[r1 + 1] += ay * c1[1] + ax * c1[2];
                    }
                }
            }
            if with_mass {
                let nv = self.values(q);
                let wr = w * density;
                for a in 0..n {
                    let na = wr * nv[a];
                    for b in a..n {
                        me[a * n + b] += na * nv[b];
                    }
                }
            }
        }
        // Mirror: K is symmetric (D is), so fill the lower node-pair blocks
        // and the lower half of the diagonal blocks.
        for r in 0..nd {
            for c in 0..r {
                ke[r * nd + c] = ke[c * nd + r];
            }
        }
        if with_mass {
            for a in 0..n {
                for b in 0..a {
                    me[a * n + b] = me[b * n + a];
                }
            }
        }
        Ok(area)
    }

    /// Element stiffness alone (see [`CellBasis::stiffness_and_mass`]).
    ///
    /// # Errors
    /// [`NonPositiveJacobian`].
    pub fn stiffness(
        &self,
        coords: &[[f64; 2]],
        d: &[[f64; 3]; 3],
        ke: &mut [f64],
    ) -> Result<f64, NonPositiveJacobian> {
        self.stiffness_and_mass(coords, d, 0.0, ke, &mut [])
    }

    /// Node-pair consistent mass `M_ab = ∫ ρ N_a N_b dA` into `me` (n²).
    /// Returns the cell area.
    ///
    /// # Errors
    /// [`NonPositiveJacobian`].
    pub fn mass(
        &self,
        coords: &[[f64; 2]],
        density: f64,
        me: &mut [f64],
    ) -> Result<f64, NonPositiveJacobian> {
        let n = self.n;
        me[..n * n].fill(0.0);
        let mut area = 0.0;
        for q in 0..self.n_points() {
            let j = self.jacobian(coords, q)?;
            let w = self.weights[q] * j.det;
            area += w;
            let nv = self.values(q);
            for a in 0..n {
                for b in 0..n {
                    me[a * n + b] += density * w * nv[a] * nv[b];
                }
            }
        }
        Ok(area)
    }

    /// Consistent body-force vector `f_(2a+i) = ∫ N_a b_i(x) dA` into `fe`
    /// (2n), for a force per unit volume `b(x)`.
    ///
    /// # Errors
    /// [`NonPositiveJacobian`].
    pub fn body_force(
        &self,
        coords: &[[f64; 2]],
        force: impl Fn([f64; 2]) -> [f64; 2],
        fe: &mut [f64],
    ) -> Result<(), NonPositiveJacobian> {
        let n = self.n;
        fe[..2 * n].fill(0.0);
        for q in 0..self.n_points() {
            let j = self.jacobian(coords, q)?;
            let w = self.weights[q] * j.det;
            let nv = self.values(q);
            let mut x = [0.0; 2];
            for a in 0..n {
                x[0] += nv[a] * coords[a][0];
                x[1] += nv[a] * coords[a][1];
            }
            let b = force(x);
            for a in 0..n {
                fe[2 * a] += w * nv[a] * b[0];
                fe[2 * a + 1] += w * nv[a] * b[1];
            }
        }
        Ok(())
    }
}

/// Points per direction of the full Gauss rule: 2 for Q1, 3 for Q2.
pub fn full_rule(kind: CellKind) -> usize {
    match kind {
        CellKind::Quad4 => 2,
        CellKind::Quad9 => 3,
    }
}

/// HRZ lumping (Hinton-Rock-Zienkiewicz, METHOD.md §3): from the node-pair
/// consistent mass `me` (n²), `m_J = M_JJ · (element mass) / Σ_K M_KK`,
/// with the element mass the sum of all entries of `me`. Writes n values.
pub fn hrz_lumped_mass(me: &[f64], n: usize, out: &mut [f64]) {
    let total: f64 = me[..n * n].iter().sum();
    let diag: f64 = (0..n).map(|a| me[a * n + a]).sum();
    let scale = total / diag;
    for a in 0..n {
        out[a] = me[a * n + a] * scale;
    }
}

/// Strain (ε_xx, ε_yy, γ_xy) at reference point `xi` of a cell with node
/// coordinates `coords` and interleaved nodal displacements `ue` (2n).
///
/// # Errors
/// [`NonPositiveJacobian`].
pub fn strain_at(
    kind: CellKind,
    coords: &[[f64; 2]],
    ue: &[f64],
    xi: [f64; 2],
) -> Result<[f64; 3], NonPositiveJacobian> {
    let n = kind.nodes_per_cell();
    let mut rg = [[0.0; 2]; MAX_NODES];
    let mut g = [[0.0; 2]; MAX_NODES];
    cell_gradients(kind, xi, &mut rg[..n]);
    let j = Jacobian::from_gradients(coords, &rg[..n]);
    if !(j.det > 0.0 && j.det.is_finite()) {
        return Err(NonPositiveJacobian { det: j.det });
    }
    j.physical_gradients(&rg[..n], &mut g[..n]);
    let mut e = [0.0; 3];
    for a in 0..n {
        let (ux, uy) = (ue[2 * a], ue[2 * a + 1]);
        e[0] += g[a][0] * ux;
        e[1] += g[a][1] * uy;
        e[2] += g[a][1] * ux + g[a][0] * uy;
    }
    Ok(e)
}

/// σ = D ε in Voigt notation.
#[inline]
pub fn stress_from_strain(d: &[[f64; 3]; 3], e: [f64; 3]) -> [f64; 3] {
    [
        d[0][0] * e[0] + d[0][1] * e[1] + d[0][2] * e[2],
        d[1][0] * e[0] + d[1][1] * e[1] + d[1][2] * e[2],
        d[2][0] * e[0] + d[2][1] * e[1] + d[2][2] * e[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::{cell_nodes, Q2_NODES};

    /// Expected (BENCHMARK.md, closed form): on a rectangular Q2 element the
    /// diagonal of the consistent mass is the tensor product of the 1-D
    /// quadratic diagonal (2/15, 8/15, 2/15)·L/2, so HRZ gives corner :
    /// mid-side : centre = 1 : 4 : 16 in units of (element mass)/36.
    #[test]
    fn hrz_on_a_rectangular_q2_element_is_1_4_16() {
        let (lx, ly, rho) = (1.0, 0.5, 2.5);
        let coords: Vec<[f64; 2]> = Q2_NODES
            .iter()
            .map(|p| [(p[0] + 1.0) * lx / 2.0 + 3.0, (p[1] + 1.0) * ly / 2.0])
            .collect();
        let b = CellBasis::full(CellKind::Quad9);
        let mut me = [0.0; 81];
        let area = b.mass(&coords, rho, &mut me).unwrap();
        assert!((area - lx * ly).abs() < 1e-14);
        let mut m = [0.0; 9];
        hrz_lumped_mass(&me, 9, &mut m);
        let unit = rho * lx * ly / 36.0;
        let expected = [1.0, 1.0, 1.0, 1.0, 4.0, 4.0, 4.0, 4.0, 16.0];
        for a in 0..9 {
            assert!(
                (m[a] / unit - expected[a]).abs() < 1e-12,
                "node {a}: {}",
                m[a] / unit
            );
        }
    }

    /// Expected: ∫ρ dA = ρ·area (area of a quadrilateral by the shoelace
    /// formula); HRZ keeps the total and is positive.
    #[test]
    fn element_mass_sums_to_rho_area_and_hrz_is_positive() {
        let corners = [[0.0, 0.0], [2.0, 0.3], [1.7, 1.9], [-0.2, 1.1]];
        let shoelace: f64 = 0.5
            * (0..4)
                .map(|i| {
                    corners[i][0] * corners[(i + 1) % 4][1]
                        - corners[(i + 1) % 4][0] * corners[i][1]
                })
                .sum::<f64>();
        for kind in [CellKind::Quad4, CellKind::Quad9] {
            // Nodes from the bilinear map of the corners: straight edges.
            let coords: Vec<[f64; 2]> = cell_nodes(kind)
                .iter()
                .map(|&xi| crate::geometry::map_point(CellKind::Quad4, &corners, xi))
                .collect();
            let b = CellBasis::full(kind);
            let n = kind.nodes_per_cell();
            let mut me = [0.0; 81];
            b.mass(&coords, 3.0, &mut me).unwrap();
            let total: f64 = me[..n * n].iter().sum();
            assert!((total - 3.0 * shoelace).abs() < 1e-12);
            let mut m = [0.0; 9];
            hrz_lumped_mass(&me, n, &mut m);
            assert!(m[..n].iter().all(|&v| v > 0.0));
            assert!((m[..n].iter().sum::<f64>() - 3.0 * shoelace).abs() < 1e-12);
        }
    }

    #[test]
    fn inverted_cell_is_refused() {
        let coords = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]; // clockwise
        let b = CellBasis::full(CellKind::Quad4);
        let mut ke = [0.0; 64];
        assert!(b
            .stiffness(
                &coords,
                &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                &mut ke
            )
            .is_err());
    }
}
