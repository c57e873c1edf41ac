//! Scenes to run in-process: the paper's cases read from their TOML files
//! (the few keys the slab needs) and assembled by
//! `stickslip_time::scenes::Slab`, and a run recorder that keeps the time
//! histories the checks and figures use. The single-DOF friction oscillator
//! is `stickslip_time::scenes::sdof`.

use std::path::{Path, PathBuf};

use stickslip_contact::ContactSurface;
use stickslip_fem::{Dirichlet, Hypothesis, Material, Model, Traction};
use stickslip_mesh::Mesh;
use stickslip_time::scenes::{Slab, TractionLoad};
use stickslip_time::{
    Dynamics, Energy, History, Integrator, Load, MassKind, Scheme, Settings, StickReduction,
};

/// A deliberate defect, injected to show that `verify` catches it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// The friction bound negated on every contact node: friction pushes
    /// along the slip instead of against it.
    FrictionSign,
    /// The stick/slip iteration without Remark 4.2.
    NoRemark42,
    /// Central difference given a mass other than the HRZ lumped one (the
    /// consistent mass's diagonal, unscaled) and Newmark the lumped mass
    /// instead of the consistent one: the mass does not match the scheme.
    WrongMass,
}

impl Fault {
    /// Parses the `--fault` option.
    pub fn parse(s: &str) -> Result<Fault, String> {
        match s {
            "friction-sign" => Ok(Fault::FrictionSign),
            "no-remark-4-2" => Ok(Fault::NoRemark42),
            "wrong-mass" => Ok(Fault::WrongMass),
            _ => Err(format!(
                "--fault {s:?}: expected friction-sign, no-remark-4-2 or wrong-mass"
            )),
        }
    }
}

/// The parts of a case file the slab scenes need.
#[derive(Clone, Debug)]
pub struct Case {
    /// File stem, e.g. `cd-step-eps1e-4`.
    pub name: String,
    /// The mesh file, resolved against the case's directory.
    pub mesh_file: PathBuf,
    /// E, ν, ρ (plane strain).
    pub material: [f64; 3],
    /// (group, component, value).
    pub dirichlet: Vec<(String, usize, f64)>,
    /// (group, traction vector, history).
    pub tractions: Vec<(String, [f64; 2], History)>,
    /// Contact group, pressure F_n, μ, ε.
    pub contact: (String, f64, f64, f64),
    /// Time settings.
    pub settings: Settings,
}

fn key<'a>(t: &'a toml::Table, path: &str, file: &Path) -> Result<&'a toml::Value, String> {
    let mut cur = t;
    let parts: Vec<&str> = path.split('.').collect();
    for (i, p) in parts.iter().enumerate() {
        let v = cur
            .get(*p)
            .ok_or_else(|| format!("{}: missing key `{path}`", file.display()))?;
        if i + 1 == parts.len() {
            return Ok(v);
        }
        cur = v
            .as_table()
            .ok_or_else(|| format!("{}: `{path}`: `{p}` is not a table", file.display()))?;
    }
    unreachable!("a path has at least one part")
}

fn float(v: &toml::Value, what: &str, file: &Path) -> Result<f64, String> {
    v.as_float()
        .or_else(|| v.as_integer().map(|i| i as f64))
        .ok_or_else(|| format!("{}: `{what}` must be a number", file.display()))
}

fn history(v: Option<&toml::Value>, file: &Path) -> Result<History, String> {
    match v {
        None => Ok(History::Step),
        Some(toml::Value::String(s)) => match s.as_str() {
            "step" => Ok(History::Step),
            "constant" => Ok(History::Constant),
            other => Err(format!(
                "{}: history {other:?}: this tool reads \"step\", \"constant\" or {{ sin = {{ omega }} }}",
                file.display()
            )),
        },
        Some(toml::Value::Table(t)) => {
            let omega = t
                .get("sin")
                .and_then(|s| s.get("omega"))
                .ok_or_else(|| format!("{}: history table without sin.omega", file.display()))?;
            Ok(History::Sin {
                omega: float(omega, "history.sin.omega", file)?,
            })
        }
        Some(_) => Err(format!("{}: history of an unknown form", file.display())),
    }
}

/// The entries of the array of tables `name` (none when absent), each with
/// its `group`.
fn grouped_tables<'a>(
    t: &'a toml::Table,
    name: &str,
    file: &Path,
) -> impl Iterator<Item = Result<(&'a toml::Value, &'a str), String>> + 'a {
    let (name, file) = (name.to_string(), file.to_path_buf());
    t.get(&name)
        .and_then(|v| v.as_array())
        .into_iter()
        .flatten()
        .map(move |d| {
            let group = d
                .get("group")
                .and_then(|g| g.as_str())
                .ok_or_else(|| format!("{}: {name} without group", file.display()))?;
            Ok((d, group))
        })
}

impl Case {
    /// Reads a case file.
    ///
    /// # Errors
    /// Unreadable file, TOML syntax, a missing or mistyped key.
    pub fn read(path: &Path) -> Result<Case, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let t: toml::Table =
            toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mesh = key(&t, "mesh.file", path)?
            .as_str()
            .ok_or_else(|| format!("{}: mesh.file must be a string", path.display()))?;
        let material = [
            float(key(&t, "material.E", path)?, "material.E", path)?,
            float(key(&t, "material.nu", path)?, "material.nu", path)?,
            float(key(&t, "material.rho", path)?, "material.rho", path)?,
        ];
        let mut dirichlet = Vec::new();
        for entry in grouped_tables(&t, "dirichlet", path) {
            let (d, group) = entry?;
            for (c, k) in ["ux", "uy"].iter().enumerate() {
                if let Some(v) = d.get(*k) {
                    dirichlet.push((group.to_string(), c, float(v, k, path)?));
                }
            }
        }
        let mut tractions = Vec::new();
        for entry in grouped_tables(&t, "traction", path) {
            let (d, group) = entry?;
            let v = d
                .get("t")
                .and_then(|v| v.as_array())
                .filter(|a| a.len() == 2)
                .ok_or_else(|| format!("{}: traction.t must be [tx, ty]", path.display()))?;
            tractions.push((
                group.to_string(),
                [float(&v[0], "t", path)?, float(&v[1], "t", path)?],
                history(d.get("history"), path)?,
            ));
        }
        let contact = (
            key(&t, "contact.group", path)?
                .as_str()
                .unwrap_or("contact")
                .to_string(),
            float(key(&t, "contact.pressure", path)?, "contact.pressure", path)?,
            float(key(&t, "contact.mu", path)?, "contact.mu", path)?,
            float(key(&t, "contact.eps", path)?, "contact.eps", path)?,
        );
        let scheme = match key(&t, "time.scheme", path)?.as_str() {
            Some("central_difference") => Scheme::CentralDifference,
            Some("newmark") => Scheme::Newmark {
                beta: float(key(&t, "time.beta", path)?, "time.beta", path)?,
                gamma: float(key(&t, "time.gamma", path)?, "time.gamma", path)?,
            },
            other => return Err(format!("{}: time.scheme {other:?}", path.display())),
        };
        let dt = float(key(&t, "time.dt", path)?, "time.dt", path)?;
        let t_end = float(key(&t, "time.t_end", path)?, "time.t_end", path)?;
        let mut settings = Settings::new(scheme, dt, t_end);
        if let Ok(r) = key(&t, "time.stick_reduction", path) {
            settings.stick_reduction = Some(StickReduction {
                dt: float(
                    r.get("dt")
                        .ok_or_else(|| format!("{}: stick_reduction.dt", path.display()))?,
                    "stick_reduction.dt",
                    path,
                )?,
                steps: r
                    .get("steps")
                    .and_then(|s| s.as_integer())
                    .ok_or_else(|| format!("{}: stick_reduction.steps", path.display()))?
                    as usize,
            });
        }
        Ok(Case {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            mesh_file: dir.join(mesh),
            material,
            dirichlet,
            tractions,
            contact,
            settings,
        })
    }

    /// Every `*.toml` in `dir`, sorted by name.
    ///
    /// # Errors
    /// An unreadable directory or case.
    pub fn read_dir(dir: &Path) -> Result<Vec<Case>, String> {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        paths.sort();
        paths.iter().map(|p| Case::read(p)).collect()
    }

    /// True for a Heaviside end load (the H(t) runs), false for sin.
    pub fn is_step(&self) -> bool {
        self.tractions.iter().all(|t| t.2 == History::Step)
    }
}

/// A slab scene ready to run: the model, Γ_C, loads and settings, each open
/// to change (faults are injected here).
#[derive(Debug)]
pub struct Scene {
    /// The mesh.
    pub mesh: Mesh,
    /// The finite-element model.
    pub model: Model,
    /// The system handed to the integrator.
    pub dynamics: Dynamics,
    /// Γ_C.
    pub contact: Option<ContactSurface>,
    /// Pressure (constant) and end loads.
    pub loads: Vec<Load>,
    /// Time settings.
    pub settings: Settings,
}

impl Scene {
    /// The scene of a case file.
    ///
    /// # Errors
    /// Mesh, model or contact errors, as text naming the case.
    pub fn from_case(case: &Case) -> Result<Scene, String> {
        let ctx = |e: String| format!("case {}: {e}", case.name);
        let mesh = Mesh::from_file(&case.mesh_file).map_err(|e| ctx(e.to_string()))?;
        let [e, nu, rho] = case.material;
        let material =
            Material::new(e, nu, rho, Hypothesis::PlaneStrain).map_err(|e| ctx(e.to_string()))?;
        let conditions: Vec<Dirichlet> = case
            .dirichlet
            .iter()
            .map(|(g, c, v)| Dirichlet::new(g.clone(), *c, *v))
            .collect();
        let (group, pressure, mu, eps) = case.contact.clone();
        // The prescribed normal traction on Γ_C is a load like any other
        // (METHOD.md §3), present before t = 0.
        let mut tractions: Vec<TractionLoad> = vec![(
            group.as_str(),
            Traction::Pressure(pressure),
            History::Constant,
        )];
        for (g, t, h) in &case.tractions {
            tractions.push((g.as_str(), Traction::Vector(*t), h.clone()));
        }
        let slab = Slab::assemble(
            mesh,
            &material,
            &conditions,
            &tractions,
            Some((group.as_str(), pressure, mu, eps)),
        )
        .map_err(|e| ctx(e.to_string()))?;
        Ok(Scene {
            dynamics: Dynamics::from_model(&slab.model),
            mesh: slab.mesh,
            model: slab.model,
            contact: slab.contact,
            loads: slab.loads,
            settings: case.settings.clone(),
        })
    }

    /// Applies a deliberate defect.
    pub fn inject(&mut self, fault: Fault) {
        match fault {
            Fault::FrictionSign => {
                if let Some(c) = &mut self.contact {
                    for n in &mut c.nodes {
                        n.bound = -n.bound;
                    }
                }
            }
            Fault::NoRemark42 => self.settings.iteration.remark_4_2 = false,
            Fault::WrongMass => match self.settings.scheme {
                Scheme::CentralDifference => {
                    let m = &self.dynamics.consistent_mass;
                    for (i, row) in m.row_iter().enumerate() {
                        let d = row
                            .col_indices()
                            .iter()
                            .zip(row.values())
                            .find(|(c, _)| **c == i)
                            .map_or(0.0, |(_, v)| *v);
                        self.dynamics.lumped_mass[i] = d;
                    }
                }
                Scheme::Newmark { .. } => self.settings.mass = Some(MassKind::Lumped),
            },
        }
    }

    /// Mesh node at (x, y).
    pub fn node_at(&self, x: f64, y: f64) -> Option<usize> {
        self.mesh
            .nodes
            .iter()
            .position(|p| (p[0] - x).abs() < 1e-9 && (p[1] - y).abs() < 1e-9)
    }

    /// Runs to t_end, recording the paper's quantities every step. Settings
    /// refused by the integrator or a failed step end the trace early with
    /// [`Trace::error`] set.
    pub fn run(&self) -> Trace {
        let n81 = self
            .node_at(8.0, 0.0)
            .expect("the slab has node 81 at (8, 0)");
        let n85 = self
            .node_at(8.0, 1.0)
            .expect("the slab has node 85 at (8, 1)");
        let n71 = self
            .node_at(7.0, 0.0)
            .expect("the slab has node 71 at (7, 0)");
        let contact = self.contact.as_ref().expect("a slab scene has Γ_C");
        let idx = |n: usize| contact.nodes.iter().position(|c| c.node == n);
        let (c71, c81) = (idx(n71).expect("71 on Γ_C"), idx(n81).expect("81 on Γ_C"));
        let d81 = self.model.dofs.free(n81, 0).expect("u_x(81) free");
        let d85 = self.model.dofs.free(n85, 0).expect("u_x(85) free");
        let mut trace = Trace {
            contact_x: contact
                .nodes
                .iter()
                .map(|c| self.mesh.nodes[c.node][0])
                .collect(),
            normal_dt: self.settings.dt,
            ..Trace::default()
        };
        let mut integ = match Integrator::new(
            self.dynamics.clone(),
            self.contact.clone(),
            self.loads.clone(),
            self.settings.clone(),
        ) {
            Ok(i) => i,
            Err(e) => {
                trace.error = Some(e.to_string());
                return trace;
            }
        };
        trace.mass = Some(integ.mass_kind());
        let mut sigma = vec![0.0; contact.len()];
        let mut slip = vec![0.0; contact.len()];
        let mut record = |i: &Integrator, dt: f64, trace: &mut Trace| {
            i.friction_stress(&mut sigma);
            i.slip_velocity(&mut slip);
            trace.t.push(i.time());
            trace.dt.push(dt);
            trace.ux81.push(i.displacement()[d81]);
            trace.ux85.push(i.displacement()[d85]);
            trace.sigma71.push(sigma[c71]);
            trace.sigma81.push(sigma[c81]);
            trace.v81.push(slip[c81]);
            trace.stuck81.push(i.classes()[c81].is_stuck());
            trace.energy.push(i.energy());
            trace.sigma_all.push(sigma.clone());
        };
        record(&integ, 0.0, &mut trace);
        while !integ.done() {
            match integ.step() {
                Ok(info) => {
                    trace.iterations += info.iterations as u64;
                    record(&integ, info.dt, &mut trace);
                }
                Err(e) => {
                    trace.error = Some(e.to_string());
                    return trace;
                }
            }
        }
        trace
    }
}

/// Time histories of one run; entry 0 is the initial state.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// Times.
    pub t: Vec<f64>,
    /// The step that led to each time (0 for the initial state).
    pub dt: Vec<f64>,
    /// The case's normal Δt.
    pub normal_dt: f64,
    /// u_x at node 81 (8, 0).
    pub ux81: Vec<f64>,
    /// u_x at node 85 (8, 1).
    pub ux85: Vec<f64>,
    /// σ_T at node 71 (7, 0).
    pub sigma71: Vec<f64>,
    /// σ_T at node 81.
    pub sigma81: Vec<f64>,
    /// Tangential velocity at node 81.
    pub v81: Vec<f64>,
    /// Node 81 stuck (|v_T| ≤ ε).
    pub stuck81: Vec<bool>,
    /// The energy ledger.
    pub energy: Vec<Energy>,
    /// σ_T at every friction node (ordered along Γ_C).
    pub sigma_all: Vec<Vec<f64>>,
    /// x of every friction node.
    pub contact_x: Vec<f64>,
    /// Stick/slip iterations in all.
    pub iterations: u64,
    /// The mass the integrator used.
    pub mass: Option<MassKind>,
    /// Why the run stopped before t_end, if it did.
    pub error: Option<String>,
}
