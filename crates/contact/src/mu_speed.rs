//! Static against kinetic friction (METHOD.md §9): μ(w) = μk + (μs − μk)
//! e^{−|w|/vs} on the slip speed, written as the static bound g = μs·p
//! times the factor m(|w|) = r + (1 − r) e^{−|w|/vs}, r = μk/μs, so that
//! σ_T = −g m(|w|) φ_ε(w).
//!
//! The nodal scalar equation of a diagonal step, w + c m(|w|) φ_ε(w) = q
//! (c = w_J g τᵀD⁻¹τ, q the step's slip without friction), is no longer
//! monotone: on the slip branch h(w) = w + c m(w) is convex and falls
//! near ε where c (1 − r)/vs > 1, and where vs is below ε and r small the
//! stuck branch w (1 + c m(w)/ε) may rise, fall and rise again inside
//! [0, ε], so several roots may exist. The choice
//! ([`Weakening::solve_nodal`]) is the least stuck root when there is one
//! (the one continuous in q from q = 0), else the slip root, which is then
//! unique and has q's sign: h is odd, and on the slip branch convex from
//! below q at ε to +∞, so it crosses q once.

use crate::law::FrictionLaw;
use crate::surface::ContactSurface;

/// The fall of the friction coefficient with the slip speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weakening {
    /// r = μk/μs in [0, 1].
    pub ratio: f64,
    /// vs > 0, the slip speed over which μ falls by 1/e of μs − μk.
    pub speed: f64,
}

impl Weakening {
    /// m(s) = r + (1 − r) e^{−s/vs}: μ(s)/μs, 1 at s = 0, r as s → ∞.
    #[inline]
    pub fn factor(&self, s: f64) -> f64 {
        self.ratio + (1.0 - self.ratio) * (-s / self.speed).exp()
    }

    /// The root of w + c m(|w|) φ_ε(w) = q (c ≥ 0): the least stuck one,
    /// in [−ε, ε], where one exists, else the slip one (module doc).
    pub fn solve_nodal(&self, law: &FrictionLaw, q: f64, c: f64) -> f64 {
        let (a, eps) = (q.abs(), law.eps);
        // The stuck branch h(w) = w (1 + c m(w)/ε) on [0, ε], 0 at 0.
        let stuck = |w: f64| w + c * self.factor(w) * w / eps;
        let w = match self.stuck_peak(eps, c) {
            // h rises to a peak inside [0, ε], falls, and rises again:
            // below the peak it rises, and h(w) ≥ w, so the least root of
            // a ≤ h(peak) is in [0, min(a, peak)] ...
            Some(peak) if a <= stuck(peak) => bisect(|w| stuck(w) - a, 0.0, a.min(peak)),
            // ... and of h(peak) < a ≤ h(ε) past the fall, where h rises
            // from below h(peak) to h(ε), crossing a once.
            Some(peak) if a <= stuck(eps) => bisect(|w| stuck(w) - a, peak, eps),
            // h rises on [0, ε].
            None if a <= stuck(eps) => bisect(|w| stuck(w) - a, 0.0, a.min(eps)),
            // w + c m(w) − a: ≤ 0 at max(ε, a − c) (m ≤ 1, and h(ε) < a),
            // ≥ 0 at a − c r (m ≥ r).
            _ => bisect(
                |w| w + c * self.factor(w) - a,
                eps.max(a - c),
                (a - c * self.ratio).max(eps),
            ),
        };
        w.copysign(q)
    }

    /// Where the stuck branch h(w) = w (1 + c m(w)/ε) peaks inside (0, ε),
    /// if it does. h′ = 1 + (c/ε)(w m)′ with (w m)′ = r + (1 − r)
    /// e^{−w/vs} (1 − w/vs), which falls on [0, 2vs] to its least value
    /// at 2vs and rises after: h′ > 0 at 0, and where h′(2vs) < 0 its one
    /// zero before 2vs is h's local maximum (where μk/μs is small and vs
    /// below ε).
    fn stuck_peak(&self, eps: f64, c: f64) -> Option<f64> {
        let slope = |w: f64| {
            let r = self.ratio;
            1.0 + c / eps * (r + (1.0 - r) * (-w / self.speed).exp() * (1.0 - w / self.speed))
        };
        let low = 2.0 * self.speed;
        if slope(low) >= 0.0 {
            return None;
        }
        // −h′ rises from below 0 at 0 to above 0 at 2vs.
        let peak = bisect(|w| -slope(w), 0.0, low);
        (peak < eps).then_some(peak)
    }
}

/// A root of `f` in [lo, hi] with f(lo) ≤ 0 ≤ f(hi), by bisection to the
/// last bit: the interval halves until its ends are adjacent doubles.
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..2100 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let v = f(mid);
        if v == 0.0 {
            return mid;
        }
        if v < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if f(hi).abs() < f(lo).abs() {
        hi
    } else {
        lo
    }
}

impl ContactSurface {
    /// Sets node j's fall of μ with the slip speed (`None`: the constant
    /// law). A surface of constant μ everywhere keeps none.
    pub fn set_weakening(&mut self, mut law: impl FnMut(usize) -> Option<Weakening>) {
        self.weakening = (0..self.nodes.len()).map(&mut law).collect();
        if self.weakening.iter().all(Option::is_none) {
            self.weakening.clear();
        }
    }

    /// Node j's fall of μ, `None` for the constant law.
    #[inline]
    pub fn weakening_of(&self, j: usize) -> Option<Weakening> {
        self.weakening.get(j).copied().flatten()
    }

    /// True when some node's μ falls with the slip speed.
    pub fn weakens(&self) -> bool {
        !self.weakening.is_empty()
    }

    /// μ(|w|)/μs at node j and slip `w`: 1, exactly, for the constant law.
    #[inline]
    pub(crate) fn factor(&self, j: usize, w: f64) -> f64 {
        self.weakening_of(j).map_or(1.0, |k| k.factor(w.abs()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chosen root satisfies its equation, is stuck whenever a stuck
    /// root exists (|q| ≤ ε + c m(ε)), and slips with q's sign otherwise;
    /// where c (1 − r)/vs > 1 the equation has three roots for some q
    /// (stuck and two slip ones), counted here by sign changes of the
    /// residual on a fine grid, and the stuck one is taken.
    #[test]
    fn the_root_is_stuck_when_it_can_be() {
        let law = FrictionLaw { eps: 1e-4 };
        let k = Weakening {
            ratio: 0.5,
            speed: 1e-3,
        };
        let mut three = 0;
        for &c in &[1e-4, 1e-3, 5e-3, 2e-2] {
            let h = |w: f64| w + c * k.factor(w.abs()) * law.phi(w);
            for i in -400..=400 {
                let q = f64::from(i) * 5e-5;
                let w = k.solve_nodal(&law, q, c);
                let scale = q.abs() + c;
                assert!(
                    (h(w) - q).abs() <= 1e-12 * scale,
                    "c = {c}, q = {q}: residual {}",
                    h(w) - q
                );
                let stuck_exists = q.abs() <= law.eps + c * k.factor(law.eps);
                assert_eq!(
                    w.abs() <= law.eps,
                    stuck_exists,
                    "c = {c}, q = {q}: w = {w}"
                );
                if !stuck_exists {
                    assert_eq!(w.signum(), q.signum());
                }
                // Roots on w > 0: sign changes of h − q on a grid to 10q.
                let roots = (0..20_000)
                    .map(|n| f64::from(n) * 1e-6)
                    .map(|w| h(w) - q)
                    .collect::<Vec<_>>()
                    .windows(2)
                    .filter(|p| p[0] == 0.0 || p[0].signum() != p[1].signum())
                    .count();
                if q > 0.0 && roots >= 3 {
                    three += 1;
                    assert!(
                        w.abs() <= law.eps,
                        "c = {c}, q = {q}: three roots, took {w}"
                    );
                }
            }
        }
        assert!(three > 0, "some q with three roots");
    }

    /// With vs below ε and μk/μs small the stuck branch peaks inside
    /// [0, ε] and falls to h(ε) = ε + c m(ε): for q between h(ε) and the
    /// peak a stuck root exists all the same, and is taken. r = 0.01, vs =
    /// 5e-4, ε = 1e-3, c = 0.1: h(ε) = ε + c (r + (1 − r) e⁻²) = 0.015398,
    /// the peak 0.0192 near w = 5.3e-4 (h evaluated on a grid here, not by
    /// the solver's search).
    #[test]
    fn a_stuck_root_past_the_stuck_branch_peak_is_taken() {
        let law = FrictionLaw { eps: 1e-3 };
        let k = Weakening {
            ratio: 0.01,
            speed: 5e-4,
        };
        let c = 0.1;
        let h = |w: f64| w + c * k.factor(w.abs()) * law.phi(w);
        let at_eps = h(law.eps);
        let peak = (0..=10_000)
            .map(|n| h(f64::from(n) * 1e-7))
            .fold(0.0, f64::max);
        assert!((at_eps - 0.0153982).abs() < 1e-7, "{at_eps}");
        assert!(peak > 0.019 && peak < 0.0193, "{peak}");
        for i in 1..10 {
            let q = at_eps + (peak - at_eps) * f64::from(i) / 10.0;
            for q in [q, -q] {
                let w = k.solve_nodal(&law, q, c);
                assert!(w.abs() <= law.eps, "q = {q}: took the slip root {w}");
                assert!(
                    (h(w) - q).abs() <= 1e-12 * (q.abs() + c),
                    "q = {q}: residual"
                );
            }
        }
        // Above the peak only the slip root is left.
        let w = k.solve_nodal(&law, 1.01 * peak, c);
        assert!(w > law.eps && (h(w) - 1.01 * peak).abs() <= 1e-12);
    }

    /// Where the stuck branch rises, falls and rises again inside [0, ε]
    /// (r = 0.01, vs = 1e-4, ε = 1e-3, c = 0.1: a peak near w = 1.1e-4, a
    /// dip near 5.4e-4), a q may have three stuck roots; the least is
    /// taken, the one that grows continuously with q from 0, found here
    /// as the first grid point where h reaches q.
    #[test]
    fn the_least_of_several_stuck_roots_is_taken() {
        let law = FrictionLaw { eps: 1e-3 };
        let k = Weakening {
            ratio: 0.01,
            speed: 1e-4,
        };
        let c = 0.1;
        let h = |w: f64| w + c * k.factor(w.abs()) * law.phi(w);
        let step = 1e-8;
        let grid: Vec<f64> = (0..=100_000).map(|n| h(f64::from(n) * step)).collect();
        let top = grid.iter().copied().fold(0.0, f64::max);
        let mut three = 0;
        let mut last = 0.0;
        for i in 1..=200 {
            let q = top * f64::from(i) / 200.0;
            let first = grid.iter().position(|&v| v >= q).expect("a stuck root") as f64 * step;
            let w = k.solve_nodal(&law, q, c);
            assert!((h(w) - q).abs() <= 1e-12 * (q + c), "q = {q}: residual");
            assert!(
                w <= first && w >= first - step,
                "q = {q}: took {w}, the least root is in [{}, {first}]",
                first - step
            );
            assert!(w >= last, "q = {q}: {w} below the last q's {last}");
            last = w;
            let crossings = grid
                .windows(2)
                .filter(|p| (p[0] - q).signum() != (p[1] - q).signum())
                .count();
            three += usize::from(crossings >= 3);
        }
        assert!(three > 0, "some q with three stuck roots");
    }

    #[test]
    fn the_factor_falls_from_one_to_r() {
        let k = Weakening {
            ratio: 0.6,
            speed: 0.01,
        };
        assert_eq!(k.factor(0.0), 1.0);
        // e^{−1} of the fall at s = vs: 0.6 + 0.4/e.
        assert!((k.factor(0.01) - (0.6 + 0.4 * (-1f64).exp())).abs() < 1e-15);
        assert!((k.factor(1.0) - 0.6).abs() < 1e-15);
    }
}
