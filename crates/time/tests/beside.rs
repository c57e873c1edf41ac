//! From 100k free DOFs the explicit scheme estimates its critical step
//! (Lanczos) on a thread of its own beside the static preload: beside the
//! preload's analysis where the run's Δt could be refused, beside the
//! whole preload where it cannot (within Gershgorin's bound on ω_max, or
//! `allow_unstable`). Either way the critical step and the initial state
//! have the bits of the sequential computation, written out here with the
//! crates' public functions (the preload's factor in single precision,
//! refined), and a Δt above the critical step is still refused. Where the
//! dissection's two first halves are known, the preload is factorized by
//! them on both threads, and the critical step comes before it.

use nalgebra_sparse::CsrMatrix;
use stickslip_linalg::{
    backward_error, FillOrder, Product, SparseCholesky, SplitSingle, BACKWARD_ERROR,
};
use stickslip_testkit::{structured_slab, Slab};
use stickslip_time::stability::{critical_step_with, gershgorin_bound, largest_eigenvalue};
use stickslip_time::{Dynamics, History, Integrator, Scheme, Settings, TimeError};

/// The paper's slab on a Q1 grid of 102,770 free DOFs (above the 100k
/// from which the critical step runs beside the preload).
fn slab() -> Slab {
    let s = Slab::paper(structured_slab(456, 112, false), 1e-4, History::Step, true).unwrap();
    assert!(
        s.model.dofs.n_free() >= 100_000,
        "{}",
        s.model.dofs.n_free()
    );
    s
}

/// The scene's dynamics, its K·x by K's symmetric node blocks (no stencil
/// types: [`critical_step`] here forms the same); its fill order without
/// the dissection's halves, so that the preload's factor is K's whole.
fn dynamics(s: &Slab) -> Dynamics {
    let mut d = halved_dynamics(s);
    let order = d.fill_order.dissection_order().expect("a dissection");
    d.fill_order = FillOrder::dissection_unless_amd(order.to_vec());
    d
}

/// [`dynamics`] with the fill order the model chose, the dissection's
/// halves known.
fn halved_dynamics(s: &Slab) -> Dynamics {
    let mut d = Dynamics::from_model(&s.model);
    d.stencils = false;
    d
}

/// Δt_crit as a run estimates it, on one thread: Lanczos on the step's
/// own product (the node blocks, `stencils` being off), capped by
/// Gershgorin's bound.
fn critical_step(k: &CsrMatrix<f64>, m: &[f64]) -> f64 {
    let product = Product::without_csr(k, false).expect("K's node blocks");
    critical_step_with(|x, y| product.spmv(x, y), m, Some(gershgorin_bound(k, m)))
}

fn integrator(s: &Slab, settings: Settings) -> Result<Integrator, TimeError> {
    Integrator::new(dynamics(s), s.contact.clone(), s.loads.clone(), settings)
}

/// The preload R(0⁻): the pressure, constant; the end load is a step, 0
/// before t = 0.
fn preload(s: &Slab, d: &Dynamics) -> Vec<f64> {
    let mut r0 = d.constant_load.clone();
    for l in &s.loads {
        let theta = l.history.before_start();
        for (r, f) in r0.iter_mut().zip(&l.vector) {
            *r += theta * f;
        }
    }
    r0
}

/// With the dissection's halves the preload is `SplitSingle`'s refined
/// solve, after the critical step (both take the two threads), whether
/// the run's Δt could be refused or not; the bits are the sequential
/// computation's, and the preload is the whole factor's to round-off.
#[test]
fn by_halves_the_critical_step_comes_first() {
    let s = slab();
    let d = halved_dynamics(&s);
    let (k, m) = (&d.stiffness, &d.lumped_mass);
    let dt_crit = critical_step(k, m);
    let load = preload(&s, &d);
    d.fill_order.keep_dissection();
    let order = d.fill_order.dissection_order().unwrap();
    let halves = d.fill_order.halves().expect("the slab's halves");
    let mut split = SplitSingle::analyze(k, order, halves)
        .unwrap()
        .expect("the halves are uncoupled");
    split.factorize(k).unwrap();
    let mut r0 = load.clone();
    split.solve_refined(k, &mut r0, BACKWARD_ERROR).unwrap();
    assert!(backward_error(k, &r0, &load) <= BACKWARD_ERROR);
    let mut whole = load.clone();
    let mut chol = SparseCholesky::analyze(k, &d.fill_order).unwrap();
    chol.factorize(k).unwrap();
    chol.solve_in_place(&mut whole);
    let norm = whole.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let apart = whole
        .iter()
        .zip(&r0)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(apart <= 1e-9 * norm, "{apart:e} of {norm:e}");
    let cd = |dt| Settings::new(Scheme::CentralDifference, dt, 0.5);
    let halved = |settings| {
        Integrator::new(
            halved_dynamics(&s),
            s.contact.clone(),
            s.loads.clone(),
            settings,
        )
    };
    let mut allowed = cd(2.0 * dt_crit);
    allowed.allow_unstable = true;
    for (what, settings) in [
        ("refusable", cd(0.99 * dt_crit)),
        ("within the bound", cd(1e-9)),
        ("allowed", allowed),
    ] {
        let i = halved(settings).unwrap();
        assert_eq!(
            i.dt_crit().map(f64::to_bits),
            Some(dt_crit.to_bits()),
            "{what}"
        );
        assert!(i.displacement() == &r0[..], "{what}: r₀");
        let order = [
            "critical step",
            "preload ordering",
            "preload factor",
            "preload solve",
        ];
        let taken: Vec<_> = parts(&i)
            .into_iter()
            .filter(|p| order.contains(p))
            .collect();
        assert_eq!(taken, order, "{what}: the parts' order");
    }
    match halved(cd(1.01 * dt_crit)) {
        Err(TimeError::Unstable { dt_crit: said, .. }) => {
            assert_eq!(said.to_bits(), dt_crit.to_bits());
        }
        other => panic!("not refused: {other:?}"),
    }
}

/// The names of an integrator's setup parts, in the order taken.
fn parts(i: &Integrator) -> Vec<&'static str> {
    i.setup_times().parts().iter().map(|(n, _)| *n).collect()
}

#[test]
fn the_critical_step_beside_the_preload_has_the_sequential_bits() {
    let s = slab();
    let d = dynamics(&s);
    let (k, m) = (&d.stiffness, &d.lumped_mass);
    // Sequentially: Lanczos on K and the lumped mass, then Remark 4.1's
    // r₀ = K⁻¹ R(0⁻) by Cholesky on the dissection's order (the preload:
    // the pressure, constant; the end load is a step, 0 before t = 0).
    let dt_crit = critical_step(k, m);
    let mut r0 = preload(&s, &d);
    // From 100k free DOFs the factor is single precision, refined by CG
    // to backward error 2u.
    d.fill_order.keep_dissection();
    let load = r0.clone();
    let mut chol = SparseCholesky::analyze(k, &d.fill_order).unwrap();
    chol.factorize_single(k).unwrap();
    chol.solve_refined(k, &mut r0, BACKWARD_ERROR).unwrap();
    assert!(backward_error(k, &r0, &load) <= BACKWARD_ERROR);
    // The double factor's solve: two solutions of backward errors η₁, η₂
    // differ by at most κ(K)(η₁ + η₂) relative, and the slab's K (Q1, h =
    // 1/112 of its height) has κ(K) well under 1e6: 1e-9 holds that.
    let mut double = load.clone();
    chol.factorize(k).unwrap();
    chol.solve_in_place(&mut double);
    let norm = double.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let apart = double
        .iter()
        .zip(&r0)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(apart <= 1e-9 * norm, "{apart:e} of {norm:e}");

    // Gershgorin's bound is above the estimate (both at or above ω_max²
    // here, the estimate by at most stability::RESIDUAL, and the critical
    // step caps it by the bound), so its Δt is below the critical step:
    // this one can be refused.
    let bound = gershgorin_bound(k, m);
    let lambda = largest_eigenvalue(k, m, 300);
    assert!(bound >= lambda, "{bound} < {lambda}");
    let refusable = 0.99 * dt_crit;
    assert!(refusable > 2.0 / bound.sqrt());
    let cd = |dt| Settings::new(Scheme::CentralDifference, dt, 0.5);
    let analysis = integrator(&s, cd(refusable)).unwrap();
    // Within the bound, or allowed above it: nothing to refuse.
    let within = integrator(&s, cd(1e-9)).unwrap();
    let mut unstable = cd(2.0 * dt_crit);
    unstable.allow_unstable = true;
    let allowed = integrator(&s, unstable).unwrap();
    for (what, i, order) in [
        (
            "beside the analysis",
            &analysis,
            [
                "preload ordering",
                "critical step",
                "preload factor",
                "preload solve",
            ],
        ),
        (
            "beside the preload (within the bound)",
            &within,
            [
                "preload ordering",
                "preload factor",
                "preload solve",
                "critical step",
            ],
        ),
        (
            "beside the preload (allowed)",
            &allowed,
            [
                "preload ordering",
                "preload factor",
                "preload solve",
                "critical step",
            ],
        ),
    ] {
        assert_eq!(
            i.dt_crit().map(f64::to_bits),
            Some(dt_crit.to_bits()),
            "{what}"
        );
        assert!(i.displacement() == &r0[..], "{what}: r₀");
        let taken: Vec<_> = parts(i).into_iter().filter(|p| order.contains(p)).collect();
        assert_eq!(taken, order, "{what}: the parts' order");
    }
    // Above the critical step: refused, its Δt_crit the same.
    match integrator(&s, cd(1.01 * dt_crit)) {
        Err(TimeError::Unstable { dt_crit: said, .. }) => {
            assert_eq!(said.to_bits(), dt_crit.to_bits());
        }
        other => panic!("not refused: {other:?}"),
    }
}

/// With a compliant foundation the estimate adds its springs w_J c_n ννᵀ,
/// which Gershgorin's bound on K does not hold: a Δt within that bound may
/// still be refused, so only the preload's analysis runs beside Lanczos
/// (its parts in that order) and a Δt between the springs' critical step
/// and K's bound is refused. The foundation lies 1 below the slab's bottom
/// (out of reach: the preload is K r₀ = R(0⁻)), c_n = 1e8, whose springs
/// (about c_n h/m per node) raise ω_max² far above K's bound.
#[test]
fn with_a_compliant_foundation_only_the_analysis_runs_beside() {
    use stickslip_contact::{Compliance, ContactSurface};
    let mut s = slab();
    let law = Compliance {
        cn: 1e8,
        mn: 1.0,
        ct: 0.0,
        mt: 1.0,
    };
    let floor = ([0.0, -1.0], [0.0, 1.0]);
    s.contact = Some(
        ContactSurface::on_foundation(&s.mesh, &s.model.dofs, "contact", floor, law, 1e-4).unwrap(),
    );
    let d = dynamics(&s);
    let k_step = 2.0 / gershgorin_bound(&d.stiffness, &d.lumped_mass).sqrt();
    let cd = |dt| Settings::new(Scheme::CentralDifference, dt, 0.5);
    let within = integrator(&s, cd(1e-9)).unwrap();
    let dt_crit = within.dt_crit().unwrap();
    assert!(dt_crit < 0.1 * k_step, "{dt_crit} vs K's {k_step}");
    let order = [
        "preload ordering",
        "critical step",
        "preload factor",
        "preload solve",
    ];
    let taken: Vec<_> = parts(&within)
        .into_iter()
        .filter(|p| order.contains(p))
        .collect();
    assert_eq!(taken, order);
    match integrator(&s, cd((dt_crit * k_step).sqrt())) {
        Err(TimeError::Unstable { dt_crit: said, .. }) => {
            assert_eq!(said.to_bits(), dt_crit.to_bits());
        }
        other => panic!("not refused: {other:?}"),
    }
}
