//! A foundation that moves (METHOD.md §9): the law acts on the slip
//! w_T = v_T − V, V the foundation's speed along the node's tangent τ_J.
//! Per node the dissipation rate is f w ≥ 0 (f = w_J g_J φ_ε(w) along τ),
//! and the foundation feeds −f V into the body, its work W_f.

use crate::surface::ContactSurface;

impl ContactSurface {
    /// Sets node j's foundation speed V_J to `speed(j)` (along τ_J). A
    /// surface whose foundation never moves keeps no speeds at all.
    pub fn set_foundation(&mut self, mut speed: impl FnMut(usize) -> f64) {
        self.foundation.resize(self.nodes.len(), 0.0);
        for (j, v) in self.foundation.iter_mut().enumerate() {
            *v = speed(j);
        }
    }

    /// V_J of node j, 0 at rest.
    #[inline]
    pub fn foundation_speed(&self, j: usize) -> f64 {
        self.foundation.get(j).copied().unwrap_or(0.0)
    }

    /// True when some node's foundation moves.
    pub fn foundation_moves(&self) -> bool {
        self.foundation.iter().any(|&v| v != 0.0)
    }

    /// The slip w = v_T − V_J of node j moving at `v_t`: v_t itself, bit
    /// for bit, where the foundation is at rest (v − 0 is v).
    #[inline]
    pub fn slip(&self, j: usize, v_t: f64) -> f64 {
        v_t - self.foundation_speed(j)
    }
}

/// The work of one node's friction over a step whose tangential motion
/// is `increment` (τ·Δr), with `f`, `f_old` its force at the step's ends
/// and `v` the foundation's speed: (dissipated, foundation's work), the
/// dissipated work on the slip increment − vΔt and the foundation's
/// −f̄ vΔt, so that their difference is f̄·increment, the friction's work
/// on the body (METHOD.md §9: d(KE + SE)/dt = P_ext − D + W_f′).
#[inline]
pub(crate) fn split_work(f: f64, f_old: f64, increment: f64, v: f64, dt: f64) -> (f64, f64) {
    let mean = 0.5 * (f + f_old);
    if v == 0.0 {
        return (mean * increment, 0.0);
    }
    let carried = v * dt;
    (mean * (increment - carried), -mean * carried)
}
