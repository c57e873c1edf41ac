//! Remark 4.1's static preload with a compliant foundation (METHOD.md §8,
//! §10), frictionless: K r = R₀ + F_c(r), F_c the foundation's nodal
//! forces w_J c_n δ_J^{m_n} ν, δ_J = max(0, −(g₀ + ν·r_J)). It is the
//! minimum of the convex Π(r) = ½rᵀKr − R₀ᵀr + Σ w_J c_n δ_J^{m_n+1}/(m_n+1),
//! found by Newton with the tangent K + Σ w_J c_n m_n δ_J^{m_n−1} ννᵀ (the
//! nodes in contact) and a line search on Π's slope along the step, which
//! only rises (Π convex): every step lowers Π. For m_n = 1 Π is piecewise
//! quadratic, and the iteration ends once the nodes in contact stop
//! changing. Nodes may start inside the foundation (g₀ < 0, an
//! interference): Π is the same convex function, F_c(0) ≠ 0, and the
//! preload settles them even where no load acts before t = 0.
//!
//! A floating part: the rigid motions the supports leave free split into
//! those the foundation never holds (they move no compliant node along ν,
//! a slide along the straight foundation), on which the preload must be
//! balanced and which are pinned and taken out as `floating.rs` does, and
//! those it holds once nodes press into it. While the nodes in contact do
//! not hold the latter (a part that starts touching the foundation), the
//! tangent is singular along them: each node out of contact then adds a
//! spring as stiff as its own diagonal of K, which keeps the step a
//! descent direction of Π until contact holds the part.

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::ContactSurface;
use stickslip_fem::{RigidMode, SetupTimes};
use stickslip_linalg::csr::{dot, spmv};
use stickslip_linalg::{Analysis, FillOrder, SparseCholesky};

use crate::floating;
use crate::initial::Mass;
use crate::settings::TimeError;

/// The residual ‖K r − R₀ − F_c(r)‖ that ends the iteration, relative to
/// ‖R₀‖ or, where larger, to ‖F_c(0)‖ (nodes starting inside).
const TOLERANCE: f64 = 1e-11;
/// Newton steps before the preload is declared without equilibrium.
const MAX_STEPS: usize = 100;
/// Evaluations of the slope in one line search.
const MAX_SEARCH: usize = 60;
/// A line search that finds Π still falling this many Newton steps out
/// gives up: the loads carry the part away from the foundation.
const FAR: f64 = 1e12;
/// A line search stops once the slope is this fraction of its start's.
const SEARCH_TOLERANCE: f64 = 1e-3;
/// A symmetric positive semi-definite small matrix's eigenvalue below this
/// fraction of its largest is zero.
const NULL: f64 = 1e-10;

/// Adds the foundation's nodal forces w_J c_n δ_J^{m_n} ν at displacement
/// `r` to `out` (per free DOF) and returns its stored energy Σ w_J c_n
/// δ_J^{m_n+1}/(m_n+1).
pub(crate) fn add_foundation_forces(contact: &ContactSurface, r: &[f64], out: &mut [f64]) -> f64 {
    let mut stored = 0.0;
    for c in &contact.compliance {
        let node = &contact.nodes[c.index];
        let delta = c.approach(node, r);
        if delta == 0.0 {
            continue;
        }
        stored += node.weight * c.law.energy(delta);
        let f = node.weight * c.law.traction(delta);
        for comp in 0..2 {
            if let Some(d) = node.dofs[comp] {
                out[d] += f * c.normal[comp];
            }
        }
    }
    stored
}

/// r₀ in place of the preload `r` (see the module's comment), with K's
/// analysis if the caller made it (`analyzed`: the tangent has K's
/// pattern, the springs sitting in each node's block of it).
///
/// # Errors
/// [`TimeError::Unbalanced`] when the preload does work along a rigid
/// motion the foundation never holds, or pulls the part off the
/// foundation along one it holds; [`TimeError::Static`] when K with the
/// foundation is singular.
pub(crate) fn solve(
    k: &CsrMatrix<f64>,
    (mass, fill_order, modes): (Mass, &FillOrder, &[RigidMode]),
    contact: &ContactSurface,
    r: &mut [f64],
    times: &mut SetupTimes,
    analyzed: Option<Analysis>,
) -> Result<(), TimeError> {
    let preload = r.to_vec();
    let along = along_normal(contact, modes);
    let (never, held) = split(modes, &along);
    floating::balanced(&never, &preload)?;
    let pins = if never.is_empty() {
        Vec::new()
    } else {
        floating::pins(&never)
    };
    let mut tangent = k.clone();
    let slots = slots(contact, &tangent);
    let diagonal: Vec<f64> = (0..k.nrows())
        .map(|i| slot(k, i, i).map_or(0.0, |p| k.values()[p]))
        .collect();
    // Against R₀, or the foundation's push at r = 0 where nodes start
    // inside it (with R₀ = 0 an interference is all that presses).
    let (zero, mut pushed) = (vec![0.0; r.len()], vec![0.0; r.len()]);
    add_foundation_forces(contact, &zero, &mut pushed);
    let scale = norm(&preload).max(norm(&pushed));
    let mut solver = match analyzed {
        Some(analysis) => SparseCholesky::on(analysis).map_err(TimeError::Static)?,
        None => times
            .time("preload ordering", || {
                SparseCholesky::analyze(&tangent, fill_order)
            })
            .map_err(TimeError::Static)?,
    };
    let (mut g, mut trial, mut gt) = (vec![0.0; r.len()], vec![0.0; r.len()], vec![0.0; r.len()]);
    let x = r;
    x.fill(0.0);
    let residual = |x: &[f64], g: &mut [f64]| {
        spmv(k, x, g);
        for (g, p) in g.iter_mut().zip(&preload) {
            *g -= p;
        }
        let mut forces = vec![0.0; x.len()];
        add_foundation_forces(contact, x, &mut forces);
        for (g, f) in g.iter_mut().zip(&forces) {
            *g -= f;
        }
        for &p in &pins {
            g[p] = 0.0;
        }
    };
    for _ in 0..MAX_STEPS {
        residual(x, &mut g);
        if norm(&g) <= TOLERANCE * scale {
            floating::remove_rigid_motion(mass, &never, x);
            return Ok(());
        }
        // The tangent: K and the springs of the nodes in contact, or of
        // every node out of it while those do not hold the part.
        let springs = springs(contact, x, &along, &held, &diagonal);
        tangent.values_mut().copy_from_slice(k.values());
        for (s, (c, kt)) in slots.iter().zip(contact.compliance.iter().zip(&springs)) {
            for (a, row) in s.iter().enumerate() {
                for (b, p) in row.iter().enumerate() {
                    if let Some(p) = p {
                        tangent.values_mut()[*p] += kt * c.normal[a] * c.normal[b];
                    }
                }
            }
        }
        floating::pin(&mut tangent, &pins);
        times
            .time("preload factor", || solver.factorize(&tangent))
            .map_err(TimeError::Static)?;
        let mut d: Vec<f64> = g.iter().map(|g| -g).collect();
        times.time("preload solve", || solver.solve_in_place(&mut d));
        let Some(alpha) = search(x, &d, &g, (&mut trial, &mut gt), &residual) else {
            break;
        };
        for (x, d) in x.iter_mut().zip(&d) {
            *x += alpha * d;
        }
    }
    // No equilibrium: Π falls without bound (or the steps ran out) along
    // the motions the foundation holds, whose load pulls the part off it.
    residual(x, &mut g);
    let work: Vec<(String, f64)> = held
        .iter()
        .map(|h| {
            let z = combine(modes, h);
            let work = z.iter().zip(&preload).map(|(z, p)| z * p).sum::<f64>();
            let why = format!(
                ", which the foundation of surface {} holds only against loads pressing the part \
                 into it (it only pushes)",
                contact.names()
            );
            (label(modes, h) + &why, work)
        })
        .collect();
    if work.is_empty() {
        return Err(TimeError::Settings(format!(
            "the initial static state on the compliant foundation of surface {} did not converge \
             in {MAX_STEPS} Newton steps (residual {:.3e} of the preload's {:.3e}): start at rest \
             ([initial] state = \"rest\")",
            contact.names(),
            norm(&g),
            scale
        )));
    }
    Err(TimeError::Unbalanced(work))
}

/// The step length α along `d` from `x` where Π's slope dᵀG(x + αd),
/// negative at 0 and rising, reaches 0: 1 where the slope there is near 0,
/// else the root by regula falsi (Illinois) after doubling α past it
/// where it is still negative at 1. `None` where it stays negative up to
/// [`FAR`]: Π falls without bound, the loads carry the part away.
fn search(
    x: &[f64],
    d: &[f64],
    g: &[f64],
    (trial, gt): (&mut [f64], &mut [f64]),
    residual: &dyn Fn(&[f64], &mut [f64]),
) -> Option<f64> {
    let mut slope = |alpha: f64| {
        for ((t, x), d) in trial.iter_mut().zip(x).zip(d) {
            *t = x + alpha * d;
        }
        residual(trial, gt);
        gt.iter().zip(d).map(|(g, d)| g * d).sum::<f64>()
    };
    let start = g.iter().zip(d).map(|(g, d)| g * d).sum::<f64>();
    // A step that is no descent (start ≥ 0 or NaN) is only round-off.
    if start.is_nan() || start >= 0.0 {
        return Some(1.0);
    }
    let close = |s: f64| s.abs() <= SEARCH_TOLERANCE * start.abs();
    let mut hi = (1.0, slope(1.0));
    if close(hi.1) {
        return Some(1.0);
    }
    let mut lo = (0.0, start);
    while hi.1 < 0.0 {
        if hi.0 >= FAR {
            return None;
        }
        lo = hi;
        hi = (2.0 * hi.0, slope(2.0 * hi.0));
    }
    let mut side = 0;
    let mut alpha = hi.0;
    for _ in 0..MAX_SEARCH {
        alpha = (lo.0 * hi.1 - hi.0 * lo.1) / (hi.1 - lo.1);
        let s = slope(alpha);
        if close(s) {
            break;
        }
        if s < 0.0 {
            lo = (alpha, s);
            if side == -1 {
                hi.1 *= 0.5;
            }
            side = -1;
        } else {
            hi = (alpha, s);
            if side == 1 {
                lo.1 *= 0.5;
            }
            side = 1;
        }
    }
    Some(alpha)
}

/// Each spring's stiffness k_J (the tangent gains k_J ννᵀ at node J): w_J
/// c_n m_n δ_J^{m_n−1} where δ_J > 0; where the nodes in contact leave a
/// held motion free, the largest diagonal of K at each node out of
/// contact.
fn springs(
    contact: &ContactSurface,
    x: &[f64],
    along: &[Vec<f64>],
    held: &[Vec<f64>],
    diagonal: &[f64],
) -> Vec<f64> {
    let deltas: Vec<f64> = contact
        .compliance
        .iter()
        .map(|c| c.approach(&contact.nodes[c.index], x))
        .collect();
    let mut springs: Vec<f64> = contact
        .compliance
        .iter()
        .zip(&deltas)
        .map(|(c, &delta)| {
            if delta > 0.0 {
                contact.nodes[c.index].weight * c.law.stiffness(delta)
            } else {
                0.0
            }
        })
        .collect();
    if !held.is_empty() && !holds(&springs, along, held) {
        for ((c, kt), &delta) in contact.compliance.iter().zip(&mut springs).zip(&deltas) {
            if delta == 0.0 {
                *kt = contact.nodes[c.index]
                    .dofs
                    .iter()
                    .flatten()
                    .fold(0.0, |m: f64, &d| m.max(diagonal[d]));
            }
        }
    }
    springs
}

/// True when springs `k_J` along ν hold every motion of `held`: Σ_J k_J
/// (ν·z_J)(ν·z_J)ᵀ is definite on them.
fn holds(springs: &[f64], along: &[Vec<f64>], held: &[Vec<f64>]) -> bool {
    let n = held.len();
    let mut b = vec![vec![0.0; n]; n];
    for (k, a) in springs.iter().zip(along) {
        let p: Vec<f64> = held
            .iter()
            .map(|h| h.iter().zip(a).map(|(h, a)| h * a).sum())
            .collect();
        for i in 0..n {
            for j in 0..n {
                b[i][j] += k * p[i] * p[j];
            }
        }
    }
    let (values, _) = eigen(&b);
    let largest = values.iter().fold(0.0_f64, |m, v| m.max(*v));
    largest > 0.0 && values.iter().all(|v| *v > NULL * largest)
}

/// Per compliant node, ν·z_J of each rigid motion z.
fn along_normal(contact: &ContactSurface, modes: &[RigidMode]) -> Vec<Vec<f64>> {
    contact
        .compliance
        .iter()
        .map(|c| {
            let node = &contact.nodes[c.index];
            modes
                .iter()
                .map(|m| {
                    (0..2)
                        .filter_map(|comp| node.dofs[comp].map(|d| c.normal[comp] * m.vector[d]))
                        .sum()
                })
                .collect()
        })
        .collect()
}

/// The rigid motions the foundation never holds (as motions, from the
/// null space of Σ_J (ν·z_J)(ν·z_J)ᵀ) and those it may hold (as
/// coefficients of `modes`).
fn split(modes: &[RigidMode], along: &[Vec<f64>]) -> (Vec<RigidMode>, Vec<Vec<f64>>) {
    let n = modes.len();
    if n == 0 {
        return (Vec::new(), Vec::new());
    }
    let mut a = vec![vec![0.0; n]; n];
    for p in along {
        for i in 0..n {
            for j in 0..n {
                a[i][j] += p[i] * p[j];
            }
        }
    }
    let (values, vectors) = eigen(&a);
    let largest = values.iter().fold(0.0_f64, |m, v| m.max(*v));
    let (mut never, mut held) = (Vec::new(), Vec::new());
    for (value, v) in values.iter().zip(vectors) {
        if *value > NULL * largest {
            held.push(v);
        } else {
            never.push(RigidMode {
                label: label(modes, &v),
                vector: combine(modes, &v),
            });
        }
    }
    (never, held)
}

/// Σ_i v_i z_i.
fn combine(modes: &[RigidMode], v: &[f64]) -> Vec<f64> {
    let mut z = vec![0.0; modes[0].vector.len()];
    for (m, c) in modes.iter().zip(v) {
        if *c != 0.0 {
            for (z, m) in z.iter_mut().zip(&m.vector) {
                *z += c * m;
            }
        }
    }
    z
}

/// The name of Σ_i v_i z_i: the motion's own where one dominates.
fn label(modes: &[RigidMode], v: &[f64]) -> String {
    let parts: Vec<&str> = modes
        .iter()
        .zip(v)
        .filter(|(_, c)| c.abs() > 1e-9)
        .map(|(m, _)| m.label.as_str())
        .collect();
    match parts.as_slice() {
        [one] => (*one).to_string(),
        _ => format!("a combination of {}", parts.join(" and ")),
    }
}

/// Eigenvalues and unit eigenvectors of a small symmetric matrix (faer's
/// self-adjoint eigendecomposition). Should it fail (entries not finite),
/// the values are NaN: no comparison holds, so nothing counts as held.
fn eigen(a: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = a.len();
    let m = faer::Mat::from_fn(n, n, |i, j| a[i][j]);
    let Ok(e) = m.self_adjoint_eigen(faer::Side::Lower) else {
        let unit = |j: usize| (0..n).map(|i| f64::from(u8::from(i == j))).collect();
        return (vec![f64::NAN; n], (0..n).map(unit).collect());
    };
    let (s, u) = (e.S(), e.U());
    let values = (0..n).map(|i| s[i]).collect();
    let vectors = (0..n)
        .map(|j| (0..n).map(|i| u[(i, j)]).collect())
        .collect();
    (values, vectors)
}

/// Where each compliant node's 2×2 block (x, y by x, y) sits in `k`'s
/// values (`None` for a fixed component).
fn slots(contact: &ContactSurface, k: &CsrMatrix<f64>) -> Vec<[[Option<usize>; 2]; 2]> {
    contact
        .compliance
        .iter()
        .map(|c| {
            let dofs = contact.nodes[c.index].dofs;
            let at = |a: usize, b: usize| match (dofs[a], dofs[b]) {
                (Some(i), Some(j)) => slot(k, i, j),
                _ => None,
            };
            [[at(0, 0), at(0, 1)], [at(1, 0), at(1, 1)]]
        })
        .collect()
}

/// The position of entry (i, j) in `k`'s values (K's pattern holds every
/// pair of DOFs of one node).
fn slot(k: &CsrMatrix<f64>, i: usize, j: usize) -> Option<usize> {
    let (offsets, cols, _) = k.csr_data();
    let row = &cols[offsets[i]..offsets[i + 1]];
    row.binary_search(&j).ok().map(|p| offsets[i] + p)
}

fn norm(x: &[f64]) -> f64 {
    dot(x, x).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The decomposition of [[2, 1, 0], [1, 2, 0], [0, 0, 0]]:
    /// eigenvalues 3, 1, 0 (the closed form of a 2×2 block [[a, b], [b, a]]
    /// is a ± b), each A v = λ v.
    #[test]
    fn eigen_finds_the_closed_form() {
        let a = vec![
            vec![2.0, 1.0, 0.0],
            vec![1.0, 2.0, 0.0],
            vec![0.0, 0.0, 0.0],
        ];
        let (values, vectors) = eigen(&a);
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        for (got, want) in sorted.iter().zip([0.0, 1.0, 3.0]) {
            assert!((got - want).abs() < 1e-14, "{values:?}");
        }
        for (l, v) in values.iter().zip(&vectors) {
            for i in 0..3 {
                let av: f64 = (0..3).map(|j| a[i][j] * v[j]).sum();
                assert!((av - l * v[i]).abs() < 1e-14);
            }
        }
    }
}
