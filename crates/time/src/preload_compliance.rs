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
//! not hold the latter (a part that starts off the foundation, or touches
//! it at one corner), the tangent is singular along them. Where the
//! residual does work along such a free motion, the step is that rigid
//! motion alone: K z = 0, so Π along it changes only by the loads' work
//! and the foundation's energy, and the line search carries the part as
//! far as the foundation lets it, however far off it starts (a Newton
//! step on springs standing in for the foundation would move it by a
//! fixed fraction of its deformation per step instead). Otherwise each
//! node out of contact adds a spring as stiff as its own diagonal of K,
//! which keeps the step a descent direction of Π until contact holds the
//! part.

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::ContactSurface;
use stickslip_fem::{RigidMode, RigidMotion, SetupTimes};
use stickslip_linalg::csr::{diagonal, dot, index, spmv};
use stickslip_linalg::{Analysis, FillOrder, SparseCholesky};

use crate::floating::{self, BALANCE_TOLERANCE};
use crate::initial::Mass;
use crate::settings::{TimeError, UnbalancedMotion};

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
    let vectors: Vec<&[f64]> = modes.iter().map(|m| m.vector.as_slice()).collect();
    let along = along_normal(contact, &vectors);
    let (never, held) = split(modes, &along);
    floating::balanced(&never, &preload)?;
    let pins = if never.is_empty() {
        Vec::new()
    } else {
        floating::pins(&never)
    };
    let mut tangent = k.clone();
    let slots = slots(contact, &tangent);
    let diagonal = diagonal(k);
    let free = Held::new(contact, modes, (&held, &never, &pins), &diagonal);
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
    // The rigid steps' motion z is kept out of x and folded into the gaps
    // of a copy of the surface: K z = 0, but K (x + z) in floating point
    // carries z's round-off, which for a part far off the foundation (z
    // the gap, x its deformation) can exceed the tolerance.
    let (mut surface, mut rigid) = (contact.clone(), vec![0.0; x.len()]);
    let residual = |surface: &ContactSurface, x: &[f64], g: &mut [f64]| {
        spmv(k, x, g);
        for (g, p) in g.iter_mut().zip(&preload) {
            *g -= p;
        }
        let mut forces = vec![0.0; x.len()];
        add_foundation_forces(surface, x, &mut forces);
        for (g, f) in g.iter_mut().zip(&forces) {
            *g -= f;
        }
        for &p in &pins {
            g[p] = 0.0;
        }
    };
    for _ in 0..MAX_STEPS {
        residual(&surface, x, &mut g);
        if norm(&g) <= TOLERANCE * scale {
            for (x, z) in x.iter_mut().zip(&rigid) {
                *x += z;
            }
            floating::remove_rigid_motion(mass, &never, x);
            return Ok(());
        }
        let at = |x: &[f64], g: &mut [f64]| residual(&surface, x, g);
        let mut springs = contact_springs(&surface, x);
        if !free.motions.is_empty() && !holds(&springs, &free.along) {
            // A held motion the nodes in contact leave free: the rigid step
            // along it where the residual does work along it.
            let (mut kx, mut terms) = (vec![0.0; x.len()], vec![0.0; x.len()]);
            spmv(k, x, &mut kx);
            add_foundation_forces(&surface, x, &mut terms);
            for ((t, kx), p) in terms.iter_mut().zip(&kx).zip(&preload) {
                *t = t.abs() + kx.abs() + p.abs();
            }
            let threshold = TOLERANCE * scale;
            if let Some(e) = free.rigid_step(&surface, (x, &g), &springs, (&terms, threshold)) {
                let Some(alpha) = search(x, &e, &g, (&mut trial, &mut gt), &at) else {
                    break;
                };
                for (z, e) in rigid.iter_mut().zip(&e) {
                    *z += alpha * e;
                }
                for (moved, c) in surface.compliance.iter_mut().zip(&contact.compliance) {
                    moved.gap = c.gap + c.along_normal(&contact.nodes[c.index], &rigid);
                }
                continue;
            }
            // The tangent: K and the springs of the nodes in contact, and
            // of every node out of it while those do not hold the part.
            stand_in(&surface, x, &free.stand_in, &mut springs);
        }
        tangent.values_mut().copy_from_slice(k.values());
        for (s, (c, kt)) in slots.iter().zip(surface.compliance.iter().zip(&springs)) {
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
        let Some(alpha) = search(x, &d, &g, (&mut trial, &mut gt), &at) else {
            break;
        };
        for (x, d) in x.iter_mut().zip(&d) {
            *x += alpha * d;
        }
    }
    // No equilibrium: Π falls without bound (or the steps ran out) along
    // the motions the foundation holds, whose load pulls the part off it
    // (those the loads do work along, as `floating::balanced` judges).
    residual(&surface, x, &mut g);
    let work: Vec<UnbalancedMotion> = held
        .iter()
        .filter_map(|h| {
            let z = combine(modes, h);
            let (work, size) = floating::work_along(&z, &preload);
            // A motion that moves every compliant node off the foundation
            // (or every one into it), as a translation towards a floor: a
            // load pressing the part along it into the foundation is what
            // the foundation holds, so it is no cause (a part tipped over
            // is, by the rotation).
            let approach: Vec<f64> = along
                .iter()
                .map(|a| a.iter().zip(h).map(|(a, h)| a * h).sum())
                .collect();
            let reach = approach.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
            let off = approach.iter().all(|a| *a > NULL.sqrt() * reach);
            let into = approach.iter().all(|a| *a < -NULL.sqrt() * reach);
            if (off && work < 0.0) || (into && work > 0.0) {
                return None;
            }
            let why = format!(
                ", which the foundation of surface {} holds only against loads pressing the part \
                 into it (it only pushes)",
                contact.names()
            );
            let (name, amount, motion, _) = describe(modes, h);
            floating::does_work(work, size).then(|| UnbalancedMotion {
                label: name + &why,
                motion,
                work: work / amount,
            })
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

/// The held motions as the rigid steps use them.
struct Held {
    /// Each held motion's DOF vector, cleared at the pins.
    motions: Vec<Vec<f64>>,
    /// Per compliant node, ν·z_J of each of them.
    along: Vec<Vec<f64>>,
    /// Per compliant node, its largest diagonal of K: the stand-in spring.
    stand_in: Vec<f64>,
}

impl Held {
    /// The motions `held` (coefficients of `modes`), each cleared at the
    /// `pins` by never-held motions (which change neither Π nor the
    /// approaches), so that a step along them keeps the pinned DOFs, where
    /// the residual is not evaluated, where they are.
    fn new(
        contact: &ContactSurface,
        modes: &[RigidMode],
        (held, never, pins): (&[Vec<f64>], &[RigidMode], &[usize]),
        diagonal: &[f64],
    ) -> Held {
        let motions: Vec<Vec<f64>> = held
            .iter()
            .map(|h| {
                let mut z = combine(modes, h);
                if !pins.is_empty() {
                    let a = pins
                        .iter()
                        .map(|&p| never.iter().map(|m| m.vector[p]).collect())
                        .collect();
                    let b = pins.iter().map(|&p| z[p]).collect();
                    let c = floating::solve_small(a, b).unwrap_or_else(|| vec![0.0; never.len()]);
                    for (m, c) in never.iter().zip(&c) {
                        for (z, m) in z.iter_mut().zip(&m.vector) {
                            *z -= c * m;
                        }
                    }
                }
                z
            })
            .collect();
        let vectors: Vec<&[f64]> = motions.iter().map(Vec::as_slice).collect();
        let along = along_normal(contact, &vectors);
        let stand_in = contact
            .compliance
            .iter()
            .map(|c| {
                contact.nodes[c.index]
                    .dofs
                    .iter()
                    .flatten()
                    .fold(0.0, |m: f64, &d| m.max(diagonal[d]))
            })
            .collect();
        Held {
            motions,
            along,
            stand_in,
        }
    }

    /// The rigid step from `x`, residual `g`, where the nodes in contact
    /// (stiffness `springs`) leave held motions free: the one of them the
    /// stand-in springs s_J would balance against the residual, the
    /// minimum of ½eᵀ(Σ_J s_J ννᵀ)e + gᵀe over the free motions e,
    /// stretched so that α = 1 brings the nearest node off the foundation
    /// onto it where that is farther. `None` where contact holds every
    /// motion or the residual's work along the free ones is round-off:
    /// below the convergence test's `threshold` per unit motion or, as
    /// `floating::balanced` judges, against `terms` (|K x| + |R₀| + |F_c|
    /// per DOF) along it.
    fn rigid_step(
        &self,
        contact: &ContactSurface,
        (x, g): (&[f64], &[f64]),
        springs: &[f64],
        (terms, threshold): (&[f64], f64),
    ) -> Option<Vec<f64>> {
        let n = self.motions.len();
        let (values, vectors) = eigen(&gram(springs, &self.along, n));
        let largest = values.iter().fold(0.0_f64, |m, v| m.max(*v));
        // A NaN value (a failed decomposition) is held by nothing, as in
        // `holds`.
        let held = |v: f64| v > NULL * largest;
        let free: Vec<&Vec<f64>> = values
            .iter()
            .zip(&vectors)
            .filter(|(v, _)| !held(**v))
            .map(|(_, u)| u)
            .collect();
        if free.is_empty() {
            return None;
        }
        let metric = gram(&self.stand_in, &self.along, n);
        let work: Vec<f64> = self.motions.iter().map(|z| dot(z, g)).collect();
        let times = |u: &[f64], v: &[f64]| (0..n).map(|i| u[i] * v[i]).sum::<f64>();
        let a = free
            .iter()
            .map(|u| {
                let mu: Vec<f64> = metric.iter().map(|row| times(row, u)).collect();
                free.iter().map(|v| times(v, &mu)).collect()
            })
            .collect();
        let b = free.iter().map(|u| -times(u, &work)).collect();
        let c = floating::solve_small(a, b)?;
        let mut e = vec![0.0; x.len()];
        for (u, c) in free.iter().zip(&c) {
            for (z, u) in self.motions.iter().zip(u.iter()) {
                for (e, z) in e.iter_mut().zip(z) {
                    *e += c * u * z;
                }
            }
        }
        let slope = dot(g, &e);
        let size: f64 = e.iter().zip(terms).map(|(e, t)| e.abs() * t).sum();
        if !(-slope > BALANCE_TOLERANCE * size && -slope > threshold * norm(&e)) {
            return None;
        }
        // The approach along e grows at −ν·e_J: a node off the foundation,
        // at signed approach a < 0, reaches it at α = a/(ν·e_J).
        let nearest = contact
            .compliance
            .iter()
            .filter_map(|c| {
                let node = &contact.nodes[c.index];
                let rate = c.along_normal(node, &e);
                let approach = c.signed_approach(node, x);
                (approach < 0.0 && rate < 0.0).then(|| approach / rate)
            })
            .fold(f64::INFINITY, f64::min);
        if nearest.is_finite() && nearest > 1.0 {
            e.iter_mut().for_each(|e| *e *= nearest);
        }
        Some(e)
    }
}

/// Each node's spring stiffness k_J (the tangent gains k_J ννᵀ at node J):
/// w_J c_n m_n δ_J^{m_n−1} where δ_J > 0, else 0.
fn contact_springs(contact: &ContactSurface, x: &[f64]) -> Vec<f64> {
    contact
        .compliance
        .iter()
        .map(|c| {
            let delta = c.approach(&contact.nodes[c.index], x);
            if delta > 0.0 {
                contact.nodes[c.index].weight * c.law.stiffness(delta)
            } else {
                0.0
            }
        })
        .collect()
}

/// The stand-in spring (`Held::stand_in`, per compliant node) at each
/// node out of contact in place of its spring (where those in contact
/// leave a held motion free).
fn stand_in(contact: &ContactSurface, x: &[f64], stand: &[f64], springs: &mut [f64]) {
    for ((c, kt), s) in contact.compliance.iter().zip(springs).zip(stand) {
        if c.approach(&contact.nodes[c.index], x) == 0.0 {
            *kt = *s;
        }
    }
}

/// True when springs `k_J` along ν hold every held motion (`along`: ν·z_J
/// of each at each node): Σ_J k_J (ν·z_J)(ν·z_J)ᵀ is definite.
fn holds(springs: &[f64], along: &[Vec<f64>]) -> bool {
    let n = along.first().map_or(0, Vec::len);
    let (values, _) = eigen(&gram(springs, along, n));
    let largest = values.iter().fold(0.0_f64, |m, v| m.max(*v));
    largest > 0.0 && values.iter().all(|v| *v > NULL * largest)
}

/// Σ_J k_J p_J p_Jᵀ (n × n) of the rows p_J of `along`.
fn gram(weights: &[f64], along: &[Vec<f64>], n: usize) -> Vec<Vec<f64>> {
    let mut b = vec![vec![0.0; n]; n];
    for (k, p) in weights.iter().zip(along) {
        for i in 0..n {
            for j in 0..n {
                b[i][j] += k * p[i] * p[j];
            }
        }
    }
    b
}

/// Per compliant node, ν·z_J of each motion z of `vectors`.
fn along_normal(contact: &ContactSurface, vectors: &[&[f64]]) -> Vec<Vec<f64>> {
    contact
        .compliance
        .iter()
        .map(|c| {
            let node = &contact.nodes[c.index];
            vectors.iter().map(|z| c.along_normal(node, z)).collect()
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
    let (values, vectors) = eigen(&gram(&vec![1.0; along.len()], along, n));
    let largest = values.iter().fold(0.0_f64, |m, v| m.max(*v));
    let (mut never, mut held) = (Vec::new(), Vec::new());
    for (value, v) in values.iter().zip(vectors) {
        if *value > NULL * largest {
            held.push(v);
        } else {
            let (label, amount, motion, whose) = describe(modes, &v);
            let mut vector = combine(modes, &v);
            vector.iter_mut().for_each(|z| *z /= amount);
            never.push(RigidMode {
                label,
                motion,
                whose,
                vector,
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

/// The name of Σ_i v_i z_i and how much of the named motion it is, by
/// which its work is divided to give the net force along the translation
/// named or the moment about the centre named: a single motion by its own
/// name; one part's translations t by the translation along t/|t|, |t| of
/// it; with that part's rotation ω ρ_p about p, by the rotation about the
/// point q it turns about, ω of it (t + ω ρ_p = ω ρ_q for q = p + (−t_y,
/// t_x)/ω); other combinations by their parts, 1 of them.
/// Also the sum's motion and the part it moves, where it is one motion.
fn describe(modes: &[RigidMode], v: &[f64]) -> (String, f64, Option<RigidMotion>, String) {
    let parts: Vec<(&RigidMode, f64)> = modes
        .iter()
        .zip(v)
        .filter(|(_, c)| c.abs() > 1e-9)
        .map(|(m, c)| (m, *c))
        .collect();
    if let [(one, c)] = parts.as_slice() {
        return (one.label.clone(), *c, one.motion, one.whose.clone());
    }
    let combination = || {
        let names: Vec<&str> = parts.iter().map(|(m, _)| m.label.as_str()).collect();
        let name = format!("a combination of {}", names.join(" and "));
        (name, 1.0, None, String::new())
    };
    // The translation t, the rotation (centre, ω) if any, and the part.
    let (mut t, mut rotation, mut whose) = ([0.0; 2], None, None);
    for (m, c) in &parts {
        match m.motion {
            Some(RigidMotion::Translation(d)) => {
                t[0] += c * d[0];
                t[1] += c * d[1];
            }
            Some(RigidMotion::Rotation(p)) => {
                if rotation.replace((p, *c)).is_some() {
                    return combination();
                }
            }
            None => return combination(),
        }
        if *whose.get_or_insert(m.whose.as_str()) != m.whose {
            return combination();
        }
    }
    let whose = whose.unwrap_or("");
    match rotation {
        Some((p, omega)) => {
            let q = [p[0] - t[1] / omega, p[1] + t[0] / omega];
            (
                format!("rotation about ({:.6}, {:.6}){whose}", q[0], q[1]),
                omega,
                Some(RigidMotion::Rotation(q)),
                whose.to_string(),
            )
        }
        None => {
            let size = t[0].hypot(t[1]);
            let d = [t[0] / size, t[1] / size];
            (
                format!("translation along ({:.6}, {:.6}){whose}", d[0], d[1]),
                size,
                Some(RigidMotion::Translation(d)),
                whose.to_string(),
            )
        }
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
            // K's pattern holds every pair of DOFs of one node.
            let at = |a: usize, b: usize| match (dofs[a], dofs[b]) {
                (Some(i), Some(j)) => index(k, i, j),
                _ => None,
            };
            [[at(0, 0), at(0, 1)], [at(1, 0), at(1, 1)]]
        })
        .collect()
}

fn norm(x: &[f64]) -> f64 {
    dot(x, x).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two nodes, at q = (1, 1.25) and (0, 0), and the motions of a free
    /// part: translations and the rotation about p = (1, ½). 0.6 t_x +
    /// 0.8 ρ_p leaves q still (0.8·(−(1.25 − ½), 0) + (0.6, 0) = 0): the
    /// rotation about q, 0.8 of it; 0.6 t_x − 0.8 t_y is the translation
    /// along (0.6, −0.8), 1 of it.
    #[test]
    fn describe_names_a_combination_by_the_motion_it_is() {
        let points = [[1.0, 1.25], [0.0, 0.0]];
        let field = |u: &dyn Fn([f64; 2]) -> [f64; 2]| -> Vec<f64> {
            points.iter().flat_map(|&x| u(x)).collect()
        };
        let modes = [
            RigidMode {
                label: "translation in x".into(),
                motion: Some(RigidMotion::Translation([1.0, 0.0])),
                whose: String::new(),
                vector: field(&|_| [1.0, 0.0]),
            },
            RigidMode {
                label: "translation in y".into(),
                motion: Some(RigidMotion::Translation([0.0, 1.0])),
                whose: String::new(),
                vector: field(&|_| [0.0, 1.0]),
            },
            RigidMode {
                label: "rotation about (1.000000, 0.500000)".into(),
                motion: Some(RigidMotion::Rotation([1.0, 0.5])),
                whose: String::new(),
                vector: field(&|[x, y]| [-(y - 0.5), x - 1.0]),
            },
        ];
        let turn = [0.6, 0.0, 0.8];
        let still = combine(&modes, &turn);
        assert!(
            still[0].abs() < 1e-15 && still[1].abs() < 1e-15,
            "{still:?}"
        );
        let (name, amount, motion, _) = describe(&modes, &turn);
        assert_eq!(name, "rotation about (1.000000, 1.250000)");
        assert!((amount - 0.8).abs() < 1e-15);
        assert_eq!(motion, Some(RigidMotion::Rotation([1.0, 1.25])));
        let (name, amount, _, _) = describe(&modes, &[0.6, -0.8, 0.0]);
        assert_eq!(name, "translation along (0.600000, -0.800000)");
        assert!((amount - 1.0).abs() < 1e-15);
        let (name, amount, _, _) = describe(&modes, &[0.0, -1.0, 0.0]);
        assert_eq!(name, "translation in y");
        assert_eq!(amount, -1.0);
    }

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
