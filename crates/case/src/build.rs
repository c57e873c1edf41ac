//! From a validated case to what runs it: the mesh, the model (DOF map, K,
//! M, lumped M), the loads, the contact surface, the settings and the
//! integrator. Every problem the mesh reveals (a group it lacks, a group of
//! the wrong dimension, a free rigid-body motion, Δt above the critical
//! step, ...) is an [`InputError`] naming the case file and the line of the
//! key concerned, all of them reported together where they are found in
//! one pass.

use stickslip_contact::{ContactSurface, IterationOptions};
use stickslip_fem::{
    body_force_load, traction_load, Dirichlet, DofMap, Hypothesis as FemHypothesis, Material,
    Model, SetupTimes, Traction,
};
use stickslip_mesh::Mesh;
use stickslip_time::{
    Dynamics, ExplicitFriction, History as TimeHistory, ImplicitSolver, InitialState as TimeStart,
    Integrator, Load, MassKind as TimeMass, Rayleigh, Scheme as TimeScheme, Settings,
    StickReduction as TimeReduction, TimeError,
};

use crate::error::{listed, InputError};
use crate::schema::{Case, History, Hypothesis, InitialState, MassKind, Scheme};

/// A case assembled: everything the integrator is built from, each part
/// open to change before it is (`verify` injects its faults here).
#[derive(Debug)]
pub struct Scene {
    /// The mesh.
    pub mesh: Mesh,
    /// K, M (where assembled: [`assemble_for_run`]), lumped M, DOF map.
    pub model: Model,
    /// The friction nodes of the case's surfaces, if it has any.
    pub contact: Option<ContactSurface>,
    /// Each contact surface's pressure history, in case order
    /// ([`Integrator::set_pressure_histories`]).
    pub pressure_histories: Vec<TimeHistory>,
    /// Each contact surface's foundation history, in case order
    /// ([`Integrator::set_foundation_histories`]).
    pub foundation_histories: Vec<TimeHistory>,
    /// The tractions in case order, then the body force, then each contact
    /// surface's pressure, each restricted to the free DOFs.
    pub loads: Vec<Load>,
    /// Scheme, Δt, mass, iteration, step reduction.
    pub settings: Settings,
    /// How long the mesh read, the model's parts and the loads took.
    pub setup: SetupTimes,
}

/// A case turned into the objects that run it, with the model kept for
/// inspection (`check`, `advise`, the pilots).
#[derive(Debug)]
pub struct Prepared {
    /// The mesh.
    pub mesh: Mesh,
    /// K, M, lumped M, DOF map.
    pub model: Model,
    /// The integrator at t = 0 (initial state computed).
    pub integrator: Integrator,
}

/// A case turned into the objects that run it, for a run: K and M (where
/// assembled) have moved into the integrator (a copy left in a model would
/// be held for the whole run, 24 bytes per stored entry of K beside the
/// step's own data).
#[derive(Debug)]
pub struct Running {
    /// The mesh.
    pub mesh: Mesh,
    /// The DOF map of the integrator's free DOFs.
    pub dofs: DofMap,
    /// The integrator at t = 0 (initial state computed).
    pub integrator: Integrator,
    /// How long the setup's parts took: the scene's, then the
    /// integrator's ([`Integrator::setup_times`]).
    pub setup: SetupTimes,
}

/// [`assemble`] and the integrator, the model kept.
///
/// # Errors
/// Every input problem found, as one [`InputError`].
pub fn prepare(case: &Case) -> Result<Prepared, InputError> {
    assemble(case)?.prepared(case)
}

impl Scene {
    /// The integrator of this scene, its K and M copied (the scene can
    /// build another).
    ///
    /// # Errors
    /// The settings refused (Δt above the critical step, a mass the scheme
    /// cannot take), or the initial static solve failed.
    pub fn integrator(&self) -> Result<Integrator, TimeError> {
        let dynamics = Dynamics::from_model(&self.model);
        let mut i = Integrator::new(
            dynamics,
            self.contact.clone(),
            self.loads.clone(),
            self.settings.clone(),
        )?;
        i.set_pressure_histories(&self.pressure_histories)?;
        i.set_foundation_histories(&self.foundation_histories)?;
        Ok(i)
    }

    /// The integrator, the model kept.
    ///
    /// # Errors
    /// As [`Scene::integrator`], located in `case`.
    pub fn prepared(self, case: &Case) -> Result<Prepared, InputError> {
        let dynamics = Dynamics::from_model(&self.model);
        let mut integrator = Integrator::new(dynamics, self.contact, self.loads, self.settings)
            .map_err(|e| refused(case, e))?;
        integrator
            .set_pressure_histories(&self.pressure_histories)
            .and_then(|()| integrator.set_foundation_histories(&self.foundation_histories))
            .map_err(|e| refused(case, e))?;
        Ok(Prepared {
            mesh: self.mesh,
            model: self.model,
            integrator,
        })
    }

    /// The integrator, K and M moved into it.
    ///
    /// # Errors
    /// As [`Scene::prepared`].
    pub fn running(self, case: &Case) -> Result<Running, InputError> {
        let dofs = self.model.dofs.clone();
        let dynamics = Dynamics::from_model_owned(self.model);
        let mut integrator = Integrator::new(dynamics, self.contact, self.loads, self.settings)
            .map_err(|e| refused(case, e))?;
        integrator
            .set_pressure_histories(&self.pressure_histories)
            .and_then(|()| integrator.set_foundation_histories(&self.foundation_histories))
            .map_err(|e| refused(case, e))?;
        let mut setup = self.setup;
        setup.extend(integrator.setup_times());
        Ok(Running {
            mesh: self.mesh,
            dofs,
            integrator,
            setup,
        })
    }
}

/// The integrator's refusal, at the key it concerns and under its table.
fn refused(case: &Case, e: TimeError) -> InputError {
    let at = |key: &'static str| case.locations.contains_key(key).then_some(key);
    let (key, table) = match e {
        TimeError::Unstable { .. } => ("time.dt", "[time]"),
        // Damping that made a stable Δt unstable is to blame, not Δt.
        TimeError::UnstableDamped { dt, undamped, .. } if dt <= undamped => (
            at("material.damping.beta").unwrap_or("material.damping"),
            "[material]",
        ),
        TimeError::UnstableDamped { .. } => ("time.dt", "[time]"),
        TimeError::Static(_) => ("dirichlet.0.group", "[time]"),
        TimeError::Unbalanced(_) => {
            // The loads before t = 0 are to blame where no [initial] or
            // [[dirichlet]] is written: the first surface's pressure.
            let pressure = case.contact_key(0, "pressure");
            let (key, table) = match (at("initial.state"), at("dirichlet.0.group")) {
                (Some(key), _) => (key.to_string(), "[initial]: "),
                (None, Some(key)) => (key.to_string(), "[[dirichlet]]: "),
                _ if case.locations.contains_key(&pressure) => (pressure, "[contact]: "),
                _ => (String::new(), ""),
            };
            return InputError(format!("{}{table}{e}", case.at(&key)));
        }
        _ => ("time.scheme", "[time]"),
    };
    InputError(format!("{}{table}: {e}", case.at(key)))
}

/// The time crate's copy of a load history.
fn history(h: &History) -> TimeHistory {
    match h {
        History::Constant => TimeHistory::Constant,
        History::Step => TimeHistory::Step,
        History::Sin { omega } => TimeHistory::Sin { omega: *omega },
        History::Table(points) => TimeHistory::Table(points.iter().map(|p| (p[0], p[1])).collect()),
    }
}

/// The time crate's settings of a case.
pub fn settings(case: &Case) -> Settings {
    let scheme = match case.time.scheme {
        Scheme::CentralDifference => TimeScheme::CentralDifference,
        Scheme::Newmark => TimeScheme::Newmark {
            beta: case.time.beta,
            gamma: case.time.gamma,
        },
        Scheme::QuasiStatic => TimeScheme::QuasiStatic,
    };
    Settings {
        scheme,
        mass: case.time.mass.map(|m| match m {
            MassKind::Consistent => TimeMass::Consistent,
            MassKind::Lumped => TimeMass::Lumped,
        }),
        dt: case.time.dt,
        t_end: case.time.t_end,
        stick_reduction: case.time.stick_reduction.as_ref().map(|r| TimeReduction {
            dt: r.dt,
            steps: r.steps,
        }),
        iteration: case
            .contact
            .first()
            .map_or_else(IterationOptions::default, |c| IterationOptions {
                remark_4_2: c.remark_4_2,
                max_iterations: c.max_iterations,
            }),
        allow_unstable: case.time.allow_unstable,
        explicit_friction: ExplicitFriction::ClosedForm,
        initial_state: match case.initial.state {
            InitialState::Static => TimeStart::Static,
            InitialState::Rest => TimeStart::Rest,
        },
        // Needs the mesh: `assemble` fills it in.
        initial_velocity: None,
        damping: case
            .material
            .damping
            .map_or_else(Rayleigh::default, |d| Rayleigh {
                alpha: d.alpha,
                beta: d.beta,
            }),
        implicit_solver: ImplicitSolver::Schur,
        restoring: false,
    }
}

/// Checks a group the case names against the mesh: it exists (else the
/// message lists the mesh's groups), when `dim` is given has that
/// dimension, has elements, and (a line group) lies on the boundary.
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
            // Gmsh writes a physical group whose entities are missing
            // (`Physical Curve("load") = {7};` without a curve 7) as a name
            // without elements: a load or support there acts on nothing.
            _ if g.elements == 0 => {
                problems.push(format!(
                    "{}{key} = {name:?}: the physical group {name:?} has no elements in the mesh {}, \
                     so {purpose} there would act on nothing; {} (Gmsh keeps a group whose entities \
                     are missing, empty) and mesh again",
                    case.at(key),
                    case.mesh.file.display(),
                    g.empty_remedy()
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

/// Reads the mesh and builds the model, the loads, the contact surface,
/// and the settings. The
/// integrator is not built yet: [`Scene::prepared`], [`Scene::running`].
///
/// # Errors
/// Every input problem found, as one [`InputError`].
pub fn assemble(case: &Case) -> Result<Scene, InputError> {
    assemble_with(case, true)
}

/// [`assemble`] for a run of the case's own scheme: the consistent mass
/// only where that scheme reads it (Newmark with `time.mass` consistent,
/// its default), so that a central-difference or quasi-static run neither
/// assembles nor holds it. The scene then serves that scheme only: an
/// integrator of Newmark with the consistent mass refuses it.
///
/// # Errors
/// As [`assemble`].
pub fn assemble_for_run(case: &Case) -> Result<Scene, InputError> {
    let consistent =
        case.time.scheme == Scheme::Newmark && case.time.mass != Some(MassKind::Lumped);
    assemble_with(case, consistent)
}

/// [`assemble`], the consistent mass only `with_mass`.
fn assemble_with(case: &Case, with_mass: bool) -> Result<Scene, InputError> {
    let mut setup = SetupTimes::default();
    let mesh = setup
        .time("mesh read", || Mesh::from_file(&case.mesh.file))
        .map_err(|e| InputError(format!("{}{e}", case.at("mesh.file"))))?;
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
    for (i, c) in case.contact.iter().enumerate() {
        groups_ok &= check_group(
            &mesh,
            case,
            &case.contact_key(i, "group"),
            &c.group,
            Some(1),
            "the contact surface",
            &mut problems,
        );
    }

    for (i, v) in case.initial.velocities.iter().enumerate() {
        groups_ok &= check_group(
            &mesh,
            case,
            &format!("initial.velocities.{i}.group"),
            &v.group,
            None,
            "an initial velocity",
            &mut problems,
        );
    }

    let hypothesis = match case.material.hypothesis {
        Hypothesis::PlaneStrain => FemHypothesis::PlaneStrain,
        Hypothesis::PlaneStress => FemHypothesis::PlaneStress,
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
        (Some(material), true) => match if with_mass {
            Model::new(&mesh, material, &conditions)
        } else {
            Model::without_consistent_mass(&mesh, material, &conditions)
        } {
            Ok(m) => Some(m),
            Err(e) => {
                problems.push(format!("{dirichlet_at}[[dirichlet]]: {e}"));
                None
            }
        },
        _ => None,
    };
    if let Some(m) = &model {
        // A part's free rigid motions are the integrator's to handle (the
        // static preload on their complement, or a start at rest); a node
        // of no cell has no stiffness at all, and nothing can hold it.
        // Quasi-static increments factorize Δt K, and neither friction nor
        // a compliant foundation stands in for a support there.
        let free = m.dofs.free_rigid_motions();
        let quasi_static = case.time.scheme == Scheme::QuasiStatic;
        let refused: Vec<&String> = free
            .iter()
            .filter(|l| quasi_static || l.contains("belongs to no cell"))
            .collect();
        if quasi_static && !refused.is_empty() {
            problems.push(format!(
                "{dirichlet_at}the supports leave a rigid-body motion free for the initial static solve \
                 and for the quasi-static increments, each of which factorizes dt K, singular along it \
                 (neither friction nor a compliant foundation holds a body without supports): {}; \
                 add [[dirichlet]] conditions that prevent it (e.g. uy = 0 on a bottom or top group and ux = 0 on an end)",
                refused.iter().map(|l| l.as_str()).collect::<Vec<_>>().join(", ")
            ));
        } else if !refused.is_empty() {
            problems.push(format!(
                "{dirichlet_at}{}; add [[dirichlet]] conditions that hold it, or remove it from the mesh",
                refused.iter().map(|l| l.as_str()).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    let (Some(model), Some(_)) = (model.filter(|_| groups_ok && problems.is_empty()), material)
    else {
        return Err(InputError(listed(problems)));
    };

    setup.extend(&model.setup);
    let loads_started = std::time::Instant::now();
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
            history: TimeHistory::Constant,
        });
    }
    let surfaces =
        crate::surfaces::surfaces(case, &mesh, &model.dofs, &restrict, history, &mut problems);
    loads.extend(surfaces.loads);
    if !problems.is_empty() {
        return Err(InputError(listed(problems)));
    }
    let mut settings = settings(case);
    settings.initial_velocity = initial_velocity(case, &mesh, &model.dofs);
    setup.add("loads", loads_started.elapsed().as_secs_f64());
    Ok(Scene {
        mesh,
        model,
        contact: surfaces.contact,
        pressure_histories: surfaces.histories,
        foundation_histories: surfaces.foundation_histories,
        loads,
        settings,
        setup,
    })
}

/// ṙ₀ on the free DOFs from `[initial]`: `velocity` at every node, then
/// each `[[initial.velocities]]` entry on its group's nodes, in case order
/// (the groups are checked against the mesh already). `None` when the case
/// gives no velocity, so that a run without one stays as it was.
fn initial_velocity(case: &Case, mesh: &Mesh, dofs: &DofMap) -> Option<Vec<f64>> {
    let initial = &case.initial;
    if initial.velocity.is_none() && initial.velocities.is_empty() {
        return None;
    }
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    if let Some(v) = initial.velocity {
        for node in full.chunks_exact_mut(2) {
            node.copy_from_slice(&v);
        }
    }
    for entry in &initial.velocities {
        if let Ok(group) = mesh.group(&entry.group) {
            for &node in &group.nodes {
                full[2 * node..2 * node + 2].copy_from_slice(&entry.velocity);
            }
        }
    }
    let mut free = vec![0.0; dofs.n_free()];
    dofs.restrict(&full, &mut free);
    Some(free)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's slab on the committed Q2 8×2 mesh with `extra` TOML
    /// appended, loaded from a scratch directory.
    fn slab_case(name: &str, extra: &str) -> Case {
        slab_case_text(name, extra).0
    }

    /// 1-based line of the first line of `text` holding `needle`.
    fn line_of(text: &str, needle: &str) -> usize {
        text.lines()
            .position(|l| l.contains(needle))
            .expect("needle")
            + 1
    }

    /// [`slab_case`] and its text.
    fn slab_case_text(name: &str, extra: &str) -> (Case, String) {
        let mesh = stickslip_testkit::meshes_dir().join("slab-q2-8x2.msh");
        let text = format!(
            r#"[mesh]
file = "{}"
[material]
E = 1000
nu = 0.3
rho = 1.0
[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[contact]
group = "contact"
pressure = 300.0
mu = 0.3
eps = 1e-4
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.5
{extra}"#,
            mesh.display().to_string().replace('\\', "/")
        );
        let path = stickslip_testkit::scratch(&format!("build-{name}")).join("case.toml");
        std::fs::write(&path, &text).unwrap();
        (crate::load(&path, &[]).unwrap(), text)
    }

    /// `velocity` sets every node, a group's entry its own nodes; held
    /// DOFs have none (the left end's u_x, the top's u_y).
    #[test]
    fn initial_velocities_go_to_their_nodes() {
        let case = slab_case(
            "velocities",
            "[initial]\nstate = \"rest\"\nvelocity = [0.5, 0.25]\n\
             [[initial.velocities]]\ngroup = \"contact\"\nvelocity = [1.0, -2.0]\n",
        );
        let scene = assemble(&case).unwrap();
        assert_eq!(scene.settings.initial_state, TimeStart::Rest);
        let v = scene.settings.initial_velocity.as_ref().unwrap();
        let contact = scene.mesh.group("contact").unwrap().nodes.clone();
        let dofs = &scene.model.dofs;
        let mut seen = [false; 2];
        for node in 0..scene.mesh.nodes.len() {
            let on_contact = contact.binary_search(&node).is_ok();
            let want = if on_contact { [1.0, -2.0] } else { [0.5, 0.25] };
            for c in 0..2 {
                if let Some(i) = dofs.free(node, c) {
                    assert_eq!(v[i], want[c], "node {node} component {c}");
                    seen[usize::from(on_contact)] = true;
                }
            }
        }
        assert_eq!(seen, [true, true]);
    }

    /// Without an `[initial]` velocity the settings carry none (the run's
    /// bits are those of a case without the section).
    #[test]
    fn no_initial_section_no_velocity() {
        let scene = assemble(&slab_case("none", "")).unwrap();
        assert_eq!(scene.settings.initial_state, TimeStart::Static);
        assert!(scene.settings.initial_velocity.is_none());
    }

    /// An unknown group and a velocity of the wrong length are refused at
    /// their lines.
    #[test]
    fn bad_initial_velocities_name_their_lines() {
        let (case, text) = slab_case_text(
            "unknown-group",
            "[[initial.velocities]]\ngroup = \"nowhere\"\nvelocity = [1.0, 0.0]\n",
        );
        let e = assemble(&case).unwrap_err().0;
        let at = format!("case.toml:{}:", line_of(&text, "\"nowhere\""));
        assert!(
            e.contains(&at) && e.contains("no physical group \"nowhere\""),
            "{e}"
        );
        let mesh = stickslip_testkit::meshes_dir().join("slab-q2-8x2.msh");
        let path = stickslip_testkit::scratch("build-length").join("case.toml");
        let text = format!(
            "[mesh]\nfile = \"{}\"\n[material]\nE = 1000\nnu = 0.3\nrho = 1.0\n\
             [time]\nscheme = \"central_difference\"\ndt = 1e-3\nt_end = 0.5\n\
             [initial]\nvelocity = [1.0, 0.0, 2.0]\n",
            mesh.display().to_string().replace('\\', "/")
        );
        std::fs::write(&path, &text).unwrap();
        let e = crate::load(&path, &[]).unwrap_err().0;
        let at = format!("case.toml:{}:", line_of(&text, "[1.0, 0.0, 2.0]"));
        assert!(
            e.contains(&at) && e.contains("a vector of two numbers"),
            "{e}"
        );
    }
}
