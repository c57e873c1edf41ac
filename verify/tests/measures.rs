//! The measures the verify rows are built on, checked on signals whose
//! answer is known by construction.

use std::path::Path;

use stickslip_verify::suites::paper::ringing;
use stickslip_verify::suites::rates::fitted_order;
use stickslip_verify::suites::reference::{parse, to_csv};
use stickslip_verify::Trace;

/// A trace of node 81: slipping for 5 steps, then stuck with σ = f(k).
fn stuck_trace(f: impl Fn(usize) -> f64) -> Trace {
    let n = 60;
    let dt = 5e-3;
    Trace {
        t: (0..n).map(|k| k as f64 * dt).collect(),
        dt: (0..n).map(|k| if k == 0 { 0.0 } else { dt }).collect(),
        normal_dt: dt,
        sigma81: (0..n).map(|k| if k < 5 { 90.0 } else { f(k) }).collect(),
        stuck81: (0..n).map(|k| k == 0 || k >= 5).collect(),
        ..Trace::default()
    }
}

#[test]
fn ringing_of_an_alternation_is_its_amplitude() {
    // 60 + 0.1k ± 7: step-to-step changes ±14 ± 0.1, so the zig-zag measure
    // min(|Δ_k|, |Δ_{k+1}|)/2 = (14 − 0.1)/2.
    let t = stuck_trace(|k| 60.0 + 0.1 * k as f64 + if k % 2 == 0 { 7.0 } else { -7.0 });
    let (ts, a) = ringing(&t).unwrap();
    assert!((ts - 5.0 * 5e-3).abs() < 1e-15);
    assert!((a - 6.95).abs() < 1e-12, "amplitude {a}");
}

#[test]
fn ringing_of_a_smooth_signal_is_small() {
    // 60 + A sin(ωt), A = 10, ω = 2π/0.2, sampled at Δt = 5e-3: it turns
    // only at its extrema, where the smaller of the two changes around the
    // turn is at most A(ωΔt)² ≈ 0.247, so the measure is at most half that.
    let t =
        stuck_trace(|k| 60.0 + 10.0 * (2.0 * std::f64::consts::PI * k as f64 * 5e-3 / 0.2).sin());
    let (_, a) = ringing(&t).unwrap();
    assert!(
        a <= 0.5 * 10.0 * (2.0 * std::f64::consts::PI * 5e-3 / 0.2f64).powi(2),
        "amplitude {a}"
    );
}

#[test]
fn fitted_order_recovers_a_power_law() {
    let x = [0.1, 0.05, 0.025, 0.0125];
    let e: Vec<f64> = x.iter().map(|h: &f64| 3.0 * h.powf(2.5)).collect();
    assert!((fitted_order(&x, &e) - 2.5).abs() < 1e-12);
}

#[test]
fn reference_csv_round_trips_exactly_and_rejects_bad_fields() {
    let mut t = stuck_trace(|k| (k as f64).sqrt() / 3.0);
    let n = t.t.len();
    t.ux81 = (0..n).map(|k| 0.936 - 1e-3 * k as f64 / 7.0).collect();
    t.ux85 = t.ux81.clone();
    t.sigma71 = t.sigma81.clone();
    t.v81 = vec![-1.0 / 3.0; n];
    t.energy = vec![stickslip_time::Energy::default(); n];
    let text = to_csv(&t);
    let cols = parse(&text, Path::new("x.csv")).unwrap();
    assert_eq!(cols[1], t.ux81, "17 significant digits round-trip f64");
    assert_eq!(cols[4], t.sigma81);
    let bad = text.replacen("0.", "0,x", 1);
    let e = parse(&bad, Path::new("x.csv")).unwrap_err();
    assert!(e.contains("x.csv: line"), "{e}");
}
