//! `stickslip run` and `stickslip check`: from a validated case to a model,
//! an integrator and the HDF5 results, step by step.
//!
//! Everything that can be refused is refused in [`prepare`], before any
//! time step, as an [`InputError`] (exit code 2). Once stepping starts,
//! every completed output step is in the file; a failure marks the file
//! `complete = false`, records the reason and returns [`Outcome::Failed`].

use std::io::IsTerminal;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use stickslip_contact::{ContactSurface, IterationOptions};
use stickslip_fem::{
    body_force_load, traction_load, Dirichlet, DofMap, ElementClasses, Hypothesis as FemHypothesis,
    Material, Model, NodeOrder, Traction,
};
use stickslip_mesh::Mesh;
use stickslip_time::{
    Dynamics, ExplicitFriction, History, ImplicitSolver, Integrator, Load, MassKind, Scheme,
    Settings, StickReduction, TimeError,
};

/// `eprintln!` that does not panic when stderr is closed: a run's
/// messages must not end it (`stickslip run ... 2>&1 | head` closes the
/// pipe while the run goes on, and a panic there lost the steps since the
/// last flush).
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

/// [`say!`] on stdout.
macro_rules! say_out {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

use crate::case::{self, Case};
use crate::error::InputError;
use crate::output::{self, CheckpointExtra, Header, Record, ResultsWriter, Summary};

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
}

/// A case turned into the objects that run it, with the model kept for
/// inspection (`check`, `advise`).
#[derive(Debug)]
pub struct Prepared {
    /// The mesh.
    pub mesh: Mesh,
    /// K, M, lumped M, DOF map.
    pub model: Model,
    /// The integrator at t = 0 (initial state computed).
    pub integrator: Integrator,
}

/// A case turned into the objects that run it, for `run`: K and M have
/// moved into the integrator (a copy left in a model would be held for the
/// whole run, 24 bytes per stored entry of K beside the step's own data).
#[derive(Debug)]
pub struct Running {
    /// The mesh.
    pub mesh: Mesh,
    /// The DOF map of the integrator's free DOFs.
    pub dofs: DofMap,
    /// The integrator at t = 0 (initial state computed).
    pub integrator: Integrator,
}

/// Free DOFs from which a run or check says when the model is assembled
/// (its setup then takes seconds: 12 s at 1.1M DOFs).
const SETUP_NOTE_DOFS: usize = 200_000;

/// Seconds between progress lines where stderr is not a terminal.
const PROGRESS_LOG_SECS: u64 = 60;

fn input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(InputError(msg.into()))
}

fn history(h: &case::History) -> History {
    match h {
        case::History::Constant => History::Constant,
        case::History::Step => History::Step,
        case::History::Sin { omega } => History::Sin { omega: *omega },
        case::History::Table(points) => {
            History::Table(points.iter().map(|p| (p[0], p[1])).collect())
        }
    }
}

/// Checks a group the case names against the mesh: it exists (else the
/// message lists the mesh's groups) and, when `dim` is given, has that
/// dimension.
fn check_group(
    mesh: &Mesh,
    case: &Case,
    key: &str,
    name: &str,
    dim: Option<u8>,
    purpose: &str,
    problems: &mut Vec<String>,
) -> bool {
    match mesh.group(name) {
        Err(e) if matches!(e.kind, stickslip_mesh::MeshErrorKind::AmbiguousGroup { .. }) => {
            problems.push(format!(
                "{}{key} = {name:?}: in {}: {e}",
                case.at(key),
                case.mesh.file.display()
            ));
            false
        }
        Err(_) => {
            let have: Vec<String> = mesh
                .groups
                .iter()
                .map(|g| format!("{:?} (dim {})", g.name, g.dim))
                .collect();
            problems.push(format!(
                "{}{key} = {name:?}: the mesh {} has no physical group {name:?}; it has: {}; \
                 use one of those, or add the group in Gmsh (Physical Curve/Surface)",
                case.at(key),
                case.mesh.file.display(),
                if have.is_empty() {
                    "none".to_string()
                } else {
                    have.join(", ")
                }
            ));
            false
        }
        Ok(g) => match dim {
            Some(d) if g.dim != d => {
                problems.push(format!(
                    "{}{key} = {name:?}: {purpose} needs a group of boundary lines (dimension {d}), \
                     but {name:?} has dimension {}; name the boundary edges in Gmsh with a Physical Curve",
                    case.at(key),
                    g.dim
                ));
                false
            }
            // A line inside the body (Gmsh's `Line{..} In Surface{..}`):
            // a load or friction there would act inside the body.
            Some(_) if mesh.interior_edges(g) > 0 => {
                problems.push(format!(
                    "{}{key} = {name:?}: {purpose} must be on the boundary, but {} of the group's {} edges \
                     lie inside the body (each a side of two cells, as an embedded curve's are); name the \
                     boundary edges instead",
                    case.at(key),
                    mesh.interior_edges(g),
                    g.edges.len()
                ));
                false
            }
            _ => true,
        },
    }
}

/// Builds mesh, model, loads, contact surface and integrator. Every problem
/// with the input is collected (groups the mesh lacks, groups of the wrong
/// dimension, free rigid-body motions, Δt above the critical step, ...) and
/// reported together as one [`InputError`], each naming the case file and
/// line. `progress`: a line on stderr once a large model is assembled
/// ([`SETUP_NOTE_DOFS`]).
///
/// # Errors
/// Input problems (exit 2) as [`InputError`]; nothing else is expected.
pub fn prepare(case: &Case, progress: bool) -> anyhow::Result<Prepared> {
    let (mesh, _, model, integrator) = build(case, false, true, progress)?;
    Ok(Prepared {
        mesh,
        model: model.expect("kept when asked"),
        integrator,
    })
}

/// [`prepare`] for a run, which will [`Integrator::restore`] a checkpoint
/// when `restoring` (no initial static solve: the checkpoint has the state).
/// K and M move into the integrator.
///
/// # Errors
/// As [`prepare`].
pub fn prepare_run(case: &Case, restoring: bool, progress: bool) -> anyhow::Result<Running> {
    let (mesh, dofs, _, integrator) = build(case, restoring, false, progress)?;
    Ok(Running {
        mesh,
        dofs,
        integrator,
    })
}

/// [`prepare`] and [`prepare_run`]: the model is returned when
/// `keep_model`, else its matrices move into the integrator. With
/// `progress`, a model of [`SETUP_NOTE_DOFS`] free DOFs or more gets a line
/// on stderr before the integrator's setup (its factorizations take
/// seconds there, with nothing else on the screen).
fn build(
    case: &Case,
    restoring: bool,
    keep_model: bool,
    progress: bool,
) -> anyhow::Result<(Mesh, DofMap, Option<Model>, Integrator)> {
    let started = Instant::now();
    let mesh = Mesh::from_file(&case.mesh.file)
        .map_err(|e| input(format!("{}{e}", case.at("mesh.file"))))?;
    let mut problems = Vec::new();

    // Groups first: everything after needs them.
    let mut groups_ok = true;
    for (i, d) in case.dirichlet.iter().enumerate() {
        groups_ok &= check_group(
            &mesh,
            case,
            &format!("dirichlet.{i}.group"),
            &d.group,
            None,
            "a Dirichlet condition",
            &mut problems,
        );
    }
    let dirichlet_ok = groups_ok;
    for (i, t) in case.traction.iter().enumerate() {
        groups_ok &= check_group(
            &mesh,
            case,
            &format!("traction.{i}.group"),
            &t.group,
            Some(1),
            "a traction",
            &mut problems,
        );
    }
    if let Some(c) = &case.contact {
        groups_ok &= check_group(
            &mesh,
            case,
            "contact.group",
            &c.group,
            Some(1),
            "the contact surface",
            &mut problems,
        );
    }

    let hypothesis = match case.material.hypothesis {
        case::Hypothesis::PlaneStrain => FemHypothesis::PlaneStrain,
        case::Hypothesis::PlaneStress => FemHypothesis::PlaneStress,
    };
    let material = match Material::new(
        case.material.e,
        case.material.nu,
        case.material.rho,
        hypothesis,
    ) {
        Ok(m) => Some(m),
        Err(e) => {
            problems.push(format!("{}[material]: {e}", case.at("material.E")));
            None
        }
    };
    let mut conditions = Vec::new();
    for d in &case.dirichlet {
        for (component, value) in [(0, d.ux), (1, d.uy)] {
            if let Some(value) = value {
                conditions.push(Dirichlet {
                    group: d.group.clone(),
                    component,
                    value,
                });
            }
        }
    }
    let dirichlet_at = case.at("dirichlet.0.group");
    let model = match (&material, dirichlet_ok) {
        (Some(material), true) => match Model::new(&mesh, material, &conditions) {
            Ok(m) => Some(m),
            Err(e) => {
                problems.push(format!("{dirichlet_at}[[dirichlet]]: {e}"));
                None
            }
        },
        _ => None,
    };
    if let Some(m) = &model {
        // The initial static solve (Remark 4.1) is frictionless: the
        // supports alone must hold the body (DofMap checks each connected part).
        let free = m.dofs.free_rigid_motions();
        if !free.is_empty() {
            problems.push(format!(
                "{dirichlet_at}the supports leave a rigid-body motion free for the initial static solve: {}; \
                 add [[dirichlet]] conditions that prevent it (e.g. uy = 0 on a bottom or top group and ux = 0 on an end)",
                free.join(", ")
            ));
        }
    }
    let Some(model) = model.filter(|_| groups_ok && problems.is_empty()) else {
        return Err(input(crate::error::listed(problems)));
    };

    let n_full = 2 * mesh.nodes.len();
    let n_free = model.dofs.n_free();
    let mut full = vec![0.0; n_full];
    let mut loads = Vec::new();
    let restrict = |full: &[f64]| {
        let mut free = vec![0.0; n_free];
        model.dofs.restrict(full, &mut free);
        free
    };
    for (i, t) in case.traction.iter().enumerate() {
        full.iter_mut().for_each(|x| *x = 0.0);
        let traction = match (t.t, t.pressure) {
            (Some(v), None) => Traction::Vector(v),
            (None, Some(p)) => Traction::Pressure(p),
            _ => {
                problems.push(format!(
                    "{}[[traction]] on {:?}: give exactly one of t or pressure",
                    case.at(&format!("traction.{i}.group")),
                    t.group
                ));
                continue;
            }
        };
        match traction_load(&mesh, &t.group, traction, &mut full) {
            Ok(()) => loads.push(Load {
                vector: restrict(&full),
                history: history(&t.history),
            }),
            Err(e) => problems.push(format!(
                "{}[[traction]]: {e}",
                case.at(&format!("traction.{i}.group"))
            )),
        }
    }
    if let Some(f) = case.body_force {
        full.iter_mut().for_each(|x| *x = 0.0);
        body_force_load(&mesh, f, &mut full);
        loads.push(Load {
            vector: restrict(&full),
            history: History::Constant,
        });
    }
    let mut iteration = IterationOptions::default();
    let mut contact = None;
    if let Some(c) = &case.contact {
        // The prescribed normal traction on Γ_C is a load like any other,
        // present before t = 0 (it makes the initial static state).
        full.iter_mut().for_each(|x| *x = 0.0);
        match traction_load(&mesh, &c.group, Traction::Pressure(c.pressure), &mut full) {
            Ok(()) => loads.push(Load {
                vector: restrict(&full),
                history: History::Constant,
            }),
            Err(e) => problems.push(format!("{}[contact]: {e}", case.at("contact.group"))),
        }
        iteration = IterationOptions {
            remark_4_2: c.remark_4_2,
            max_iterations: c.max_iterations,
        };
        match ContactSurface::from_group(&mesh, &model.dofs, &c.group, c.pressure, c.mu, c.eps) {
            // Every node's tangential DOF held: the friction the case asks
            // for could act nowhere (before, it was dropped silently, and
            // the file had no /contact).
            Ok(s) if s.is_empty() => problems.push(format!(
                "{}[contact]: no node of group \"{}\" can slide: [[dirichlet]] conditions hold the tangential \
                 motion of all its {} nodes, so friction would act nowhere; remove the [[dirichlet]] on the \
                 contact surface's tangential direction, or remove [contact] for a run without friction",
                case.at("contact.group"),
                c.group,
                s.excluded.len()
            )),
            Ok(s) => contact = Some(s),
            Err(e) => problems.push(format!("{}[contact]: {e}", case.at("contact.group"))),
        }
    }
    if !problems.is_empty() {
        return Err(input(crate::error::listed(problems)));
    }
    let scheme = match case.time.scheme {
        case::Scheme::CentralDifference => Scheme::CentralDifference,
        case::Scheme::Newmark => Scheme::Newmark {
            beta: case.time.beta,
            gamma: case.time.gamma,
        },
    };
    let settings = Settings {
        scheme,
        mass: case.time.mass.map(|m| match m {
            case::MassKind::Consistent => MassKind::Consistent,
            case::MassKind::Lumped => MassKind::Lumped,
        }),
        dt: case.time.dt,
        t_end: case.time.t_end,
        stick_reduction: case.time.stick_reduction.as_ref().map(|r| StickReduction {
            dt: r.dt,
            steps: r.steps,
        }),
        iteration,
        allow_unstable: case.time.allow_unstable,
        explicit_friction: ExplicitFriction::ClosedForm,
        initial_velocity: None,
        // The state is read at every record: the modal step of small
        // systems pays 3n² for each read, so with a record at every step
        // the factor's step costs less (the paper's Newmark case, 20,000
        // steps end to end: 24.4 µs a step by the factor, 26.5 µs modal),
        // from every second step on the modal one.
        reads_every: Some(case.output.every.max(1) as u64),
        restoring,
    };
    // The explicit step forms K·x by stencil types where the mesh's
    // numbering repeats its node rows (structured meshes numbered row by
    // row), else from element classes where the mesh has them (structured
    // Q2 meshes), else from a compact copy of the assembled K
    // (stickslip-time's kernels.rs picks).
    let classes = match (scheme, &material) {
        (Scheme::CentralDifference, Some(material)) => {
            ElementClasses::new(&mesh, material, &model.dofs)
        }
        _ => None,
    };
    let dofs = model.dofs.clone();
    if progress && dofs.n_free() >= SETUP_NOTE_DOFS {
        let order = model.fill_order.name();
        let work = match (scheme, restoring) {
            (Scheme::CentralDifference, true) => "the step's operators".to_string(),
            (Scheme::CentralDifference, false) => format!(
                "the initial state (a static solve by sparse Cholesky, ordered by {order}, when loads act before t = 0) and the step's operators"
            ),
            (Scheme::Newmark { .. }, _) => format!(
                "the factor of the step's operator (sparse Cholesky, ordered by {order}) and the initial state"
            ),
        };
        say!(
            "model: {} free DOFs, assembled in {:.1} s; now {work}",
            dofs.n_free(),
            started.elapsed().as_secs_f64(),
        );
    }
    let (dynamics, model) = if keep_model {
        (Dynamics::from_model(&model), Some(model))
    } else {
        (Dynamics::from_model_owned(model), None)
    };
    let dynamics = dynamics.with_element_classes(classes);
    let integrator = Integrator::new(dynamics, contact, loads, settings).map_err(|e| {
        let key = match e {
            TimeError::Unstable { .. } => "time.dt",
            TimeError::Static(_) => "dirichlet.0.group",
            _ => "time.scheme",
        };
        input(format!("{}[time]: {e}", case.at(key)))
    })?;
    Ok((mesh, dofs, model, integrator))
}

/// `stickslip check`: validate, print the model size, Δt_crit and solver.
///
/// # Errors
/// Input problems as [`InputError`].
pub fn check(case: &Case) -> anyhow::Result<()> {
    let p = prepare(case, true)?;
    let i = &p.integrator;
    println!("case        {}", case.path.display());
    if let Some(t) = &case.title {
        println!("title       {t}");
    }
    println!(
        "mesh        {} nodes, {} {} cells ({})",
        p.mesh.nodes.len(),
        p.mesh.n_cells(),
        p.mesh.kind.name(),
        case.mesh.file.display()
    );
    println!(
        "DOFs        {} free of {}, numbered {}",
        p.model.dofs.n_free(),
        2 * p.mesh.nodes.len(),
        match p.model.dofs.node_order() {
            NodeOrder::Mesh => "node by node in the mesh file's order",
            NodeOrder::Grid => "row by row of the structured grid the nodes form",
            NodeOrder::Bandwidth => "by reverse Cuthill-McKee (a band around the diagonal)",
        }
    );
    match i.contact() {
        Some(c) => println!(
            "contact     {:?}: {} friction nodes ({} left out: tangential motion fixed), eps = {:e}",
            c.group,
            c.len(),
            c.excluded.len(),
            c.law.eps
        ),
        None => println!("contact     none (no friction code runs)"),
    }
    // The explicit integrator computed it already (by its own K·x);
    // Newmark's did not.
    let crit = i.dt_crit().unwrap_or_else(|| {
        stickslip_time::stability::critical_step(&p.model.stiffness, &p.model.lumped_mass)
    });
    println!("dt_crit     {crit:.6e} (central difference, lumped mass: 2/omega_max)");
    // As the integrator counts: a last step within 1e-6 Δt of t_end is
    // not a step of its own.
    let steps = (case.time.t_end / case.time.dt - 1e-6).ceil().max(1.0);
    if i.is_explicit() {
        // A preload (a constant load, nonzero prescribed displacements)
        // puts the initial state at r₀ = K⁻¹ R(0⁻): one factorization of
        // K, the only one of the run; else r₀ = 0 and there is none.
        let preloaded = i.displacement().iter().any(|&x| x != 0.0);
        println!(
            "solver      explicit: {}; friction solved node by node in closed form; K·x by {}",
            if preloaded {
                format!(
                    "no linear system per step (the preloaded initial state by one sparse Cholesky (faer, {}) of K)",
                    p.model.fill_order.name()
                )
            } else {
                "no linear system".to_string()
            },
            i.stiffness_product()
        );
    } else if i.implicit_solver() == ImplicitSolver::Direct {
        println!(
            "solver      implicit Newmark: sparse Cholesky (faer, {}) of A₀ + C, analysed once, refactorized when dt or the stuck set changes; nnz(K) = {}; K·x by {}",
            p.model.fill_order.name(),
            p.model.stiffness.nnz(),
            i.stiffness_product()
        );
    } else if i.implicit_solver() == ImplicitSolver::Modal {
        let n_c = i.contact().map_or(0, |c| c.len());
        println!(
            "solver      implicit Newmark in the {n} modes of (K, M) (dense eigensolver once; up to {} DOFs): A₀ diagonal, no K·x per step; friction on the {n_c} contact unknowns by the Schur complement",
            stickslip_time::MODAL_MAX_DOFS,
            n = p.model.stiffness.nrows(),
        );
    } else {
        let n_c = i.contact().map_or(0, |c| c.len());
        println!(
            "solver      implicit Newmark: sparse Cholesky (faer, {}) of A₀, analysed once, factorized once per distinct dt; friction on the {n_c} contact unknowns by the Schur complement; nnz(K) = {}; K·x by {}",
            p.model.fill_order.name(),
            p.model.stiffness.nnz(),
            i.stiffness_product()
        );
    }
    println!(
        "steps       about {steps} to t_end = {} with dt = {:e}",
        case.time.t_end, case.time.dt
    );
    if !i.is_explicit() {
        // Stability is no guide for an implicit step: say what it resolves.
        println!(
            "accuracy    Newmark is stable at any dt, but follows a vibration only when its period spans \
             about 10 steps or more: here periods above {:.3e}; the mesh's shortest is {:.3e} (pi dt_crit)",
            10.0 * case.time.dt,
            std::f64::consts::PI * crit
        );
    }
    let (records, bytes) =
        output_size(case, p.mesh.nodes.len(), i.contact().map_or(0, |c| c.len()));
    println!(
        "output      about {records} records (every {} steps) of {}, {}",
        case.output.every,
        case.output.file.display(),
        human_bytes(bytes)
    );
    if let Some(free) = room_for(&case.output.file, true) {
        if bytes > free as f64 {
            println!(
                "warning     that is more than the {} free on its disk: `run` refuses it; write fewer records (output.every) or elsewhere (-o)",
                human_bytes(free as f64)
            );
        }
    }
    // The integrator holds the initial state already (the static solve of
    // Remark 4.1 ran in its setup): the run's warning, before the run.
    let mut u = vec![0.0; 2 * p.mesh.nodes.len()];
    p.model.dofs.expand(i.displacement(), &mut u);
    for w in setup_warnings(&p.mesh, &u, i) {
        println!("warning     {w}");
    }
    Ok(())
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

/// Records and bytes a run of `case` writes from t = 0 (uncompressed): per
/// record u, v, a at every node (6 doubles), the contact's stress and slip
/// (2 doubles) and state (1 byte), about 12 scalars besides (time, the
/// ledger, dt, iterations).
fn output_size(case: &Case, nodes: usize, contact_nodes: usize) -> (f64, f64) {
    let steps = (case.time.t_end / case.time.dt - 1e-6).ceil().max(1.0);
    let every = case.output.every.max(1) as f64;
    let records = (steps / every).floor() + 1.0;
    // The node vectors take whole chunks of rows.
    let block = output::vector_chunk_rows(nodes) as f64;
    let rows = (records / block).ceil() * block;
    let bytes = rows * 48.0 * nodes as f64
        + records * (17.0 * contact_nodes as f64 + 96.0 + crate::xdmf::BYTES_PER_STEP as f64);
    (records, bytes)
}

/// Bytes free for the results file `out`: its disk's free space, and with
/// `force` the old OUT.h5 and OUT.xdmf, which the run removes first.
fn room_for(out: &Path, force: bool) -> Option<u64> {
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

/// The initial (static) displacement, where it exceeds the part's size:
/// no small strains are left, which is most often a mix of units (E in MPa
/// with loads in Pa: displacements of 340% of the part went without a
/// word). The paper's slab itself moves 12% of its length (0.975 of 8).
fn large_static_displacement(mesh: &Mesh, u: &[f64]) -> Option<String> {
    let [lo, hi] = stickslip_mesh::bounding_box(mesh.nodes.iter().copied());
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let (node, max) = u
        .chunks_exact(2)
        .map(|d| d[0].hypot(d[1]))
        .enumerate()
        .fold((0, 0.0_f64), |m, (i, d)| if d > m.1 { (i, d) } else { m });
    (size > 0.0 && max > size).then(|| {
        format!(
            "the initial static displacement reaches {max:.3e} at ({}, {}), {:.0}% of the part's size {size:.3e}: \
             linear elasticity assumes small strains; check the units of E, the loads and the lengths",
            mesh.nodes[node][0],
            mesh.nodes[node][1],
            100.0 * max / size
        )
    })
}

/// What runs but is likely not meant, in the words `check` prints and a
/// fresh run says before its first step (one list, so the two cannot
/// drift apart): `u` is the initial displacement at every node.
fn setup_warnings(mesh: &Mesh, u: &[f64], integrator: &Integrator) -> Vec<String> {
    stickslip_mesh::degenerate_cells(mesh, stickslip_mesh::DEGENERATE_RATIO)
        .map(|d| d.to_string())
        .into_iter()
        .chain(large_static_displacement(mesh, u))
        .chain(integrator.contact().and_then(|c| oblique_supports(mesh, c)))
        .collect()
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
        "{count} of the {} friction nodes of \"{}\" have {fixed} fixed by a [[dirichlet]] condition although the face is not normal \
         to that axis there (up to {:.1}° off, at ({x}, {y})): friction acts along the face's tangent, but these nodes can move only along {free}, \
         so the support takes part of the friction force and the slip is the tangent's share of their motion; \
         support the contact face only where it is straight along x or y, or leave it free and let the [contact] pressure carry the normal load",
        c.len(),
        c.group,
        off.asin().to_degrees()
    ))
}

/// The `/solver` attribute `fill_order` a run writes: the decided ordering
/// of its sparse Cholesky factors; where the choice is still open because
/// the run factorized nothing (explicit, no preload, from 100k free DOFs),
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
fn human_bytes(b: f64) -> String {
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
struct FullState {
    u: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    stress: Vec<f64>,
    slip: Vec<f64>,
    state: Vec<i8>,
}

fn record<'a>(
    i: &Integrator,
    dofs: &DofMap,
    s: &'a mut FullState,
    dt: f64,
    iterations: u32,
) -> Record<'a> {
    dofs.expand(i.displacement(), &mut s.u);
    dofs.expand_homogeneous(i.velocity(), &mut s.v);
    dofs.expand_homogeneous(i.acceleration(), &mut s.a);
    i.friction_stress(&mut s.stress);
    i.slip_velocity(&mut s.slip);
    for (o, c) in s.state.iter_mut().zip(i.classes()) {
        *o = c.code();
    }
    let e = i.energy();
    Record {
        t: i.time(),
        displacement: &s.u,
        velocity: &s.v,
        acceleration: &s.a,
        friction_stress: &s.stress,
        slip_velocity: &s.slip,
        state: &s.state,
        kinetic: e.kinetic,
        strain: e.strain,
        external_work: e.external_work,
        dissipated: e.dissipated,
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
    /// second Ctrl-C (the file keeps every step up to its last flush).
    ///
    /// # Errors
    /// The handlers cannot be installed.
    pub fn install() -> std::io::Result<StopFlags> {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let flags = StopFlags::default();
        let any = Arc::new(AtomicBool::new(false));
        for (sig, flag) in [
            (SIGINT, &flags.sigint),
            (SIGTERM, &flags.sigterm),
            (SIGHUP, &flags.sighup),
        ] {
            // Order matters: the shutdown hook must see `any` still false on
            // the first signal (signal-hook's documented pattern).
            second_signal_exits(sig, Arc::clone(&any))?;
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
#[allow(unsafe_code)]
fn second_signal_exits(sig: i32, any: Arc<AtomicBool>) -> std::io::Result<()> {
    const MSG: &[u8] = b"\nstopped at once by a second signal: the results file keeps every step \
up to its last flush (complete = false); continue it with --restart\n";
    // SAFETY: the action only loads an atomic and calls write(2) and
    // _exit(2), which are async-signal-safe.
    unsafe {
        signal_hook::low_level::register(sig, move || {
            if any.load(Ordering::SeqCst) {
                libc::write(2, MSG.as_ptr().cast(), MSG.len());
                libc::_exit(130);
            }
        })?;
    }
    Ok(())
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

/// Energy blow-up of an explicit run (issue 8).
///
/// The energy ledger (METHOD.md §6) says kinetic + strain = E₀ + W − D with
/// D ≥ 0, so kinetic + strain ≤ E₀ + |W| + D for any run the scheme follows
/// faithfully; a stable central-difference run breaks this only by its
/// O(Δt²) energy error. Past Δt_crit the highest mode grows by |λ|² per step,
/// λ the larger root of λ² − (2 − ω²Δt²)λ + 1 = 0 (|λ|² = 1.8 at ωΔt = 2.02,
/// 5.9 at ωΔt = 2.2), from round-off: a growth that must cross any fixed
/// multiple of the physical bound within a few steps of reaching it, while
/// W grows only linearly in the amplitude (R·Δr) and the energies
/// quadratically. Hence the test kinetic + strain > 10 (E₀ + |W| + D): the
/// factor 10 leaves the stable scheme's error far behind and costs about
/// log(10)/log(|λ|²) ≈ 1.3 to 4 steps of detection delay.
fn blow_up(i: &Integrator, initial: f64) -> Option<f64> {
    let e = i.energy();
    let mechanical = e.kinetic + e.strain;
    let bound = BLOW_UP_FACTOR * (initial.abs() + e.external_work.abs() + e.dissipated.abs());
    (mechanical > bound && mechanical > f64::MIN_POSITIVE).then_some(bound)
}

/// `stickslip run`: integrate to t_end writing every `output.every`-th
/// step; flush and checkpoint every `output.flush_every` steps or
/// `output.flush_seconds` seconds; stop cleanly on SIGINT, SIGTERM or SIGHUP; with
/// `options.restart`, continue the file `out` from its checkpoint.
///
/// # Errors
/// Input problems as [`InputError`] (also: a restart whose case changes the
/// physics); I/O failures of the results file.
pub fn execute(case: &Case, out: &Path, options: &RunOptions) -> anyhow::Result<Outcome> {
    let started = Instant::now();
    let quiet = options.quiet;
    let Running {
        mesh,
        dofs,
        mut integrator,
    } = prepare_run(case, options.restart, !quiet)?;
    let (contact_nodes, contact_s): (Vec<usize>, Vec<f64>) = integrator
        .contact()
        .map(|c| c.nodes.iter().map(|n| (n.node, n.s)).unzip())
        .unwrap_or_default();
    let n_c = contact_nodes.len();
    let n_full = 2 * mesh.nodes.len();
    let mut full = FullState {
        u: vec![0.0; n_full],
        v: vec![0.0; n_full],
        a: vec![0.0; n_full],
        stress: vec![0.0; n_c],
        slip: vec![0.0; n_c],
        state: vec![0; n_c],
    };
    // E₀ for the blow-up test: kinetic + strain at t = 0.
    let node_order = dofs.node_order();
    let e0 = integrator.energy();
    let mut initial_mechanical = e0.kinetic + e0.strain;
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
        let (records, bytes) = output_size(case, mesh.nodes.len(), n_c);
        if let Some(free) = room_for(out, true).filter(|&f| bytes > f as f64) {
            return Err(input(format!(
                "{}: the run would write about {records} records ({}) to {}, whose disk has {} free; \
                 write every Nth step (output.every), shorten time.t_end, or write elsewhere with -o",
                case.path.display(),
                human_bytes(bytes),
                out.display(),
                human_bytes(free as f64)
            )));
        }
    }
    // Held until this run returns, from before its first write: a second
    // run's --force or --restart, or a probe, sees the file in use
    // ([`crate::results_file::in_use`]).
    let _lock = if options.restart {
        let lock = crate::results_file::RunLock::take(out)?;
        // `stickslip stress`'s file ends where the earlier run ended.
        let stress = crate::stress_cmd::stress_path(out);
        if stress.is_file() {
            std::fs::remove_file(&stress).ok();
            if !quiet {
                say!(
                    "restart: removed {} (the earlier run's stresses); run `stickslip stress {}` again after this run",
                    stress.display(),
                    out.display()
                );
            }
        }
        lock
    } else {
        crate::results_file::claim(out)?
    };
    let (mut writer, wall_before, mut max_balance, mut times) = if options.restart {
        let stored = output::read_checkpoint(out)
            .map_err(|e| input(format!("--restart {}: {e:#}", out.display())))?;
        let changes = case::restart_changes(&stored.case_source, &case.source)
            .map_err(|e| input(format!("--restart {}: {e}", out.display())))?;
        if !changes.is_empty() {
            return Err(input(format!(
                "{}: --restart {}: the case changes what the stored run computed:\n  {}\n\
                 a restart may change only time.t_end, output.*, title and mesh.ladder; undo those changes, or start a new run with -o NEW.h5",
                case.path.display(),
                out.display(),
                changes.join("\n  ")
            )));
        }
        if let Some(change) = output::stored_mesh_change(out, &mesh)
            .map_err(|e| input(format!("--restart {}: {e:#}", out.display())))?
        {
            return Err(input(format!(
                "{}: --restart {}: {} has changed since the run began ({change}); restart with \
                 the mesh the run began on, or start a new run with -o NEW.h5",
                case.path.display(),
                out.display(),
                case.mesh.file.display()
            )));
        }
        let cp = &stored.checkpoint;
        if case.time.t_end < cp.t {
            return Err(input(format!(
                "{}time.t_end = {} is before the checkpoint's t = {} in {}; give a t_end >= {}",
                case.at("time.t_end"),
                case.time.t_end,
                cp.t,
                out.display(),
                cp.t
            )));
        }
        initial_mechanical = cp.initial_mechanical;
        // The stored run's solver (modal iff its checkpoint holds the modal
        // state), whatever output.every is now: a restart continues bit
        // for bit.
        let modal = !cp.modal.is_empty();
        if modal != (integrator.implicit_solver() == ImplicitSolver::Modal) {
            let solver = if modal {
                ImplicitSolver::Modal
            } else {
                ImplicitSolver::Schur
            };
            integrator
                .set_implicit_solver(solver)
                .map_err(|e| input(format!("--restart {}: {e}", out.display())))?;
        }
        // A state stored in another node order (a file of a version
        // before the node orders, or STICKSLIP_DOF_ORDER changed) is read
        // into this run's numbering; the modal state, whose modes depend
        // on the numbering, is then formed again from it.
        let remapped;
        let n_free = dofs.n_free();
        let lengths_fit = [&cp.displacement, &cp.velocity, &cp.acceleration]
            .iter()
            .all(|x| x.len() == n_free);
        // (Other lengths: `restore` says what is wrong.)
        let cp = if stored.extra.node_order != node_order.code() && lengths_fit {
            let theirs = NodeOrder::from_code(stored.extra.node_order)
                .and_then(|order| dofs.renumbered(&mesh, order))
                .ok_or_else(|| {
                    input(format!(
                        "--restart {}: its state's node_order {} does not apply to {} (a newer version's order, or a structured grid's on a mesh that is none); restart with the version and the mesh the run started from",
                        out.display(),
                        stored.extra.node_order,
                        case.mesh.file.display()
                    ))
                })?;
            let to_ours = |x: &[f64]| dofs.from_numbering(&theirs, x);
            remapped = stickslip_time::Checkpoint {
                displacement: to_ours(&cp.displacement),
                velocity: to_ours(&cp.velocity),
                acceleration: to_ours(&cp.acceleration),
                modal: Vec::new(),
                ..cp.clone()
            };
            &remapped
        } else {
            cp
        };
        integrator
            .restore(cp)
            .map_err(|e| input(format!("--restart {}: {e}", out.display())))?;
        let mut w = ResultsWriter::open_append(out, stored.extra.rows, mesh.nodes.len(), n_c)?;
        w.set_case(&case.source)?;
        if !quiet {
            say!(
                "restart: continuing {} from step {}, t = {} ({} records kept)",
                out.display(),
                cp.steps,
                cp.t,
                stored.extra.rows
            );
        }
        (
            w,
            stored.extra.wall_time_s,
            stored.extra.max_balance,
            stored.times,
        )
    } else {
        let header = Header {
            case_source: &case.source,
            mesh: &mesh,
            contact_nodes: &contact_nodes,
            contact_s: &contact_s,
        };
        let mut w = ResultsWriter::create_with(out, &header, case.output.compression)
            .with_context(|| format!("cannot create the results file {}", out.display()))?;
        w.append(&record(&integrator, &dofs, &mut full, 0.0, 0))?;
        // Kept in the file and printed with --quiet too: quiet silences
        // progress, not what the user should know.
        let warnings = setup_warnings(&mesh, &full.u, &integrator);
        for w in &warnings {
            say!("{}: warning: {w}", case.path.display());
        }
        w.set_warnings(&warnings)?;
        (w, 0.0, 0.0, vec![integrator.time()])
    };
    writer.auto_flush = false;
    writer.flush_every_steps = case.output.flush_every.max(1);
    writer.flush_every_secs = case.output.flush_seconds;
    let extra = |rows: usize, max_balance: f64| CheckpointExtra {
        rows,
        wall_time_s: wall_before + started.elapsed().as_secs_f64(),
        max_balance,
        node_order: node_order.code(),
    };
    let xdmf_path = crate::xdmf::xdmf_path(out);
    let contact_line = integrator
        .contact()
        .map(|c| crate::views::ContactLine::new(&mesh, &c.group, &contact_nodes));
    let layout = crate::views::Layout {
        n_nodes: mesh.nodes.len(),
        contact: contact_line.as_ref(),
    };
    let xdmf = |times: &[f64]| {
        crate::xdmf::write_companions(out, &layout, (mesh.kind, mesh.n_cells()), times)
    };
    // A state to continue from exists from the start (the initial state, or
    // the restored one).
    writer.write_checkpoint(&integrator.checkpoint(), &extra(writer.rows(), max_balance))?;
    xdmf(&times)?;
    let mut last_xdmf = Instant::now();
    // How long the last rewrite took: the next waits ten times that (and at
    // least flush_seconds), so the rewrites, each O(rows), stay under a
    // tenth of the run however many rows (at a fixed interval they took 42%
    // of a run of 320k rows).
    let mut xdmf_secs = 0.0_f64;

    let every = case.output.every.max(1) as u64;
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let bar = indicatif::ProgressBar::new(1000);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% {msg}, ETA {eta}",
            )
            .expect("valid template"),
        );
        bar
    });
    // Where stderr is a log, not a terminal: a line a minute instead of
    // the bar, so a batch job's log shows a long run moving.
    let log_progress = !quiet && !std::io::stderr().is_terminal();
    let mut last_log = Instant::now();
    let setup_s = started.elapsed().as_secs_f64();
    let stepping = Instant::now();
    if log_progress {
        say!(
            "setup done in {setup_s:.1} s; stepping from t = {} to t_end = {} (about {} steps), a progress line a minute",
            integrator.time(),
            integrator.t_end(),
            ((integrator.t_end() - integrator.time()) / case.time.dt).ceil()
        );
    }
    let t_end = integrator.t_end();
    // A restart starts where its checkpoint was: the share done and the
    // time left count from there.
    let t_start = integrator.time();
    let steps_before = integrator.steps();
    let mut failure: Option<String> = None;
    let mut interrupted: Option<&'static str> = None;
    // The state before the last step (and the rows then): that step is
    // shortened to land on t_end, so a restart with a later t_end must redo
    // it at full length to match a run that never stopped.
    let mut before_last: Option<(stickslip_time::Checkpoint, usize)> = None;
    while !integrator.done() {
        let near_end = integrator.t_end() - integrator.time() <= case.time.dt * (1.0 + 1e-6);
        let before = near_end.then(|| (integrator.checkpoint(), writer.rows()));
        match integrator.step() {
            Ok(info) => {
                max_balance = max_balance.max(integrator.energy().balance.abs());
                writer.count_step();
                let write = integrator.steps() % every == 0 || integrator.done();
                let mut rec = |writer: &mut ResultsWriter, full: &mut FullState| {
                    times.push(integrator.time());
                    writer.append(&record(
                        &integrator,
                        &dofs,
                        full,
                        info.dt,
                        info.iterations as u32,
                    ))
                };
                if write {
                    // HDF5 writes a chunk of rows as it fills: the room for
                    // it is checked before, as before a flush.
                    if writer.append_writes() {
                        if let Some(e) = disk_nearly_full(&writer, &dofs, out, &integrator) {
                            failure = Some(e);
                            break;
                        }
                    }
                    rec(&mut writer, &mut full)?;
                }
                if integrator.is_explicit() {
                    if let Some(bound) = blow_up(&integrator, initial_mechanical) {
                        if !write {
                            rec(&mut writer, &mut full)?;
                        }
                        let e = integrator.energy();
                        let crit = integrator.dt_crit().unwrap_or(f64::NAN);
                        failure = Some(format!(
                            "step {} (t = {:.6e}): energy blow-up: kinetic + strain = {:.3e} exceeds {BLOW_UP_FACTOR} x (initial + |work| + dissipated) = {bound:.3e}; \
                             central difference is unstable at time.dt = {:e}, above its critical step dt_crit = {crit:.6e}: \
                             use time.dt < {crit:.4e} (e.g. {:.4e}) and remove time.allow_unstable",
                            integrator.steps(),
                            integrator.time(),
                            e.kinetic + e.strain,
                            case.time.dt,
                            0.9 * crit
                        ));
                        break;
                    }
                }
                if integrator.done() {
                    before_last = before;
                    break;
                }
                if let Some(sig) = options.stop.received() {
                    interrupted = Some(sig);
                    break;
                }
                if writer.flush_due() {
                    if let Some(e) = disk_nearly_full(&writer, &dofs, out, &integrator) {
                        failure = Some(e);
                        break;
                    }
                    writer.write_checkpoint(
                        &integrator.checkpoint(),
                        &extra(writer.rows(), max_balance),
                    )?;
                    // The XML lists every row: rewrite it at most every
                    // flush_seconds, and ten times as seldom as it takes.
                    let wait = case.output.flush_seconds.max(10.0 * xdmf_secs);
                    if last_xdmf.elapsed().as_secs_f64() >= wait {
                        let t = Instant::now();
                        xdmf(&times)?;
                        xdmf_secs = t.elapsed().as_secs_f64();
                        last_xdmf = Instant::now();
                    }
                    if log_progress && last_log.elapsed().as_secs() >= PROGRESS_LOG_SECS {
                        last_log = Instant::now();
                        let wall = started.elapsed().as_secs_f64();
                        let done = (integrator.time() - t_start) / (t_end - t_start).max(1e-300);
                        say!(
                            "progress: t = {:.6e} of {t_end} ({:.1}%), step {}, {:.0} s elapsed, about {:.0} s left",
                            integrator.time(),
                            100.0 * done,
                            integrator.steps(),
                            wall,
                            wall * (1.0 - done) / done.max(1e-12)
                        );
                    }
                }
                if let Some(bar) = &bar {
                    let rate = (integrator.steps() - steps_before) as f64
                        / started.elapsed().as_secs_f64().max(1e-9);
                    bar.set_position((1000.0 * integrator.time() / t_end) as u64);
                    bar.set_message(format!(
                        "t = {:.4e} of {t_end}, step {}, {rate:.0} steps/s",
                        integrator.time(),
                        integrator.steps()
                    ));
                }
            }
            Err(e) => {
                failure = Some(e.to_string());
                break;
            }
        }
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let complete = failure.is_none() && interrupted.is_none();
    if complete || interrupted.is_some() {
        // A failed run keeps the checkpoint of its last flush: the state at
        // the failure is not one to continue from.
        let (cp, rows) = before_last.unwrap_or_else(|| (integrator.checkpoint(), writer.rows()));
        writer.write_checkpoint(&cp, &extra(rows, max_balance))?;
    }
    let reason = match (&failure, interrupted) {
        (Some(f), _) => Some(f.clone()),
        (None, Some(sig)) => Some(format!(
            "interrupted by {sig} at step {}, t = {}; continue with --restart (and the run's --set overrides, if any)",
            integrator.steps(),
            integrator.time()
        )),
        _ => None,
    };
    let summary = Summary {
        wall_time_s: wall_before + started.elapsed().as_secs_f64(),
        steps: integrator.steps(),
        factorizations: integrator.factorizations(),
        dt_crit: integrator.dt_crit(),
        failure: reason.clone(),
        stiffness_product: integrator.stiffness_product().into(),
        fill_order: fill_order_attr(integrator.fill_order(), options.restart),
    };
    let steps_run = integrator.steps() - steps_before;
    let step_s = stepping.elapsed().as_secs_f64() / steps_run.max(1) as f64;
    let rows = writer.rows();
    let warnings = writer.warnings();
    writer.finish(complete, &summary)?;
    xdmf(&times)?;
    let e = integrator.energy();
    let status = if complete {
        "complete"
    } else if interrupted.is_some() {
        "interrupted"
    } else {
        "failed"
    };
    if !quiet {
        say!(
            "{} {} steps to t = {:.6} ({} stick/slip iterations, {} factorizations, K by {}) in {:.3} s (setup {setup_s:.3} s, {} a step with output)",
            match status {
                "complete" => "done:",
                "interrupted" => "interrupted:",
                _ => "stopped:",
            },
            integrator.steps(),
            integrator.time(),
            integrator.total_iterations(),
            integrator.factorizations(),
            summary.stiffness_product,
            summary.wall_time_s,
            human_seconds(step_s)
        );
        // Newmark's γ > ½ dissipates by design, outside the ledger.
        let damped = if case.time.scheme == case::Scheme::Newmark && case.time.gamma > 0.5 {
            format!(
                " (Newmark gamma = {} > 1/2 damps numerically; the balance holds that loss)",
                case.time.gamma
            )
        } else {
            String::new()
        };
        say!(
            "energy: total {:.6} (kinetic {:.6}, strain {:.6}, work {:.6}, dissipated {:.6}); largest |balance| {:.3e}{damped}",
            e.total, e.kinetic, e.strain, e.external_work, e.dissipated, max_balance
        );
        say!("results: {} ({rows} records)", out.display());
    }
    if options.json {
        let j = serde_json::json!({
            "status": status,
            "case": case.path.display().to_string(),
            "output": out.display().to_string(),
            "xdmf": xdmf_path.display().to_string(),
            "warnings": warnings,
            "complete": complete,
            "steps": integrator.steps(),
            "t": integrator.time(),
            "t_end": t_end,
            "records": rows,
            "wall_time_s": summary.wall_time_s,
            "setup_s": setup_s,
            "step_s": step_s,
            "iterations": integrator.total_iterations(),
            "factorizations": integrator.factorizations(),
            "stiffness_product": summary.stiffness_product,
            "fill_order": summary.fill_order,
            "dt": case.time.dt,
            "dt_crit": integrator.dt_crit(),
            "energy": {
                "kinetic": e.kinetic,
                "strain": e.strain,
                "external_work": e.external_work,
                "dissipated": e.dissipated,
                "total": e.total,
                "balance": e.balance,
                "max_abs_balance": max_balance,
            },
            "failure": reason,
            "restarted": options.restart,
        });
        say_out!("{j}");
    }
    if let Some(sig) = interrupted {
        say!(
            "interrupted by {sig}: stopped after step {}, t = {} of t_end = {t_end}; {} holds {rows} records (up to t = {}) and a checkpoint (complete = false)",
            integrator.steps(),
            integrator.time(),
            out.display(),
            times.last().copied().unwrap_or(0.0)
        );
        let sets: String = options
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
        None => Ok(Outcome::Complete),
        Some(e) => {
            say!("error: {}: {e}", case.path.display());
            say!(
                "error: {} keeps every step completed before the failure ({rows} records, complete = false, reason in its failure attribute)",
                out.display()
            );
            Ok(Outcome::Failed)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh explicit run from 100k free DOFs without a preload
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
        let mesh = stickslip_fem::testing::rectangle(
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
    }
}
