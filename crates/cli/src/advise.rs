//! `stickslip advise` (issue 6, deliverable 3): the cheapest configuration
//! (element order, mesh of the case's `mesh.ladder`, scheme, Δt, ε) whose
//! estimated error on one output is below a tolerance, from error
//! estimates measured on the user's own case.
//!
//! Error estimates. The pilots (below) include a reference run R, the
//! most accurate one they afford: central difference at 0.9 Δt_crit on the
//! mesh after the pilots of the highest element order. Every pilot run X
//! then has the error √(‖X − R‖² + e_R²) ([`with_reference`]), e_R from
//! the differences of R's own ladder (Richardson with the observed order
//! and correlation, [`ladder_errors`]); e_R enters only in quadrature, so
//! its uncertainty matters little. Measured this way, against the
//! finest run rather than from differences of neighbouring levels, the
//! estimate needs no model of how the errors of successive levels line up:
//! on the slab they are only partly aligned (stick/slip events move between
//! refinements; measured cosines 0.4-0.8), which made the Richardson
//! estimates from neighbour differences off by up to 1.5×.
//!
//! A candidate that was not run is estimated from three measured parts
//! combined in quadrature ([`Candidate::estimate`]): the error of its mesh
//! with its family's base Δt (central difference at 0.9 Δt_crit: the
//! combined h and Δt error of that path, since its Δt is tied to h;
//! Newmark at t_end/200), the change its method and Δt make from that base
//! on the pilot mesh, and the change its ε makes there. Meshes finer than
//! the measured ones continue the last measured decrease (observed order,
//! capped at the theoretical one; none when the errors stopped decreasing).
//! Newmark's errors per mesh, all at t_end/200, carry that Δt's error,
//! which no mesh reduces: the decrease is continued on the errors less
//! that part (estimated from the Δt pilots) and the part added back, so
//! that a finer mesh's estimate does not fall below it.
//!
//! * h: the first three meshes of each element order in the ladder, run
//!   with central difference at 0.9 Δt_crit of each mesh (its own family:
//!   lumped mass, Δt tied to h) and with Newmark ¼/½ at Δt = t_end/200
//!   (consistent mass; shared by the three Newmark variants); the
//!   reference R on the fourth mesh of the highest order.
//! * Δt: on one pilot mesh (the second of the highest order), central
//!   difference at 0.9, 0.45, 0.225 Δt_crit and each Newmark variant at
//!   Δt = t_end/50, /100, /200, /400.
//! * ε: the case's ε is the model the user asked for (its error part is 0);
//!   10ε and 100ε are candidates whose part is the measured difference to
//!   the case's ε on the pilot mesh (central difference, 0.9 Δt_crit). ε
//!   enters as O(√ε) (METHOD.md §2, Theorem 2.3), so no extrapolation to
//!   smaller ε is offered.
//!
//! Pilots run over the whole [0, t_end]: the error measures are integrals
//! (or the end value) over that interval, so a shorter run would not
//! measure them. The predicted time is steps × nnz(K) times one seconds-
//! per-step-per-entry constant per scheme measured on the pilots.

use std::path::{Component, Path, PathBuf};
use std::time::Instant;

use anyhow::Context;

use stickslip_case::pilot::{self, relative_l2, sample, Trace};
use stickslip_case::InputError;
use stickslip_case::{
    self as case, prepare, Case, Method, Prepared, Scheme as CaseScheme, PAPER_REDUCTION,
};

/// The output the tolerance is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// u_x at a node.
    Ux,
    /// u_y at a node.
    Uy,
    /// σ_T at a contact node.
    FrictionStress,
    /// Total energy at t_end.
    Energy,
}

impl Quantity {
    /// Parses `--on`.
    ///
    /// # Errors
    /// An unknown name, with the accepted ones.
    pub fn parse(s: &str) -> Result<Quantity, String> {
        match s {
            "ux" => Ok(Quantity::Ux),
            "uy" => Ok(Quantity::Uy),
            "friction_stress" => Ok(Quantity::FrictionStress),
            "energy" => Ok(Quantity::Energy),
            _ => Err(format!(
                "--on {s:?}: expected ux, uy, friction_stress or energy"
            )),
        }
    }

    /// Name as given to `--on`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Ux => "ux",
            Quantity::Uy => "uy",
            Quantity::FrictionStress => "friction_stress",
            Quantity::Energy => "energy",
        }
    }
}

/// Error of the finer of two solutions at refinement ratio `ratio` (> 1)
/// with convergence order `order` (> 0), from their difference.
pub fn richardson(difference: f64, ratio: f64, order: f64) -> f64 {
    difference.abs() / (ratio.powf(order) - 1.0)
}

/// Observed order from the differences of three levels (coarse−middle and
/// middle−fine) at a constant ratio; None when the differences do not
/// decrease (not in the asymptotic range).
pub fn observed_order(d_coarse: f64, d_fine: f64, ratio: f64) -> Option<f64> {
    let (a, b) = (d_coarse.abs(), d_fine.abs());
    (a > b && b > 0.0 && ratio > 1.0).then(|| (a / b).ln() / ratio.ln())
}

/// Predicts the error at a finer level from the error at a measured level:
/// e(level + k) = e(level) / ratio^(k·order).
pub fn extrapolate(error: f64, ratio: f64, order: f64, levels: u32) -> f64 {
    error / ratio.powf(order * f64::from(levels))
}

/// Lowest order used: an observed order below it, or differences that do
/// not decrease, are taken as this (a conservative, slow convergence).
pub const MIN_ORDER: f64 = 0.5;
/// Order assumed from two levels only (no observed order): 1, below every
/// theoretical order here, as the stick/slip kinks make it.
pub const TWO_LEVEL_ORDER: f64 = 1.0;

/// The correlation c of the errors of successive levels from the three
/// differences of three levels. Model: e_1 = ρ1 R e_0, e_2 = ρ2 R e_1 with
/// ⟨e_k, e_{k+1}⟩ = c |e_k| |e_{k+1}| and c² two levels apart (c = 1: the
/// aligned power law of classical Richardson extrapolation; c = 0: errors
/// that differ in phase, as stick/slip events at slightly different times
/// make them). Then |q_0 − q_1|² = E²(1 + ρ1² − 2ρ1 c) and |q_0 − q_2|² =
/// E²(1 + ρ1²ρ2² − 2ρ1ρ2 c²); their ratio fixes c. The root nearest 1 is
/// taken (the larger error); no root in [−1, 1] gives 1.
pub fn correlation(d01: f64, d02: f64, rho1: f64, rho2: f64) -> f64 {
    let target = (d02 / d01).powi(2);
    let f = |c: f64| {
        (1.0 + (rho1 * rho2).powi(2) - 2.0 * rho1 * rho2 * c * c)
            / (1.0 + rho1 * rho1 - 2.0 * rho1 * c)
            - target
    };
    let mut prev = (1.0, f(1.0));
    if prev.1 == 0.0 {
        return 1.0;
    }
    for k in 1..=2000 {
        let c = 1.0 - f64::from(k) * 1e-3;
        let v = f(c);
        if v == 0.0 || (v > 0.0) != (prev.1 > 0.0) {
            // Linear interpolation inside the bracket.
            return prev.0 + (c - prev.0) * prev.1 / (prev.1 - v);
        }
        prev = (c, v);
    }
    1.0
}

/// Errors at every level of a ladder from the differences of the measured
/// levels. `diffs[k]` = ‖q_k − q_{k+1}‖ for the `diffs.len() + 1` measured
/// levels; `skip` = ‖q_{n−2} − q_n‖ of the last three measured levels (None
/// with two levels); `ratios[k]` = refinement ratio from level k to k + 1
/// for all levels (measured and beyond); `max_order` caps the observed
/// order (the theoretical one).
///
/// The last three measured levels give the order p (from the ratio of
/// their differences) and the correlation c of successive errors
/// ([`correlation`]); the first of them then has the error E =
/// d / √(1 + ρ² − 2ρc), ρ = r^−p, and each finer level ρ times the one
/// before (measured or not). With two levels, c = 1 and p =
/// [`TWO_LEVEL_ORDER`]: classical Richardson, |q_0 − q_1| / (r^p − 1) for
/// the finer. Coarser measured levels get the bound e_k ≤ e_{k+1} +
/// |q_k − q_{k+1}|. Returns (errors per level, order, correlation).
pub fn ladder_errors(
    diffs: &[f64],
    skip: Option<f64>,
    ratios: &[f64],
    max_order: f64,
) -> (Vec<f64>, f64, f64) {
    let levels = ratios.len() + 1;
    let n = diffs.len();
    let mut e = vec![f64::NAN; levels];
    if n == 0 {
        return (e, f64::NAN, f64::NAN);
    }
    let (first, p, c) = match skip.filter(|_| n >= 2) {
        Some(d02) => {
            let l = n - 2;
            let p = observed_order(diffs[l], diffs[l + 1], ratios[l + 1])
                .unwrap_or(MIN_ORDER)
                .clamp(MIN_ORDER, max_order);
            let (r1, r2) = (ratios[l].powf(-p), ratios[l + 1].powf(-p));
            (l, p, correlation(diffs[l], d02, r1, r2))
        }
        None => (n - 1, TWO_LEVEL_ORDER.min(max_order), 1.0),
    };
    let rho = ratios[first].powf(-p);
    e[first] = diffs[first].abs() / (1.0 + rho * rho - 2.0 * rho * c).max(0.0).sqrt();
    for k in first + 1..levels {
        e[k] = extrapolate(e[k - 1], ratios[k - 1], p, 1);
    }
    for k in (0..first).rev() {
        e[k] = e[k + 1] + diffs[k].abs();
    }
    (e, p, c)
}

/// The error of a run X from its distance to the reference run R and R's
/// own error: √(‖X − R‖² + e_R²), the two taken as independent parts (a
/// measured difference and the uncertainty of the standard it was measured
/// against, combined as in the GUM). Between the bounds of the triangle
/// inequality, ‖X − R‖ − e_R ≤ e_X ≤ ‖X − R‖ + e_R.
pub fn with_reference(distance: f64, e_ref: f64) -> f64 {
    distance.hypot(e_ref)
}

/// Errors on every level of a ladder from the errors of its first
/// `measured.len()` levels: finer levels by e_{k+1} = e_k / r^p with p
/// observed from the last two measured errors (capped at `max_order`, the
/// theoretical order); when those do not decrease the ladder is not in its
/// asymptotic range (another error, e.g. Δt's, dominates) and no further
/// decrease is assumed (p = 0). With one measured level, p =
/// [`TWO_LEVEL_ORDER`]. Returns (errors per level, p).
pub fn continue_errors(measured: &[f64], ratios: &[f64], max_order: f64) -> (Vec<f64>, f64) {
    let levels = ratios.len() + 1;
    let n = measured.len().min(levels);
    let mut e = measured[..n].to_vec();
    if n == 0 {
        return (vec![f64::NAN; levels], f64::NAN);
    }
    let p = if n >= 2 {
        observed_order(e[n - 2], e[n - 1], ratios[n - 2]).map_or(0.0, |p| p.min(max_order))
    } else {
        TWO_LEVEL_ORDER.min(max_order)
    };
    for k in n..levels {
        let next = extrapolate(e[k - 1], ratios[k - 1], p, 1);
        e.push(next);
    }
    (e, p)
}

/// The error of a run at Δt from its changes at 2Δt and Δt/2 (`d_coarse`
/// = |X(2Δt) − X(Δt)|, `d_fine` = |X(Δt) − X(Δt/2)|): X(Δt/2)'s error by
/// [`richardson`] at the observed order (at least [`MIN_ORDER`], at most
/// `max_order`; [`MIN_ORDER`] when the changes do not decrease), plus
/// d_fine, as the aligned errors of a power law in Δt add.
pub fn dt_error(d_coarse: f64, d_fine: f64, max_order: f64) -> f64 {
    let p =
        observed_order(d_coarse, d_fine, 2.0).map_or(MIN_ORDER, |p| p.clamp(MIN_ORDER, max_order));
    d_fine + richardson(d_fine, 2.0, p)
}

/// [`continue_errors`] for errors with a part that no refinement of the
/// mesh reduces (Newmark's Δt error at its fixed Δt, `floor`): the measured
/// errors less the floor in quadrature are continued, and the floor is
/// added back in quadrature. Continued errors stay at or above the floor
/// (where [`continue_errors`] would take them below it on the decrease of
/// the measured levels, which the floor slows) and at or below the last
/// measured error; measured levels keep their measured errors.
pub fn continue_errors_above(
    measured: &[f64],
    ratios: &[f64],
    max_order: f64,
    floor: f64,
) -> (Vec<f64>, f64) {
    let Some(&last) = measured.last() else {
        return continue_errors(measured, ratios, max_order);
    };
    let above: Vec<f64> = measured
        .iter()
        .map(|e| (e * e - floor * floor).max(0.0).sqrt())
        .collect();
    let (e, p) = continue_errors(&above, ratios, max_order);
    let e = e
        .iter()
        .enumerate()
        .map(|(k, x)| match measured.get(k) {
            Some(&m) => m,
            None => x.hypot(floor).min(last),
        })
        .collect();
    (e, p)
}

/// Central-difference Δt as fractions of Δt_crit (as in the chart).
pub const CD_FRACTIONS: [f64; 3] = [0.9, 0.45, 0.225];
/// Newmark Δt = t_end / these.
pub const NEWMARK_DIVISIONS: [f64; 4] = [50.0, 100.0, 200.0, 400.0];
/// ε candidates: the case's ε times these.
pub const EPS_FACTORS: [f64; 3] = [1.0, 10.0, 100.0];
/// Uniform sample times for the L2-in-time norms.
pub const SAMPLES: usize = 5001;

/// One configuration the advisor can choose.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Element order.
    pub order: u8,
    /// Mesh file as written in the case's ladder.
    pub mesh: String,
    /// Index of the mesh in the ladder.
    pub mesh_index: usize,
    /// Method.
    pub method: Method,
    /// Normal Δt.
    pub dt: f64,
    /// ε.
    pub eps: f64,
    /// Estimated parts: the error of this mesh with the family's base Δt
    /// (central difference 0.9 Δt_crit, Newmark t_end/200), the change
    /// that this method and Δt make on the pilot mesh, the change that
    /// this ε makes there. A configuration that was run as a pilot has its
    /// own measured error here and zeros.
    pub parts: [f64; 3],
    /// Predicted wall time, seconds.
    pub predicted_time: f64,
    /// Free DOFs.
    pub dofs: usize,
    /// Predicted steps.
    pub steps: f64,
    /// Whether the mesh was a pilot of the h estimate (else extrapolated).
    pub measured_h: bool,
    /// Whether this very configuration was a pilot run.
    pub run: bool,
}

impl Candidate {
    /// The estimated error: the parts in quadrature, √(e_h² + δ_Δt² +
    /// δ_ε²). The parts are not independent errors of one kind that add
    /// (their sum is a bound only when they are aligned); the changes a Δt
    /// or ε makes are taken as uncorrelated with the mesh's error, as the
    /// measured distances show for the runs that were made.
    pub fn estimate(&self) -> f64 {
        self.parts.iter().map(|x| x * x).sum::<f64>().sqrt()
    }
}

/// Predicted times within this factor of the cheapest are a tie. They
/// rest on timings of millisecond pilots, which vary by about that much on
/// a shared machine: the README's example picked Q2 16×4 Newmark (0.014 s
/// predicted) in one run of five and Q1 64×16 central difference (0.015-
/// 0.020 s) in the others. The estimates do not depend on timing.
pub const TIE: f64 = 1.5;

/// The cheapest candidate whose estimate is at most `tol`, where those
/// within [`TIE`] of the cheapest predicted time tie and the most accurate
/// of them wins (so the choice does not follow the machine's load); None
/// when none qualifies.
pub fn pick(candidates: &[Candidate], tol: f64) -> Option<&Candidate> {
    let meets = || {
        candidates
            .iter()
            .filter(|c| c.estimate().is_finite() && c.estimate() <= tol)
    };
    let cheapest = meets()
        .map(|c| c.predicted_time)
        .fold(f64::INFINITY, f64::min);
    meets()
        .filter(|c| c.predicted_time <= TIE * cheapest)
        .min_by(|a, b| {
            a.estimate()
                .total_cmp(&b.estimate())
                .then(a.predicted_time.total_cmp(&b.predicted_time))
        })
}

/// One mesh of the ladder, as the case sees it.
#[derive(Clone, Debug)]
pub struct LadderMesh {
    /// Resolved path.
    pub path: PathBuf,
    /// As written in the case.
    pub text: String,
    /// Element order.
    pub order: u8,
    /// Cells.
    pub cells: usize,
    /// Free DOFs.
    pub dofs: usize,
    /// Stored entries of K.
    pub nnz: usize,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Central difference's critical step (lumped mass).
    pub dt_crit: f64,
    /// Position of the probed node (None for the energy).
    pub node_at: Option<[f64; 2]>,
}

fn input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(InputError(msg.into()))
}

/// Where the quantity is read in one prepared model.
enum Probe {
    Dof(usize),
    Contact(usize),
    Energy,
}

fn nearest(
    points: impl Iterator<Item = (usize, [f64; 2])>,
    at: [f64; 2],
) -> Option<(usize, [f64; 2])> {
    points
        .map(|(i, p)| (i, p, (p[0] - at[0]).powi(2) + (p[1] - at[1]).powi(2)))
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .map(|(i, p, _)| (i, p))
}

fn probe_of(
    case: &Case,
    p: &Prepared,
    q: Quantity,
    at: Option<[f64; 2]>,
) -> anyhow::Result<(Probe, Option<[f64; 2]>)> {
    let need_at = || {
        at.ok_or_else(|| {
            input(format!(
                "--on {} needs --at X,Y (the node nearest to it is used)",
                q.name()
            ))
        })
    };
    match q {
        Quantity::Energy => Ok((Probe::Energy, None)),
        Quantity::Ux | Quantity::Uy => {
            let at = need_at()?;
            let comp = usize::from(q == Quantity::Uy);
            let (node, pos) =
                nearest(p.mesh.nodes.iter().copied().enumerate(), at).ok_or_else(|| {
                    input(format!(
                        "{}: the mesh has no nodes",
                        case.mesh.file.display()
                    ))
                })?;
            match p.model.dofs.free(node, comp) {
                Some(d) => Ok((Probe::Dof(d), Some(pos))),
                None => Err(input(format!(
                    "--on {} --at {},{}: the nearest node of {} at ({}, {}) has {} prescribed by a [[dirichlet]] condition; \
                     nothing to estimate there, choose another point",
                    q.name(),
                    at[0],
                    at[1],
                    case.mesh.file.display(),
                    pos[0],
                    pos[1],
                    q.name()
                ))),
            }
        }
        Quantity::FrictionStress => {
            let at = need_at()?;
            let c = p.integrator.contact().ok_or_else(|| {
                input(format!(
                    "{}: --on friction_stress needs a [contact] section; the case has none",
                    case.path.display()
                ))
            })?;
            let (k, pos) = nearest(
                c.nodes
                    .iter()
                    .enumerate()
                    .map(|(k, n)| (k, p.mesh.nodes[n.node])),
                at,
            )
            .ok_or_else(|| {
                input(format!(
                    "{}: the contact group {:?} has no friction nodes",
                    case.path.display(),
                    c.group
                ))
            })?;
            Ok((Probe::Contact(k), Some(pos)))
        }
    }
}

/// Runs `case` (already configured) to t_end recording `q` at the node
/// nearest `at` (nothing but the energies for [`Quantity::Energy`]); the
/// time includes building the model.
///
/// # Errors
/// Input problems as [`InputError`]; a step that fails.
pub fn run_traced(case: &Case, q: Quantity, at: Option<[f64; 2]>) -> anyhow::Result<Trace> {
    let pilot = pilot::Pilot::new(case)?;
    let probes: Vec<pilot::Probe> = match probe_of(case, &pilot.prepared, q, at)?.0 {
        Probe::Dof(d) => vec![pilot::Probe::Dof(d)],
        Probe::Contact(k) => vec![pilot::Probe::Contact(k)],
        Probe::Energy => Vec::new(),
    };
    pilot.run(&probes).map_err(|e| {
        anyhow::anyhow!(
            "{} on {} ({}, dt = {:e}): {e}",
            case.path.display(),
            case.mesh.file.display(),
            match case.time.scheme {
                CaseScheme::CentralDifference => "central difference".to_string(),
                CaseScheme::Newmark => format!("newmark {}/{}", case.time.beta, case.time.gamma),
            },
            case.time.dt,
        )
    })
}

/// The uniform grid of [`SAMPLES`] times on [0, t_end].
pub fn grid(t_end: f64) -> Vec<f64> {
    pilot::grid(t_end, SAMPLES)
}

/// The error measure of `a` against `b` (docs/work-precision.csv's):
/// ‖a − b‖ / ‖b − b(0)‖ in the discrete L2-in-time norm for u_x, u_y
/// (relative to the motion; the initial state is the static solution),
/// ‖a − b‖ / ‖b‖ for σ_T, and |E_a(t_end) − E_b(t_end)| / |E_b(t_end) −
/// E_b(0)| for the energy.
pub fn distance(q: Quantity, a: &Trace, b: &Trace, grid: &[f64]) -> f64 {
    if q == Quantity::Energy {
        return (a.energy_end - b.energy_end).abs() / (b.energy_end - b.energy0).abs();
    }
    let sa = sample(&a.t, &a.values[0], grid);
    let sb = sample(&b.t, &b.values[0], grid);
    let offset = if q == Quantity::FrictionStress {
        0.0
    } else {
        sb[0]
    };
    relative_l2(&sa, &sb, offset)
}

/// One pilot run, for the report.
#[derive(Clone, Debug)]
pub struct Pilot {
    /// Ladder index.
    pub mesh_index: usize,
    /// Method.
    pub method: Method,
    /// Δt.
    pub dt: f64,
    /// ε.
    pub eps: f64,
    /// Steps.
    pub steps: u64,
    /// Seconds.
    pub secs: f64,
}

/// Everything the pilots measured: the candidates with their estimates.
#[derive(Clone, Debug)]
pub struct Estimates {
    /// The quantity.
    pub quantity: Quantity,
    /// The ladder.
    pub ladder: Vec<LadderMesh>,
    /// Every candidate.
    pub candidates: Vec<Candidate>,
    /// The pilot runs.
    pub pilots: Vec<Pilot>,
    /// Total wall time of the pilots and the ladder's set-up, seconds.
    pub seconds: f64,
    /// Per ladder: what, the order used (NaN where none is), and its
    /// numbers: the reference's measured differences, the estimated errors
    /// per mesh (h ladders), the changes per Δt or ε.
    pub orders: Vec<(String, f64, Vec<f64>)>,
    /// Remarks for the report (probe positions that differ, skipped meshes).
    pub notes: Vec<String>,
}

struct Pilots<'a> {
    case: &'a Case,
    q: Quantity,
    at: Option<[f64; 2]>,
    ladder: &'a [LadderMesh],
    runs: Vec<(usize, Method, f64, f64, Trace)>,
    log: &'a mut dyn FnMut(&str),
}

impl Pilots<'_> {
    /// Runs (or reuses) one configuration; returns its index in `runs`.
    fn run(&mut self, m: usize, method: Method, dt: f64, eps: f64) -> anyhow::Result<usize> {
        if let Some(k) = self
            .runs
            .iter()
            .position(|r| r.0 == m && r.1 == method && r.2 == dt && r.3 == eps)
        {
            return Ok(k);
        }
        let c = method.configure(self.case, &self.ladder[m].path, dt, eps);
        let tr = run_traced(&c, self.q, self.at).with_context(|| {
            format!(
                "pilot run on {} ({}, dt = {dt:.4e}, eps = {eps:e})",
                self.ladder[m].text,
                method.name()
            )
        })?;
        (self.log)(&format!(
            "pilot  {:28} {:20} dt {:.4e} eps {:.0e}: {:6} steps, {:.3} s",
            self.ladder[m].text,
            method.name(),
            dt,
            eps,
            tr.steps,
            tr.secs
        ));
        self.runs.push((m, method, dt, eps, tr));
        Ok(self.runs.len() - 1)
    }

    fn trace(&self, k: usize) -> &Trace {
        &self.runs[k].4
    }

    /// Differences of consecutive runs (finer normalizes).
    fn diffs(&self, runs: &[usize], grid: &[f64]) -> Vec<f64> {
        runs.windows(2)
            .map(|w| distance(self.q, self.trace(w[0]), self.trace(w[1]), grid))
            .collect()
    }

    /// ‖q_{n−2} − q_n‖ of the last three runs (None with fewer).
    fn skip(&self, runs: &[usize], grid: &[f64]) -> Option<f64> {
        (runs.len() >= 3).then(|| {
            let n = runs.len();
            distance(
                self.q,
                self.trace(runs[n - 3]),
                self.trace(runs[n - 1]),
                grid,
            )
        })
    }

    /// Seconds per step per DOF of a run.
    fn cost(&self, k: usize) -> f64 {
        let t = self.trace(k);
        t.secs / (t.steps.max(1) as f64 * t.nnz.max(1) as f64)
    }
}

/// Reads the ladder of `case`: each mesh prepared once (groups checked,
/// order, DOFs, Δt_crit, probe position).
///
/// # Errors
/// No ladder, a mesh the case does not fit, a probe that cannot be placed.
pub fn read_ladder(
    case: &Case,
    q: Quantity,
    at: Option<[f64; 2]>,
) -> anyhow::Result<Vec<LadderMesh>> {
    if case.mesh.ladder.len() < 2 {
        return Err(input(format!(
            "{}mesh.ladder: advise needs at least two meshes of one element order to estimate the \
             discretization error in h; add e.g. ladder = [\"coarse.msh\", \"medium.msh\", \"fine.msh\"] \
             to [mesh] (same geometry and group names, coarse to fine)",
            case.at(if case.mesh.ladder.is_empty() { "mesh.file" } else { "mesh.ladder" })
        )));
    }
    let mut out = Vec::new();
    // The first mesh's extent, which every other must share: a ladder is
    // one geometry refined (10% slack per side: a coarse mesh of a curved
    // boundary falls short of it).
    let mut first: Option<(String, [[f64; 2]; 2])> = None;
    for (path, text) in case.mesh.ladder.iter().zip(&case.mesh.ladder_text) {
        if !path.is_file() {
            return Err(input(format!(
                "{}mesh.ladder entry {text:?}: {} does not exist (paths are relative to the case file's directory); \
                 check the name, or make the mesh with Gmsh",
                case.at("mesh.ladder"),
                path.display()
            )));
        }
        // A Newmark set-up never refuses a Δt; the static solve checks the supports.
        let c = Method::Trapezoidal.configure(case, path, case.time.t_end / 50.0, eps_of(case));
        let p = prepare(&c).map_err(|e| {
            input(format!(
                "{}mesh.ladder entry {text:?}: {}",
                case.at("mesh.ladder"),
                e.0
            ))
        })?;
        let b = p.mesh.bbox();
        let size = (b[1][0] - b[0][0]).max(b[1][1] - b[0][1]);
        let show = |b: [[f64; 2]; 2]| {
            format!(
                "x in [{}, {}], y in [{}, {}]",
                b[0][0], b[1][0], b[0][1], b[1][1]
            )
        };
        match &first {
            None => {
                if let Some(p) = at {
                    if crate::probe::off_the_body(b, p) {
                        return Err(input(format!(
                            "--at {},{}: the point lies outside the mesh ({}); give a point on the body",
                            p[0],
                            p[1],
                            show(b)
                        )));
                    }
                }
                first = Some((text.clone(), b));
            }
            Some((t0, b0)) => {
                let apart = (0..2)
                    .flat_map(|i| (0..2).map(move |k| (b[i][k] - b0[i][k]).abs()))
                    .fold(0.0_f64, f64::max);
                if apart > 0.1 * size {
                    return Err(input(format!(
                        "{}mesh.ladder entry {text:?} spans {} but {t0:?} spans {}: a ladder is one \
                         geometry meshed finer and finer; give meshes of the same body",
                        case.at("mesh.ladder"),
                        show(b),
                        show(*b0)
                    )));
                }
            }
        }
        let (_, node_at) = probe_of(&c, &p, q, at)?;
        let dt_crit =
            stickslip_time::stability::critical_step(&p.model.stiffness, &p.model.lumped_mass);
        out.push(LadderMesh {
            path: path.clone(),
            text: text.clone(),
            order: match p.mesh.kind {
                stickslip_mesh::CellKind::Quad4 => 1,
                stickslip_mesh::CellKind::Quad9 => 2,
            },
            cells: p.mesh.n_cells(),
            dofs: p.model.dofs.n_free(),
            nnz: p.model.stiffness.nnz(),
            contact_nodes: p.integrator.contact().map_or(0, |c| c.len()),
            dt_crit,
            node_at,
        });
    }
    Ok(out)
}

fn eps_of(case: &Case) -> f64 {
    case.contact.as_ref().map_or(f64::NAN, |c| c.eps)
}

/// The pilot runs and every candidate's estimate (independent of the
/// tolerance: [`pick`] then chooses). `log` receives one line per pilot.
///
/// # Errors
/// As [`read_ladder`]; a pilot run that fails.
pub fn estimate(
    case: &Case,
    q: Quantity,
    at: Option<[f64; 2]>,
    log: &mut dyn FnMut(&str),
) -> anyhow::Result<Estimates> {
    let start = Instant::now();
    let ladder = read_ladder(case, q, at)?;
    let mut notes = Vec::new();
    if let Some(first) = ladder.iter().find_map(|m| m.node_at) {
        for m in &ladder {
            if let Some(p) = m.node_at {
                if (p[0] - first[0]).hypot(p[1] - first[1])
                    > 1e-9 * (1.0 + first[0].hypot(first[1]))
                {
                    notes.push(format!(
                        "the probed node of {} is at ({}, {}), not at ({}, {}) as on {}: its differences mix places",
                        m.text, p[0], p[1], first[0], first[1], ladder[0].text
                    ));
                }
            }
        }
    }
    let t_end = case.time.t_end;
    let eps0 = eps_of(case);
    let g_all = grid(t_end);
    let nm_dt: Vec<f64> = NEWMARK_DIVISIONS.iter().map(|d| t_end / d).collect();
    let dt_h = t_end / 200.0;
    let mut pilots = Pilots {
        case,
        q,
        at,
        ladder: &ladder,
        runs: Vec::new(),
        log,
    };
    let mut orders = Vec::new();

    // h: per element order, the first three meshes of the ladder.
    struct Group {
        order: u8,
        meshes: Vec<usize>,
        ratios: Vec<f64>,
        /// Pilot runs per measured mesh: central difference, Newmark ¼/½.
        cd_runs: Vec<usize>,
        nm_runs: Vec<usize>,
        /// Seconds per step per stored entry of K: central difference, Newmark ¼/½.
        cost_cd: f64,
        cost_nm: f64,
    }
    let mut groups = Vec::new();
    for order in [1u8, 2] {
        let meshes: Vec<usize> = (0..ladder.len())
            .filter(|&m| ladder[m].order == order)
            .collect();
        if meshes.len() < 2 {
            if let Some(&m) = meshes.first() {
                notes.push(format!(
                    "{} is the only Q{order} mesh of the ladder: no h estimate for Q{order}, left out",
                    ladder[m].text
                ));
            }
            continue;
        }
        let ratios: Vec<f64> = meshes
            .windows(2)
            .map(|w| (ladder[w[1]].cells as f64 / ladder[w[0]].cells as f64).sqrt())
            .collect();
        if let Some(k) = ratios.iter().position(|r| r.is_nan() || *r <= 1.0) {
            return Err(input(format!(
                "{}mesh.ladder: {} has no more cells than {} before it; list the Q{order} meshes coarse to fine",
                case.at("mesh.ladder"),
                ladder[meshes[k + 1]].text,
                ladder[meshes[k]].text
            )));
        }
        let pilot_levels = meshes.len().min(3);
        let mut cd_runs = Vec::new();
        let mut nm_runs = Vec::new();
        for &m in &meshes[..pilot_levels] {
            cd_runs.push(pilots.run(
                m,
                Method::CentralDifference,
                CD_FRACTIONS[0] * ladder[m].dt_crit,
                eps0,
            )?);
            nm_runs.push(pilots.run(m, Method::Trapezoidal, dt_h, eps0)?);
        }
        groups.push(Group {
            order,
            cost_cd: pilots.cost(*cd_runs.last().expect("two levels")),
            cost_nm: pilots.cost(*nm_runs.last().expect("two levels")),
            meshes,
            ratios,
            cd_runs,
            nm_runs,
        });
    }
    if groups.is_empty() {
        return Err(input(format!(
            "{}mesh.ladder: advise needs at least two meshes of one element order (Q1 or Q2); add a refinement",
            case.at("mesh.ladder")
        )));
    }
    // The reference R: central difference at 0.9 Δt_crit (explicit, the
    // cheapest step) on the mesh after the pilots of the highest order, or
    // on its finest pilot when the ladder has no more. Its own error e_R
    // comes from the differences of its ladder ([`ladder_errors`]).
    let top = groups.len() - 1;
    {
        let g = &mut groups[top];
        if g.meshes.len() > g.cd_runs.len() {
            let m = g.meshes[g.cd_runs.len()];
            let k = pilots.run(
                m,
                Method::CentralDifference,
                CD_FRACTIONS[0] * ladder[m].dt_crit,
                eps0,
            )?;
            g.cd_runs.push(k);
        }
    }
    let (r_run, e_ref) = {
        let g = &groups[top];
        let d = pilots.diffs(&g.cd_runs, &g_all);
        let (e, p, c) = ladder_errors(
            &d,
            pilots.skip(&g.cd_runs, &g_all),
            &g.ratios,
            f64::from(g.order) + 1.0,
        );
        let n = g.cd_runs.len();
        orders.push((
            format!(
                "reference R = Q{} {} (central difference, 0.9 dt_crit): error {:.2e} from the Q{} differences (correlation {c:.2})",
                g.order,
                ladder[g.meshes[n - 1]].text,
                e[n - 1],
                g.order
            ),
            p,
            d,
        ));
        (g.cd_runs[n - 1], e[n - 1])
    };
    // The error of a pilot run X: X − R plus R's own error, added in
    // quadrature, e_X = √(‖X − R‖² + e_R²): the measured difference and
    // the reference's uncertainty combined as independent parts (as a
    // measurement's uncertainty is combined with its reference standard's).
    // This uses the distance to the most accurate run, not the differences
    // of neighbours, whose errors are only partly aligned (stick/slip
    // events move between refinements) so that Richardson's model of them
    // misjudges the finer level's error.
    let err_of = |pilots: &Pilots, k: usize| -> f64 {
        if k == r_run {
            e_ref
        } else {
            with_reference(
                distance(q, pilots.trace(k), pilots.trace(r_run), &g_all),
                e_ref,
            )
        }
    };
    // Errors of the (mesh, base Δt) configurations per order and family:
    // measured pilots, then finer meshes by the order observed from the
    // last two measured errors.
    let mut e_cd_all = Vec::new();
    let mut e_nm_all = Vec::new();
    for g in &groups {
        let max_order = f64::from(g.order) + 1.0;
        let mc: Vec<f64> = g.cd_runs.iter().map(|&k| err_of(&pilots, k)).collect();
        let (ec, pc) = continue_errors(&mc, &g.ratios, max_order);
        orders.push((
            format!(
                "errors, Q{} meshes, central difference (0.9 dt_crit)",
                g.order
            ),
            pc,
            ec.clone(),
        ));
        e_cd_all.push(ec);
    }
    // Δt and ε on the second mesh of the highest order: each run's change
    // from its family's base configuration on that mesh (central
    // difference at 0.9 Δt_crit; Newmark ¼/½ at t_end/200).
    let pm = groups[top].meshes[1];
    let crit = ladder[pm].dt_crit;
    let cd_runs: Vec<usize> = CD_FRACTIONS
        .iter()
        .map(|f| pilots.run(pm, Method::CentralDifference, f * crit, eps0))
        .collect::<anyhow::Result<_>>()?;
    let nm_base = pilots.run(pm, Method::Trapezoidal, dt_h, eps0)?;
    let d_dt_cd: Vec<f64> = cd_runs
        .iter()
        .map(|&k| distance(q, pilots.trace(k), pilots.trace(cd_runs[0]), &g_all))
        .collect();
    orders.push((
        "changes, dt, central difference (from 0.9 dt_crit)".into(),
        f64::NAN,
        d_dt_cd.clone(),
    ));
    let mut d_dt_nm = Vec::new();
    let mut nm_runs_by_method = Vec::new();
    for method in [
        Method::Trapezoidal,
        Method::TrapezoidalReduced,
        Method::Damped,
    ] {
        let runs: Vec<usize> = nm_dt
            .iter()
            .map(|&dt| pilots.run(pm, method, dt, eps0))
            .collect::<anyhow::Result<_>>()?;
        let d: Vec<f64> = runs
            .iter()
            .map(|&k| distance(q, pilots.trace(k), pilots.trace(nm_base), &g_all))
            .collect();
        orders.push((
            format!(
                "changes, dt, {} (from nm-0.25-0.5 at t_end/200)",
                method.name()
            ),
            f64::NAN,
            d.clone(),
        ));
        d_dt_nm.push((method, d));
        nm_runs_by_method.push((method, runs));
    }
    // Newmark's errors per mesh at t_end/200 hold that Δt's error, which
    // no mesh reduces: it is estimated from the ¼/½ changes at t_end/100
    // and t_end/400 on the pilot mesh (the same Δt on every mesh, so taken
    // as every mesh's) and held as a floor under the finer meshes' errors
    // ([`continue_errors_above`]; continued as mesh error, the errors of
    // finer meshes went below it).
    let k_h = NEWMARK_DIVISIONS
        .iter()
        .position(|d| *d == 200.0)
        .expect("t_end/200 in the ladder");
    let dt_floor = {
        let d = &d_dt_nm[0].1;
        dt_error(d[k_h - 1], d[k_h + 1], 2.0)
    };
    for g in &groups {
        let mn: Vec<f64> = g.nm_runs.iter().map(|&k| err_of(&pilots, k)).collect();
        let (en, pn) = continue_errors_above(&mn, &g.ratios, f64::from(g.order) + 1.0, dt_floor);
        orders.push((
            format!(
                "errors, Q{} meshes, Newmark (t_end/200; its dt error {dt_floor:.2e} held under finer meshes)",
                g.order
            ),
            pn,
            en.clone(),
        ));
        e_nm_all.push(en);
    }
    let mut d_eps = vec![0.0];
    let eps_list: Vec<f64> = if case.contact.is_some() {
        let base = cd_runs[0];
        for f in &EPS_FACTORS[1..] {
            let k = pilots.run(
                pm,
                Method::CentralDifference,
                CD_FRACTIONS[0] * crit,
                eps0 * f,
            )?;
            d_eps.push(distance(q, pilots.trace(k), pilots.trace(base), &g_all));
        }
        orders.push(("changes, eps x 1, 10, 100".into(), f64::NAN, d_eps.clone()));
        EPS_FACTORS.iter().map(|f| eps0 * f).collect()
    } else {
        vec![eps0]
    };

    // Cost of the Newmark variants relative to Newmark ¼/½ at the same Δt on
    // the pilot mesh; extra steps of the reduction per contact node.
    let trap = &nm_runs_by_method[0].1;
    // One cost constant per scheme for all meshes (geometric mean over the
    // element orders): a step's work is proportional to nnz(K), so the
    // ranking of meshes within a scheme is by steps × nnz, which is exact,
    // rather than by timings of millisecond pilots on a shared machine.
    let shared = |f: fn(&Group) -> f64| {
        (groups.iter().map(|g| f(g).ln()).sum::<f64>() / groups.len() as f64).exp()
    };
    let (cost_cd, cost_nm) = (shared(|g| g.cost_cd), shared(|g| g.cost_nm));
    let mut candidates = Vec::new();
    for (gi, gr) in groups.iter().enumerate() {
        for (level, &m) in gr.meshes.iter().enumerate() {
            let lm = &ladder[m];
            for method in Method::ALL {
                let (dts, e_base, cost): (Vec<f64>, f64, f64) = match method {
                    Method::CentralDifference => (
                        CD_FRACTIONS.iter().map(|f| f * lm.dt_crit).collect(),
                        e_cd_all[gi][level],
                        cost_cd,
                    ),
                    _ => {
                        let runs = &nm_runs_by_method
                            .iter()
                            .find(|r| r.0 == method)
                            .expect("run")
                            .1;
                        let rel = pilots.cost(runs[k_h]) / pilots.cost(trap[k_h]);
                        (nm_dt.clone(), e_nm_all[gi][level], cost_nm * rel)
                    }
                };
                let measured_h = match method {
                    Method::CentralDifference => level < gr.cd_runs.len(),
                    _ => level < gr.nm_runs.len(),
                };
                for (kd, &dt) in dts.iter().enumerate() {
                    let d_dt = match method {
                        Method::CentralDifference => d_dt_cd[kd],
                        _ => d_dt_nm.iter().find(|e| e.0 == method).expect("estimated").1[kd],
                    };
                    let mut steps = (t_end / dt).ceil();
                    if method == Method::TrapezoidalReduced {
                        let runs = &nm_runs_by_method
                            .iter()
                            .find(|r| r.0 == method)
                            .expect("run")
                            .1;
                        let extra = (pilots.trace(runs[kd]).steps as f64 - steps).max(0.0);
                        let per_node = extra / ladder[pm].contact_nodes.max(1) as f64;
                        steps += per_node * lm.contact_nodes as f64;
                    }
                    for (ke, &eps) in eps_list.iter().enumerate() {
                        // A configuration that was itself run: its error
                        // against R directly.
                        let own = pilots
                            .runs
                            .iter()
                            .position(|r| r.0 == m && r.1 == method && r.2 == dt && r.3 == eps);
                        let parts = match own {
                            Some(k) => [err_of(&pilots, k), 0.0, 0.0],
                            None => [e_base, d_dt, d_eps[ke]],
                        };
                        candidates.push(Candidate {
                            order: gr.order,
                            mesh: lm.text.clone(),
                            mesh_index: m,
                            method,
                            dt,
                            eps,
                            parts,
                            predicted_time: cost * lm.nnz as f64 * steps,
                            dofs: lm.dofs,
                            steps,
                            measured_h,
                            run: own.is_some(),
                        });
                    }
                }
            }
        }
    }
    let pilots_out = pilots
        .runs
        .iter()
        .map(|r| Pilot {
            mesh_index: r.0,
            method: r.1,
            dt: r.2,
            eps: r.3,
            steps: r.4.steps,
            secs: r.4.secs,
        })
        .collect();
    Ok(Estimates {
        quantity: q,
        ladder,
        candidates,
        pilots: pilots_out,
        seconds: start.elapsed().as_secs_f64(),
        orders,
        notes,
    })
}

/// `path` relative to the directory `base` (both made absolute first).
fn relative_to(path: &Path, base: &Path) -> PathBuf {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, b) = (abs(path), abs(base));
    let pc: Vec<Component> = p.components().collect();
    let bc: Vec<Component> = b.components().collect();
    let common = pc.iter().zip(&bc).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return p;
    }
    let mut out = PathBuf::new();
    for _ in common..bc.len() {
        out.push("..");
    }
    for c in &pc[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// The case text with the chosen configuration, for `--write OUT.toml`:
/// the case as written (comments and layout kept, by toml_edit) with
/// mesh.file, [time] and contact.eps changed; paths are rewritten relative
/// to OUT's directory when it is not the case's.
///
/// # Errors
/// The case text does not parse (it did when it was loaded).
pub fn adjusted_case(
    case: &Case,
    c: &Candidate,
    ladder: &[LadderMesh],
    out: &Path,
    header: &str,
) -> anyhow::Result<String> {
    use toml_edit::{value, Array, InlineTable, Item, Value};
    let mut doc: toml_edit::DocumentMut = case
        .source
        .parse()
        .with_context(|| format!("{}: the case text no longer parses", case.path.display()))?;
    let case_dir = case.path.parent().unwrap_or(Path::new("")).to_path_buf();
    let out_dir = out.parent().unwrap_or(Path::new("")).to_path_buf();
    let same_dir = std::fs::canonicalize(if case_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        &case_dir
    })
    .ok()
        == std::fs::canonicalize(if out_dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &out_dir
        })
        .ok();
    let rel = |m: &LadderMesh| -> String {
        if same_dir {
            m.text.clone()
        } else {
            relative_to(
                &m.path,
                if out_dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    &out_dir
                },
            )
            .display()
            .to_string()
        }
    };
    let set = |t: &mut toml_edit::Table, k: &str, v: Value| match t.get_mut(k) {
        Some(Item::Value(old)) => {
            let decor = old.decor().clone();
            *old = v;
            *old.decor_mut() = decor;
        }
        _ => {
            t.insert(k, Item::Value(v));
        }
    };
    let mesh = doc["mesh"]
        .as_table_mut()
        .context("[mesh] is not a table")?;
    set(mesh, "file", Value::from(rel(&ladder[c.mesh_index])));
    if !same_dir {
        if let Some(Item::Value(Value::Array(a))) = mesh.get_mut("ladder") {
            let new: Array = ladder.iter().map(|m| Value::from(rel(m))).collect();
            for (slot, v) in a.iter_mut().zip(new.iter()) {
                let decor = slot.decor().clone();
                *slot = v.clone();
                *slot.decor_mut() = decor;
            }
        }
    }
    let time = doc["time"]
        .as_table_mut()
        .context("[time] is not a table")?;
    match c.method.newmark() {
        None => {
            set(time, "scheme", Value::from("central_difference"));
            time.remove("beta");
            time.remove("gamma");
        }
        Some((beta, gamma)) => {
            set(time, "scheme", Value::from("newmark"));
            set(time, "beta", Value::from(beta));
            set(time, "gamma", Value::from(gamma));
        }
    }
    set(time, "dt", Value::from(c.dt));
    time.remove("mass");
    time.remove("allow_unstable");
    if c.method == Method::TrapezoidalReduced {
        let r = case.time.stick_reduction.unwrap_or(PAPER_REDUCTION);
        let mut t = InlineTable::new();
        t.insert("dt", Value::from(r.dt));
        t.insert("steps", Value::from(r.steps as i64));
        time.remove("stick_reduction");
        time.insert("stick_reduction", value(t));
    } else {
        time.remove("stick_reduction");
    }
    if case.contact.is_some() {
        let contact = doc["contact"]
            .as_table_like_mut()
            .context("[contact] is not a table")?;
        match contact.get_mut("eps") {
            Some(Item::Value(old)) => {
                let decor = old.decor().clone();
                *old = Value::from(c.eps);
                *old.decor_mut() = decor;
            }
            _ => {
                contact.insert("eps", value(c.eps));
            }
        }
    }
    let mut text = String::new();
    for line in header.lines() {
        text.push_str("# ");
        text.push_str(line);
        text.push('\n');
    }
    text.push_str(&doc.to_string());
    // What we write must load as a case.
    case::load_str(out, &text, &[])
        .map_err(|e| anyhow::anyhow!("the adjusted case does not load: {}", e.0))?;
    Ok(text)
}

/// Parses `--at X,Y`.
///
/// # Errors
/// Not two finite numbers.
pub fn parse_point(s: &str) -> Result<[f64; 2], InputError> {
    let bad = || {
        InputError(format!(
            "--at {s:?}: expected two numbers X,Y, e.g. --at 8,1"
        ))
    };
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if x.is_finite() && y.is_finite() {
        Ok([x, y])
    } else {
        Err(bad())
    }
}

/// The command's options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Tolerance on the relative error.
    pub tol: f64,
    /// The output.
    pub quantity: Quantity,
    /// The point (ux, uy, friction_stress).
    pub at: Option<[f64; 2]>,
    /// Write the adjusted case here.
    pub write: Option<PathBuf>,
    /// One JSON object on stdout instead of the report.
    pub json: bool,
}

/// How `advise` ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// A configuration meets the tolerance (estimated).
    Found,
    /// None of the ladder's does.
    NotReachable,
}

fn describe(c: &Candidate, ladder: &[LadderMesh]) -> String {
    let extra = if c.method == Method::CentralDifference {
        format!(" ({:.3} dt_crit)", c.dt / ladder[c.mesh_index].dt_crit)
    } else {
        String::new()
    };
    format!(
        "Q{} {} ({} DOFs), {}, dt = {:.4e}{extra}, eps = {:e}",
        c.order,
        c.mesh,
        c.dofs,
        c.method.label(),
        c.dt,
        c.eps
    )
}

/// `stickslip advise`: pilots, choice, report, `--write`.
///
/// # Errors
/// Input problems as [`InputError`]; pilot runs that fail; an unwritable output.
pub fn command(case: &Case, o: &Options) -> anyhow::Result<Verdict> {
    // A relative error of 1 or more is no accuracy (the coarsest pilot
    // meets it whatever it computes).
    if !(o.tol > 0.0 && o.tol < 1.0) {
        let tol = o.tol.to_string();
        let tol = if tol.len() > 12 {
            format!("{:e}", o.tol)
        } else {
            tol
        };
        return Err(input(format!(
            "--tol {tol}: give a relative error between 0 and 1, e.g. --tol 1e-2"
        )));
    }
    if o.quantity == Quantity::Energy && o.at.is_some() {
        return Err(input(
            "--at goes with --on ux, uy or friction_stress; --on energy is the body's total energy \
             at t_end, at no point: leave --at out"
                .to_string(),
        ));
    }
    if let Some(w) = &o.write {
        if w.is_dir() {
            return Err(input(format!(
                "--write {}: it is a directory; give a file name in it, e.g. --write {}",
                w.display(),
                w.join("advised.toml").display()
            )));
        }
        // Never over a file: it may be the case being advised, or another.
        if w.exists() {
            return Err(input(format!(
                "--write {}: the file exists; give a new name (advise never overwrites a file)",
                w.display()
            )));
        }
        if let Some(dir) = w
            .parent()
            .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
        {
            return Err(input(format!(
                "--write {}: the directory {} does not exist; create it or write elsewhere",
                w.display(),
                dir.display()
            )));
        }
    }
    let json = o.json;
    let mut log = |l: &str| {
        if !json {
            eprintln!("{l}");
        }
    };
    let est = estimate(case, o.quantity, o.at, &mut log)?;
    let what = match (o.quantity, est.ladder[0].node_at) {
        (Quantity::Energy, _) => "total energy at t_end, relative to E(0) - E(t_end)".to_string(),
        (q, Some(p)) => format!(
            "{} at the node ({}, {}), relative L2 in time",
            match q {
                Quantity::Ux => "u_x",
                Quantity::Uy => "u_y",
                _ => "friction stress",
            },
            p[0],
            p[1]
        ),
        (q, None) => q.name().to_string(),
    };
    let choice = pick(&est.candidates, o.tol);
    let best = est
        .candidates
        .iter()
        .filter(|c| c.estimate().is_finite())
        .min_by(|a, b| a.estimate().total_cmp(&b.estimate()));
    let pilot_runs = est.pilots.len();
    if json {
        let cand = |c: &Candidate| {
            serde_json::json!({
                "order": c.order,
                "mesh": c.mesh,
                "dofs": c.dofs,
                "method": c.method.name(),
                "dt": c.dt,
                "eps": c.eps,
                "estimate": c.estimate(),
                "estimate_h": c.parts[0],
                "estimate_dt": c.parts[1],
                "estimate_eps": c.parts[2],
                "h_measured": c.measured_h,
                "pilot": c.run,
                "steps": c.steps,
                "predicted_time_s": c.predicted_time,
            })
        };
        let j = serde_json::json!({
            "case": case.path.display().to_string(),
            "on": o.quantity.name(),
            "measure": what,
            "tol": o.tol,
            "found": choice.is_some(),
            "choice": choice.map(cand),
            "most_accurate": best.map(cand),
            "pilot_runs": pilot_runs,
            "pilot_time_s": est.seconds,
            "orders": est.orders.iter().map(|(w, p, d)| serde_json::json!({"what": w, "order": p, "values": d})).collect::<Vec<_>>(),
            "notes": est.notes,
            "written": o.write.as_ref().filter(|_| choice.is_some()).map(|w| w.display().to_string()),
        });
        println!("{j}");
    }
    // The report up to the choice: where no configuration qualifies, the
    // errors per mesh are what tells how much finer the ladder must go.
    if !json {
        println!("case        {}", case.path.display());
        println!("on          {what}, tol {:e}", o.tol);
        println!("pilots      {pilot_runs} runs in {:.2} s", est.seconds);
        for (w, p, d) in &est.orders {
            let d: Vec<String> = d.iter().map(|x| format!("{x:.2e}")).collect();
            let p = if p.is_nan() {
                String::new()
            } else {
                format!("; order {p:.2}")
            };
            println!("  {w}: {}{p}", d.join(", "));
        }
        for n in &est.notes {
            println!("note        {n}");
        }
    }
    let Some(c) = choice else {
        let b = best.map_or("none".to_string(), |b| {
            format!("{:.3e} with {}", b.estimate(), describe(b, &est.ladder))
        });
        eprintln!(
            "error: {}: no configuration of the ladder reaches an estimated error of {:e} on {what}; \
             the smallest estimate is {b}; add finer meshes to mesh.ladder or loosen --tol",
            case.path.display(),
            o.tol
        );
        return Ok(Verdict::NotReachable);
    };
    if !json {
        println!("choice      {}", describe(c, &est.ladder));
        if c.run {
            println!(
                "estimate    {:.3e} (this configuration was a pilot: its distance to the reference, with the reference's error)",
                c.estimate()
            );
        } else {
            println!(
                "estimate    {:.3e} = sqrt(mesh {:.3e}{}^2 + dt {:.3e}^2 + eps {:.3e}^2)",
                c.estimate(),
                c.parts[0],
                if c.measured_h { "" } else { " (extrapolated)" },
                c.parts[1],
                c.parts[2]
            );
        }
        println!(
            "predicted   {:.3} s ({:.0} steps x {} DOFs; the pilots' seconds per step per entry of K)",
            c.predicted_time, c.steps, c.dofs
        );
    }
    if let Some(w) = &o.write {
        let header = format!(
            "Adjusted by `stickslip advise --tol {:e} --on {}`: {}\nestimated error {:.3e}, predicted run time {:.3} s",
            o.tol,
            o.quantity.name(),
            describe(c, &est.ladder),
            c.estimate(),
            c.predicted_time
        );
        let text = adjusted_case(case, c, &est.ladder, w, &header)?;
        std::fs::write(w, text).with_context(|| format!("cannot write {}", w.display()))?;
        if !json {
            println!("written     {}", w.display());
        }
    }
    Ok(Verdict::Found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn richardson_recovers_the_error_of_a_power_law() {
        // e(h) = C h^p exactly: a − b = C h^p (1 − r^−p), e(h/r) = C (h/r)^p.
        let (c, p, h, r) = (3.0_f64, 2.0_f64, 0.1_f64, 2.0_f64);
        let e = |h: f64| c * h.powf(p);
        let estimate = richardson(e(h) - e(h / r), r, p);
        assert!((estimate - e(h / r)).abs() < 1e-14);
        let order = observed_order(e(h) - e(h / r), e(h / r) - e(h / r / r), r).unwrap();
        assert!((order - p).abs() < 1e-12);
        assert!((extrapolate(e(h), r, p, 2) - e(h / 4.0)).abs() < 1e-14);
        // Not asymptotic: differences that grow give no order.
        assert!(observed_order(1.0, 2.0, 2.0).is_none());
    }

    #[test]
    fn ladder_errors_of_a_power_law() {
        // Levels h, h/2, h/4 measured, h/8 beyond; e = C h^p exactly (all
        // errors aligned, c = 1) with p = 1.5 (below the cap 2): every
        // level's error is recovered.
        let (c, p, h) = (2.0_f64, 1.5_f64, 0.2_f64);
        let e = |k: i32| c * (h / 2f64.powi(k)).powf(p);
        let diffs = [e(0) - e(1), e(1) - e(2)];
        let skip = Some(e(0) - e(2));
        let (est, order, corr) = ladder_errors(&diffs, skip, &[2.0, 2.0, 2.0], 2.0);
        assert!((order - p).abs() < 1e-12);
        assert!((corr - 1.0).abs() < 1e-3, "{corr}");
        for k in 0..4 {
            assert!(
                (est[k] - e(k as i32)).abs() < 1e-3 * e(k as i32),
                "{k}: {est:?}"
            );
        }
        // The cap: an observed order above it is not trusted.
        let (_, capped, _) = ladder_errors(&diffs, skip, &[2.0, 2.0, 2.0], 1.0);
        assert_eq!(capped, 1.0);
        // Two levels: classical Richardson with the assumed order.
        let (est, order, _) = ladder_errors(&[1.0], None, &[2.0, 2.0], 2.0);
        assert_eq!(order, TWO_LEVEL_ORDER);
        assert!((est[1] - 1.0 / (2f64.powf(TWO_LEVEL_ORDER) - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn ladder_errors_of_errors_that_differ_in_phase() {
        // Errors along three orthogonal directions (c = 0), halving per
        // level: e_0 = (1, 0, 0), e_1 = (0, ½, 0), e_2 = (0, 0, ¼). The
        // differences are not aligned with the errors; the model recovers
        // |e_k| where classical Richardson (c = 1) would give |e_2| =
        // |q_1 − q_2| = 0.56 (2.2 times too large).
        let rho = 0.5_f64;
        let d01 = (1.0 + rho * rho).sqrt();
        let d12 = rho * d01;
        let d02 = (1.0 + rho.powi(4)).sqrt();
        assert!((correlation(d01, d02, rho, rho)).abs() < 1e-3);
        let (est, order, _) = ladder_errors(&[d01, d12], Some(d02), &[2.0, 2.0], 2.0);
        assert!((order - 1.0).abs() < 1e-12);
        for (k, want) in [1.0, 0.5, 0.25].iter().enumerate() {
            assert!((est[k] - want).abs() < 1e-3, "{k}: {est:?}");
        }
    }

    #[test]
    fn errors_against_a_reference() {
        // e_X = X − R + e_R with the two parts orthogonal: |e_X|² = d² +
        // e_R² (Pythagoras), and inside the triangle-inequality bounds.
        let (d, e_r) = (3.0, 4.0);
        assert_eq!(with_reference(d, e_r), 5.0);
        assert!(with_reference(d, e_r) <= d + e_r && with_reference(d, e_r) >= e_r - d);
        assert_eq!(with_reference(d, 0.0), d);
    }

    #[test]
    fn continue_errors_of_a_power_law_and_of_a_floor() {
        // e = C h^p, p = 1.5, measured on three of five levels: the last
        // two give p, the finer levels follow it exactly.
        let e = |k: i32| 2.0 * (0.2 / 2f64.powi(k)).powf(1.5);
        let (est, p) = continue_errors(&[e(0), e(1), e(2)], &[2.0; 4], 2.0);
        assert!((p - 1.5).abs() < 1e-12);
        for k in 0..5 {
            assert!(
                (est[k] - e(k as i32)).abs() < 1e-12 * e(k as i32),
                "{k}: {est:?}"
            );
        }
        // Capped at the theoretical order.
        assert_eq!(continue_errors(&[e(0), e(1)], &[2.0; 2], 1.0).1, 1.0);
        // Errors that stop decreasing (a Δt floor): no decrease assumed.
        let (est, p) = continue_errors(&[0.04, 0.015, 0.017], &[2.0; 3], 3.0);
        assert_eq!(p, 0.0);
        assert_eq!(est[3], 0.017);
    }

    #[test]
    fn continue_errors_above_a_dt_floor() {
        // e = √((C h^p)² + f²): a mesh part with p = 2 and a Δt part f
        // that no mesh reduces, measured on three of five levels.
        let f = 0.01;
        let e = |k: i32| (3.0 * (0.2 / 2f64.powi(k)).powi(2)).hypot(f);
        let measured = [e(0), e(1), e(2)];
        let (est, p) = continue_errors_above(&measured, &[2.0; 4], 3.0, f);
        assert!((p - 2.0).abs() < 1e-9, "{p}");
        for k in 0..5 {
            assert!(
                (est[k] - e(k as i32)).abs() < 1e-9 * e(k as i32),
                "{k}: {est:?}"
            );
        }
        // Continued as mesh error, the floor's slower decrease was taken
        // on, and the finest levels fell below the floor itself.
        let (plain, _) = continue_errors(&measured, &[2.0; 4], 3.0);
        assert!(plain[4] < f && plain[4] < 0.9 * e(4), "{plain:?}");
        // A floor above the measured errors: they stay as measured and
        // the finer levels at the last of them.
        let (est, _) = continue_errors_above(&[0.03, 0.02, 0.015], &[2.0; 4], 3.0, 0.05);
        assert_eq!(est, vec![0.03, 0.02, 0.015, 0.015, 0.015]);
    }

    #[test]
    fn dt_error_of_a_power_law() {
        // X(Δt) = X* + C Δt²: changes at 2Δt → Δt and Δt → Δt/2 give
        // X(Δt)'s error C Δt².
        let x = |dt: f64| 1.0 + 5.0 * dt * dt;
        let dt = 0.01;
        let (dc, df) = ((x(2.0 * dt) - x(dt)).abs(), (x(dt) - x(dt / 2.0)).abs());
        assert!((dt_error(dc, df, 2.0) - 5.0 * dt * dt).abs() < 1e-12);
        // Changes that do not decrease: the slowest order, a larger error.
        assert!(dt_error(df, df, 2.0) > 2.0 * df);
    }

    #[test]
    fn pick_takes_the_cheapest_that_meets_the_tolerance() {
        let cand = |t: f64, e: f64| Candidate {
            order: 2,
            mesh: "m".into(),
            mesh_index: 0,
            method: Method::CentralDifference,
            dt: 1e-3,
            eps: 1e-4,
            parts: [e, 0.0, 0.0],
            predicted_time: t,
            dofs: 1,
            steps: 1.0,
            measured_h: true,
            run: false,
        };
        // Times more than TIE apart: the cheapest that meets the tolerance.
        let all = vec![
            cand(1.0, 0.5),
            cand(2.0, 0.05),
            cand(3.5, 0.01),
            cand(0.5, f64::NAN),
        ];
        assert_eq!(pick(&all, 0.1).unwrap().predicted_time, 2.0);
        assert_eq!(pick(&all, 0.02).unwrap().predicted_time, 3.5);
        assert!(pick(&all, 1e-3).is_none());
        // Within TIE of the cheapest, the most accurate: 1.4 s over 1.0 s
        // (0.05 against 0.09); 1.6 s is past 1.5 × 1.0 s.
        let close = vec![cand(1.0, 0.09), cand(1.4, 0.05), cand(1.6, 0.01)];
        assert_eq!(pick(&close, 0.1).unwrap().predicted_time, 1.4);
        assert_eq!(
            Quantity::parse("friction_stress"),
            Ok(Quantity::FrictionStress)
        );
        assert!(Quantity::parse("sigma").is_err());
    }

    #[test]
    fn points_and_relative_paths() {
        assert_eq!(parse_point("8, -1").unwrap(), [8.0, -1.0]);
        assert!(parse_point("8").is_err());
        assert!(parse_point("8,nan").is_err());
        assert_eq!(
            relative_to(Path::new("/a/b/m.msh"), Path::new("/a/c")),
            PathBuf::from("../b/m.msh")
        );
    }
}
