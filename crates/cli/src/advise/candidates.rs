//! A configuration the advisor can choose, with its estimated error and
//! predicted time, and the pick among them for a tolerance.

use stickslip_case::Method;

/// One configuration the advisor can choose.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Element order.
    pub order: u8,
    /// Mesh file as written in the case's ladder.
    pub mesh: String,
    /// Index of the mesh in the ladder.
    pub mesh_index: usize,
    /// Method.
    pub method: Method,
    /// Normal Δt.
    pub dt: f64,
    /// ε.
    pub eps: f64,
    /// Estimated parts: the error of this mesh with the family's base Δt
    /// (central difference 0.9 Δt_crit, Newmark t_end/200), the change
    /// that this method and Δt make on the pilot mesh, the change that
    /// this ε makes there. A configuration that was run as a pilot has its
    /// own measured error here and zeros.
    pub parts: [f64; 3],
    /// Predicted wall time, seconds.
    pub predicted_time: f64,
    /// Free DOFs.
    pub dofs: usize,
    /// Predicted steps.
    pub steps: f64,
    /// Whether the mesh was a pilot of the h estimate (else extrapolated).
    pub measured_h: bool,
    /// Whether this very configuration was a pilot run.
    pub run: bool,
}

impl Candidate {
    /// The estimated error: the parts in quadrature, √(e_h² + δ_Δt² +
    /// δ_ε²). The parts are not independent errors of one kind that add
    /// (their sum is a bound only when they are aligned); the changes a Δt
    /// or ε makes are taken as uncorrelated with the mesh's error, as the
    /// measured distances show for the runs that were made.
    pub fn estimate(&self) -> f64 {
        self.parts.iter().map(|x| x * x).sum::<f64>().sqrt()
    }
}

/// Predicted times within this factor of the cheapest are a tie. They
/// rest on timings of millisecond pilots, which vary by about that much on
/// a shared machine: the README's example picked Q2 16×4 Newmark (0.014 s
/// predicted) in one run of five and Q1 64×16 central difference (0.015-
/// 0.020 s) in the others. The estimates do not depend on timing.
pub const TIE: f64 = 1.5;

/// The cheapest candidate whose estimate is at most `tol`, where those
/// within [`TIE`] of the cheapest predicted time tie and the most accurate
/// of them wins (so the choice does not follow the machine's load); None
/// when none qualifies.
pub fn pick(candidates: &[Candidate], tol: f64) -> Option<&Candidate> {
    let meets = || {
        candidates
            .iter()
            .filter(|c| c.estimate().is_finite() && c.estimate() <= tol)
    };
    let cheapest = meets()
        .map(|c| c.predicted_time)
        .fold(f64::INFINITY, f64::min);
    meets()
        .filter(|c| c.predicted_time <= TIE * cheapest)
        .min_by(|a, b| {
            a.estimate()
                .total_cmp(&b.estimate())
                .then(a.predicted_time.total_cmp(&b.predicted_time))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pick_takes_the_cheapest_that_meets_the_tolerance() {
        let cand = |t: f64, e: f64| Candidate {
            order: 2,
            mesh: "m".into(),
            mesh_index: 0,
            method: Method::CentralDifference,
            dt: 1e-3,
            eps: 1e-4,
            parts: [e, 0.0, 0.0],
            predicted_time: t,
            dofs: 1,
            steps: 1.0,
            measured_h: true,
            run: false,
        };
        // Times more than TIE apart: the cheapest that meets the tolerance.
        let all = vec![
            cand(1.0, 0.5),
            cand(2.0, 0.05),
            cand(3.5, 0.01),
            cand(0.5, f64::NAN),
        ];
        assert_eq!(pick(&all, 0.1).unwrap().predicted_time, 2.0);
        assert_eq!(pick(&all, 0.02).unwrap().predicted_time, 3.5);
        assert!(pick(&all, 1e-3).is_none());
        // Within TIE of the cheapest, the most accurate: 1.4 s over 1.0 s
        // (0.05 against 0.09); 1.6 s is past 1.5 × 1.0 s.
        let close = vec![cand(1.0, 0.09), cand(1.4, 0.05), cand(1.6, 0.01)];
        assert_eq!(pick(&close, 0.1).unwrap().predicted_time, 1.4);
    }
}
