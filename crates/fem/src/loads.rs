//! Consistent load vectors (METHOD.md §3): edge tractions on named boundary
//! groups and body forces. They ADD into full (interleaved nodal) vectors so
//! several loads can be summed into one.

use stickslip_mesh::{Edge, Mesh};

use crate::element::{CellBasis, MAX_NODES};
use crate::error::FemError;
use crate::geometry::Jacobian;
use crate::quadrature::GaussLegendre;
use crate::reference::{line2, line3};

/// A traction on a boundary group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Traction {
    /// A fixed vector (t_x, t_y), force per unit length.
    Vector([f64; 2]),
    /// A normal pressure p: t = −p·n with n the outward normal, so p > 0
    /// pushes into the body.
    Pressure(f64),
}

/// The geometry of one boundary edge at its quadrature points.
pub(crate) struct EdgeGeometry {
    /// Nodes: line2 (start, end), line3 (start, end, mid).
    pub nodes: [usize; 3],
    /// 2 or 3.
    pub n: usize,
}

impl EdgeGeometry {
    pub(crate) fn of(edge: &Edge) -> Self {
        match edge.mid {
            Some(m) => EdgeGeometry {
                nodes: [edge.nodes[0], edge.nodes[1], m],
                n: 3,
            },
            None => EdgeGeometry {
                nodes: [edge.nodes[0], edge.nodes[1], usize::MAX],
                n: 2,
            },
        }
    }

    /// Shape values, position x(s) and derivative dx/ds at `s` in [-1, 1].
    #[inline]
    pub(crate) fn eval(&self, mesh: &Mesh, s: f64, nv: &mut [f64; 3]) -> ([f64; 2], [f64; 2]) {
        let mut dn = [0.0; 3];
        if self.n == 3 {
            line3(s, nv, &mut dn);
        } else {
            line2(s, nv, &mut dn);
        }
        let (mut x, mut dx) = ([0.0; 2], [0.0; 2]);
        for a in 0..self.n {
            let p = mesh.nodes[self.nodes[a]];
            x[0] += nv[a] * p[0];
            x[1] += nv[a] * p[1];
            dx[0] += dn[a] * p[0];
            dx[1] += dn[a] * p[1];
        }
        (x, dx)
    }
}

/// The dimension-1 group `name`, for `purpose`.
pub(crate) fn line_group<'m>(
    mesh: &'m Mesh,
    name: &str,
    purpose: &str,
) -> Result<&'m stickslip_mesh::Group, FemError> {
    let g = crate::find_group(mesh, name, purpose)?;
    if g.dim != 1 {
        return Err(FemError::WrongGroupDimension {
            name: name.to_string(),
            purpose: purpose.to_string(),
            dim: g.dim,
        });
    }
    Ok(g)
}

/// Adds the consistent load `∫ N_a t ds` of a traction on group `group`
/// into `full` (length 2·n_nodes).
///
/// # Errors
/// Unknown group, or a group that is not made of boundary lines.
///
/// # Panics
/// If `full` has the wrong length.
pub fn traction_load(
    mesh: &Mesh,
    group: &str,
    traction: Traction,
    full: &mut [f64],
) -> Result<(), FemError> {
    traction_load_with(
        mesh,
        group,
        |_, n| match traction {
            Traction::Vector(t) => t,
            Traction::Pressure(p) => [-p * n[0], -p * n[1]],
        },
        full,
    )
}

/// Adds the consistent load of a traction that varies along the boundary:
/// `traction(x, n)` gets the point and the unit outward normal there.
///
/// # Errors
/// Unknown group, or a group that is not made of boundary lines.
///
/// # Panics
/// If `full` has the wrong length.
pub fn traction_load_with(
    mesh: &Mesh,
    group: &str,
    traction: impl Fn([f64; 2], [f64; 2]) -> [f64; 2],
    full: &mut [f64],
) -> Result<(), FemError> {
    assert_eq!(full.len(), 2 * mesh.nodes.len(), "full vector length");
    let g = line_group(mesh, group, "a traction")?;
    // 3 points for line2, 4 for line3: exact for constant tractions on
    // curved line3 edges and accurate for smooth varying ones.
    let rule2 = GaussLegendre::new(3);
    let rule3 = GaussLegendre::new(4);
    let mut nv = [0.0; 3];
    for edge in &g.edges {
        let eg = EdgeGeometry::of(edge);
        let rule = if eg.n == 3 { &rule3 } else { &rule2 };
        for (&s, &w) in rule.points().iter().zip(rule.weights()) {
            let (x, dx) = eg.eval(mesh, s, &mut nv);
            let len = (dx[0] * dx[0] + dx[1] * dx[1]).sqrt();
            if len == 0.0 {
                continue;
            }
            // Outward normal: the tangent turned clockwise (body on the left).
            let normal = [dx[1] / len, -dx[0] / len];
            let t = traction(x, normal);
            for a in 0..eg.n {
                let v = eg.nodes[a];
                full[2 * v] += w * len * nv[a] * t[0];
                full[2 * v + 1] += w * len * nv[a] * t[1];
            }
        }
    }
    Ok(())
}

/// Adds the consistent body-force load `∫ N_a f dA` of a constant force per
/// unit volume into `full`.
///
/// # Panics
/// If `full` has the wrong length.
pub fn body_force_load(mesh: &Mesh, force_per_volume: [f64; 2], full: &mut [f64]) {
    body_force_load_with(mesh, |_| force_per_volume, full);
}

/// Adds the consistent load of a body force varying in space, `force(x)`.
/// Cells are integrated with the full Gauss rule (a mesh that assembles
/// into a [`crate::Model`] has positive det J there).
///
/// # Panics
/// If `full` has the wrong length.
pub fn body_force_load_with(mesh: &Mesh, force: impl Fn([f64; 2]) -> [f64; 2], full: &mut [f64]) {
    body_force_load_rule(mesh, &CellBasis::full(mesh.kind), force, full);
}

/// As [`body_force_load_with`] with a chosen cell rule.
pub fn body_force_load_rule(
    mesh: &Mesh,
    basis: &CellBasis,
    force: impl Fn([f64; 2]) -> [f64; 2],
    full: &mut [f64],
) {
    assert_eq!(full.len(), 2 * mesh.nodes.len(), "full vector length");
    let n = basis.n_nodes();
    let mut coords = [[0.0; 2]; MAX_NODES];
    for c in 0..mesh.n_cells() {
        let cell = mesh.cell(c);
        for (x, &v) in coords.iter_mut().zip(cell) {
            *x = mesh.nodes[v];
        }
        for q in 0..basis.n_points() {
            let j = Jacobian::from_gradients(&coords[..n], basis.gradients(q));
            let w = basis.weight(q) * j.det;
            let nv = basis.values(q);
            let mut x = [0.0; 2];
            for a in 0..n {
                x[0] += nv[a] * coords[a][0];
                x[1] += nv[a] * coords[a][1];
            }
            let f = force(x);
            for (a, &v) in cell.iter().enumerate() {
                full[2 * v] += w * nv[a] * f[0];
                full[2 * v + 1] += w * nv[a] * f[1];
            }
        }
    }
}
