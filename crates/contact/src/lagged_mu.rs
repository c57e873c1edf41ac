//! μ falling with the slip speed in the stick/slip iteration (METHOD.md
//! §9 with §5, §11): μ lagged by one step.
//!
//! With μ(w) = μk + (μs − μk) e^{−|w|/vs} a slipping node's force
//! w_J μ(|w|) p φ_ε(w) falls as |w| grows, so a step is no longer the
//! minimization of a convex function and the iteration of §5 need not
//! settle. Taking μ at each iterate's own slip, a node can go round for
//! ever: stuck with the low μ of a fast iterate, it comes out slipping
//! forward; slipping with the high μ of that slow iterate, it comes out
//! going backward, which Remark 4.2 makes stuck, with the low μ of that
//! fast iterate again (the test below; Remark 4.2 ends a reversal, not a
//! cycle through the stuck class).
//!
//! The iterating solvers therefore take each node's μ at its slip of the
//! previous converged step, w = τ·ṙ_{K−1} − V_J: for the step, g_J
//! μ(|w|)/μs is a constant bound, the step is the constant law's problem
//! (strictly convex, one solution) and the iteration is the constant law's,
//! which Remark 4.2 makes end. The step is solved on a copy of the surface
//! with those bounds and the constant law ([`ContactSurface::lagged`],
//! [`ContactSurface::lag_bounds`]); its forces are the ones the step
//! applied, so the energy ledger closes as for the constant law. V_J is the
//! foundation's speed at the step's end (the same as at its start unless a
//! `foundation_history` changes it): the bounds are a function of the state
//! a step starts from, so a restart continues bit for bit.
//!
//! What the lag costs: the force applied is off by w_J p |μ(w_K) − μ(w_{K−1})|
//! ≤ w_J p (μs − μk)/vs · |w_K − w_{K−1}|, one step's change of the slip,
//! O(Δt) where the slip moves smoothly: a run where μ varies is first
//! order in Δt, and the lag vanishes as Δt → 0 (the belt's stick-slip in
//! `cargo xtask verify`: Newmark against central difference's nodal closed
//! form, which takes μ at the step's own slip, as Δt halves). At a
//! break-away the lag keeps μs for the first slipping step; a stuck node
//! creeps at most ε, so its μ stays within (μs − μk) ε/vs of μs. With
//! μs = μk the factor is 1 exactly and the run is the constant law's, bit
//! for bit.

use crate::surface::ContactSurface;

impl ContactSurface {
    /// These nodes with the constant law: the surface a step of the
    /// iteration runs on where μ falls with the slip speed, its bounds set
    /// per step by [`ContactSurface::lag_bounds`] (module doc).
    pub fn lagged(&self) -> ContactSurface {
        let mut s = self.clone();
        s.weakening.clear();
        s
    }

    /// Sets this surface's bounds (a [`ContactSurface::lagged`] copy of
    /// `base`) to base's g_J μ(|w_J|)/μs at the slip w_J of `velocity`
    /// (free DOFs as base numbers them), with base's foundation speeds;
    /// counts a revision when a bound changed.
    pub fn lag_bounds(&mut self, base: &ContactSurface, velocity: &[f64]) {
        self.foundation.clone_from(&base.foundation);
        self.set_bounds(|j| {
            let n = &base.nodes[j];
            n.bound * base.factor(j, base.slip(j, n.tangential(velocity)))
        });
    }
}

#[cfg(test)]
mod tests {
    use crate::iteration::tests::{unit_node, Masses};
    use crate::iteration::StepSystem;
    use crate::iteration::{iterate, IterationFailure, IterationOptions, IterationReport};
    use crate::law::SlipState;
    use crate::surface::{ContactNode, ContactSurface};
    use crate::Weakening;

    /// μ at each iterate's own slip: before every solve the bounds are set
    /// at the slip of the iterate the last solve left (the safeguard off).
    struct PerIterate<'a> {
        base: &'a ContactSurface,
        work: ContactSurface,
        inner: Masses,
    }

    impl StepSystem for PerIterate<'_> {
        type Error = ();

        fn solve(
            &mut self,
            _: &ContactSurface,
            classes: &[SlipState],
            velocity: &mut [f64],
        ) -> Result<(), ()> {
            self.work.lag_bounds(self.base, velocity);
            self.inner.solve(&self.work, classes, velocity)
        }
    }

    /// One mass m = 1 on a unit node (w = 1, g = μs p = 1), ε = 0.01,
    /// μk/μs = 0.2, vs = 0.1, right-hand side b = 0.5, slipping forward at
    /// w = 0.05 at the last step. The step's equation v + m(|v|) φ_ε(v) =
    /// 0.5 has its stuck root (0.5 ≤ ε + m(ε) = 0.934).
    ///
    /// μ at each iterate: slipping forward with m(0.05) = 0.685 gives v =
    /// 0.5 − 0.685 < −ε, a reversal, stuck; stuck with m(0.185) = 0.326
    /// gives 0.5/(1 + 32.6) > ε, slipping; slipping with m of that slow
    /// iterate (0.84 to 0.89) gives v < −ε, stuck again with the low μ of
    /// the fast one: two classes in turn to the cap, one node changing.
    ///
    /// μ lagged (the bounds set once from the last step's slip): slipping
    /// with m(0.05) reverses, stuck gives 0.5/(1 + 68.5) < ε, which the
    /// next solve confirms: two solves, v = 0.5/(1 + m(0.05)/ε) to a
    /// rounding, m(0.05) = 0.2 + 0.8 e^{−0.5} written out.
    #[test]
    fn a_lagged_mu_ends_the_cycle_mu_per_iterate_runs() {
        let eps = 0.01;
        let mut base = ContactSurface::from_nodes("mass", vec![unit_node(0)], eps).unwrap();
        base.set_weakening(|_| {
            Some(Weakening {
                ratio: 0.2,
                speed: 0.1,
            })
        });
        let masses = || Masses {
            mass: vec![1.0],
            b: vec![0.5],
            solves: 0,
        };
        let cap = 40;
        let options = IterationOptions {
            remark_4_2: true,
            max_iterations: cap,
        };
        let last_step = 0.05;

        let mut classes = vec![SlipState::SlipPositive];
        let (mut scratch, mut v) = (classes.clone(), vec![last_step]);
        let mut off = PerIterate {
            base: &base,
            work: base.lagged(),
            inner: masses(),
        };
        let work = base.lagged();
        let result = iterate(&work, &mut off, &mut classes, &mut scratch, &mut v, options);
        assert_eq!(
            result,
            Err(IterationFailure::Cap {
                iterations: cap,
                changing: 1
            })
        );
        assert_eq!(off.inner.solves, cap);
        // Still going round: odd solves leave it stuck, even ones slipping
        // forward again.
        assert_eq!(classes, [SlipState::SlipPositive]);

        let mut classes = vec![SlipState::SlipPositive];
        let mut v = vec![last_step];
        let mut on = base.lagged();
        on.lag_bounds(&base, &v);
        let mut system = masses();
        let result = iterate(
            &on,
            &mut system,
            &mut classes,
            &mut scratch,
            &mut v,
            options,
        );
        assert_eq!(result, Ok(IterationReport { iterations: 2 }));
        assert_eq!(system.solves, 2);
        assert_eq!(classes, [SlipState::Stuck]);
        let m = 0.2 + 0.8 * (-0.5f64).exp();
        let stuck = 0.5 / (1.0 + m / eps);
        assert!(
            (v[0] - stuck).abs() <= 4.0 * f64::EPSILON * stuck,
            "{} vs {stuck}",
            v[0]
        );
    }

    /// With μs = μk the lagged bounds are the built ones, bit for bit, and
    /// count no revision; with μk < μs a node at rest keeps μs and one
    /// slipping at w gets μ(|w|): on a foundation at V the slip v − V.
    #[test]
    fn lagged_bounds_are_the_law_at_the_last_slip() {
        let node = |j: usize| ContactNode {
            weight: 0.5,
            bound: 0.3,
            ..unit_node(j)
        };
        let mut base = ContactSurface::from_nodes("line", vec![node(0), node(1)], 1e-3).unwrap();
        base.set_weakening(|_| {
            Some(Weakening {
                ratio: 1.0,
                speed: 0.01,
            })
        });
        let mut lagged = base.lagged();
        lagged.lag_bounds(&base, &[0.7, -3.0]);
        assert_eq!(lagged.nodes, base.nodes);
        assert_eq!(lagged.revision, base.revision);
        assert!(!lagged.weakens());

        base.set_weakening(|_| {
            Some(Weakening {
                ratio: 0.5,
                speed: 0.01,
            })
        });
        base.set_foundation(|j| [0.0, 0.02][j]);
        lagged.lag_bounds(&base, &[0.0, 0.03]);
        assert_eq!(lagged.nodes[0].bound, 0.3);
        // Slip 0.03 − 0.02 = vs: μ/μs = 0.5 + 0.5/e.
        let expected = 0.3 * (0.5 + 0.5 * (-1f64).exp());
        assert!((lagged.nodes[1].bound - expected).abs() <= 2.0 * f64::EPSILON * expected);
        assert_eq!(lagged.foundation, base.foundation);
        assert_eq!(lagged.revision, base.revision + 1);
    }
}
