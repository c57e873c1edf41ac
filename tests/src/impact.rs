//! The bar-impact problem of Hughes et al. (1976) on a compliant wall
//! (METHOD.md §10): a strip of length L (ν = 0, its transverse motion held,
//! so a 1-D bar of wave speed c = √(E/ρ)) moving at v₀ touches a rigid wall
//! at t = 0. With a rigid wall the contact lasts 2L/c at the stress ρcv₀
//! and the bar leaves at −v₀; a wall of finite stiffness c_n approaches
//! these as c_n grows.

use stickslip_contact::{Compliance, ContactSurface};
use stickslip_fem::{Dirichlet, Hypothesis, Material, Model};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_time::{Dynamics, InitialState, Integrator, Scheme, Settings, TimeError};

use crate::grid::rectangle;
use crate::scene::SceneError;

/// The bar's length.
pub const L: f64 = 1.0;
/// Its height (one row of cells).
pub const H: f64 = 0.05;
/// The impact speed.
pub const V0: f64 = 0.1;
/// E = ρ = 1: c = 1, so the rigid wall's contact time is 2L and its
/// stress ρcv₀ = v₀.
pub const C: f64 = 1.0;

/// What one run of the bar gave.
#[derive(Clone, Copy, Debug)]
pub struct Impact {
    /// From t = 0 to the last step the wall pushed.
    pub contact_time: f64,
    /// The wall's mean stress over the middle half of the contact, [L/2c,
    /// 3L/2c].
    pub stress: f64,
    /// The bar's mean velocity at the end (t = 3L/c).
    pub exit_velocity: f64,
    /// The ledger's largest |balance| over the initial kinetic energy.
    pub balance: f64,
    /// The explicit critical step the run had (with the wall's springs).
    pub dt_crit: f64,
    /// The largest mechanical energy (kinetic + strain + the wall's) over
    /// the initial kinetic energy: 1 for an exact run.
    pub growth: f64,
}

/// The frictionless linear wall (m_n = 1) of stiffness `cn·E/h` for the
/// bar of `nx` cells (h = L/nx: `cn` is the wall's stiffness relative to
/// a cell's).
pub fn wall(nx: usize, cn: f64) -> Compliance {
    Compliance {
        cn: cn * nx as f64 / L,
        mn: 1.0,
        ct: 0.0,
        mt: 1.0,
    }
}

/// The bar of `nx` Q1 cells, at v₀ and touching the wall x = L at t = 0,
/// its integrators made on demand.
#[derive(Debug)]
pub struct Bar {
    /// The mesh.
    pub mesh: Mesh,
    /// The model (transverse motion held).
    pub model: Model,
    /// The wall's surface.
    pub contact: ContactSurface,
    v0: Vec<f64>,
}

impl Bar {
    /// The bar of `nx` cells against a wall of law `law`.
    ///
    /// # Errors
    /// The scene's.
    pub fn new(nx: usize, law: Compliance) -> Result<Bar, SceneError> {
        let mesh = rectangle(CellKind::Quad4, nx, 1, [0.0, 0.0], [L, H]);
        let material = Material::new(1.0, 0.0, 1.0, Hypothesis::PlaneStrain)?;
        let model = Model::new(&mesh, &material, &[Dirichlet::new("domain", 1, 0.0)])?;
        let wall = ([L, 0.0], [-1.0, 0.0]);
        let contact = ContactSurface::on_foundation(&mesh, &model.dofs, "right", wall, law, 1e-3)?;
        let mut v0 = vec![0.0; model.dofs.n_free()];
        for node in 0..mesh.nodes.len() {
            if let Some(d) = model.dofs.free(node, 0) {
                v0[d] = V0;
            }
        }
        Ok(Bar {
            mesh,
            model,
            contact,
            v0,
        })
    }

    /// A fresh integrator from rest at v₀ with step `dt` to 3L/c.
    ///
    /// # Errors
    /// The integrator's.
    pub fn integrator(&self, dt: f64, allow_unstable: bool) -> Result<Integrator, TimeError> {
        self.integrator_with(Scheme::CentralDifference, dt, allow_unstable)
    }

    /// [`Bar::integrator`] by `scheme` (Newmark with the consistent mass).
    ///
    /// # Errors
    /// The integrator's.
    pub fn integrator_with(
        &self,
        scheme: Scheme,
        dt: f64,
        allow_unstable: bool,
    ) -> Result<Integrator, TimeError> {
        let mut s = Settings::new(scheme, dt, 3.0 * L / C);
        s.initial_state = InitialState::Rest;
        s.initial_velocity = Some(self.v0.clone());
        s.allow_unstable = allow_unstable;
        Integrator::new(
            Dynamics::from_model(&self.model),
            Some(self.contact.clone()),
            Vec::new(),
            s,
        )
    }

    /// The explicit critical step with the wall's springs.
    ///
    /// # Errors
    /// The integrator's.
    pub fn dt_crit(&self) -> Result<f64, TimeError> {
        Ok(self.integrator(1e-6, false)?.dt_crit().unwrap_or(f64::NAN))
    }
}

/// The bar of `nx` Q1 cells against a wall of law `law`, by central
/// difference at `courant` times its critical step, run to 3L/c.
///
/// # Errors
/// The scene's or the integrator's.
pub fn run(nx: usize, law: Compliance, courant: f64) -> Result<Impact, SceneError> {
    run_with(nx, law, courant, false)
}

/// [`run`], above the critical step too where `allow_unstable` (the
/// stability study's bisection); a run whose state leaves the floating-
/// point range ends there with [`Impact::growth`] infinite.
///
/// # Errors
/// The scene's or the integrator's, but for a non-finite state.
pub fn run_with(
    nx: usize,
    law: Compliance,
    courant: f64,
    allow_unstable: bool,
) -> Result<Impact, SceneError> {
    let bar = Bar::new(nx, law)?;
    let dt_crit = bar.dt_crit()?;
    let run = bar.integrator(courant * dt_crit, allow_unstable)?;
    measure(&bar, run, dt_crit, allow_unstable)
}

/// The bar of `nx` Q1 cells against a wall of law `law` by Newmark
/// (β, γ) with the consistent mass and step `dt`, run to 3L/c
/// ([`Impact::dt_crit`] is the explicit one's, for scale).
///
/// # Errors
/// The scene's or the integrator's.
pub fn run_newmark(
    nx: usize,
    law: Compliance,
    (beta, gamma): (f64, f64),
    dt: f64,
) -> Result<Impact, SceneError> {
    let bar = Bar::new(nx, law)?;
    let dt_crit = bar.dt_crit()?;
    let run = bar.integrator_with(Scheme::Newmark { beta, gamma }, dt, false)?;
    measure(&bar, run, dt_crit, false)
}

/// Steps `run` to its end and measures the impact.
fn measure(
    bar: &Bar,
    mut run: Integrator,
    dt_crit: f64,
    allow_unstable: bool,
) -> Result<Impact, SceneError> {
    let (mesh, model, contact) = (&bar.mesh, &bar.model, &bar.contact);
    let mut growth: f64 = 1.0;
    let e0 = run.energy().kinetic;
    let n_c = contact.len();
    let mut sigma = vec![0.0; n_c];
    let (mut last, mut sum, mut count, mut balance) = (0.0_f64, 0.0, 0usize, 0.0_f64);
    while !run.done() {
        match run.step() {
            Ok(_) => {}
            Err(TimeError::NonFinite { .. }) if allow_unstable => {
                growth = f64::INFINITY;
                break;
            }
            Err(e) => return Err(e.into()),
        }
        let t = run.time();
        let e = run.energy();
        growth = crate::max_or_nan([growth, (e.kinetic + e.strain + e.foundation_stored) / e0]);
        run.normal_traction(&mut sigma);
        let c = run.contact().expect("a contact surface");
        let force: f64 = c.nodes.iter().zip(&sigma).map(|(n, s)| n.weight * s).sum();
        if force > 0.0 {
            last = t;
        }
        if (0.5 * L / C..=1.5 * L / C).contains(&t) {
            sum += force / H;
            count += 1;
        }
        balance = crate::max_or_nan([balance, run.energy().balance.abs() / e0]);
    }
    // The mean velocity with the trapezoid weights of the uniform grid
    // (the lumped mass of Q1 cells of one size).
    let (mut mv, mut m) = (0.0, 0.0);
    for (node, x) in mesh.nodes.iter().enumerate() {
        if let Some(d) = model.dofs.free(node, 0) {
            let w = if x[0] == 0.0 || x[0] == L { 0.5 } else { 1.0 };
            mv += w * run.velocity()[d];
            m += w;
        }
    }
    Ok(Impact {
        contact_time: last,
        stress: sum / count.max(1) as f64,
        exit_velocity: mv / m,
        balance,
        dt_crit,
        growth,
    })
}
