//! `stickslip check`: a case validated and its model built as a run
//! would build it, then what the run would be (model size, contact,
//! Δt_crit, solver, steps, output) and the warnings a run prints before
//! its first step, without stepping.

use std::fmt::Write as _;

use stickslip_case::{self as case, Case, InputError};
use stickslip_fem::NodeOrder;
use stickslip_time::ImplicitSolver;

use crate::frames::Schedule;
use crate::run::{friction_off, human_bytes, output_size, prepare, setup_warnings};

/// `stickslip check`: validate, and say the model size, Δt_crit and
/// solver: the report is returned for the caller to print, which can fail
/// (`println!` would panic on a full disk).
///
/// # Errors
/// Input problems as [`InputError`].
pub fn check(case: &Case) -> anyhow::Result<String> {
    // The results file a run of the case writes (without -o), refused
    // where `run` would refuse it, at its line of the case.
    crate::results_file::check_output_place(
        &case.output.file,
        &crate::results_file::case_inputs(case),
    )
    .map_err(|e| InputError(format!("{}output.file: {}", case.at("output.file"), e.0)))?;
    let p = prepare(case, true)?;
    let mut report = String::new();
    // A line of the report (writing to a String cannot fail).
    macro_rules! put {
        ($($t:tt)*) => {{
            let _ = writeln!(report, $($t)*);
        }};
    }
    let i = &p.integrator;
    put!("case        {}", case.path.display());
    if let Some(t) = &case.title {
        put!("title       {t}");
    }
    put!(
        "mesh        {} nodes, {} {} cells ({})",
        p.mesh.nodes.len(),
        p.mesh.n_cells(),
        p.mesh.kind.name(),
        case.mesh.file.display()
    );
    put!(
        "DOFs        {} free of {}, numbered {}",
        p.model.dofs.n_free(),
        2 * p.mesh.nodes.len(),
        match p.model.dofs.node_order() {
            NodeOrder::Mesh => "node by node in the mesh file's order",
            NodeOrder::Grid => "row by row of the structured grid the nodes form",
            NodeOrder::Bandwidth => "by reverse Cuthill-McKee (a band around the diagonal)",
        }
    );
    let free: Vec<String> = crate::run::motion_holders(case, &p.model.dofs, i)
        .into_iter()
        .map(|(label, held)| format!("{label} ({})", held.describe()))
        .collect();
    if !free.is_empty() {
        // With nothing holding one the run warns (`setup_warnings`,
        // below).
        put!(
            "floating    the supports leave free: {}; the static preload, if any, is solved \
             without those motions",
            free.join(", ")
        );
    }
    match i.contact() {
        Some(c) => put!(
            "contact     {}: {} friction nodes ({} left out: tangential motion fixed), eps = {}",
            c.names(),
            c.len(),
            c.excluded.len(),
            // One ε, or each surface's where they differ.
            if case.contact.iter().all(|s| s.eps == c.law.eps) {
                format!("{:e}", c.law.eps)
            } else {
                let each: Vec<String> = case
                    .contact
                    .iter()
                    .map(|s| format!("{:e}", s.eps))
                    .collect();
                each.join(" / ")
            }
        ),
        None => put!("contact     none (no friction code runs)"),
    }
    if let Some(c) = i.contact().filter(|c| c.is_compliant()) {
        put!(
            "foundation  {} of them on a compliant foundation (law = \"compliance\"); {}",
            c.compliance.len(),
            if i.is_explicit() {
                "dt_crit below includes its springs"
            } else {
                "each step solves its normal and friction forces together (Newton)"
            }
        );
    }
    if let Some(why) = friction_off(case, i).filter(|_| i.contact().is_some()) {
        put!("friction    off: {why}; the steps run no friction code");
    }
    // The explicit integrator computed it already (by its own K·x);
    // Newmark's did not.
    // Quasi-static increments have no inertia: no critical step, no
    // vibration to resolve.
    let quasi_static = case.time.scheme == case::Scheme::QuasiStatic;
    let crit = i.dt_crit().unwrap_or_else(|| {
        stickslip_time::stability::critical_step(&p.model.stiffness, &p.model.lumped_mass)
    });
    let damped = case.material.damping.is_some_and(|d| d.beta > 0.0) && i.is_explicit();
    if !quasi_static {
        put!(
            "dt_crit     {crit:.6e} (central difference, lumped mass: {})",
            if damped {
                "(2/omega_max)(sqrt(1+xi^2) - xi), xi = beta omega_max/2"
            } else {
                "2/omega_max"
            }
        );
    }
    // As the integrator counts: a last step within 1e-6 Δt of t_end is
    // not a step of its own.
    let steps = (case.time.t_end / case.time.dt - 1e-6).ceil().max(1.0);
    if i.is_explicit() {
        // A preload (a constant load, nonzero prescribed displacements)
        // puts the initial state at r₀ = K⁻¹ R(0⁻): one factorization of
        // K, the only one of the run; else r₀ = 0 and there is none.
        let preloaded = i.displacement().iter().any(|&x| x != 0.0);
        put!(
            "solver      explicit: {}; {}; K·x by {}",
            if preloaded {
                format!(
                    "no linear system per step (the preloaded initial state by one sparse Cholesky (faer, {}) of K)",
                    p.model.fill_order.name()
                )
            } else {
                "no linear system".to_string()
            },
            if i.friction() {
                "friction solved node by node in closed form"
            } else {
                "no friction"
            },
            i.stiffness_product()
        );
    } else if i.implicit_solver() == ImplicitSolver::Direct {
        put!(
            "solver      implicit Newmark: sparse Cholesky (faer, {}) of A₀ + C, analysed once, refactorized when dt or the stuck set changes; nnz(K) = {}; K·x by {}",
            p.model.fill_order.name(),
            p.model.stiffness.nnz(),
            i.stiffness_product()
        );
    } else if quasi_static {
        let n_c = i.contact().map_or(0, |c| c.len());
        put!(
            "solver      quasi-static increments (no inertia): sparse Cholesky (faer, {}) of dt·K, analysed once, factorized once per distinct dt; friction on the {n_c} contact unknowns by the Schur complement; nnz(K) = {}",
            p.model.fill_order.name(),
            p.model.stiffness.nnz(),
        );
    } else {
        let friction = match i.contact().filter(|_| i.friction()) {
            Some(c) => format!(
                "friction on the {} contact unknowns by the Schur complement",
                c.len()
            ),
            None => "no friction".to_string(),
        };
        put!(
            "solver      implicit Newmark: sparse Cholesky (faer, {}) of A₀, analysed once, factorized once per distinct dt; {friction}; nnz(K) = {}; K·x by {}",
            p.model.fill_order.name(),
            p.model.stiffness.nnz(),
            i.stiffness_product()
        );
    }
    put!(
        "steps       about {steps} to t_end = {} with dt = {:e}",
        case.time.t_end,
        case.time.dt
    );
    if !i.is_explicit() && !quasi_static {
        // Stability is no guide for an implicit step: say what it resolves.
        put!(
            "accuracy    Newmark is stable at any dt, but follows a vibration only when its period spans \
             about 10 steps or more: here periods above {:.3e}; the mesh's shortest is {:.3e} (pi dt_crit)",
            10.0 * case.time.dt,
            std::f64::consts::PI * crit
        );
    }
    let size = output_size(
        case,
        p.mesh.nodes.len(),
        i.contact().map_or(0, |c| c.len()),
        p.model.dofs.n_free(),
    );
    put!(
        "output      {}: about {} frames of u, v, a ({}) and {} rows of histories (time, energy, contact), {}",
        case.output.file.display(),
        size.frames,
        Schedule::new(case.output.fields(), case.time.t_end).describe(),
        size.rows,
        human_bytes(size.bytes)
    );
    if let Some(free) = size.short_of_room(&case.output.file, true) {
        put!(
            "warning     with the {} a run keeps free while it writes, that needs more than the {} free on its disk: `run` refuses it; write fewer frames (output.frames, output.interval, output.every) or elsewhere (-o)",
            human_bytes(size.kept),
            human_bytes(free as f64)
        );
    }
    // The integrator holds the initial state already (the static solve of
    // Remark 4.1 ran in its setup): the run's warning, before the run.
    let mut u = vec![0.0; 2 * p.mesh.nodes.len()];
    p.model.dofs.expand(i.displacement(), &mut u);
    for w in setup_warnings(case, &p.mesh, &p.model.dofs, &u, i) {
        put!("warning     {w}");
    }
    Ok(report)
}
