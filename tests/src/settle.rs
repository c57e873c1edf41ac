//! A block settling on a compliant floor (METHOD.md §10): the block [0, 1]
//! × [0, ½] (E = 1000, ν = 0.3, ρ = 1) stands on the frictionless
//! foundation y = 0 and its top is pressed by a uniform pressure p from
//! t = 0; mass-proportional damping brings it to rest, where every bottom
//! node carries the foundation's traction c_n δ^{m_n} = p (the pressure
//! passes through the block unchanged), so the approach is (p/c_n)^{1/m_n}.
//! The same block preloaded statically (the pressure present before t = 0)
//! starts there.

use stickslip_contact::{Compliance, ContactSurface};
use stickslip_fem::{traction_load, Hypothesis, Material, Model, Traction};
use stickslip_mesh::CellKind;
use stickslip_time::{
    Dynamics, History, InitialState, Integrator, Load, Rayleigh, Scheme, Settings, TimeError,
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
    let block = Block::new(nx, cn, mn)?;
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
        block.integrator(s)
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
    Ok(block.approaches(run.displacement()))
}

/// The bottom nodes' largest and smallest approach in the static preload
/// (`[initial] state = "static"`, the pressure present before t = 0) of
/// the same block, and the run after `steps` steps of half the critical
/// step from it, undamped: a preload in equilibrium with the foundation
/// stays where it is.
///
/// # Errors
/// The scene's or the integrator's.
pub fn preload(nx: usize, cn: f64, mn: f64, steps: usize) -> Result<Preload, SceneError> {
    let block = Block::new(nx, cn, mn)?;
    let build = |dt: f64| block.integrator(Settings::new(Scheme::CentralDifference, dt, 1.0));
    let dt_crit = build(1e-6)?.dt_crit().unwrap_or(f64::NAN);
    let mut run = build(0.5 * dt_crit)?;
    let initial = block.approaches(run.displacement());
    for _ in 0..steps {
        run.step()?;
    }
    Ok(Preload {
        initial,
        after: block.approaches(run.displacement()),
        largest_speed: crate::max_or_nan(run.velocity().iter().map(|v| v.abs()).chain([0.0])),
        run,
    })
}

/// What [`preload`] found.
#[derive(Debug)]
pub struct Preload {
    /// The largest and smallest approach at t = 0.
    pub initial: (f64, f64),
    /// The same after the steps.
    pub after: (f64, f64),
    /// The largest |ṙ| of a free DOF after them.
    pub largest_speed: f64,
    /// The run.
    pub run: Integrator,
}

/// The block's model, floor and load on its top.
#[derive(Debug)]
pub struct Block {
    model: Model,
    contact: ContactSurface,
    loads: Vec<Load>,
}

impl Block {
    /// The block of `nx` × `nx/2` cells on a frictionless floor of `cn`,
    /// `mn`, pressed by P on its top.
    ///
    /// # Errors
    /// The scene's.
    pub fn new(nx: usize, cn: f64, mn: f64) -> Result<Block, SceneError> {
        Block::loaded(nx, cn, mn, Traction::Pressure(P), 0.0)
    }

    /// The same block with `top` on its top, constant from before t = 0,
    /// `gap` above the floor.
    ///
    /// # Errors
    /// The scene's.
    pub fn loaded(
        nx: usize,
        cn: f64,
        mn: f64,
        top: Traction,
        gap: f64,
    ) -> Result<Block, SceneError> {
        let mesh = rectangle(CellKind::Quad4, nx, nx / 2, [0.0, 0.0], [1.0, 0.5]);
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain)?;
        let model = Model::new(&mesh, &material, &[])?;
        let law = Compliance {
            cn,
            mn,
            ct: 0.0,
            mt: mn,
        };
        let floor = ([0.0, -gap], [0.0, 1.0]);
        let contact =
            ContactSurface::on_foundation(&mesh, &model.dofs, "bottom", floor, law, 1e-3)?;
        let mut full = vec![0.0; 2 * mesh.nodes.len()];
        traction_load(&mesh, "top", top, &mut full)?;
        let mut vector = vec![0.0; model.dofs.n_free()];
        model.dofs.restrict(&full, &mut vector);
        let loads = vec![Load {
            vector,
            history: History::Constant,
        }];
        Ok(Block {
            model,
            contact,
            loads,
        })
    }

    /// Its integrator.
    ///
    /// # Errors
    /// The integrator's.
    pub fn integrator(&self, settings: Settings) -> Result<Integrator, TimeError> {
        Integrator::new(
            Dynamics::from_model(&self.model),
            Some(self.contact.clone()),
            self.loads.clone(),
            settings,
        )
    }

    /// The bottom nodes' largest and smallest approach −r_y − gap.
    pub fn approaches(&self, r: &[f64]) -> (f64, f64) {
        let (mut most, mut least) = (f64::NEG_INFINITY, f64::INFINITY);
        for n in &self.contact.nodes {
            let d = n.dofs[1].map_or(0.0, |d| -r[d]);
            let d = d - self.contact.compliance[0].gap;
            most = crate::max_or_nan([most, d]);
            least = crate::min_or_nan([least, d]);
        }
        (most, least)
    }
}
