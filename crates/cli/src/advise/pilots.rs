//! Pilot runs: one configured case run to t_end with the output traced at
//! its probe, and the runs of one estimate, each made once and kept.

use anyhow::Context;

use stickslip_case::pilot::{self, Trace};
use stickslip_case::{Case, Method, Prepared, Scheme as CaseScheme};

use super::input;
use super::ladder::LadderMesh;
use super::quantity::{distance, Quantity};

/// Where the quantity is read in one prepared model.
pub(super) enum Probe {
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

pub(super) fn probe_of(
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
            // A node of the group whose tangential motion a support fixes
            // carries none: the nearest friction node moved with the mesh.
            let closest = nearest(p.mesh.nodes.iter().copied().enumerate(), at);
            if let Some((_, pos)) = closest.filter(|(n, _)| c.excluded.contains(n)) {
                return Err(input(format!(
                    "--on friction_stress --at {},{}: the nearest node of {} at ({}, {}) carries \
                     no friction (a [[dirichlet]] condition fixes its tangential motion): nothing \
                     to estimate there, choose a point at a friction node",
                    at[0],
                    at[1],
                    case.mesh.file.display(),
                    pos[0],
                    pos[1]
                )));
            }
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
/// Input problems as [`InputError`](stickslip_case::InputError); a step that fails.
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
                CaseScheme::QuasiStatic => "quasi-static".to_string(),
            },
            case.time.dt,
        )
    })
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

/// The pilot runs of one estimate: each configuration (ladder index,
/// method, Δt, ε) run once and its trace kept.
pub(super) struct Pilots<'a> {
    pub(super) case: &'a Case,
    pub(super) q: Quantity,
    pub(super) at: Option<[f64; 2]>,
    pub(super) ladder: &'a [LadderMesh],
    pub(super) runs: Vec<(usize, Method, f64, f64, Trace)>,
    pub(super) log: &'a mut dyn FnMut(&str),
}

impl Pilots<'_> {
    /// Runs (or reuses) one configuration; returns its index in `runs`.
    pub(super) fn run(
        &mut self,
        m: usize,
        method: Method,
        dt: f64,
        eps: f64,
    ) -> anyhow::Result<usize> {
        if let Some(k) = self
            .runs
            .iter()
            .position(|r| r.0 == m && r.1 == method && r.2 == dt && r.3.to_bits() == eps.to_bits())
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
        // The first pilot tells whether the output moves at all: a
        // relative error of one that does not is undefined (every figure
        // was NaN, and the advice to add finer meshes).
        if self.runs.is_empty() {
            let moved = super::quantity::motion(self.q, &tr, &super::quantity::grid(c.time.t_end));
            if moved == 0.0 || !moved.is_finite() {
                return Err(input(format!(
                    "--on {}{}: it does not change over the run on {} (its motion is {moved:e}), \
                     so no relative error of it is defined; choose another output or point",
                    self.q.name(),
                    self.at
                        .map_or(String::new(), |[x, y]| format!(" --at {x},{y}")),
                    self.ladder[m].text,
                )));
            }
        }
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

    pub(super) fn trace(&self, k: usize) -> &Trace {
        &self.runs[k].4
    }

    /// Differences of consecutive runs (finer normalizes).
    pub(super) fn diffs(&self, runs: &[usize], grid: &[f64]) -> Vec<f64> {
        runs.windows(2)
            .map(|w| distance(self.q, self.trace(w[0]), self.trace(w[1]), grid))
            .collect()
    }

    /// ‖q_{n−2} − q_n‖ of the last three runs (None with fewer).
    pub(super) fn skip(&self, runs: &[usize], grid: &[f64]) -> Option<f64> {
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
    pub(super) fn cost(&self, k: usize) -> f64 {
        let t = self.trace(k);
        t.secs / (t.steps.max(1) as f64 * t.nnz.max(1) as f64)
    }
}
