//! `stickslip run` and `stickslip check`: from a validated case to a model,
//! an integrator and the HDF5 results, step by step.
//!
//! Everything that can be refused is refused in [`prepare`], before any
//! time step, as an [`InputError`] (exit code 2). Once stepping starts,
//! every completed output step is in the file; a failure marks the file
//! `complete = false`, records the reason and returns [`Outcome::Failed`].

use std::io::IsTerminal;
use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use stickslip_contact::{ContactSurface, IterationOptions};
use stickslip_fem::{
    body_force_load, traction_load, Dirichlet, Hypothesis as FemHypothesis, Material, Model,
    Traction,
};
use stickslip_mesh::Mesh;
use stickslip_time::{
    Dynamics, ExplicitFriction, History, Integrator, Load, MassKind, Scheme, Settings,
    StickReduction, TimeError,
};

use crate::case::{self, Case};
use crate::error::InputError;
use crate::output::{Header, Record, ResultsWriter, Summary};

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Reached t_end; the file is complete.
    Complete,
    /// Stopped early (iteration cap, non-finite state); the file holds every
    /// completed step and `complete = false`.
    Failed,
}

/// A case turned into the objects that run it.
pub struct Prepared {
    /// The mesh.
    pub mesh: Mesh,
    /// K, M, lumped M, DOF map.
    pub model: Model,
    /// The integrator at t = 0 (initial state computed).
    pub integrator: Integrator,
}

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

/// Builds mesh, model, loads, contact surface and integrator; every problem
/// with the input is an [`InputError`] naming the case file.
///
/// # Errors
/// Input problems (exit 2) as [`InputError`]; nothing else is expected.
pub fn prepare(case: &Case) -> anyhow::Result<Prepared> {
    let case_name = case.path.display().to_string();
    let mesh = Mesh::from_file(&case.mesh.file).map_err(|e| input(format!("{e}")))?;
    let hypothesis = match case.material.hypothesis {
        case::Hypothesis::PlaneStrain => FemHypothesis::PlaneStrain,
        case::Hypothesis::PlaneStress => FemHypothesis::PlaneStress,
    };
    let material = Material::new(
        case.material.e,
        case.material.nu,
        case.material.rho,
        hypothesis,
    )
    .map_err(|e| input(format!("{case_name}: [material]: {e}")))?;
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
    let model = Model::new(&mesh, &material, &conditions)
        .map_err(|e| input(format!("{case_name}: [[dirichlet]]: {e}")))?;
    let n_full = 2 * mesh.nodes.len();
    let n_free = model.dofs.n_free();
    let mut full = vec![0.0; n_full];
    let mut loads = Vec::new();
    let restrict = |full: &[f64]| {
        let mut free = vec![0.0; n_free];
        model.dofs.restrict(full, &mut free);
        free
    };
    for t in &case.traction {
        full.iter_mut().for_each(|x| *x = 0.0);
        let traction = match (t.t, t.pressure) {
            (Some(v), None) => Traction::Vector(v),
            (None, Some(p)) => Traction::Pressure(p),
            _ => {
                return Err(input(format!(
                    "{case_name}: [[traction]] on {:?}: give exactly one of t or pressure",
                    t.group
                )))
            }
        };
        traction_load(&mesh, &t.group, traction, &mut full)
            .map_err(|e| input(format!("{case_name}: [[traction]]: {e}")))?;
        loads.push(Load {
            vector: restrict(&full),
            history: history(&t.history),
        });
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
    let contact = match &case.contact {
        None => None,
        Some(c) => {
            // The prescribed normal traction on Γ_C is a load like any other,
            // present before t = 0 (it makes the initial static state).
            full.iter_mut().for_each(|x| *x = 0.0);
            traction_load(&mesh, &c.group, Traction::Pressure(c.pressure), &mut full)
                .map_err(|e| input(format!("{case_name}: [contact]: {e}")))?;
            loads.push(Load {
                vector: restrict(&full),
                history: History::Constant,
            });
            iteration = IterationOptions {
                remark_4_2: c.remark_4_2,
                max_iterations: c.max_iterations,
            };
            Some(
                ContactSurface::from_group(&mesh, &model.dofs, &c.group, c.pressure, c.mu, c.eps)
                    .map_err(|e| input(format!("{case_name}: [contact]: {e}")))?,
            )
        }
    };
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
    };
    let integrator = Integrator::new(Dynamics::from_model(&model), contact, loads, settings)
        .map_err(|e| input(format!("{case_name}: [time]: {e}")))?;
    Ok(Prepared {
        mesh,
        model,
        integrator,
    })
}

/// `stickslip check`: validate, print the model size, Δt_crit and solver.
///
/// # Errors
/// Input problems as [`InputError`].
pub fn check(case: &Case) -> anyhow::Result<()> {
    let p = prepare(case)?;
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
        "DOFs        {} free of {}",
        p.model.dofs.n_free(),
        2 * p.mesh.nodes.len()
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
    let crit = stickslip_time::stability::critical_step(&p.model.stiffness, &p.model.lumped_mass);
    println!("dt_crit     {crit:.6e} (central difference, lumped mass: 2/omega_max)");
    let steps = (case.time.t_end / case.time.dt).ceil();
    if i.is_explicit() {
        println!(
            "solver      explicit: no linear system; friction solved node by node in closed form"
        );
    } else {
        println!(
            "solver      implicit Newmark: sparse Cholesky (faer, AMD), analysed once, refactorized when dt or the stuck set changes; nnz(K) = {}",
            p.model.stiffness.nnz()
        );
    }
    println!(
        "steps       about {steps} to t_end = {} with dt = {:e}",
        case.time.t_end, case.time.dt
    );
    Ok(())
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
    model: &Model,
    s: &'a mut FullState,
    dt: f64,
    iterations: u32,
) -> Record<'a> {
    model.dofs.expand(i.displacement(), &mut s.u);
    model.dofs.expand_homogeneous(i.velocity(), &mut s.v);
    model.dofs.expand_homogeneous(i.acceleration(), &mut s.a);
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

/// `stickslip run`: integrate to t_end writing every `output.every`-th step.
///
/// # Errors
/// Input problems as [`InputError`]; I/O failures of the results file.
pub fn execute(case: &Case, out: &Path, quiet: bool) -> anyhow::Result<Outcome> {
    let started = Instant::now();
    let Prepared {
        mesh,
        model,
        mut integrator,
    } = prepare(case)?;
    let (contact_nodes, contact_s): (Vec<usize>, Vec<f64>) = integrator
        .contact()
        .map(|c| c.nodes.iter().map(|n| (n.node, n.s)).unzip())
        .unwrap_or_default();
    let n_c = contact_nodes.len();
    let header = Header {
        case_source: &case.source,
        mesh: &mesh,
        contact_nodes: &contact_nodes,
        contact_s: &contact_s,
    };
    let mut writer = ResultsWriter::create(out, &header)
        .with_context(|| format!("cannot create the results file {}", out.display()))?;
    let n_full = 2 * mesh.nodes.len();
    let mut full = FullState {
        u: vec![0.0; n_full],
        v: vec![0.0; n_full],
        a: vec![0.0; n_full],
        stress: vec![0.0; n_c],
        slip: vec![0.0; n_c],
        state: vec![0; n_c],
    };
    writer.append(&record(&integrator, &model, &mut full, 0.0, 0))?;

    let every = case.output.every.max(1) as u64;
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let bar = indicatif::ProgressBar::new(1000);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} t = {msg} ({eta} left)",
            )
            .expect("valid template"),
        );
        bar
    });
    let t_end = integrator.t_end();
    let mut max_balance: f64 = 0.0;
    let mut failure = None;
    while !integrator.done() {
        match integrator.step() {
            Ok(info) => {
                max_balance = max_balance.max(integrator.energy().balance.abs());
                if integrator.steps() % every == 0 || integrator.done() {
                    writer.append(&record(
                        &integrator,
                        &model,
                        &mut full,
                        info.dt,
                        info.iterations as u32,
                    ))?;
                }
                if let Some(bar) = &bar {
                    bar.set_position((1000.0 * integrator.time() / t_end) as u64);
                    bar.set_message(format!("{:.4e}", integrator.time()));
                }
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let summary = Summary {
        wall_time_s: started.elapsed().as_secs_f64(),
        steps: integrator.steps(),
        factorizations: integrator.factorizations(),
        dt_crit: integrator.dt_crit(),
        failure: failure.as_ref().map(|e| e.to_string()),
    };
    let complete = failure.is_none();
    writer.finish(complete, &summary)?;
    if !quiet {
        let e = integrator.energy();
        eprintln!(
            "{} {} steps to t = {:.6} ({} stick/slip iterations, {} factorizations) in {:.3} s",
            if complete { "done:" } else { "stopped:" },
            integrator.steps(),
            integrator.time(),
            integrator.total_iterations(),
            integrator.factorizations(),
            summary.wall_time_s
        );
        eprintln!(
            "energy: total {:.6} (kinetic {:.6}, strain {:.6}, work {:.6}, dissipated {:.6}); largest |balance| {:.3e}",
            e.total, e.kinetic, e.strain, e.external_work, e.dissipated, max_balance
        );
        eprintln!("results: {}", out.display());
    }
    match failure {
        None => Ok(Outcome::Complete),
        Some(e) => {
            eprintln!("error: {}: {e}", case.path.display());
            if matches!(e, TimeError::NonFinite { .. }) {
                eprintln!(
                    "the file keeps every step completed before the failure (complete = false)"
                );
            }
            Ok(Outcome::Failed)
        }
    }
}
