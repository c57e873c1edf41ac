//! Cells that are valid but nearly degenerate.
//!
//! The reader refuses cells whose Jacobian determinant det J is not
//! positive at their nodes and Gauss points. A cell can pass that and
//! still be nearly degenerate: Gmsh's quad recombination can leave a cell
//! with two sides on one curved boundary, a corner angle near 180°, where
//! det J at that corner is a tiny fraction of its value elsewhere in the
//! cell. Strains there are formed with J⁻¹ and the nodal stresses blow up
//! (on a Q2 half-annulus, det J at one corner was 5e-5 of the centre's
//! and the nodal von Mises there read 5.1e4 against a 99th percentile of
//! 570). Such cells run, so they are reported, not refused.

use crate::{CellKind, Mesh};

/// The fraction of a cell's largest det J below which its smallest makes
/// it nearly degenerate. A rectangle has 1, a parallelogram 1, a
/// trapezoid whose short side is half its long one 0.5, and the cells of
/// the committed meshes, curved Q2 cells on holes included, 0.32 and more;
/// the half-annulus's cells were at 5e-5.
pub const DEGENERATE_RATIO: f64 = 0.02;

/// The nearly degenerate cells of a mesh ([`degenerate_cells`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Degenerate {
    /// Cells whose smallest det J (over their nodes and Gauss points) is
    /// below `ratio` times their largest.
    pub cells: usize,
    /// Cells of the mesh.
    pub of: usize,
    /// The ratio the cells were measured against.
    pub ratio: f64,
    /// The worst of them: its index, Gmsh's element tag, its centroid
    /// (the mean of its corners) and its smallest over largest det J.
    pub worst: (usize, u64, [f64; 2], f64),
}

impl std::fmt::Display for Degenerate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (_, tag, [x, y], r) = self.worst;
        write!(
            f,
            "{} of the {} cells are nearly degenerate: somewhere in each, det J is below {} of its largest value \
             in the cell (worst: element {tag} near ({x:.6}, {y:.6}), {r:.1e}), as where a cell has two sides on one \
             curved boundary; strains and stresses there are unreliable (the nodal stresses can be orders of \
             magnitude off). In Gmsh, re-mesh with more cells along curved boundaries, with smoothing \
             (Mesh.Smoothing = 10) or another recombination (Mesh.RecombinationAlgorithm), or mesh the region \
             transfinite; `stickslip mesh FILE` reports again",
            self.cells, self.of, self.ratio
        )
    }
}

/// Smallest over largest det J of cell `c`, over its nodes and Gauss
/// points (3×3 for quad9, 2×2 for quad4).
pub fn jacobian_ratio(mesh: &Mesh, c: usize) -> f64 {
    let cell = mesh.cell(c);
    let (lo, hi) = match mesh.kind {
        CellKind::Quad4 => {
            let p = [0, 1, 2, 3].map(|k| mesh.nodes[cell[k]]);
            min_max(&crate::basis::quad4_dets(&p))
        }
        CellKind::Quad9 => {
            let p = std::array::from_fn(|k| mesh.nodes[cell[k]]);
            min_max(&crate::basis::quad9_dets(&crate::basis::quad9_grid(&p)))
        }
    };
    lo / hi
}

fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &d| {
            (lo.min(d), hi.max(d))
        })
}

/// The cells whose [`jacobian_ratio`] is below `ratio` (use
/// [`DEGENERATE_RATIO`]), or `None` if there are none.
pub fn degenerate_cells(mesh: &Mesh, ratio: f64) -> Option<Degenerate> {
    let mut count = 0;
    let mut worst: Option<(usize, f64)> = None;
    for c in 0..mesh.n_cells() {
        let r = jacobian_ratio(mesh, c);
        if r < ratio {
            count += 1;
            if worst.is_none_or(|(_, w)| r < w) {
                worst = Some((c, r));
            }
        }
    }
    let (c, r) = worst?;
    let corners = &mesh.cell(c)[..4];
    let centroid = [0, 1].map(|k| corners.iter().map(|&n| mesh.nodes[n][k]).sum::<f64>() / 4.0);
    Some(Degenerate {
        cells: count,
        of: mesh.n_cells(),
        ratio,
        worst: (c, mesh.cell_tags[c], centroid, r),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A "dart" (0,0), (2,0), (2,2), (1, 1 + δ) next to a unit square,
    /// as quad4 or as straight-sided quad9 cells. det J of the bilinear
    /// map at a corner is a quarter of the cross product of its two sides:
    /// 1 at (2,0), (1 + δ)/2 at (0,0), 1/2 at (2,2) and δ/2 at the dart's
    /// tip, and affine in between, so the ratio is δ/2.
    fn dart(delta: f64, kind: CellKind) -> Mesh {
        let tip = [1.0, 1.0 + delta];
        let corners = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], tip];
        let square = [[2.0, 0.0], [3.0, 0.0], [3.0, 1.0], [2.0, 1.0]];
        let mut nodes = Vec::new();
        let mut cells = Vec::new();
        for quad in [corners, square] {
            let mut cell: Vec<[f64; 2]> = quad.to_vec();
            if kind == CellKind::Quad9 {
                let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                for k in 0..4 {
                    cell.push(mid(quad[k], quad[(k + 1) % 4]));
                }
                cell.push(mid(mid(quad[0], quad[2]), mid(quad[1], quad[3])));
            }
            for p in cell {
                cells.push(nodes.len());
                nodes.push(p);
            }
        }
        Mesh {
            node_tags: (1..=nodes.len() as u64).collect(),
            nodes,
            kind,
            cells,
            cell_tags: vec![7, 8],
            groups: Vec::new(),
            source: Default::default(),
        }
    }

    #[test]
    fn a_dart_is_reported_with_its_ratio_and_a_square_is_not() {
        for kind in [CellKind::Quad4, CellKind::Quad9] {
            let mesh = dart(1e-3, kind);
            assert!((jacobian_ratio(&mesh, 0) - 5e-4).abs() < 1e-12, "{kind:?}");
            assert!((jacobian_ratio(&mesh, 1) - 1.0).abs() < 1e-12, "{kind:?}");
            let d = degenerate_cells(&mesh, DEGENERATE_RATIO).expect("the dart");
            assert_eq!((d.cells, d.of, d.worst.0, d.worst.1), (1, 2, 0, 7));
            assert!((d.worst.3 - 5e-4).abs() < 1e-12);
            assert_eq!(d.worst.2, [1.25, (3.0 + 1e-3) / 4.0]);
            let said = d.to_string();
            assert!(
                said.starts_with("1 of the 2 cells are nearly degenerate"),
                "{said}"
            );
            assert!(
                said.contains("element 7 near (1.250000, 0.750250), 5.0e-4"),
                "{said}"
            );
            // δ = 0.1 gives 0.05, above the bound: no report.
            assert_eq!(degenerate_cells(&dart(0.1, kind), DEGENERATE_RATIO), None);
        }
    }

    /// A quad9 whose mid-side node is pulled towards the centre is curved:
    /// its ratio comes from inside, not from the corners. The square's
    /// side x = 3 with its mid-side node moved to (3 − d, 0.5): at
    /// (ξ, η) = (1, 0), ∂x/∂ξ = (0.5 − 1.5 d, 0) and ∂x/∂η = (0, 0.5), so
    /// det J = 0.25 − 0.75 d; at (−1, 0) it is 0.25 + 0.25 d, the largest;
    /// the ratio (1 − 3d)/(1 + d) is 1/13 at d = 0.3 (the cell inverts at
    /// d = 1/3).
    #[test]
    fn a_curved_quad9_is_measured_inside() {
        let mut mesh = dart(1.0, CellKind::Quad9);
        assert!((jacobian_ratio(&mesh, 1) - 1.0).abs() < 1e-12);
        mesh.nodes[9 + 5] = [2.7, 0.5];
        let curved = jacobian_ratio(&mesh, 1);
        assert!((curved - 1.0 / 13.0).abs() < 1e-12, "{curved}");
    }

    /// The committed meshes have no such cell.
    #[test]
    fn the_committed_meshes_have_none() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/meshes");
        let mut seen = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "msh") {
                let mesh = Mesh::from_file(&path).unwrap();
                let worst = (0..mesh.n_cells())
                    .map(|c| jacobian_ratio(&mesh, c))
                    .fold(f64::INFINITY, f64::min);
                eprintln!("{}: smallest ratio {worst:.3}", path.display());
                assert_eq!(
                    degenerate_cells(&mesh, DEGENERATE_RATIO),
                    None,
                    "{}",
                    path.display()
                );
                seen += 1;
            }
        }
        assert!(seen > 0);
    }
}
