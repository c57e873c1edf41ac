//! Error estimates from the differences of runs on a refinement ladder:
//! Richardson's with observed orders, the correlation of the errors of
//! successive levels, errors continued to finer levels, and the error of a
//! run measured against a reference.

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

/// Lowest order used: an observed order below it, or differences that do
/// not decrease, are taken as this (a conservative, slow convergence).
pub const MIN_ORDER: f64 = 0.5;
/// Order assumed from two levels only (no observed order): 1, below every
/// theoretical order here, as the stick/slip kinks make it.
pub const TWO_LEVEL_ORDER: f64 = 1.0;

/// The correlation c of the errors of successive levels from the three
/// differences of three levels. Model: e_1 = ρ1 R e_0, e_2 = ρ2 R e_1 with
/// ⟨e_k, e_{k+1}⟩ = c |e_k| |e_{k+1}| and c² two levels apart (c = 1: the
/// aligned power law of classical Richardson extrapolation; c = 0: errors
/// that differ in phase, as stick/slip events at slightly different times
/// make them). Then |q_0 − q_1|² = E²(1 + ρ1² − 2ρ1 c) and |q_0 − q_2|² =
/// E²(1 + ρ1²ρ2² − 2ρ1ρ2 c²); their ratio fixes c. The root nearest 1 is
/// taken (the larger error); no root in [−1, 1] gives 1.
pub fn correlation(d01: f64, d02: f64, rho1: f64, rho2: f64) -> f64 {
    let target = (d02 / d01).powi(2);
    let f = |c: f64| {
        (1.0 + (rho1 * rho2).powi(2) - 2.0 * rho1 * rho2 * c * c)
            / (1.0 + rho1 * rho1 - 2.0 * rho1 * c)
            - target
    };
    let mut prev = (1.0, f(1.0));
    if prev.1 == 0.0 {
        return 1.0;
    }
    for k in 1..=2000 {
        let c = 1.0 - f64::from(k) * 1e-3;
        let v = f(c);
        if v == 0.0 || (v > 0.0) != (prev.1 > 0.0) {
            // Linear interpolation inside the bracket.
            return prev.0 + (c - prev.0) * prev.1 / (prev.1 - v);
        }
        prev = (c, v);
    }
    1.0
}

/// Errors at every level of a ladder from the differences of the measured
/// levels. `diffs[k]` = ‖q_k − q_{k+1}‖ for the `diffs.len() + 1` measured
/// levels; `skip` = ‖q_{n−2} − q_n‖ of the last three measured levels (None
/// with two levels); `ratios[k]` = refinement ratio from level k to k + 1
/// for all levels (measured and beyond); `max_order` caps the observed
/// order (the theoretical one).
///
/// The last three measured levels give the order p (from the ratio of
/// their differences) and the correlation c of successive errors
/// ([`correlation`]); the first of them then has the error E =
/// d / √(1 + ρ² − 2ρc), ρ = r^−p, and each finer level ρ times the one
/// before (measured or not). With two levels, c = 1 and p =
/// [`TWO_LEVEL_ORDER`]: classical Richardson, |q_0 − q_1| / (r^p − 1) for
/// the finer. Coarser measured levels get the bound e_k ≤ e_{k+1} +
/// |q_k − q_{k+1}|. Returns (errors per level, order, correlation).
pub fn ladder_errors(
    diffs: &[f64],
    skip: Option<f64>,
    ratios: &[f64],
    max_order: f64,
) -> (Vec<f64>, f64, f64) {
    let levels = ratios.len() + 1;
    let n = diffs.len();
    let mut e = vec![f64::NAN; levels];
    if n == 0 {
        return (e, f64::NAN, f64::NAN);
    }
    let (first, p, c) = match skip.filter(|_| n >= 2) {
        Some(d02) => {
            let l = n - 2;
            let p = observed_order(diffs[l], diffs[l + 1], ratios[l + 1])
                .unwrap_or(MIN_ORDER)
                .clamp(MIN_ORDER, max_order);
            let (r1, r2) = (ratios[l].powf(-p), ratios[l + 1].powf(-p));
            (l, p, correlation(diffs[l], d02, r1, r2))
        }
        None => (n - 1, TWO_LEVEL_ORDER.min(max_order), 1.0),
    };
    let rho = ratios[first].powf(-p);
    e[first] = diffs[first].abs() / (1.0 + rho * rho - 2.0 * rho * c).max(0.0).sqrt();
    for k in first + 1..levels {
        e[k] = extrapolate(e[k - 1], ratios[k - 1], p, 1);
    }
    for k in (0..first).rev() {
        e[k] = e[k + 1] + diffs[k].abs();
    }
    (e, p, c)
}

/// The error of a run X from its distance to the reference run R and R's
/// own error: √(‖X − R‖² + e_R²), the two taken as independent parts (a
/// measured difference and the uncertainty of the standard it was measured
/// against, combined as in the GUM). Between the bounds of the triangle
/// inequality, ‖X − R‖ − e_R ≤ e_X ≤ ‖X − R‖ + e_R.
pub fn with_reference(distance: f64, e_ref: f64) -> f64 {
    distance.hypot(e_ref)
}

/// Errors on every level of a ladder from the errors of its first
/// `measured.len()` levels: finer levels by e_{k+1} = e_k / r^p with p
/// observed from the last two measured errors (capped at `max_order`, the
/// theoretical order); when those do not decrease the ladder is not in its
/// asymptotic range (another error, e.g. Δt's, dominates) and no further
/// decrease is assumed (p = 0). With one measured level, p =
/// [`TWO_LEVEL_ORDER`]. Returns (errors per level, p).
pub fn continue_errors(measured: &[f64], ratios: &[f64], max_order: f64) -> (Vec<f64>, f64) {
    let levels = ratios.len() + 1;
    let n = measured.len().min(levels);
    let mut e = measured[..n].to_vec();
    if n == 0 {
        return (vec![f64::NAN; levels], f64::NAN);
    }
    let p = if n >= 2 {
        observed_order(e[n - 2], e[n - 1], ratios[n - 2]).map_or(0.0, |p| p.min(max_order))
    } else {
        TWO_LEVEL_ORDER.min(max_order)
    };
    for k in n..levels {
        let next = extrapolate(e[k - 1], ratios[k - 1], p, 1);
        e.push(next);
    }
    (e, p)
}

/// The error of a run at Δt from its changes at 2Δt and Δt/2 (`d_coarse`
/// = |X(2Δt) − X(Δt)|, `d_fine` = |X(Δt) − X(Δt/2)|): X(Δt/2)'s error by
/// [`richardson`] at the observed order (at least [`MIN_ORDER`], at most
/// `max_order`; [`MIN_ORDER`] when the changes do not decrease), plus
/// d_fine, as the aligned errors of a power law in Δt add.
pub fn dt_error(d_coarse: f64, d_fine: f64, max_order: f64) -> f64 {
    let p =
        observed_order(d_coarse, d_fine, 2.0).map_or(MIN_ORDER, |p| p.clamp(MIN_ORDER, max_order));
    d_fine + richardson(d_fine, 2.0, p)
}

/// [`continue_errors`] for errors with a part that no refinement of the
/// mesh reduces (Newmark's Δt error at its fixed Δt, `floor`): the measured
/// errors less the floor in quadrature are continued, and the floor is
/// added back in quadrature. Continued errors stay at or above the floor
/// (where [`continue_errors`] would take them below it on the decrease of
/// the measured levels, which the floor slows) and at or below the last
/// measured error; measured levels keep their measured errors.
pub fn continue_errors_above(
    measured: &[f64],
    ratios: &[f64],
    max_order: f64,
    floor: f64,
) -> (Vec<f64>, f64) {
    let Some(&last) = measured.last() else {
        return continue_errors(measured, ratios, max_order);
    };
    let above: Vec<f64> = measured
        .iter()
        .map(|e| (e * e - floor * floor).max(0.0).sqrt())
        .collect();
    let (e, p) = continue_errors(&above, ratios, max_order);
    let e = e
        .iter()
        .enumerate()
        .map(|(k, x)| match measured.get(k) {
            Some(&m) => m,
            None => x.hypot(floor).min(last),
        })
        .collect();
    (e, p)
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
    fn ladder_errors_of_a_power_law() {
        // Levels h, h/2, h/4 measured, h/8 beyond; e = C h^p exactly (all
        // errors aligned, c = 1) with p = 1.5 (below the cap 2): every
        // level's error is recovered.
        let (c, p, h) = (2.0_f64, 1.5_f64, 0.2_f64);
        let e = |k: i32| c * (h / 2f64.powi(k)).powf(p);
        let diffs = [e(0) - e(1), e(1) - e(2)];
        let skip = Some(e(0) - e(2));
        let (est, order, corr) = ladder_errors(&diffs, skip, &[2.0, 2.0, 2.0], 2.0);
        assert!((order - p).abs() < 1e-12);
        assert!((corr - 1.0).abs() < 1e-3, "{corr}");
        for k in 0..4 {
            assert!(
                (est[k] - e(k as i32)).abs() < 1e-3 * e(k as i32),
                "{k}: {est:?}"
            );
        }
        // The cap: an observed order above it is not trusted.
        let (_, capped, _) = ladder_errors(&diffs, skip, &[2.0, 2.0, 2.0], 1.0);
        assert_eq!(capped, 1.0);
        // Two levels: classical Richardson with the assumed order.
        let (est, order, _) = ladder_errors(&[1.0], None, &[2.0, 2.0], 2.0);
        assert_eq!(order, TWO_LEVEL_ORDER);
        assert!((est[1] - 1.0 / (2f64.powf(TWO_LEVEL_ORDER) - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn ladder_errors_of_errors_that_differ_in_phase() {
        // Errors along three orthogonal directions (c = 0), halving per
        // level: e_0 = (1, 0, 0), e_1 = (0, ½, 0), e_2 = (0, 0, ¼). The
        // differences are not aligned with the errors; the model recovers
        // |e_k| where classical Richardson (c = 1) would give |e_2| =
        // |q_1 − q_2| = 0.56 (2.2 times too large).
        let rho = 0.5_f64;
        let d01 = (1.0 + rho * rho).sqrt();
        let d12 = rho * d01;
        let d02 = (1.0 + rho.powi(4)).sqrt();
        assert!((correlation(d01, d02, rho, rho)).abs() < 1e-3);
        let (est, order, _) = ladder_errors(&[d01, d12], Some(d02), &[2.0, 2.0], 2.0);
        assert!((order - 1.0).abs() < 1e-12);
        for (k, want) in [1.0, 0.5, 0.25].iter().enumerate() {
            assert!((est[k] - want).abs() < 1e-3, "{k}: {est:?}");
        }
    }

    #[test]
    fn errors_against_a_reference() {
        // e_X = X − R + e_R with the two parts orthogonal: |e_X|² = d² +
        // e_R² (Pythagoras), and inside the triangle-inequality bounds.
        let (d, e_r) = (3.0, 4.0);
        assert_eq!(with_reference(d, e_r), 5.0);
        assert!(with_reference(d, e_r) <= d + e_r && with_reference(d, e_r) >= e_r - d);
        assert_eq!(with_reference(d, 0.0), d);
    }

    #[test]
    fn continue_errors_of_a_power_law_and_of_a_floor() {
        // e = C h^p, p = 1.5, measured on three of five levels: the last
        // two give p, the finer levels follow it exactly.
        let e = |k: i32| 2.0 * (0.2 / 2f64.powi(k)).powf(1.5);
        let (est, p) = continue_errors(&[e(0), e(1), e(2)], &[2.0; 4], 2.0);
        assert!((p - 1.5).abs() < 1e-12);
        for k in 0..5 {
            assert!(
                (est[k] - e(k as i32)).abs() < 1e-12 * e(k as i32),
                "{k}: {est:?}"
            );
        }
        // Capped at the theoretical order.
        assert_eq!(continue_errors(&[e(0), e(1)], &[2.0; 2], 1.0).1, 1.0);
        // Errors that stop decreasing (a Δt floor): no decrease assumed.
        let (est, p) = continue_errors(&[0.04, 0.015, 0.017], &[2.0; 3], 3.0);
        assert_eq!(p, 0.0);
        assert_eq!(est[3], 0.017);
    }

    #[test]
    fn continue_errors_above_a_dt_floor() {
        // e = √((C h^p)² + f²): a mesh part with p = 2 and a Δt part f
        // that no mesh reduces, measured on three of five levels.
        let f = 0.01;
        let e = |k: i32| (3.0 * (0.2 / 2f64.powi(k)).powi(2)).hypot(f);
        let measured = [e(0), e(1), e(2)];
        let (est, p) = continue_errors_above(&measured, &[2.0; 4], 3.0, f);
        assert!((p - 2.0).abs() < 1e-9, "{p}");
        for k in 0..5 {
            assert!(
                (est[k] - e(k as i32)).abs() < 1e-9 * e(k as i32),
                "{k}: {est:?}"
            );
        }
        // Continued as mesh error, the floor's slower decrease was taken
        // on, and the finest levels fell below the floor itself.
        let (plain, _) = continue_errors(&measured, &[2.0; 4], 3.0);
        assert!(plain[4] < f && plain[4] < 0.9 * e(4), "{plain:?}");
        // A floor above the measured errors: they stay as measured and
        // the finer levels at the last of them.
        let (est, _) = continue_errors_above(&[0.03, 0.02, 0.015], &[2.0; 4], 3.0, 0.05);
        assert_eq!(est, vec![0.03, 0.02, 0.015, 0.015, 0.015]);
    }

    #[test]
    fn dt_error_of_a_power_law() {
        // X(Δt) = X* + C Δt²: changes at 2Δt → Δt and Δt → Δt/2 give
        // X(Δt)'s error C Δt².
        let x = |dt: f64| 1.0 + 5.0 * dt * dt;
        let dt = 0.01;
        let (dc, df) = ((x(2.0 * dt) - x(dt)).abs(), (x(dt) - x(dt / 2.0)).abs());
        assert!((dt_error(dc, df, 2.0) - 5.0 * dt * dt).abs() < 1e-12);
        // Changes that do not decrease: the slowest order, a larger error.
        assert!(dt_error(df, df, 2.0) > 2.0 * df);
    }
}
