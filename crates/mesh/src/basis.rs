//! The isoparametric maps of the two cell kinds, for the checks on their
//! Jacobian determinant det J (the reader's validity check and the
//! quality report): the quadratic Lagrange basis at the nodes and at the
//! 3×3 Gauss points the fem crate integrates with, and the bilinear map.

/// Fem node index of the quad9 node at (ξ, η) = (a - 1, b - 1), `[a][b]`.
const QUAD9_GRID: [[usize; 3]; 3] = [[0, 7, 3], [4, 8, 6], [1, 5, 2]];

/// √(3/5), the abscissa of the 3-point Gauss rule the fem crate integrates with.
const G: f64 = 0.774_596_669_241_483_4;

/// The quadratic Lagrange basis on -1, 0, 1 (`[i][a]`: basis `a` at point
/// `i`): derivatives at the nodes, values and derivatives at -G, 0, G.
const D_NODE: [[f64; 3]; 3] = [[-1.5, 2.0, -0.5], [-0.5, 0.0, 0.5], [0.5, -2.0, 1.5]];
const L_GAUSS: [[f64; 3]; 3] = [
    [0.5 * G * (G + 1.0), 1.0 - G * G, 0.5 * G * (G - 1.0)],
    [0.0, 1.0, 0.0],
    [0.5 * G * (G - 1.0), 1.0 - G * G, 0.5 * G * (G + 1.0)],
];
const D_GAUSS: [[f64; 3]; 3] = [
    [-G - 0.5, 2.0 * G, 0.5 - G],
    [-0.5, 0.0, 0.5],
    [G - 0.5, -2.0 * G, G + 0.5],
];

/// `w[0] v[0] + w[1] v[1] + w[2] v[2]`.
#[inline(always)]
fn comb(w: [f64; 3], v: [[f64; 2]; 3]) -> [f64; 2] {
    [
        w[0] * v[0][0] + w[1] * v[1][0] + w[2] * v[2][0],
        w[0] * v[0][1] + w[1] * v[1][1] + w[2] * v[2][1],
    ]
}

/// `det [a b]`.
#[inline(always)]
fn det(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The points `p` relative to the first and scaled to O(1): no overflow
/// at 1e200, no underflow at 1e-200, whatever the magnitude of the
/// coordinates (det J keeps its sign and its ratios).
fn relative<const N: usize>(p: &[[f64; 2]; N]) -> [[f64; 2]; N] {
    let o = p[0];
    let m = p.iter().fold(0.0f64, |m, q| {
        m.max((q[0] - o[0]).abs()).max((q[1] - o[1]).abs())
    });
    let s = if m > 0.0 && (1.0 / m).is_finite() {
        1.0 / m
    } else {
        1.0
    };
    p.map(|q| [(q[0] - o[0]) * s, (q[1] - o[1]) * s])
}

/// A quad9's nodes `p` (fem order) on the (ξ, η) grid, `[a][b]` as
/// [`QUAD9_GRID`], [`relative`] to node 0.
pub(crate) fn quad9_grid(p: &[[f64; 2]; 9]) -> [[[f64; 2]; 3]; 3] {
    let x = relative(p);
    QUAD9_GRID.map(|row| row.map(|k| x[k]))
}

/// det J of the quad9 map of the grid `x` ([`quad9_grid`]) at its 9 nodes,
/// then at its 3×3 Gauss points; positive for a counter-clockwise cell.
pub(crate) fn quad9_dets(x: &[[[f64; 2]; 3]; 3]) -> [f64; 18] {
    let mut out = [0.0; 18];
    let column = |v: &[[[f64; 2]; 3]; 3], j: usize| [v[0][j], v[1][j], v[2][j]];
    // At the nodes the basis is the identity: one 3-term sum a derivative.
    for (i, &di) in D_NODE.iter().enumerate() {
        for (j, &dj) in D_NODE.iter().enumerate() {
            out[3 * i + j] = det(comb(di, column(x, j)), comb(dj, x[i]));
        }
    }
    // At the Gauss points, values and η-derivatives along η first (sum
    // factorization), then the ξ sums.
    let along = |w: &[[f64; 3]; 3]| x.map(|row| w.map(|wj| comb(wj, row)));
    let (pv, qv) = (along(&L_GAUSS), along(&D_GAUSS));
    for (i, (&li, &di)) in L_GAUSS.iter().zip(&D_GAUSS).enumerate() {
        for j in 0..3 {
            out[9 + 3 * i + j] = det(comb(di, column(&pv, j)), comb(li, column(&qv, j)));
        }
    }
    out
}

/// det J of the bilinear map of the quad4 `p` (corners counter-clockwise)
/// at its corners, then at its 2×2 Gauss points (ξ, η = ±1/√3), of the
/// [`relative`] corners. det J is affine in ξ and in η here, so these
/// bound it over the cell.
pub(crate) fn quad4_dets(p: &[[f64; 2]; 4]) -> [f64; 8] {
    let x = relative(p);
    // ∂x/∂ξ and ∂x/∂η at (ξ, η) of x = Σ N_k x_k, N_k = (1 ± ξ)(1 ± η)/4.
    let at = |xi: f64, eta: f64| {
        let d = |w: [f64; 4]| {
            [
                0.25 * (w[0] * x[0][0] + w[1] * x[1][0] + w[2] * x[2][0] + w[3] * x[3][0]),
                0.25 * (w[0] * x[0][1] + w[1] * x[1][1] + w[2] * x[2][1] + w[3] * x[3][1]),
            ]
        };
        let dxi = d([-(1.0 - eta), 1.0 - eta, 1.0 + eta, -(1.0 + eta)]);
        let deta = d([-(1.0 - xi), -(1.0 + xi), 1.0 + xi, 1.0 - xi]);
        det(dxi, deta)
    };
    let g = 1.0 / 3f64.sqrt();
    [
        at(-1.0, -1.0),
        at(1.0, -1.0),
        at(1.0, 1.0),
        at(-1.0, 1.0),
        at(-g, -g),
        at(g, -g),
        at(g, g),
        at(-g, g),
    ]
}
