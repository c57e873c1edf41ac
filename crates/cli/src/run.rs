//! `stickslip run`: from a validated case to a model, an integrator and
//! the HDF5 results, step by step; the model and the setup warnings it
//! shares with `stickslip check` (`check_cmd.rs`).
//!
//! Everything that can be refused is refused before any time step (the
//! model is built by `stickslip-case`), as an [`InputError`] (exit code
//! 2). Once stepping starts, every completed step is in the file (its
//! histories; the fields at frames, `frames.rs`); a
//! failure marks the file `complete = false`, records the reason and
//! returns [`Outcome::Failed`]. Where a run starts (a new file, or a
//! restart's checkpoint) is `start.rs`.

use std::io::IsTerminal;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use stickslip_case::{self as case, Case, InputError, Prepared, Running, Scene};
use stickslip_contact::ContactSurface;
use stickslip_fem::{DofMap, SetupTimes};
use stickslip_mesh::Mesh;
use stickslip_time::{Integrator, Scheme};

use crate::frames::Schedule;
use crate::normal_stress::NormalStress;
use crate::output::{self, CheckpointExtra, Record, ResultsWriter, Summary};
use crate::start;

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Reached t_end; the file is complete.
    Complete,
    /// Stopped early (iteration cap, non-finite state, energy blow-up); the
    /// file holds every completed step, `complete = false` and the reason in
    /// its `failure` attribute.
    Failed,
    /// Stopped by SIGINT, SIGTERM or SIGHUP after a completed step; the file holds every
    /// output step so far and a checkpoint to `--restart` from.
    Interrupted,
    /// Reached t_end and the file is complete, but the `--json` summary
    /// could not be written to stdout (exit 1: a script reading it would
    /// find nothing, though the file holds the whole run).
    SummaryLost,
}

/// Free DOFs from which a run or check says when the model is assembled
/// (its setup then takes seconds: 12 s at 1.1M DOFs).
const SETUP_NOTE_DOFS: usize = 200_000;

/// Seconds between progress lines where stderr is not a terminal.
const PROGRESS_LOG_SECS: u64 = 60;

pub(crate) fn input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(InputError(msg.into()))
}

/// A case's model and integrator ([`stickslip_case::assemble`]), the
/// model kept (`check`); with `progress`, [`setup_note`].
pub(crate) fn prepare(case: &Case, progress: bool) -> Result<Prepared, InputError> {
    let started = Instant::now();
    let scene = stickslip_case::assemble(case)?;
    if progress {
        setup_note(&scene, started);
    }
    scene.prepared(case)
}

/// The model of [`prepare`] for a run, which will [`Integrator::restore`]
/// a checkpoint when `restoring` (no initial static solve: the checkpoint
/// has the state), the consistent mass only where the case's scheme reads
/// it; [`Scene::running`] then moves K and M into the integrator.
fn assemble_run(case: &Case, restoring: bool, progress: bool) -> Result<Scene, InputError> {
    let started = Instant::now();
    let mut scene = stickslip_case::assemble_for_run(case)?;
    scene.settings.restoring = restoring;
    if progress {
        setup_note(&scene, started);
    }
    Ok(scene)
}

/// Free DOFs from which a run's setup, steps and output run on a thread
/// of rayon's pool. Its parallel passes then split between this thread
/// and one other, where from outside the pool this thread waits while
/// two of the pool's do them and spin after: three threads on two cores
/// between the passes (docs/performance.md). Below it nothing starts the
/// pool (the paper's mesh, whose run takes about 14 ms).
const POOL_MIN: usize = 4_096;

/// A line on stderr before the integrator's setup where the model has
/// [`SETUP_NOTE_DOFS`] free DOFs or more: its factorizations take seconds
/// there, with nothing else on the screen.
fn setup_note(scene: &Scene, started: Instant) {
    let n_free = scene.model.dofs.n_free();
    if n_free < SETUP_NOTE_DOFS {
        return;
    }
    let order = scene.model.fill_order.name();
    let work = match (scene.settings.scheme, scene.settings.restoring) {
        (Scheme::CentralDifference, true) => "the step's operators".to_string(),
        (Scheme::CentralDifference, false) => format!(
            "the initial state (a static solve by sparse Cholesky, ordered by {order}, when loads act before t = 0) and the step's operators"
        ),
        (Scheme::Newmark { .. } | Scheme::QuasiStatic, _) => format!(
            "the factor of the step's operator (sparse Cholesky, ordered by {order}) and the initial state"
        ),
    };
    say!(
        "model: {n_free} free DOFs, assembled in {:.1} s; now {work}",
        started.elapsed().as_secs_f64(),
    );
}

/// The failure of a run whose disk has less room than its next write
/// may take ([`ResultsWriter::room_needed`]), if it has.
fn disk_nearly_full(
    writer: &ResultsWriter,
    dofs: &DofMap,
    out: &Path,
    integrator: &Integrator,
) -> Option<String> {
    let need = writer.room_needed(dofs.n_free());
    let free = crate::results_file::free_bytes(out).filter(|&f| f < need)?;
    Some(format!(
        "step {} (t = {}): the disk of {} is nearly full ({:.1} MB free, the next write may need {:.1} MB): \
         stopped before HDF5 fails half way through a write; make room and continue the run with --restart",
        integrator.steps(),
        integrator.time(),
        out.display(),
        free as f64 / 1e6,
        need as f64 / 1e6
    ))
}

/// What a run of `case` writes from t = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct OutputSize {
    /// Frames of the fields, the initial state included.
    pub(crate) frames: f64,
    /// Rows of the histories: every step and the initial state.
    pub(crate) rows: f64,
    /// Bytes, uncompressed.
    pub(crate) bytes: f64,
    /// Bytes the run keeps free beside them while it writes
    /// ([`output::room_kept`]): it stops where the disk has less, or less
    /// than that and the records not yet flushed (`room_needed`).
    pub(crate) kept: f64,
}

impl OutputSize {
    /// The disk's free bytes for `out` ([`room_for`], with what `--force`
    /// removes where `replacing`, not where the records are added to it,
    /// as a restart's), where they cannot hold the records and the room
    /// the run keeps: such a run would stop part way, at a nearly full disk.
    pub(crate) fn short_of_room(&self, out: &Path, replacing: bool) -> Option<u64> {
        room_for(out, replacing).filter(|&free| self.bytes + self.kept > free as f64)
    }

    /// The part `share` of the records (a restart's rest of the run), with
    /// the same room kept.
    pub(crate) fn share(&self, share: f64) -> OutputSize {
        OutputSize {
            frames: (self.frames * share).ceil(),
            rows: (self.rows * share).ceil(),
            bytes: self.bytes * share,
            kept: self.kept,
        }
    }
}

/// Frames, rows and bytes a run of `case` writes from t = 0
/// (uncompressed), each series in whole chunks of rows: per frame u, v, a
/// at every node (6 doubles) and its time and row; per row the contact's
/// stress and slip (2 doubles) and state (1 byte), and 10 series besides
/// (time, the ledger, dt, iterations: 68 bytes); the mesh, twice the
/// checkpoint (its two slots: r, ṙ, r̈ at 2 values a node) and HDF5's own
/// structures (about 64 kB) besides. With the room the run keeps free
/// while it writes, for a model of `n_free` free DOFs.
pub(crate) fn output_size(
    case: &Case,
    nodes: usize,
    contact_nodes: usize,
    n_free: usize,
) -> OutputSize {
    let steps = (case.time.t_end / case.time.dt - 1e-6).ceil().max(1.0);
    let schedule = Schedule::new(case.output.fields(), case.time.t_end);
    let frames = schedule.frames(steps, case.time.dt);
    let rows = if schedule.histories_every_step() {
        steps + 1.0
    } else {
        frames
    };
    let up = |n: f64, chunk: usize| (n / chunk as f64).ceil() * chunk as f64;
    let (nodes_f, n_c) = (nodes as f64, contact_nodes as f64);
    let contact = up(rows, output::contact_chunk_rows(contact_nodes, 8)) * 24.0 * n_c
        + up(rows, output::contact_chunk_rows(contact_nodes, 1)) * n_c;
    let bytes = up(frames, output::vector_chunk_rows(nodes)) * 48.0 * nodes_f
        + up(frames, output::SERIES_CHUNK) * 16.0
        + up(rows, output::SERIES_CHUNK) * 68.0
        + contact
        + 2.0 * 3.0 * 16.0 * nodes_f
        + 16.0 * nodes_f
        + 65536.0;
    let block_rows = output::vector_chunk_rows(nodes);
    OutputSize {
        frames,
        rows,
        bytes,
        kept: output::room_kept(nodes, contact_nodes, block_rows, n_free) as f64,
    }
}

/// Why the steps of `case` run no friction code, if they run none: no
/// contact surface, or one that carries no friction (μ = 0, no pressure).
pub(crate) fn friction_off(case: &Case, i: &Integrator) -> Option<String> {
    if i.friction() {
        return None;
    }
    let surfaces = &case.contact;
    Some(if surfaces.is_empty() {
        "the case has no [contact]".to_string()
    } else if surfaces
        .iter()
        .all(|c| c.mu.is_some() && c.mu_at_rest() == 0.0)
    {
        "contact.mu = 0".to_string()
    } else if surfaces.iter().all(|c| c.pressure == Some(0.0)) {
        "contact.pressure = 0".to_string()
    } else {
        "no node of the contact surfaces carries friction (w g = 0)".to_string()
    })
}

/// Bytes free for the results file `out`: its disk's free space, and with
/// `force` the old OUT.h5 and OUT.xdmf, which the run removes first.
pub(crate) fn room_for(out: &Path, force: bool) -> Option<u64> {
    let free = crate::results_file::free_bytes(out)?;
    let old: u64 = if force {
        [out.to_path_buf(), out.with_extension("xdmf")]
            .iter()
            .filter_map(|p| std::fs::metadata(p).ok())
            .filter(|m| m.is_file())
            .map(|m| m.len())
            .sum()
    } else {
        0
    };
    Some(free.saturating_add(old))
}

/// The initial (static) displacement less its mean translation, where it
/// exceeds the part's size: no small strains are left, which is most
/// often a mix of units (E in MPa with loads in Pa: displacements of 340%
/// of the part went without a word). The paper's slab itself moves 12% of
/// its length (0.975 of 8).
fn large_static_displacement(mesh: &Mesh, u: &[f64]) -> Option<String> {
    let [lo, hi] = stickslip_mesh::bounding_box(mesh.nodes.iter().copied());
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    // Less the mean translation: a compliant foundation's static start
    // may carry a free part far onto it without straining it.
    let n = (u.len() / 2).max(1) as f64;
    let mean = u
        .chunks_exact(2)
        .fold([0.0, 0.0], |m, d| [m[0] + d[0] / n, m[1] + d[1] / n]);
    let (node, max) = u
        .chunks_exact(2)
        .map(|d| (d[0] - mean[0]).hypot(d[1] - mean[1]))
        .enumerate()
        .fold((0, 0.0_f64), |m, (i, d)| if d > m.1 { (i, d) } else { m });
    (size > 0.0 && max > size).then(|| {
        // A mix of units makes the ratio huge: short either way.
        let ratio = max / size;
        let share = if ratio < 100.0 {
            format!("{:.0}% of", 100.0 * ratio)
        } else {
            format!("{ratio:.1e} times")
        };
        format!(
            "the initial static displacement, less its mean translation, reaches {max:.3e} at ({}, {}), {share} the part's size {size:.3e}: \
             linear elasticity assumes small strains; check the units of E, the loads and the lengths",
            mesh.nodes[node][0],
            mesh.nodes[node][1],
        )
    })
}

/// What runs but is likely not meant, in the words `check` prints and a
/// fresh run says before its first step (one list, so the two cannot
/// drift apart): `u` is the initial displacement at every node.
pub(crate) fn setup_warnings(
    case: &Case,
    mesh: &Mesh,
    dofs: &DofMap,
    u: &[f64],
    integrator: &Integrator,
) -> Vec<String> {
    stickslip_mesh::degenerate_cells(mesh, stickslip_mesh::DEGENERATE_RATIO)
        .map(|d| d.to_string())
        .into_iter()
        .chain(large_static_displacement(mesh, u))
        .chain(integrator.contact().and_then(|c| oblique_supports(mesh, c)))
        .chain(unheld_motions(case, dofs, integrator))
        .chain(overdamped(case))
        .collect()
}

/// Mass-proportional damping the step cannot resolve, if so: a motion
/// alpha damps keeps (1 − (1−γ)αΔt)/(1 + γαΔt) of its velocity a step
/// (γ = ½ in central difference), which is negative where αΔt > 1/(1−γ)
/// and tends to −(1−γ)/γ as alpha grows, so the velocity changes sign
/// every step and more alpha decays it less (at alpha = 1e7, Δt = 1e-3 a
/// floating slab kept 67% of its kinetic energy where alpha = 1e4 took
/// all of it).
fn overdamped(case: &Case) -> Option<String> {
    let alpha = case.material.damping.map_or(0.0, |d| d.alpha);
    let dt = case.time.dt;
    let gamma = match case.time.scheme {
        case::Scheme::QuasiStatic => return None,
        case::Scheme::CentralDifference => 0.5,
        case::Scheme::Newmark => case.time.gamma,
    };
    let limit = 1.0 / (1.0 - gamma);
    (alpha * dt > limit).then(|| {
        let factor = (1.0 - (1.0 - gamma) * alpha * dt) / (1.0 + gamma * alpha * dt);
        format!(
            "material.damping alpha = {alpha:e} with time.dt = {dt:e} gives alpha·dt = {:.3e} > \
             {limit}: a motion alpha damps changes sign every step and keeps {factor:.3} of its \
             velocity a step (e^(-alpha·dt) = {:.3e} in the equation); reduce time.dt below {:.3e}, \
             or lower alpha",
            alpha * dt,
            (-alpha * dt).exp(),
            limit / alpha
        )
    })
}

/// What can hold a rigid-body motion the supports leave free: friction
/// on a face the motion slides along, a compliant foundation it presses
/// on or pulls from (one way: contact opens the other), or nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Holders {
    pub(crate) friction: bool,
    pub(crate) foundation: bool,
}

impl Holders {
    /// The words `check` gives the motion.
    pub(crate) fn describe(self) -> &'static str {
        match (self.friction, self.foundation) {
            (true, false) => "held by friction alone",
            (true, true) => "held by friction and the compliant foundation",
            (false, true) => "held by the compliant foundation",
            (false, false) => "nothing holds it: no friction acts along it",
        }
    }
}

/// Each free rigid-body motion's shares along what can hold it, one value
/// per motion ([`DofMap::rigid_modes`]) a row: the tangent's share at each
/// node of a surface that can carry friction, the normal's at each
/// compliant node.
struct Shares {
    friction: Vec<Vec<f64>>,
    foundation: Vec<Vec<f64>>,
}

impl Shares {
    fn of(case: &Case, dofs: &DofMap, integrator: &Integrator) -> Shares {
        let modes = dofs.rigid_modes();
        let mut s = Shares {
            friction: Vec::new(),
            foundation: Vec::new(),
        };
        if let Some(c) = integrator.contact() {
            for p in c.parts.iter().filter(|p| carries_friction(case, &p.group)) {
                for n in &c.nodes[p.nodes.clone()] {
                    s.friction
                        .push(modes.iter().map(|m| n.tangential(&m.vector)).collect());
                }
            }
            for f in &c.compliance {
                let n = &c.nodes[f.index];
                s.foundation
                    .push(modes.iter().map(|m| f.along_normal(n, &m.vector)).collect());
            }
        }
        s
    }
}

/// Each rigid-body motion the supports leave free ([`DofMap::rigid_modes`])
/// with what can hold it: friction where some node of a surface that can
/// carry friction (μ > 0 with a pressure, or a compliant foundation with
/// μ or c_T > 0) has a tangent with a share of the motion; the
/// foundation where some compliant node's normal has one.
pub(crate) fn motion_holders(
    case: &Case,
    dofs: &DofMap,
    integrator: &Integrator,
) -> Vec<(String, Holders)> {
    let shares = Shares::of(case, dofs, integrator);
    dofs.rigid_modes()
        .iter()
        .enumerate()
        .map(|(a, m)| {
            let tol = 1e-9 * m.vector.iter().fold(0.0_f64, |t, v| t.max(v.abs()));
            let some = |rows: &[Vec<f64>]| rows.iter().any(|r| r[a].abs() > tol);
            let held = Holders {
                friction: some(&shares.friction),
                foundation: some(&shares.foundation),
            };
            (m.label.clone(), held)
        })
        .collect()
}

/// Whether the contact surface of `group` can carry friction: μ > 0 with
/// a pressure, or a compliant foundation with μ or c_T > 0.
fn carries_friction(case: &Case, group: &str) -> bool {
    case.contact.iter().any(|s| {
        s.group == group
            && match s.law {
                case::schema::ContactLaw::Compliance => s.ct.map_or(s.mu_at_rest(), |ct| ct) > 0.0,
                _ => s.mu_at_rest() > 0.0 && s.pressure != Some(0.0),
            }
    })
}

/// The combinations of the free rigid-body motions that nothing holds,
/// each as its motions' labels: a basis of the null space of the motions'
/// [`Shares`]. A motion friction holds alone may still be free in
/// combination: with only uy held at the left end, the slab's x
/// translation and its rotation about the end's middle each slide its
/// bottom, but their sum, a rotation about the bottom corner, moves the
/// bottom along its normal only.
fn unheld_combinations(case: &Case, dofs: &DofMap, integrator: &Integrator) -> Vec<Vec<String>> {
    let modes = dofs.rigid_modes();
    let k = modes.len();
    let shares = Shares::of(case, dofs, integrator);
    let mut g = vec![vec![0.0; k]; k];
    for row in shares.friction.iter().chain(&shares.foundation) {
        for (a, ga) in g.iter_mut().enumerate() {
            for (b, gab) in ga.iter_mut().enumerate() {
                *gab += row[a] * row[b];
            }
        }
    }
    // Each motion's column scaled to unit length (a rotation's shares grow
    // with the part's size); one with none is free outright.
    let scale: Vec<f64> = (0..k)
        .map(|a| {
            if g[a][a] > 0.0 {
                1.0 / g[a][a].sqrt()
            } else {
                0.0
            }
        })
        .collect();
    for (a, ga) in g.iter_mut().enumerate() {
        for (b, gab) in ga.iter_mut().enumerate() {
            *gab *= scale[a] * scale[b];
        }
    }
    null_space(g, 1e-9)
        .into_iter()
        .map(|v| {
            let top = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            v.iter()
                .zip(modes)
                .filter(|(x, _)| x.abs() > 1e-6 * top)
                .map(|(_, m)| m.label.clone())
                .collect()
        })
        .collect()
}

/// A basis of the null space of the symmetric k × k matrix `g` (Gauss–
/// Jordan elimination with partial pivoting; pivots below `tol` count as
/// zero).
fn null_space(mut g: Vec<Vec<f64>>, tol: f64) -> Vec<Vec<f64>> {
    let k = g.len();
    let mut pivots: Vec<usize> = Vec::new();
    for col in 0..k {
        let row = pivots.len();
        let Some((p, best)) = (row..k)
            .map(|r| (r, g[r][col].abs()))
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            break;
        };
        if best <= tol {
            continue;
        }
        g.swap(row, p);
        let pivot = g[row][col];
        g[row].iter_mut().for_each(|x| *x /= pivot);
        let pivot_row = g[row].clone();
        for (r, gr) in g.iter_mut().enumerate() {
            let f = gr[col];
            if r != row && f != 0.0 {
                gr.iter_mut().zip(&pivot_row).for_each(|(x, p)| *x -= f * p);
            }
        }
        pivots.push(col);
    }
    (0..k)
        .filter(|c| !pivots.contains(c))
        .map(|free| {
            let mut v = vec![0.0; k];
            v[free] = 1.0;
            for (i, &pc) in pivots.iter().enumerate() {
                v[pc] = -g[i][free];
            }
            v
        })
        .collect()
}

/// The rigid-body motions the supports leave free that nothing holds
/// ([`unheld_combinations`]), or `None`: a net load along such a motion
/// moves the part as a rigid body without bound.
fn unheld_motions(case: &Case, dofs: &DofMap, integrator: &Integrator) -> Option<String> {
    let unheld: Vec<String> = unheld_combinations(case, dofs, integrator)
        .into_iter()
        .map(|labels| match &labels[..] {
            [one] => one.clone(),
            several => format!("a combination of {}", several.join(" and ")),
        })
        .collect();
    let it = if unheld.len() == 1 { "it" } else { "them" };
    (!unheld.is_empty()).then(|| {
        format!(
            "the supports leave free {} and no friction acts along {it}: nothing holds the part \
             there, and any net load along {it} moves the part as a rigid body; hold {it} by a \
             [[dirichlet]] condition, or by friction on a face {it} slides along (a [contact] \
             with mu > 0 and a pressure, or a compliant foundation)",
            unheld.join(", ")
        )
    })
}

/// Degrees by which a fixed direction may leave a contact face's normal
/// before `run` and `check` warn: the friction force such a support takes
/// and the slip velocity it hides grow as the angle's sine, 1.7% at 1°.
const OBLIQUE_DEGREES: f64 = 1.0;

/// The contact nodes where a `[[dirichlet]]` condition fixes x or y more
/// than [`OBLIQUE_DEGREES`] off the face's normal (a support along an axis
/// on a curved or tilted face), or `None`. The law acts along the tangent
/// τ (METHOD.md §1), but such a node moves along its free axis only: its
/// slip velocity is τ's share of that motion and the support takes part
/// of the friction force, which nothing else reports (nodes whose tangent
/// is fixed outright carry no friction and are listed by `check`).
fn oblique_supports(mesh: &Mesh, c: &ContactSurface) -> Option<String> {
    let limit = OBLIQUE_DEGREES.to_radians().sin();
    // Per axis: a node is a friction node only with one axis free.
    let mut count = [0usize; 2];
    let mut worst: Option<(f64, usize, usize)> = None;
    for n in &c.nodes {
        // A node whose tangential motion is held (a compliant surface
        // keeps it for its normal force) carries no friction: its support
        // takes none of it.
        if n.tangent_held() {
            continue;
        }
        for axis in 0..2 {
            let off = n.tangent[axis].abs();
            if n.dofs[axis].is_none() && off > limit {
                count[axis] += 1;
                if worst.is_none_or(|w| off > w.0) {
                    worst = Some((off, n.node, axis));
                }
            }
        }
    }
    let (off, node, _) = worst?;
    let [x, y] = mesh.nodes[node];
    let (fixed, free) = match count {
        [_, 0] => ("ux", "y"),
        [0, _] => ("uy", "x"),
        _ => ("ux or uy", "the other axis"),
    };
    let count = count[0] + count[1];
    Some(format!(
        "{count} of the {} friction nodes of {} have {fixed} fixed by a [[dirichlet]] condition although the face is not normal \
         to that axis there (up to {:.1}° off, at ({x}, {y})): friction acts along the face's tangent, but these nodes can move only along {free}, \
         so the support takes part of the friction force and the slip is the tangent's share of their motion; \
         support the contact face only where it is straight along x or y, or leave it free and let the [contact] pressure carry the normal load",
        c.len(),
        c.names(),
        off.asin().to_degrees()
    ))
}

/// The `/solver` attribute `fill_order` a run writes: the decided ordering
/// of its sparse Cholesky factors; where the choice is still open because
/// the run factorized nothing (explicit, no preload, from 500 free DOFs),
/// `None` on a restart (the file keeps what the first run wrote) and
/// "none" on a fresh run, so that every results file has the attribute.
fn fill_order_attr(decided: Option<&str>, restart: bool) -> Option<String> {
    match decided {
        Some(name) => Some(name.to_string()),
        None if restart => None,
        None => Some("none".to_string()),
    }
}

/// "12.3 µs"-style duration.
fn human_seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.3} s")
    } else if s >= 1e-3 {
        format!("{:.3} ms", s * 1e3)
    } else {
        format!("{:.3} µs", s * 1e6)
    }
}

/// "1.2 GB"-style size (decimal units).
pub(crate) fn human_bytes(b: f64) -> String {
    let units = ["bytes", "kB", "MB", "GB", "TB", "PB"];
    let mut u = 0;
    let mut v = b;
    while v >= 1000.0 && u + 1 < units.len() {
        v /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{v:.0} {}", units[0])
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// Full-length (2 × nodes) copies of the free-DOF state for output.
pub(crate) struct FullState {
    pub(crate) u: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    stress: Vec<f64>,
    slip: Vec<f64>,
    state: Vec<i8>,
    normal: Vec<f64>,
    normal_stress: NormalStress,
}

impl FullState {
    /// Buffers for `nodes` mesh nodes and `n_c` contact nodes, whose
    /// normal traction `normal_stress` forms.
    pub(crate) fn new(nodes: usize, n_c: usize, normal_stress: NormalStress) -> FullState {
        FullState {
            u: vec![0.0; 2 * nodes],
            v: vec![0.0; 2 * nodes],
            a: vec![0.0; 2 * nodes],
            stress: vec![0.0; n_c],
            slip: vec![0.0; n_c],
            state: vec![0; n_c],
            normal: vec![0.0; n_c],
            normal_stress,
        }
    }
}

/// The integrator's state as a record of the results file: its fields
/// (expanded to every node) only if `frame`.
pub(crate) fn record<'a>(
    i: &Integrator,
    dofs: &DofMap,
    s: &'a mut FullState,
    (dt, iterations): (f64, u32),
    frame: bool,
) -> Record<'a> {
    if frame {
        dofs.expand(i.displacement(), &mut s.u);
        dofs.expand_homogeneous(i.velocity(), &mut s.v);
        dofs.expand_homogeneous(i.acceleration(), &mut s.a);
    }
    i.friction_stress(&mut s.stress);
    i.slip_velocity(&mut s.slip);
    i.slip_states(&mut s.state);
    s.normal_stress.fill(i, &mut s.normal);
    let e = i.energy();
    let fields = |v: &'a [f64]| if frame { v } else { &[] };
    Record {
        t: i.time(),
        displacement: fields(&s.u),
        velocity: fields(&s.v),
        acceleration: fields(&s.a),
        friction_stress: &s.stress,
        slip_velocity: &s.slip,
        state: &s.state,
        normal_stress: &s.normal,
        kinetic: e.kinetic,
        strain: e.strain,
        external_work: e.external_work,
        dissipated: e.dissipated,
        damped: e.damped,
        foundation: e.foundation,
        foundation_stored: e.foundation_stored,
        total: e.total,
        balance: e.balance,
        dt,
        iterations,
    }
}

/// The SIGINT / SIGTERM flags a run polls after each step.
#[derive(Clone, Debug, Default)]
pub struct StopFlags {
    sigint: Arc<AtomicBool>,
    sigterm: Arc<AtomicBool>,
    sighup: Arc<AtomicBool>,
}

impl StopFlags {
    /// Flags that no signal sets (a library caller stops nothing).
    pub fn none() -> StopFlags {
        StopFlags::default()
    }

    /// Registers SIGINT, SIGTERM and SIGHUP (a closed terminal or a dropped
    /// ssh session, which killed the run between flushes): the first sets
    /// the flag (the run
    /// finishes its step, flushes, checkpoints and exits 130); a second
    /// signal of either kind exits at once with 130, as users expect of a
    /// second Ctrl-C (the file keeps every step up to its last flush),
    /// unless it comes within 250 ms of the first: the same signal sent
    /// twice (GNU timeout's to the process and its group).
    ///
    /// # Errors
    /// The handlers cannot be installed.
    pub fn install() -> std::io::Result<StopFlags> {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let flags = StopFlags::default();
        let any = Arc::new(AtomicBool::new(false));
        let first = Arc::new(std::sync::atomic::AtomicU64::new(0));
        for (sig, flag) in [
            (SIGINT, &flags.sigint),
            (SIGTERM, &flags.sigterm),
            (SIGHUP, &flags.sighup),
        ] {
            // Order matters: the shutdown hook must see `any` still false on
            // the first signal (signal-hook's documented pattern).
            second_signal_exits(sig, (Arc::clone(&any), Arc::clone(&first)))?;
            signal_hook::flag::register(sig, Arc::clone(&any))?;
            signal_hook::flag::register(sig, Arc::clone(flag))?;
        }
        Ok(flags)
    }

    /// The signal received, if any.
    pub fn received(&self) -> Option<&'static str> {
        if self.sigint.load(Ordering::Relaxed) {
            Some("SIGINT")
        } else if self.sigterm.load(Ordering::Relaxed) {
            Some("SIGTERM")
        } else if self.sighup.load(Ordering::Relaxed) {
            Some("SIGHUP")
        } else {
            None
        }
    }
}

/// On `sig` after `any` is set (a second signal): one line on stderr and
/// exit 130 at once (the file keeps every flushed step). signal-hook's
/// conditional shutdown exited without a word, which left the user
/// guessing what was kept.
fn second_signal_exits(
    sig: i32,
    any: (Arc<AtomicBool>, Arc<std::sync::atomic::AtomicU64>),
) -> std::io::Result<()> {
    const MSG: &[u8] = b"\nstopped at once by a second signal: the results file keeps every step \
up to its last flush (complete = false); continue it with --restart\n";
    crate::sys::exit_on_signal_if(sig, any, MSG, 130)
}

/// How `stickslip run` behaves.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// No progress bar, no summary on stderr.
    pub quiet: bool,
    /// The closing summary as one JSON object on stdout.
    pub json: bool,
    /// Continue the results file from its checkpoint instead of creating it.
    pub restart: bool,
    /// Polled after every step.
    pub stop: StopFlags,
    /// The `--set` overrides the run was given, repeated in the command
    /// that continues it (a restart must read the same case).
    pub sets: Vec<String>,
}

/// `s` as one shell word: as it is where it holds only characters no
/// shell reads specially, else in single quotes.
fn shell_word(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-/=:,+@%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// Multiple of the physically possible mechanical energy above which an
/// explicit run is declared unstable (see [`blow_up`]).
const BLOW_UP_FACTOR: f64 = 10.0;

/// Energy blow-up of an explicit run.
///
/// The energy ledger (METHOD.md §6) says kinetic + strain = E₀ + W − D +
/// W_f less what damping and a compliant foundation take, with D ≥ 0 and
/// W_f the work of a moving foundation (a belt, METHOD.md §9), so the
/// mechanical energy is at most E₀ + |W| + D + |W_f| for any run the
/// scheme follows faithfully (without W_f a part a belt carries along,
/// its work stored as strain, was stopped as unstable); a stable
/// central-difference run breaks this only by its O(Δt²) energy error. Past Δt_crit the highest mode grows by |λ|² per step,
/// λ the larger root of λ² − (2 − ω²Δt²)λ + 1 = 0 (|λ|² = 1.8 at ωΔt = 2.02,
/// 5.9 at ωΔt = 2.2), from round-off: a growth that must cross any fixed
/// multiple of the physical bound within a few steps of reaching it, while
/// W grows only linearly in the amplitude (R·Δr) and the energies
/// quadratically. Hence the test kinetic + strain > 10 (E₀ + |W| + D +
/// |W_f|): the factor 10 leaves the stable scheme's error far behind and
/// costs about log(10)/log(|λ|²) ≈ 1.3 to 4 steps of detection delay.
fn blow_up(i: &Integrator, initial: f64) -> Option<f64> {
    let e = i.energy();
    let mechanical = e.kinetic + e.strain;
    let bound = BLOW_UP_FACTOR
        * (initial.abs() + e.external_work.abs() + e.dissipated.abs() + e.foundation.abs());
    (mechanical > bound && mechanical > f64::MIN_POSITIVE).then_some(bound)
}

/// `stickslip run`: integrate to t_end writing the histories at every
/// step and the fields at frames (`output.frames`, `output.interval`,
/// `output.every`); flush and checkpoint every `output.flush_seconds`
/// seconds from the run's start (and every `output.flush_every` steps, if
/// given); stop cleanly on SIGINT, SIGTERM or SIGHUP; with
/// `options.restart`, continue the file `out` from its checkpoint.
///
/// # Errors
/// Input problems as [`InputError`] (also: a restart whose case changes the
/// physics); I/O failures of the results file.
pub fn execute(case: &Case, out: &Path, options: &RunOptions) -> anyhow::Result<Outcome> {
    let started = Instant::now();
    let scene = assemble_run(case, options.restart, !options.quiet)?;
    if scene.model.dofs.n_free() >= POOL_MIN {
        // Called from outside the pool, `scope` runs its body on one of
        // the pool's threads.
        rayon::scope(|_| run_scene(case, out, options, scene, started))
    } else {
        run_scene(case, out, options, scene, started)
    }
}

/// [`execute`] from its assembled model.
fn run_scene(
    case: &Case,
    out: &Path,
    options: &RunOptions,
    scene: Scene,
    started: Instant,
) -> anyhow::Result<Outcome> {
    let quiet = options.quiet;
    let Running {
        mesh,
        dofs,
        mut integrator,
        setup: mut setup_parts,
    } = scene.running(case)?;
    let n_c = integrator.contact().map_or(0, |c| c.len());
    // A signal during the setup: stop before the file is touched (with
    // --force the old results would otherwise be gone for a run of one
    // step).
    if let Some(signal) = options.stop.received() {
        if !quiet {
            say!(
                "stopped by {signal} before the first step; {} is as it was",
                out.display()
            );
        }
        return Ok(Outcome::Interrupted);
    }
    // A run whose records cannot fit on the disk (a t_end or output.every
    // off by orders of magnitude filled 14 GB in 75 s): refused before it
    // starts, where the run's own stop at a full disk would come late.
    if !options.restart {
        let size = output_size(case, mesh.nodes.len(), n_c, dofs.n_free());
        if let Some(free) = size.short_of_room(out, true) {
            return Err(input(format!(
                "{}: the run would write about {} frames and {} rows ({}) to {} and keeps {} free beside \
                 them while it writes (it stops at a nearly full disk, before HDF5 fails mid-write), \
                 but its disk has {} free; write fewer frames (output.frames, output.interval, \
                 output.every), shorten time.t_end, or write elsewhere with -o",
                case.path.display(),
                size.frames,
                size.rows,
                human_bytes(size.bytes),
                out.display(),
                human_bytes(size.kept),
                human_bytes(free as f64)
            )));
        }
    }
    // Held until this run returns, from before its first write: a second
    // run's --force or --restart, or a probe, sees the file in use
    // ([`crate::results_file::in_use`]).
    let file_started = Instant::now();
    let _lock = if options.restart {
        crate::results_file::RunLock::take(out)?
    } else {
        crate::results_file::claim(out)?
    };
    let mut full = FullState::new(mesh.nodes.len(), n_c, NormalStress::new(case, &integrator));
    let opened = if options.restart {
        start::resume(case, out, quiet, &mesh, &dofs, &mut integrator)?
    } else {
        start::fresh(case, out, &mesh, &dofs, &integrator, &mut full)?
    };
    setup_parts.add("results file", file_started.elapsed().as_secs_f64());
    let mut session = Session {
        case,
        out,
        options,
        dofs: &dofs,
        integrator,
        writer: opened.writer,
        full,
        schedule: Schedule::new(case.output.fields(), case.time.t_end),
        times: opened.times,
        max_balance: opened.max_balance,
        wall_before: opened.wall_before,
        initial_mechanical: opened.initial_mechanical,
        started,
        setup_parts,
    };
    session.writer.auto_flush = false;
    session.writer.flush_every_steps = case.output.flush_every.unwrap_or(usize::MAX);
    session.writer.flush_every_secs = case.output.flush_seconds;
    session.writer.flush_clock_from(started);
    // The initial state is checkpointed where its setup took flush_seconds
    // or more: a crash then loses no more than a flush interval, as at
    // every later flush. A shorter setup is cheaper to redo than its
    // state is to write (r, v, a on every free DOF and two flushes); a
    // restart's state is already the file's checkpoint.
    if !options.restart && session.writer.flush_due() {
        let checkpoint_started = Instant::now();
        session.checkpoint(None)?;
        session.setup_parts.add(
            "first checkpoint",
            checkpoint_started.elapsed().as_secs_f64(),
        );
    }
    let setup_s = started.elapsed().as_secs_f64();
    let mut progress = Progress::new(quiet, &session.integrator);
    if progress.log {
        let i = &session.integrator;
        say!(
            "setup done in {setup_s:.1} s; stepping from t = {} to t_end = {} (about {} steps), a progress line a minute",
            i.time(),
            i.t_end(),
            ((i.t_end() - i.time()) / case.time.dt).ceil()
        );
    }
    let stepping = Instant::now();
    let ending = session.step_to_end(&mut progress)?;
    progress.finish();
    session.conclude(ending, setup_s, stepping, progress.steps_before)
}

/// The setup's parts in seconds (the results file's creation and the
/// first checkpoint among them), and what is left of `setup_s` beside
/// them as "other".
fn setup_line(parts: &SetupTimes, setup_s: f64) -> String {
    let mut line: Vec<String> = parts
        .parts()
        .iter()
        .map(|(name, s)| format!("{name} {s:.3} s"))
        .collect();
    line.push(format!("other {:.3} s", (setup_s - parts.total()).max(0.0)));
    line.join(", ")
}

/// [`setup_line`] as a JSON object, its keys with underscores.
fn setup_json(parts: &SetupTimes, setup_s: f64) -> serde_json::Value {
    let mut map = serde_json::Map::new();
    for (name, s) in parts.parts() {
        map.insert(name.replace(' ', "_"), (*s).into());
    }
    map.insert("other".into(), (setup_s - parts.total()).max(0.0).into());
    map.into()
}

/// How the stepping ended.
struct Ending {
    /// Why the run stopped early, if it failed.
    failure: Option<String>,
    /// The signal that stopped it, if one did.
    interrupted: Option<&'static str>,
    /// The failure is the stick/slip iteration's cap: the state is the
    /// last completed step's, which a restart with a larger
    /// contact.max_iterations continues from.
    resumable: bool,
    /// The state before the last step (and the rows and frames then): that step is
    /// shortened to land on t_end, so a restart with a later t_end must
    /// redo it at full length to match a run that never stopped.
    before_last: Option<(stickslip_time::Checkpoint, (usize, usize))>,
}

/// What a run shows while it steps: a bar on a terminal, else (a log) a
/// line a minute, so that a batch job's log shows a long run moving.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    log: bool,
    last_log: Instant,
    /// Where this run started (a restart: at its checkpoint), so that the
    /// share done and the time left count from there.
    t_start: f64,
    steps_before: u64,
}

impl Progress {
    fn new(quiet: bool, integrator: &Integrator) -> Progress {
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% {msg}, ETA {eta}",
                )
                .expect("valid template"),
            );
            bar
        });
        Progress {
            bar,
            log: !quiet && !terminal,
            last_log: Instant::now(),
            t_start: integrator.time(),
            steps_before: integrator.steps(),
        }
    }

    /// After every step: the bar.
    fn stepped(&self, i: &Integrator, started: Instant) {
        if let Some(bar) = &self.bar {
            let t_end = i.t_end();
            let rate =
                (i.steps() - self.steps_before) as f64 / started.elapsed().as_secs_f64().max(1e-9);
            bar.set_position((1000.0 * i.time() / t_end) as u64);
            bar.set_message(format!(
                "t = {:.4e} of {t_end}, step {}, {rate:.0} steps/s",
                i.time(),
                i.steps()
            ));
        }
    }

    /// After a flush: the log's line, once a minute.
    fn flushed(&mut self, i: &Integrator, started: Instant) {
        if self.log && self.last_log.elapsed().as_secs() >= PROGRESS_LOG_SECS {
            self.last_log = Instant::now();
            let t_end = i.t_end();
            let wall = started.elapsed().as_secs_f64();
            let done = (i.time() - self.t_start) / (t_end - self.t_start).max(1e-300);
            say!(
                "progress: t = {:.6e} of {t_end} ({:.1}%), step {}, {:.0} s elapsed, about {:.0} s left",
                i.time(),
                100.0 * done,
                i.steps(),
                wall,
                wall * (1.0 - done) / done.max(1e-12)
            );
        }
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

/// A run in progress: the integrator, the file it writes and what the
/// stepping keeps from step to step.
struct Session<'a> {
    case: &'a Case,
    out: &'a Path,
    options: &'a RunOptions,
    dofs: &'a DofMap,
    integrator: Integrator,
    writer: ResultsWriter,
    full: FullState,
    /// Which steps write the fields.
    schedule: Schedule,
    /// Times of the records written.
    times: Vec<f64>,
    max_balance: f64,
    wall_before: f64,
    initial_mechanical: f64,
    started: Instant,
    /// The setup's parts (mesh read, assembly, preload, critical step,
    /// operators), for the summary.
    setup_parts: SetupTimes,
}

impl Session<'_> {
    /// Writes `cp` (or the current state) as the file's checkpoint, with
    /// `rows` records and `frames` frames (or all so far).
    fn checkpoint(
        &mut self,
        at: Option<(stickslip_time::Checkpoint, (usize, usize))>,
    ) -> anyhow::Result<()> {
        let (cp, (rows, frames)) = at.unwrap_or_else(|| {
            let written = (self.writer.rows(), self.writer.frames());
            (self.integrator.checkpoint(), written)
        });
        let extra = CheckpointExtra {
            rows,
            frames,
            wall_time_s: self.wall_before + self.started.elapsed().as_secs_f64(),
            max_balance: self.max_balance,
            node_order: self.dofs.node_order().code(),
        };
        self.writer.write_checkpoint(&cp, &extra)
    }

    /// Appends the current state as a record, with the fields if `frame`.
    fn append(&mut self, dt: f64, iterations: u32, frame: bool) -> anyhow::Result<()> {
        self.times.push(self.integrator.time());
        self.writer.append(&record(
            &self.integrator,
            self.dofs,
            &mut self.full,
            (dt, iterations),
            frame,
        ))
    }

    /// The failure of a run whose disk has less room than its next write
    /// may take, if it has.
    fn disk_nearly_full(&self) -> Option<String> {
        disk_nearly_full(&self.writer, self.dofs, self.out, &self.integrator)
    }

    /// Steps to t_end (or a failure, a signal), writing every step's
    /// histories and the frames' fields, flushing and checkpointing when
    /// due.
    fn step_to_end(&mut self, progress: &mut Progress) -> anyhow::Result<Ending> {
        let mut ending = Ending {
            failure: None,
            interrupted: None,
            resumable: false,
            before_last: None,
        };
        while !self.integrator.done() {
            let i = &self.integrator;
            let near_end = i.t_end() - i.time() <= self.case.time.dt * (1.0 + 1e-6);
            let before =
                near_end.then(|| (i.checkpoint(), (self.writer.rows(), self.writer.frames())));
            let t_prev = i.time();
            let info = match self.integrator.step() {
                Ok(info) => info,
                Err(e) => {
                    // Only the iteration's cap is a budget a restart may
                    // raise (contact.max_iterations); Newton's cap and the
                    // time step are fixed for a restart.
                    ending.resumable = matches!(e, stickslip_time::TimeError::IterationCap { .. });
                    ending.failure = Some(e.to_string());
                    break;
                }
            };
            self.max_balance = self.max_balance.max(self.integrator.energy().balance.abs());
            self.writer.count_step();
            let i = &self.integrator;
            // A blow-up's last state is written whole: it shows where.
            let blown = i
                .is_explicit()
                .then(|| blow_up(i, self.initial_mechanical))
                .flatten();
            let frame = blown.is_some()
                || self
                    .schedule
                    .is_frame(i.steps(), t_prev, i.time(), i.done());
            if frame || self.schedule.histories_every_step() {
                // HDF5 writes a chunk of rows as it fills: the room for it
                // is checked before, as before a flush.
                if self.writer.append_writes(frame) {
                    if let Some(e) = self.disk_nearly_full() {
                        ending.failure = Some(e);
                        break;
                    }
                }
                self.append(info.dt, info.iterations as u32, frame)?;
            }
            if let Some(bound) = blown {
                ending.failure = Some(blow_up_failure(&self.integrator, bound, self.case));
                break;
            }
            if self.integrator.done() {
                ending.before_last = before;
                break;
            }
            if let Some(sig) = self.options.stop.received() {
                ending.interrupted = Some(sig);
                break;
            }
            if self.writer.flush_due() {
                if let Some(e) = self.disk_nearly_full() {
                    ending.failure = Some(e);
                    break;
                }
                self.checkpoint(None)?;
                progress.flushed(&self.integrator, self.started);
            }
            progress.stepped(&self.integrator, self.started);
        }
        Ok(ending)
    }

    /// Closes the file (the last checkpoint, the summary) and says how the
    /// run ended.
    fn conclude(
        mut self,
        ending: Ending,
        setup_s: f64,
        stepping: Instant,
        steps_before: u64,
    ) -> anyhow::Result<Outcome> {
        let Ending {
            mut failure,
            interrupted,
            mut resumable,
            mut before_last,
        } = ending;
        // A restart at its checkpoint's time takes no step, and the row it
        // ends on need not be a frame; the last step has its fields all
        // the same. The state is that row's (the checkpoint's), and the
        // checkpoint leaves the frame out, as it leaves out a last step,
        // so that a later restart continues as a run that never stopped.
        let on_last_row = self
            .times
            .last()
            .is_some_and(|t| t.to_bits() == self.integrator.time().to_bits());
        // A step that could not be made left the state at the last one
        // made: a checkpoint there lets a restart continue (with a larger
        // contact.max_iterations), unless the disk has no room for it.
        resumable &= failure.is_some() && self.disk_nearly_full().is_none();
        // So too the last step of a run interrupted or stopped so: the file
        // shows the state it stopped at, and the checkpoint, without that
        // frame, restarts as the run that never stopped.
        if (failure.is_none() || resumable) && on_last_row && !self.writer.last_row_is_frame()? {
            // The frame fills a chunk like any row: room first.
            match self.disk_nearly_full() {
                Some(why) => {
                    failure.get_or_insert(why);
                    resumable = false;
                }
                None => {
                    let kept = (self.writer.rows(), self.writer.frames());
                    let rec = record(&self.integrator, self.dofs, &mut self.full, (0.0, 0), true);
                    self.writer.frame_last_row(&rec)?;
                    before_last.get_or_insert_with(|| (self.integrator.checkpoint(), kept));
                }
            }
        }
        let complete = failure.is_none() && interrupted.is_none();
        if complete || interrupted.is_some() || resumable {
            // Another failed run (a blow-up, a full disk) keeps the
            // checkpoint of its last flush: the state at the failure is not
            // one to continue from.
            self.checkpoint(before_last)?;
        }
        let i = &self.integrator;
        let reason = match (&failure, interrupted) {
            (Some(f), _) => Some(f.clone()),
            (None, Some(sig)) => Some(format!(
                "interrupted by {sig} at step {}, t = {}; continue with --restart (and the run's --set overrides, if any)",
                i.steps(),
                i.time()
            )),
            _ => None,
        };
        let friction_off = friction_off(self.case, i);
        let summary = Summary {
            wall_time_s: self.wall_before + self.started.elapsed().as_secs_f64(),
            steps: i.steps(),
            factorizations: i.factorizations(),
            dt_crit: i.dt_crit(),
            friction_off: friction_off.clone(),
            failure: reason.clone(),
            stiffness_product: i.stiffness_product().into(),
            fill_order: fill_order_attr(i.fill_order(), self.options.restart),
        };
        let steps_run = i.steps() - steps_before;
        let step_s = stepping.elapsed().as_secs_f64() / steps_run.max(1) as f64;
        let rows = self.writer.rows();
        let frames = self.writer.frames();
        let warnings = self.writer.warnings();
        self.writer.finish(complete, &summary)?;
        let status = if complete {
            "complete"
        } else if interrupted.is_some() {
            "interrupted"
        } else {
            "failed"
        };
        let (case, out, i) = (self.case, self.out, &self.integrator);
        let e = i.energy();
        let mut summary_lost = None;
        if !self.options.quiet {
            let friction = match &friction_off {
                Some(why) => format!("friction off ({why})"),
                None if i.normal_iterations() > 0 => format!(
                    "{} stick/slip iterations, {} compliance Newton iterations",
                    i.total_iterations(),
                    i.normal_iterations()
                ),
                None => format!("{} stick/slip iterations", i.total_iterations()),
            };
            say!(
                "{} {} steps to t = {:.6} ({friction}, {} factorizations, K by {}) in {:.3} s (setup {setup_s:.3} s, {} a step with output)",
                match status {
                    "complete" => "done:",
                    "interrupted" => "interrupted:",
                    _ => "stopped:",
                },
                i.steps(),
                i.time(),
                i.factorizations(),
                summary.stiffness_product,
                summary.wall_time_s,
                human_seconds(step_s)
            );
            say!("setup: {}", setup_line(&self.setup_parts, setup_s));
            // Newmark's γ > ½ dissipates by design, outside the ledger.
            let damped = if case.time.scheme == case::Scheme::Newmark && case.time.gamma > 0.5 {
                format!(
                    " (Newmark gamma = {} > 1/2 damps numerically; the balance holds that loss)",
                    case.time.gamma
                )
            } else {
                String::new()
            };
            // Rayleigh damping's share, where the case has it.
            let mut rayleigh = if case.material.damping.is_some() {
                format!(", damped {:.6}", e.damped)
            } else {
                String::new()
            };
            // A moving foundation's work, where a surface has one.
            if case.contact.iter().any(|c| c.foundation_velocity != 0.0) {
                rayleigh.push_str(&format!(", foundation {:.6}", e.foundation));
            }
            // A compliant foundation's stored energy, where the case has one.
            if i.contact().is_some_and(|c| c.is_compliant()) {
                rayleigh.push_str(&format!(", foundation stored {:.6}", e.foundation_stored));
            }
            say!(
                "energy: total {:.6} (kinetic {:.6}, strain {:.6}, work {:.6}, dissipated {:.6}{rayleigh}); largest |balance| {:.3e}{damped}",
                e.total, e.kinetic, e.strain, e.external_work, e.dissipated, self.max_balance
            );
            say!(
                "results: {} ({rows} rows of histories; {frames} frames of u, v, a)",
                out.display()
            );
            say!(
                "view: `{}`, then open {} in ParaView (meshio and PyVista read it too)",
                view_command(out),
                crate::xdmf::xdmf_path(out).display()
            );
        }
        if self.options.json {
            let j = serde_json::json!({
                "status": status,
                "case": case.path.display().to_string(),
                "output": out.display().to_string(),
                "view_command": view_command(out),
                "warnings": warnings,
                "complete": complete,
                "steps": i.steps(),
                "t": i.time(),
                "t_end": i.t_end(),
                "records": rows,
                "frames": frames,
                "friction": friction_off.as_ref().map_or("on".to_string(), |why| format!("off: {why}")),
                "wall_time_s": summary.wall_time_s,
                "setup_s": setup_s,
                "setup_parts": setup_json(&self.setup_parts, setup_s),
                "step_s": step_s,
                "iterations": i.total_iterations(),
                "normal_iterations": i.normal_iterations(),
                "factorizations": i.factorizations(),
                "stiffness_product": summary.stiffness_product,
                "fill_order": summary.fill_order,
                "dt": case.time.dt,
                "dt_crit": i.dt_crit(),
                "energy": {
                    "kinetic": e.kinetic,
                    "strain": e.strain,
                    "external_work": e.external_work,
                    "dissipated": e.dissipated,
                    "damped": e.damped,
                    "foundation": e.foundation,
                    "foundation_stored": e.foundation_stored,
                    "total": e.total,
                    "balance": e.balance,
                    "max_abs_balance": self.max_balance,
                },
                "failure": reason,
                "restarted": self.options.restart,
            });
            if let Err(e) = crate::console::out(&format!("{j}\n")) {
                summary_lost = Some(e);
            }
        }
        if let Some(sig) = interrupted {
            say!(
                "interrupted by {sig}: stopped after step {}, t = {} of t_end = {}; {} holds {rows} records (up to t = {}) and a checkpoint (complete = false)",
                i.steps(),
                i.time(),
                i.t_end(),
                out.display(),
                self.times.last().copied().unwrap_or(0.0)
            );
            let sets: String = self
                .options
                .sets
                .iter()
                .map(|s| format!(" --set {}", shell_word(s)))
                .collect();
            say!(
                "continue with: stickslip run {} --restart {}{sets}",
                shell_word(&case.path.display().to_string()),
                shell_word(&out.display().to_string())
            );
            return Ok(Outcome::Interrupted);
        }
        match failure {
            None => match summary_lost {
                None => Ok(Outcome::Complete),
                Some(e) => {
                    // A reader that closed the pipe wants nothing more.
                    if !e.broken_pipe() {
                        say!(
                            "error: {e}; the run is complete all the same: {} holds every record \
                             (complete = true)",
                            out.display()
                        );
                    }
                    Ok(Outcome::SummaryLost)
                }
            },
            Some(e) => {
                say!("error: {}: {e}", case.path.display());
                let restart = if resumable {
                    format!(
                        " and a checkpoint at its last step: continue with `stickslip run {} --restart {}` \
                         and the run's --set overrides (contact.max_iterations may change on a restart)",
                        shell_word(&case.path.display().to_string()),
                        shell_word(&out.display().to_string())
                    )
                } else {
                    String::new()
                };
                say!(
                    "error: {} keeps every step completed before the failure ({rows} records, complete = false, reason in its failure attribute){restart}",
                    out.display()
                );
                Ok(Outcome::Failed)
            }
        }
    }
}

/// The command that writes the viewers' files of `out`, as a user would
/// type it.
fn view_command(out: &Path) -> String {
    format!("stickslip views {}", shell_word(&out.display().to_string()))
}

/// Once a restart is accepted, before it changes `out`: removes what `stickslip
/// stress` and `stickslip views` wrote beside it for the earlier run (the
/// stresses end where it ended, the XML lists its records), saying so.
/// The views file stays: `views` then keeps the views that still hold
/// and makes the others. A file only named like the stresses (another
/// run's results, say) is not this run's and stays too.
pub(crate) fn forget_companions(out: &Path, quiet: bool) {
    use crate::results_file::{foreign_companion, Companion};
    let stress = Companion::Stress.path(out);
    if stress.is_file() && foreign_companion(out, Companion::Stress).is_none() {
        std::fs::remove_file(&stress).ok();
        if !quiet {
            say!(
                "restart: removed {} (the earlier run's stresses); run `stickslip stress {}` again after this run",
                stress.display(),
                out.display()
            );
        }
    }
    let xml = [
        crate::xdmf::xdmf_path(out),
        crate::xdmf::contact_xdmf_path(out),
    ];
    let removed: Vec<String> = xml
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .map(|p| p.display().to_string())
        .collect();
    if !removed.is_empty() && !quiet {
        say!(
            "restart: removed {} (they list the earlier run's records); run `{}` again after this run",
            removed.join(" and "),
            view_command(out)
        );
    }
}

/// The failure message of an explicit run whose energy blew up
/// ([`blow_up`] gave `bound`).
fn blow_up_failure(i: &Integrator, bound: f64, case: &Case) -> String {
    let e = i.energy();
    let crit = i.dt_crit().unwrap_or(f64::NAN);
    // Only a foundation stiffening with the approach (m_n > 1), whose
    // growth time.allow_unstable let pass, outgrows a step below dt_crit.
    let stiffening = case.time.allow_unstable
        && case.contact.iter().any(|c| {
            c.law == stickslip_case::schema::ContactLaw::Compliance && c.mn.unwrap_or(1.0) > 1.0
        });
    let why = if case.time.dt > crit || crit.is_nan() {
        format!(
            "central difference is unstable at time.dt = {:e}, above its critical step dt_crit = \
             {crit:.6e}: use time.dt < {crit:.4e} (e.g. {:.4e}) and remove time.allow_unstable",
            case.time.dt,
            0.9 * crit
        )
    } else if !stiffening {
        // Below Δt_crit and without a foundation that stiffens no step of
        // the scheme's own grows: the contact's terms did (a reduced step
        // far below Δt, a regularization eps far below the slip speeds), or
        // without contact the loads or the damping.
        let from = if case.contact.is_empty() {
            "did not come from the step: check the loads and material.damping"
        } else {
            "came from the contact's terms: check contact.eps and time.stick_reduction (a \
             reduced step far below time.dt), or run the case with time.scheme = \"newmark\""
        };
        format!(
            "the step time.dt = {:e} is below central difference's critical step dt_crit = \
             {crit:.6e}, so the growth {from}",
            case.time.dt
        )
    } else {
        format!(
            "central difference is unstable at time.dt = {:e}, below its critical step dt_crit = \
             {crit:.6e} without the foundation's growing stiffness c_n m_n δ^(m_n−1): the approach \
             made it stiffer than the step allows; remove time.allow_unstable to be stopped at the \
             step the stiffness outgrows, with the time.dt it needs, or lower cn",
            case.time.dt
        )
    };
    format!(
        "step {} (t = {:.6e}): energy blow-up: kinetic + strain = {:.3e} exceeds {BLOW_UP_FACTOR} x (initial + |work| + dissipated + |foundation work|) = {bound:.3e}; {why}",
        i.steps(),
        i.time(),
        e.kinetic + e.strain,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh explicit run from 500 free DOFs without a preload
    /// factorizes nothing, so its ordering stays undecided: it wrote no
    /// `fill_order` at all and `--json` gave null (docs/results.md promised
    /// the attribute). Now it writes "none"; a restart keeps the stored one.
    #[test]
    fn an_undecided_fill_order_is_none_on_a_fresh_run_and_kept_on_a_restart() {
        assert_eq!(fill_order_attr(Some("AMD"), false).as_deref(), Some("AMD"));
        assert_eq!(
            fill_order_attr(Some("nested dissection"), true).as_deref(),
            Some("nested dissection")
        );
        assert_eq!(fill_order_attr(None, false).as_deref(), Some("none"));
        assert_eq!(fill_order_attr(None, true), None);
    }

    /// Nodes of one contact face held along different axes: the warning
    /// named only the worst node's axis ("3 of the 3 ... have uy fixed"
    /// where one had ux fixed); it now names both.
    #[test]
    fn oblique_supports_name_every_fixed_axis() {
        use stickslip_contact::ContactNode;
        let mesh = stickslip_testkit::rectangle(
            stickslip_mesh::CellKind::Quad4,
            2,
            1,
            [0.0, 0.0],
            [2.0, 1.0],
        );
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let node = |node, dofs, tangent| ContactNode {
            node,
            dofs,
            weight: 1.0,
            tangent,
            s: 0.0,
            bound: 1.0,
        };
        let held = |dofs: Vec<[Option<usize>; 2]>| {
            let nodes = dofs
                .into_iter()
                .enumerate()
                .map(|(i, d)| node(i, d, [s, s]))
                .collect();
            let c = ContactSurface::from_nodes("arc", nodes, 1.0).unwrap();
            oblique_supports(&mesh, &c).expect("a warning")
        };
        let uy = held(vec![[Some(0), None], [Some(1), None], [Some(2), None]]);
        assert!(
            uy.starts_with("3 of the 3") && uy.contains("have uy fixed"),
            "{uy}"
        );
        assert!(uy.contains("only along x"), "{uy}");
        let mixed = held(vec![[Some(0), None], [None, Some(1)], [Some(2), None]]);
        assert!(mixed.contains("have ux or uy fixed"), "{mixed}");
        assert!(mixed.contains("only along the other axis"), "{mixed}");
        // On a floor (τ along x) a node with ux held moves only along the
        // normal: no friction, no warning; a free one beside it neither.
        let floor = vec![
            node(0, [None, Some(0)], [1.0, 0.0]),
            node(1, [Some(1), Some(2)], [1.0, 0.0]),
        ];
        let c = ContactSurface::from_nodes("floor", floor, 1.0).unwrap();
        assert_eq!(oblique_supports(&mesh, &c), None);
    }

    #[test]
    fn a_huge_static_displacement_is_reported_in_short() {
        let mesh = stickslip_testkit::rectangle(
            stickslip_mesh::CellKind::Quad4,
            1,
            1,
            [0.0, 0.0],
            [1.0, 1.0],
        );
        // One node of four moved: 3/4 of its motion is not the mean's.
        let mut u = vec![0.0; 8];
        u[3] = -4e99;
        let said = large_static_displacement(&mesh, &u).expect("a warning");
        assert!(said.contains("3.0e99 times the part's size"), "{said}");
        assert!(said.len() < 300, "{said}");
        u[3] = -4.0;
        let said = large_static_displacement(&mesh, &u).expect("a warning");
        assert!(said.contains("300% of the part's size"), "{said}");
        // A part carried 300 sizes without strain: no warning.
        let carried: Vec<f64> = (0..8)
            .map(|i| if i % 2 == 1 { -300.0 } else { 0.0 })
            .collect();
        assert_eq!(large_static_displacement(&mesh, &carried), None);
    }
}
