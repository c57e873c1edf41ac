//! The paper's cases as users run them: each case file read and built by
//! stickslip-case (the reader and builder of `stickslip run`), a fault
//! injected into what it built where asked, and a run recorder that keeps
//! the time histories the checks and figures use. The single-DOF friction
//! oscillator is the test kit's `stickslip_testkit::sdof`.

use std::path::{Path, PathBuf};

use stickslip_case::Scene;
use stickslip_time::{Energy, Integrator, MassKind, Scheme, Settings};

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

    /// Applies the defect to a built scene.
    pub fn inject(self, scene: &mut Scene) {
        match self {
            Fault::FrictionSign => {
                if let Some(c) = &mut scene.contact {
                    for n in &mut c.nodes {
                        n.bound = -n.bound;
                    }
                }
            }
            Fault::NoRemark42 => scene.settings.iteration.remark_4_2 = false,
            Fault::WrongMass => match scene.settings.scheme {
                Scheme::CentralDifference => {
                    let m = scene
                        .model
                        .mass
                        .as_ref()
                        .expect("case::assemble builds the consistent mass");
                    for (i, row) in m.row_iter().enumerate() {
                        let d = row
                            .col_indices()
                            .iter()
                            .zip(row.values())
                            .find(|(c, _)| **c == i)
                            .map_or(0.0, |(_, v)| *v);
                        scene.model.lumped_mass[i] = d;
                    }
                }
                Scheme::Newmark { .. } => scene.settings.mass = Some(MassKind::Lumped),
                Scheme::QuasiStatic => {}
            },
        }
    }
}

/// A case file of the paper's, as loaded.
#[derive(Clone, Debug)]
pub struct PaperCase {
    /// File stem, e.g. `cd-step-eps1e-4`.
    pub name: String,
    /// The case.
    pub case: stickslip_case::Case,
}

impl PaperCase {
    /// Reads a case file.
    ///
    /// # Errors
    /// The case reader's message (file, line, what is wrong).
    pub fn read(path: &Path) -> Result<PaperCase, String> {
        let case = stickslip_case::load(path, &[]).map_err(|e| e.to_string())?;
        Ok(PaperCase {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            case,
        })
    }

    /// Every `*.toml` in `dir`, sorted by name.
    ///
    /// # Errors
    /// An unreadable directory or case.
    pub fn read_dir(dir: &Path) -> Result<Vec<PaperCase>, String> {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        paths.sort();
        paths.iter().map(|p| PaperCase::read(p)).collect()
    }

    /// The time crate's settings the case runs with.
    pub fn settings(&self) -> Settings {
        stickslip_case::settings(&self.case)
    }

    /// The friction law's ε.
    pub fn eps(&self) -> f64 {
        self.case.contact.first().map_or(f64::NAN, |c| c.eps)
    }

    /// True for a Heaviside end load (the H(t) runs), false for sin.
    pub fn is_step(&self) -> bool {
        self.case
            .traction
            .iter()
            .all(|t| t.history == stickslip_case::History::Step)
    }

    /// The case built as `stickslip run` builds it.
    ///
    /// # Errors
    /// The builder's message, naming the case.
    pub fn scene(&self) -> Result<Scene, String> {
        stickslip_case::assemble(&self.case).map_err(|e| format!("case {}: {e}", self.name))
    }
}

/// Mesh node at (x, y).
fn node_at(scene: &Scene, x: f64, y: f64) -> Option<usize> {
    scene
        .mesh
        .nodes
        .iter()
        .position(|p| (p[0] - x).abs() < 1e-9 && (p[1] - y).abs() < 1e-9)
}

/// Runs a slab scene to t_end, recording the paper's quantities every
/// step. Settings refused by the integrator or a failed step end the trace
/// early with [`Trace::error`] set.
pub fn run(scene: &Scene) -> Trace {
    let n81 = node_at(scene, 8.0, 0.0).expect("the slab has node 81 at (8, 0)");
    let n85 = node_at(scene, 8.0, 1.0).expect("the slab has node 85 at (8, 1)");
    let n71 = node_at(scene, 7.0, 0.0).expect("the slab has node 71 at (7, 0)");
    let contact = scene.contact.as_ref().expect("a slab scene has Γ_C");
    let idx = |n: usize| contact.nodes.iter().position(|c| c.node == n);
    let (c71, c81) = (idx(n71).expect("71 on Γ_C"), idx(n81).expect("81 on Γ_C"));
    let d81 = scene.model.dofs.free(n81, 0).expect("u_x(81) free");
    let d85 = scene.model.dofs.free(n85, 0).expect("u_x(85) free");
    let mut trace = Trace {
        contact_x: contact
            .nodes
            .iter()
            .map(|c| scene.mesh.nodes[c.node][0])
            .collect(),
        normal_dt: scene.settings.dt,
        ..Trace::default()
    };
    let mut integ = match scene.integrator() {
        Ok(i) => i,
        Err(e) => {
            trace.error = Some(e.to_string());
            return trace;
        }
    };
    trace.mass = integ.mass_kind();
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

/// A case on the paper's mesh (Q2 8×2, E = 1000, ν = 0.3, ρ = 1):
/// `material` adds lines to its `[material]`, `rest` holds its supports,
/// loads and contact, `time` the lines of its `[time]`.
pub fn paper_slab(root: &Path, material: &str, rest: &str, time: &str) -> String {
    format!(
        "[mesh]\nfile = \"{}\"\n[material]\nE = 1000.0\nnu = 0.3\nrho = 1.0\n{material}{rest}\n\
         [time]\n{time}",
        root.join("cases/meshes/slab-q2-8x2.msh").display()
    )
}

/// The integrator of case text `text`, read as if from `root/name` (the
/// path only names it in messages).
pub fn integrator_of(root: &Path, name: &str, text: &str) -> Result<Integrator, String> {
    let path = root.join(name);
    let case = stickslip_case::load_str(&path, text, &[]).map_err(|e| e.to_string())?;
    let scene = stickslip_case::assemble(&case).map_err(|e| e.to_string())?;
    scene.integrator().map_err(|e| e.to_string())
}
