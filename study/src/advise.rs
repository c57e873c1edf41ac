//! Core of `stickslip advise` (issue 6, deliverable 3): choose the cheapest
//! configuration whose estimated error on one output is below a tolerance.
//!
//! The error of a configuration is modelled as the sum of three separately
//! measured parts, e ≈ e_h + e_Δt + e_ε (a bound when they add with the
//! same sign), each estimated Richardson-style from two or three cheap
//! pilot runs that differ only in that parameter: with solutions a (coarse)
//! and b (fine) at refinement ratio r and order p, the error of b is about
//! |a − b| / (r^p − 1), and p itself is observed from three levels
//! (p = ln(|a − b| / |b − c|) / ln r) when the theoretical order does not
//! hold (the slab's corner and the stick/slip kinks lower it). ε enters as
//! O(√ε) (METHOD.md §2, Theorem 2.3), so its "order" in ε is ½.
//!
//! Only the pure selection logic lives here; the pilot runs are the
//! caller's ([`crate::run`]).

use crate::run::Method;

/// The output the tolerance is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// u_x at a node.
    Ux,
    /// u_y at a node.
    Uy,
    /// σ_T at a contact node.
    FrictionStress,
    /// Total energy at t_end.
    Energy,
}

impl Quantity {
    /// Parses `--on`.
    ///
    /// # Errors
    /// An unknown name, with the accepted ones.
    pub fn parse(s: &str) -> Result<Quantity, String> {
        match s {
            "ux" => Ok(Quantity::Ux),
            "uy" => Ok(Quantity::Uy),
            "friction_stress" => Ok(Quantity::FrictionStress),
            "energy" => Ok(Quantity::Energy),
            _ => Err(format!(
                "--on {s:?}: expected ux, uy, friction_stress or energy"
            )),
        }
    }
}

/// Error of the finer of two solutions at refinement ratio `ratio` (> 1)
/// with convergence order `order` (> 0), from their difference.
pub fn richardson(difference: f64, ratio: f64, order: f64) -> f64 {
    difference.abs() / (ratio.powf(order) - 1.0)
}

/// Observed order from the differences of three levels (coarse−middle and
/// middle−fine) at a constant ratio; None when the differences do not
/// decrease (not in the asymptotic range).
pub fn observed_order(d_coarse: f64, d_fine: f64, ratio: f64) -> Option<f64> {
    let (a, b) = (d_coarse.abs(), d_fine.abs());
    (a > b && b > 0.0 && ratio > 1.0).then(|| (a / b).ln() / ratio.ln())
}

/// Predicts the error at a finer level from the error at a measured level:
/// e(level + k) = e(level) / ratio^(k·order).
pub fn extrapolate(error: f64, ratio: f64, order: f64, levels: u32) -> f64 {
    error / ratio.powf(order * f64::from(levels))
}

/// One configuration the advisor can choose.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Element order.
    pub order: u8,
    /// Mesh file of the ladder.
    pub mesh: String,
    /// Method.
    pub method: Method,
    /// Normal Δt.
    pub dt: f64,
    /// ε.
    pub eps: f64,
    /// Estimated e_h, e_Δt, e_ε.
    pub parts: [f64; 3],
    /// Predicted wall time, seconds (cost per step × steps, measured on a
    /// pilot run of the same mesh and method).
    pub predicted_time: f64,
}

impl Candidate {
    /// The estimated error, e_h + e_Δt + e_ε.
    pub fn estimate(&self) -> f64 {
        self.parts.iter().sum()
    }
}

/// The cheapest candidate whose estimate is at most `tol` (ties: the more
/// accurate); None when none qualifies.
pub fn pick(candidates: &[Candidate], tol: f64) -> Option<&Candidate> {
    candidates
        .iter()
        .filter(|c| c.estimate().is_finite() && c.estimate() <= tol)
        .min_by(|a, b| {
            a.predicted_time
                .total_cmp(&b.predicted_time)
                .then(a.estimate().total_cmp(&b.estimate()))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn richardson_recovers_the_error_of_a_power_law() {
        // e(h) = C h^p exactly: a − b = C h^p (1 − r^−p), e(h/r) = C (h/r)^p.
        let (c, p, h, r) = (3.0_f64, 2.0_f64, 0.1_f64, 2.0_f64);
        let e = |h: f64| c * h.powf(p);
        let estimate = richardson(e(h) - e(h / r), r, p);
        assert!((estimate - e(h / r)).abs() < 1e-14);
        let order = observed_order(e(h) - e(h / r), e(h / r) - e(h / r / r), r).unwrap();
        assert!((order - p).abs() < 1e-12);
        assert!((extrapolate(e(h), r, p, 2) - e(h / 4.0)).abs() < 1e-14);
        // Not asymptotic: differences that grow give no order.
        assert!(observed_order(1.0, 2.0, 2.0).is_none());
    }

    #[test]
    fn pick_takes_the_cheapest_that_meets_the_tolerance() {
        let cand = |t: f64, e: f64| Candidate {
            order: 2,
            mesh: "m".into(),
            method: Method::CentralDifference,
            dt: 1e-3,
            eps: 1e-4,
            parts: [e, 0.0, 0.0],
            predicted_time: t,
        };
        let all = vec![
            cand(1.0, 0.5),
            cand(2.0, 0.05),
            cand(3.0, 0.01),
            cand(0.5, f64::NAN),
        ];
        assert_eq!(pick(&all, 0.1).unwrap().predicted_time, 2.0);
        assert_eq!(pick(&all, 0.02).unwrap().predicted_time, 3.0);
        assert!(pick(&all, 1e-3).is_none());
        assert_eq!(
            Quantity::parse("friction_stress"),
            Ok(Quantity::FrictionStress)
        );
        assert!(Quantity::parse("sigma").is_err());
    }
}
