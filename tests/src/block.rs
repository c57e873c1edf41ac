//! A block held only by friction: L × H, rollers (u_y = 0) on its top,
//! pressed onto a rough floor (its bottom, the contact surface) by the
//! prescribed pressure p, free in x. The rollers matter: with a prescribed
//! normal traction nothing else resists the friction's moment. Rigidly
//! the friction force μpL on the mass ρLH decelerates a sliding block at
//! a = μp/(ρH); launched at v₀ it stops after v₀/a, having slid v₀²/(2a)
//! (verify's analytic suite and examples/04 hold those closed forms).

use stickslip_fem::{Dirichlet, Hypothesis, Material, Traction};
use stickslip_mesh::CellKind;
use stickslip_time::{History, Integrator, Settings};

use crate::grid::rectangle;
use crate::scene::{SceneError, Slab};

/// The block's data.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    /// Length L (x) and height H (y).
    pub size: [f64; 2],
    /// Q1 cells along x and y.
    pub cells: [usize; 2],
    /// Young's modulus (ν = 0.3, ρ = 1, plane strain).
    pub e: f64,
    /// Floor pressure p.
    pub pressure: f64,
    /// Friction coefficient μ.
    pub mu: f64,
    /// The friction law's ε.
    pub eps: f64,
}

impl Block {
    /// The rigid deceleration while sliding, a = μp/(ρH), ρ = 1.
    pub fn deceleration(&self) -> f64 {
        self.mu * self.pressure / self.size[1]
    }

    /// The scene: the pressure (constant: part of the static preload,
    /// balanced by the rollers) and, for a push, the traction t_x =
    /// `push.0` on the left end with history `push.1`.
    ///
    /// # Errors
    /// The scene's (none for valid data).
    pub fn scene(&self, push: Option<(f64, History)>) -> Result<Slab, SceneError> {
        let mesh = rectangle(
            CellKind::Quad4,
            self.cells[0],
            self.cells[1],
            [0.0, 0.0],
            self.size,
        );
        let material = Material::new(self.e, 0.3, 1.0, Hypothesis::PlaneStrain)?;
        let mut tractions = vec![(
            "bottom",
            Traction::Pressure(self.pressure),
            History::Constant,
        )];
        if let Some((t, history)) = push {
            tractions.push(("left", Traction::Vector([t, 0.0]), history));
        }
        Slab::assemble(
            mesh,
            &material,
            &[Dirichlet::new("top", 1, 0.0)],
            &tractions,
            Some(("bottom", self.pressure, self.mu, self.eps)),
        )
    }
}

/// The mass-weighted mean of the x components of a free-DOF vector (the
/// block's rigid translation or velocity).
pub fn mean_x(slab: &Slab, x: &[f64]) -> f64 {
    let (mut sum, mut mass) = (0.0, 0.0);
    for node in 0..slab.mesh.nodes.len() {
        if let Some(d) = slab.dof(node, 0) {
            sum += slab.model.lumped_mass[d] * x[d];
            mass += slab.model.lumped_mass[d];
        }
    }
    sum / mass
}

/// What a slide did.
#[derive(Clone, Copy, Debug)]
pub struct Slide {
    /// When the block stopped: where the line through the first times
    /// its mean velocity fell to ½ and to 1/20 of its largest value
    /// reaches zero. (After the stop the stuck block rings elastically,
    /// its mean velocity a few percent of v₀ about zero; the deceleration
    /// before it is what the rigid closed form describes.)
    pub stop_time: f64,
    /// Mean x displacement at t_end.
    pub distance: f64,
}

/// Runs `slab` with `settings` (ṙ₀ = `v0` in x at every node, if
/// nonzero) to t_end.
///
/// # Errors
/// The integrator's.
pub fn slide(slab: &Slab, mut settings: Settings, v0: f64) -> Result<Slide, SceneError> {
    if v0 != 0.0 {
        let mut v = vec![0.0; slab.n_free()];
        for node in 0..slab.mesh.nodes.len() {
            if let Some(d) = slab.dof(node, 0) {
                v[d] = v0;
            }
        }
        settings.initial_velocity = Some(v);
    }
    let mut i: Integrator = slab.integrator(settings)?;
    let x0 = mean_x(slab, i.displacement());
    let mut top = v0.abs();
    let mut crossed = [f64::NAN; 2];
    while !i.done() {
        i.step()?;
        let v = mean_x(slab, i.velocity());
        top = crate::max_or_nan([top, v.abs()]);
        for (t, level) in crossed.iter_mut().zip([0.5, 0.05]) {
            if t.is_nan() && top > 0.0 && v.abs() < top && v.abs() <= level * top {
                *t = i.time();
            }
        }
    }
    let [t1, t2] = crossed;
    Ok(Slide {
        stop_time: t2 + (t2 - t1) * 0.05 / 0.45,
        distance: mean_x(slab, i.displacement()) - x0,
    })
}
