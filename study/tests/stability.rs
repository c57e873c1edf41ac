//! The qualitative facts of the stability map, on the paper's meshes: central
//! difference unstable above and stable below the estimated Δt_crit; the
//! ringing after sticking removed by the step reduction of Remark 4.3; no
//! iteration failures with Remark 4.2.

use stickslip_case::Method;
use stickslip_study::run::TRAPEZOIDAL;
use stickslip_study::slab::{self, read_mesh, LoadKind};
use stickslip_study::stability::{growth, iteration_run, ringing, threshold, STABILITY_STEPS};
use stickslip_time::Scheme;

#[test]
fn central_difference_is_stable_below_and_unstable_above_the_estimate() {
    for mesh in ["slab-q1-16x4.msh", "slab-q2-8x2.msh"] {
        let m = read_mesh(mesh).unwrap();
        for friction in [false, true] {
            let s = slab::paper(&m, 1e-4, LoadKind::Step, friction).unwrap();
            let tag = format!("{mesh} friction {friction}");
            for r in [0.5, 0.9, 0.99] {
                let g = growth(&s, r, STABILITY_STEPS).unwrap();
                assert!(g.stable(), "{tag}: Δt/Δt_crit = {r} grew {}", g.growth);
            }
            for r in [1.01, 1.1, 2.0] {
                let g = growth(&s, r, STABILITY_STEPS).unwrap();
                assert!(
                    !g.stable(),
                    "{tag}: Δt/Δt_crit = {r} grew only {}",
                    g.growth
                );
            }
            // The map's requirement: the observed threshold within 2% of
            // the Lanczos estimate of 2/ω_max; and not below it (to the
            // bisection's width, 1e-3), the estimate bounding ω_max from
            // above.
            let observed = threshold(&s, 0.9, 1.1, 1e-3, STABILITY_STEPS).unwrap();
            assert!(
                (observed - 1.0).abs() < 0.02,
                "{tag}: observed threshold {observed} × estimate"
            );
            assert!(
                observed >= 1.0 - 1e-3,
                "{tag}: observed threshold {observed} below the estimate"
            );
        }
    }
}

#[test]
fn step_reduction_removes_the_ringing_after_sticking() {
    // Node (7, 0) of the paper's mesh: w = 1/3, HRZ mass 2·0.5/36, so at
    // Δt = 5e-3, ε = 1e-4 the stuck node's ratio is x = Δt·w·g/(ε·m) ≈ 5.4e4
    // and the trapezoidal damper update (1 − x/2)/(1 + x/2) ≈ −0.99993:
    // an undamped alternation. The reduced step 1e-7 gives x ≈ 1.08 and a
    // factor ≈ 0.30 per step, 6e-6 over the 10 steps; what is left is the
    // physical variation of σ_T. Newmark 0.3025/0.6 multiplies by about
    // −(1 − γ)/γ = −0.67 per step.
    let m = read_mesh("slab-q2-8x2.msh").unwrap();
    let s = slab::paper(&m, 1e-4, LoadKind::Step, true).unwrap();
    let node = s.node_at(7.0, 0.0).unwrap();
    let amp = |method| {
        ringing(&s, node, method, 5e-3, 1e-4, 0.5)
            .unwrap()
            .expect("node (7, 0) sticks after slipping")
    };
    let plain = amp(Method::Trapezoidal);
    let reduced = amp(Method::TrapezoidalReduced);
    let damped = amp(Method::Damped);
    assert!(
        (plain.ratio - 5.4e4).abs() < 0.01 * 5.4e4,
        "x = {}",
        plain.ratio
    );
    assert!(
        plain.amplitude > 0.05,
        "Newmark ¼,½ without reduction must ring: {}",
        plain.amplitude
    );
    assert!(
        reduced.amplitude < 0.1 * plain.amplitude,
        "with reduction {} against {} without",
        reduced.amplitude,
        plain.amplitude
    );
    assert!(
        damped.amplitude < 0.1 * plain.amplitude,
        "0.3025/0.6 {} against {}",
        damped.amplitude,
        plain.amplitude
    );
    // Central difference treats the stuck node's damping by the same
    // trapezoidal rule (γ = ½), so it rings too (BENCHMARK.md).
    let cd = ringing(&s, node, Method::CentralDifference, 1e-3, 1e-4, 0.5)
        .unwrap()
        .expect("node (7, 0) sticks");
    assert!(cd.amplitude > 0.05, "central difference: {}", cd.amplitude);
}

#[test]
fn remark_4_2_leaves_no_failed_steps() {
    let m = read_mesh("slab-q2-8x2.msh").unwrap();
    for eps in [1e-1, 1e-2, 1e-4, 1e-6] {
        let s = slab::paper(&m, eps, LoadKind::Step, true).unwrap();
        for (scheme, dt) in [(Scheme::CentralDifference, 1e-3), (TRAPEZOIDAL, 5e-3)] {
            let with = iteration_run(&s, scheme, dt, true, 0.5).unwrap();
            assert_eq!(with.failed, 0, "{scheme:?} ε = {eps}: {with:?}");
            assert!(with.max_iterations <= 10, "{scheme:?} ε = {eps}: {with:?}");
        }
    }
    // Without it the iteration cycles between the two slip directions on
    // unloading (paper, Remark 4.2) at the paper's ε.
    let s = slab::paper(&m, 1e-4, LoadKind::Step, true).unwrap();
    for (scheme, dt) in [(Scheme::CentralDifference, 1e-3), (TRAPEZOIDAL, 5e-3)] {
        let without = iteration_run(&s, scheme, dt, false, 0.5).unwrap();
        assert!(without.failed > 0, "{scheme:?}: {without:?}");
    }
}

/// The committed tables, docs/stability-*.csv, are what `cargo xtask
/// stability` writes now: a change to the integrators that moves a figure
/// must regenerate them. Numbers agree to 1e-5 relative (they are printed
/// to 5-7 significant digits; the last may differ on another CPU's
/// kernels), every other field exactly.
#[test]
fn committed_tables_are_what_the_study_writes() {
    let root = stickslip_testkit::workspace_root();
    let out = stickslip_testkit::scratch("stability");
    stickslip_study::stability::main(&out, false).unwrap();
    let mut problems = Vec::new();
    for name in [
        "stability-critical.csv",
        "stability-ringing.csv",
        "stability-iteration.csv",
    ] {
        let committed = std::fs::read_to_string(root.join("docs").join(name)).unwrap();
        let fresh = std::fs::read_to_string(out.join(name)).unwrap();
        let (c_lines, f_lines): (Vec<&str>, Vec<&str>) =
            (committed.lines().collect(), fresh.lines().collect());
        if c_lines.len() != f_lines.len() {
            problems.push(format!(
                "{name}: {} lines committed, {} written",
                c_lines.len(),
                f_lines.len()
            ));
            continue;
        }
        for (i, (c, f)) in c_lines.iter().zip(&f_lines).enumerate() {
            let differs = c.split(',').count() != f.split(',').count()
                || c.split(',')
                    .zip(f.split(','))
                    .any(|(a, b)| fields_differ(a, b));
            if differs {
                problems.push(format!(
                    "{name} line {}:\n  committed {c}\n  written   {f}",
                    i + 1
                ));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    assert!(
        problems.is_empty(),
        "docs/stability-*.csv differ from a fresh run; run `cargo xtask stability` and commit them:\n{}",
        problems.join("\n")
    );
}

/// Whether a committed CSV field `a` and a fresh one `b` differ: numbers by
/// more than 1e-5 relative, anything else as text. A NaN or an infinity
/// equals only itself (in the arithmetic test it would equal anything).
fn fields_differ(a: &str, b: &str) -> bool {
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) if x.is_finite() && y.is_finite() => {
            (x - y).abs() > 1e-5 * x.abs().max(y.abs())
        }
        (Ok(x), Ok(y)) => !(x == y || x.is_nan() && y.is_nan()),
        _ => a != b,
    }
}

#[test]
fn the_tables_comparison_sees_nan_and_infinity() {
    assert!(!fields_differ("1.0000e0", "1.00001e0"));
    assert!(fields_differ("1.0000e0", "1.0001e0"));
    assert!(fields_differ("true", "false"));
    for (committed, fresh) in [
        ("1.2509e7", "NaN"),
        ("NaN", "1.2509e7"),
        ("1.2509e7", "inf"),
        ("inf", "-inf"),
        ("inf", "1e308"),
    ] {
        assert!(
            fields_differ(committed, fresh),
            "{committed} against {fresh} passed"
        );
    }
    assert!(!fields_differ("NaN", "NaN"));
    assert!(!fields_differ("inf", "inf"));
}
