//! Friction's share of a step's energy ledger (METHOD.md §6): the nodal
//! forces at the new velocity, the work they dissipate over the step, and
//! the slip → stick events that Remark 4.3's step reduction follows.

use crate::foundation::split_work;
use crate::law::SlipState;
use crate::surface::ContactSurface;

impl ContactSurface {
    /// The forces f_J = w_J g_J φ_ε(v_TJ) of free-DOF velocity `v_new` into
    /// `forces`; returns the work friction dissipated over a step of `dt`
    /// from `v` to `v_new`, Σ_J ½(f_J + f_J,old) Δs_J with Δs_J the
    /// trapezoidal increment τ_J·½Δt(ṙ_K + ṙ_{K−1})
    /// ([`ContactNode::motion`](crate::ContactNode::motion)). Δs_J is
    /// (r_K − r_{K−1})·τ_J for Newmark ¼, ½, so the energy balance closes
    /// to round-off there; with φ_ε odd and increasing the sum is never
    /// negative for any scheme. On a moving foundation the force is
    /// w_J g_J φ_ε(w) on the slip w = v_T − V and the work splits into the
    /// dissipated part, on the slip increment, and the foundation's
    /// (METHOD.md §9), the second of the pair returned (0 at rest).
    pub fn step_dissipation(
        &self,
        v_new: &[f64],
        v: &[f64],
        dt: f64,
        forces_old: &[f64],
        forces: &mut [f64],
    ) -> (f64, f64) {
        let (mut dissipated, mut foundation) = (0.0, 0.0);
        for (j, ((n, f), f_old)) in self
            .nodes
            .iter()
            .zip(forces.iter_mut())
            .zip(forces_old)
            .enumerate()
        {
            let (v_t, increment) = n.motion(v_new, v, dt);
            let w = self.slip(j, v_t);
            *f = n.force(&self.law_of(j), w) * self.factor(j, w);
            let (d, w) = split_work(*f, *f_old, increment, self.foundation_speed(j), dt);
            dissipated += d;
            foundation += w;
        }
        (dissipated, foundation)
    }
}

/// Nodes stuck in `new` that were slipping in `old`: the step's slip → stick
/// events.
pub fn stick_events(old: &[SlipState], new: &[SlipState]) -> usize {
    new.iter()
        .zip(old)
        .filter(|(new, old)| new.sticks_after(**old))
        .count()
}
