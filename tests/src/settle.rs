//! A block settling on a compliant floor (METHOD.md §10): the block [0, 1]
//! × [0, ½] (E = 1000, ν = 0.3, ρ = 1) stands on the frictionless
//! foundation y = 0 and its top is pressed by a uniform pressure p from
//! t = 0; mass-proportional damping brings it to rest, where every bottom
//! node carries the foundation's traction c_n δ^{m_n} = p (the pressure
//! passes through the block unchanged), so the approach is (p/c_n)^{1/m_n}.

use stickslip_contact::{Compliance, ContactSurface};
use stickslip_fem::{traction_load, Hypothesis, Material, Model, Traction};
use stickslip_mesh::CellKind;
use stickslip_time::{
    Dynamics, History, InitialState, Integrator, Load, Rayleigh, Scheme, Settings,
};

use crate::grid::rectangle;
use crate::scene::SceneError;

/// The pressure on the top.
pub const P: f64 = 10.0;

/// The bottom nodes' largest and smallest approach after the block of
/// `nx` × `nx/2` Q1 cells on a floor of `cn`, `mn` settled (damping α = 40,
/// central difference at half its critical step, to t = 4: the slowest
/// motion, the block bouncing on the floor, has decayed by e^{−80}).
///
/// # Errors
/// The scene's or the integrator's.
pub fn settle(nx: usize, cn: f64, mn: f64) -> Result<(f64, f64), SceneError> {
    settle_by(nx, cn, mn, None)
}

/// [`settle`] by Newmark (β, γ) with step Δt where `newmark` is `Some(((β,
/// γ), Δt))`, by central difference at half its critical step where
/// `None`.
///
/// # Errors
/// The scene's or the integrator's.
pub fn settle_by(
    nx: usize,
    cn: f64,
    mn: f64,
    newmark: Option<((f64, f64), f64)>,
) -> Result<(f64, f64), SceneError> {
    let mesh = rectangle(CellKind::Quad4, nx, nx / 2, [0.0, 0.0], [1.0, 0.5]);
    let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain)?;
    let model = Model::new(&mesh, &material, &[])?;
    let law = Compliance {
        cn,
        mn,
        ct: 0.0,
        mt: mn,
    };
    let floor = ([0.0, 0.0], [0.0, 1.0]);
    let contact = ContactSurface::on_foundation(&mesh, &model.dofs, "bottom", floor, law, 1e-3)?;
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    traction_load(&mesh, "top", Traction::Pressure(P), &mut full)?;
    let mut vector = vec![0.0; model.dofs.n_free()];
    model.dofs.restrict(&full, &mut vector);
    let loads = vec![Load {
        vector,
        history: History::Constant,
    }];
    let build = |dt: f64| {
        let scheme = match newmark {
            Some(((beta, gamma), _)) => Scheme::Newmark { beta, gamma },
            None => Scheme::CentralDifference,
        };
        let mut s = Settings::new(scheme, dt, 4.0);
        s.initial_state = InitialState::Rest;
        s.damping = Rayleigh {
            alpha: 40.0,
            beta: 0.0,
        };
        Integrator::new(
            Dynamics::from_model(&model),
            Some(contact.clone()),
            loads.clone(),
            s,
        )
    };
    let mut run = match newmark {
        Some((_, dt)) => build(dt)?,
        None => {
            let dt_crit = build(1e-6)?.dt_crit().unwrap_or(f64::NAN);
            build(0.5 * dt_crit)?
        }
    };
    while !run.done() {
        run.step()?;
    }
    let (mut most, mut least) = (f64::NEG_INFINITY, f64::INFINITY);
    for n in &contact.nodes {
        let d = n.dofs[1].map_or(0.0, |d| -run.displacement()[d]);
        most = most.max(d);
        least = least.min(d);
    }
    Ok((most, least))
}
