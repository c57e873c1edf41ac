//! The initial state of paper Remark 4.1 (METHOD.md §4): r₀ the
//! frictionless static equilibrium under the loads present at t = 0⁻ (or
//! r₀ = 0 for a start at rest, every load then acting from t = 0 on),
//! ṙ₀ = 0 (or given), r̈₀ from M r̈₀ = R(0) − K r₀ − C ṙ₀ − J(ṙ₀) (C the
//! Rayleigh damping; J the friction at the slip at t = 0, which is zero
//! at rest on a foundation at rest, so that Remark 4.1's r̈₀ is
//! frictionless). Quasi-static increments (no mass) start from the static
//! state with no friction at all.

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::ContactSurface;
use stickslip_fem::{RigidMode, SetupTimes};
use stickslip_linalg::csr::{dot, quadratic_form, spmv};
use stickslip_linalg::{
    chunks, solve_by_diagonal, Analysis, FillOrder, SparseCholesky, SplitSingle, BACKWARD_ERROR,
};

use crate::dynamics::Loads;
use crate::settings::{InitialState, Settings, TimeError};
use crate::state::{Energy, State};

/// CG iterations on a consistent mass's diagonal before its factorization
/// takes over: about twice the most measured (45, on unstructured Q1
/// meshes; 9-26 on structured ones, 35-36 on unstructured Q2).
const MASS_ITERATIONS: usize = 100;

/// The mass a scheme uses, as the initial state needs it.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Mass<'a> {
    /// The HRZ lumped mass, one value per free DOF.
    Lumped(&'a [f64]),
    /// The consistent mass.
    Consistent(&'a CsrMatrix<f64>),
    /// No mass (quasi-static increments): r̈₀ = 0, nothing kinetic.
    Massless,
}

impl Mass<'_> {
    /// x = M⁻¹ b in place (`b` given in `x`; no mass: r̈ = 0, so x = 0).
    /// A consistent M is solved by CG on its diagonal to a factor solve's
    /// backward error, or else factorized for the one solve, on `shared`
    /// (K's analysis, which M's pattern shares) where given; the analysis
    /// a factorization used is returned (`None` for CG, a lumped M or
    /// none).
    ///
    /// # Errors
    /// [`TimeError::Static`] where M's analysis or factorization fails.
    pub fn solve_in_place(
        &self,
        x: &mut [f64],
        fill_order: &FillOrder,
        shared: SharedAnalysis,
    ) -> Result<SharedAnalysis, TimeError> {
        match self {
            Mass::Lumped(m) => {
                for (x, m) in x.iter_mut().zip(*m) {
                    *x /= m;
                }
                Ok(None)
            }
            Mass::Consistent(m) => {
                // CG on M's diagonal reaches the factor's accuracy in
                // 10-50 products on any mesh (refine.rs); the factor stays
                // for a mass it does not serve (elements distorted enough
                // to spread κ(D⁻¹M)).
                if solve_by_diagonal(m, x, BACKWARD_ERROR, MASS_ITERATIONS).is_ok() {
                    return Ok(None);
                }
                let mut solver = Analysis::shared_or_of(shared, m, fill_order)
                    .and_then(SparseCholesky::on)
                    .map_err(TimeError::Static)?;
                solver.factorize(m).map_err(TimeError::Static)?;
                solver.solve_in_place(x);
                Ok(Some(solver.analysis().clone()))
            }
            Mass::Massless => {
                x.fill(0.0);
                Ok(None)
            }
        }
    }

    /// M x into `out`.
    pub fn apply(&self, x: &[f64], out: &mut [f64]) {
        match self {
            Mass::Lumped(m) => {
                for ((o, x), m) in out.iter_mut().zip(x).zip(*m) {
                    *o = m * x;
                }
            }
            Mass::Consistent(m) => spmv(m, x, out),
            Mass::Massless => out.fill(0.0),
        }
    }

    /// xᵀ M x.
    pub fn form(&self, x: &[f64], partials: &mut [[f64; 2]]) -> f64 {
        match self {
            Mass::Lumped(m) => x.iter().zip(*m).map(|(v, m)| m * v * v).sum(),
            Mass::Consistent(m) => quadratic_form(m, x, partials),
            Mass::Massless => 0.0,
        }
    }
}

/// K's symbolic analysis (its ordering and symbolic factor), which K, M
/// and the implicit steps' A₀ = c_K K + c_M M share: they have one
/// pattern (fem), so a run analyses it once.
pub(crate) type SharedAnalysis = Option<stickslip_linalg::Analysis>;

/// How the initial state's static problems are solved: the ordering of
/// their factors, the rigid motions the supports leave free (`modes`),
/// and where the preload's times go.
pub(crate) struct Statics<'a> {
    pub fill_order: &'a FillOrder,
    pub modes: &'a [RigidMode],
    pub times: &'a mut SetupTimes,
    /// K is factorized here only (the explicit scheme): the dissection is
    /// kept without AMD's analysis ([`FillOrder::keep_dissection`]), and
    /// from [`SINGLE_MIN`] free DOFs the factor is computed in single
    /// precision.
    pub single_factor: bool,
    /// Where K's analysis is kept once made here (by the preload, or by a
    /// consistent mass's factorization where CG on its diagonal stalls),
    /// for the step's operators (the implicit schemes);
    /// `None` where nothing after the initial state factorizes.
    pub analysis: Option<&'a mut SharedAnalysis>,
}

/// Free DOFs from which a preload whose factor serves it alone (the
/// explicit scheme's) is factorized in single precision and refined to
/// double's accuracy ([`SparseCholesky::solve_refined`]): where the
/// factorization is most of the setup (docs/performance.md, "The preload
/// in single precision"). Below, and so in every reference case, the
/// double factor's solve, bit for bit.
pub(crate) const SINGLE_MIN: usize = 100_000;

/// K⁻¹ r in place by sparse Cholesky, the analysis (the ordering and
/// the symbolic factor), the factor and the solve timed as the preload's.
///
/// # Errors
/// [`TimeError::Static`] when K is not positive definite.
pub(crate) fn cholesky_solve(
    k: &CsrMatrix<f64>,
    fill_order: &FillOrder,
    r: &mut [f64],
    times: &mut SetupTimes,
) -> Result<(), TimeError> {
    factor_solve(analyze(k, fill_order, times)?, k, r, times, false).map(|_| ())
}

/// Which factor solved a preload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Served {
    /// The dissection's halves in single precision, refined.
    Halves,
    /// K's whole factor in single precision, refined.
    Single,
    /// K's whole factor in double, after single precision failed
    /// (`after_single`) or without trying it.
    Double { after_single: bool },
}

/// The halves' analysis where the preload's single factor (`single`) may
/// be split: the dissection's halves known and uncoupled; else `None`,
/// `None` too where faer's analysis of a half fails (the whole analysis
/// then runs, and reports its own failure).
fn split_analysis(k: &CsrMatrix<f64>, fill_order: &FillOrder, single: bool) -> Option<SplitSingle> {
    match (fill_order.dissection_order(), fill_order.halves()) {
        (Some(order), Some(halves)) if single => {
            SplitSingle::analyze(k, order, halves).ok().flatten()
        }
        _ => None,
    }
}

/// r ← K⁻¹r, K with no free rigid motion: by the dissection's halves
/// where they serve a single factor (`single`, and no analysis made by
/// the caller: `analyzed`); else K's whole factor (single where `single`),
/// and where f32 does not serve the halves, K's whole factor in double:
/// K's condition, which f32 failed, is the same whole. K's analysis, where
/// made, is kept in `slot`.
///
/// # Errors
/// [`TimeError::Static`] from the whole factor's analysis or its
/// factorization in double.
fn preload(
    k: &CsrMatrix<f64>,
    fill_order: &FillOrder,
    r: &mut [f64],
    times: &mut SetupTimes,
    single: bool,
    analyzed: Option<Analysis>,
    slot: &mut Option<&mut SharedAnalysis>,
) -> Result<Served, TimeError> {
    let split = match analyzed {
        Some(_) => None,
        None => times.time("preload ordering", || split_analysis(k, fill_order, single)),
    };
    let tried = split.is_some();
    if split.is_some_and(|s| split_solve(s, k, r, times)) {
        return Ok(Served::Halves);
    }
    let solver = match analyzed {
        Some(analysis) => SparseCholesky::on(analysis).map_err(TimeError::Static)?,
        None => analyze(k, fill_order, times)?,
    };
    keep(slot, &solver);
    factor_solve(solver, k, r, times, single && !tried)
}

/// The preload r ← K⁻¹r by the halves' single factors, refined to
/// double's accuracy; `false` (r unchanged) where f32 does not serve K
/// (a pivot fails, or the refinement stalls), which only the time tells.
fn split_solve(
    mut split: SplitSingle,
    k: &CsrMatrix<f64>,
    r: &mut [f64],
    times: &mut SetupTimes,
) -> bool {
    times.time("preload factor", || split.factorize(k)).is_ok()
        && times
            .time("preload solve", || {
                split.solve_refined(k, r, BACKWARD_ERROR)
            })
            .is_ok()
}

/// K's analysis, timed as the preload's ordering.
fn analyze(
    k: &CsrMatrix<f64>,
    fill_order: &FillOrder,
    times: &mut SetupTimes,
) -> Result<SparseCholesky, TimeError> {
    times
        .time("preload ordering", || {
            SparseCholesky::analyze(k, fill_order)
        })
        .map_err(TimeError::Static)
}

/// [`cholesky_solve`] with K's analysis done (by `analyze`); `single`:
/// factorized in single precision and refined, or where f32's precision
/// or range does not serve K (a pivot fails, or the refinement stalls),
/// as in double after all, which only the time tells.
fn factor_solve(
    mut solver: SparseCholesky,
    k: &CsrMatrix<f64>,
    r: &mut [f64],
    times: &mut SetupTimes,
    single: bool,
) -> Result<Served, TimeError> {
    if single
        && times
            .time("preload factor", || solver.factorize_single(k))
            .is_ok()
        && times
            .time("preload solve", || {
                solver.solve_refined(k, r, BACKWARD_ERROR)
            })
            .is_ok()
    {
        return Ok(Served::Single);
    }
    times
        .time("preload factor", || solver.factorize(k))
        .map_err(TimeError::Static)?;
    times.time("preload solve", || solver.solve_in_place(r));
    Ok(Served::Double {
        after_single: single,
    })
}

/// Keeps `solver`'s analysis in `slot`, if the caller asked for it.
fn keep(slot: &mut Option<&mut SharedAnalysis>, solver: &SparseCholesky) {
    if let Some(slot) = slot.as_deref_mut() {
        *slot = Some(solver.analysis().clone());
    }
}

/// The state at t = 0 for a scheme with mass `mass`: Remark 4.1's r₀ (no
/// factorization where nothing acts before t = 0, where the run starts at
/// rest, or where the state will come from a checkpoint: r₀ = 0 then), ṙ₀, r̈₀, R(0), the contact
/// classes and forces at ṙ₀, and the energies.
///
/// Where the supports leave rigid motions free (`modes`), the static state
/// is solved on their complement (`floating.rs`).
///
/// # Errors
/// [`TimeError::Unbalanced`] when the preload does work along a free rigid
/// motion; [`TimeError::Static`] when K (or a consistent M) is otherwise
/// not positive definite.
///
/// `analyzed`: K's analysis for the preload, where the caller made it
/// (beside other work, or for the step's operators too).
pub(crate) fn initial_state(
    k: &CsrMatrix<f64>,
    mass: Mass,
    statics: Statics,
    contact: Option<&ContactSurface>,
    loads: &Loads,
    settings: &Settings,
    analyzed: Option<Analysis>,
) -> Result<State, TimeError> {
    let Statics {
        fill_order,
        modes,
        times,
        single_factor,
        mut analysis,
    } = statics;
    let n = k.nrows();
    let mut state = State::new(n, contact.map_or(0, |c| c.len()), settings.dt);
    let mut r = loads.before_start();
    let unloaded = r.iter().all(|&x| x == 0.0);
    // A compliant foundation's preload is the nonlinear static problem
    // with its forces; its r₀, r̈₀ and energies count them. It is solved
    // where loads act before t = 0 or where nodes start inside the
    // foundation (an interference: the foundation alone presses).
    let compliant = contact
        .filter(|c| c.is_compliant() && (!unloaded || c.compliance.iter().any(|k| k.gap < 0.0)));
    let compliant =
        compliant.filter(|_| !settings.restoring && settings.initial_state == InitialState::Static);
    if settings.restoring || settings.initial_state == InitialState::Rest {
        r.fill(0.0);
    } else if unloaded && compliant.is_none() {
        // Nothing acts before t = 0: r₀ = 0, no factorization.
    } else {
        if single_factor {
            fill_order.keep_dissection();
        }
        if let Some(c) = compliant {
            crate::preload_compliance::solve(
                k,
                (mass, fill_order, modes),
                c,
                &mut r,
                times,
                analyzed,
            )?;
        } else if modes.is_empty() {
            let single = single_factor && n >= SINGLE_MIN;
            preload(
                k,
                fill_order,
                &mut r,
                times,
                single,
                analyzed,
                &mut analysis,
            )?;
        } else {
            crate::floating::solve(k, mass, fill_order, modes, &mut r, times)?;
        }
    }
    state.r = r;
    if let Some(v0) = &settings.initial_velocity {
        state.v.copy_from_slice(v0);
    }
    loads.at(0.0, &mut state.load);
    // r̈₀ from M r̈₀ = R(0) − K r₀ − J(ṙ₀) − C ṙ₀, the terms in turn.
    let mut rhs = vec![0.0; n];
    spmv(k, &state.r, &mut rhs);
    for (x, l) in rhs.iter_mut().zip(&state.load) {
        *x = l - *x;
    }
    let stored = compliant.map_or(0.0, |c| {
        crate::preload_compliance::add_foundation_forces(c, &state.r, &mut rhs)
    });
    // The friction at t = 0 acts on the slip then, ṙ₀ − V (zero at rest
    // on a foundation at rest, as in Remark 4.1): M r̈₀ = R(0) − K r₀ −
    // J(ṙ₀). The first step's ledger books ½(J₁ + J₀)·Δr, which the
    // dynamics then match. Without inertia (quasi-static increments,
    // METHOD.md §11) the start is the static K r₀ = R₀ alone, with r̈₀ = 0:
    // no friction acts until the first increment applies the law (its
    // ledger books ½(J₁ + 0)·Δr), whatever the slip at t = 0 (a belt).
    if let Some(c) = contact.filter(|_| !matches!(mass, Mass::Massless)) {
        c.classify(&state.v, &mut state.classes);
        c.nodal_forces(&state.v, &mut state.forces);
        c.subtract_forces(&state.forces, &mut rhs);
    }
    // With damping and an initial velocity, − C ṙ₀.
    let damping = settings.damping;
    if damping.is_on() && settings.initial_velocity.is_some() {
        let (mut kv, mut mv) = (vec![0.0; n], vec![0.0; n]);
        spmv(k, &state.v, &mut kv);
        mass.apply(&state.v, &mut mv);
        for ((x, kv), mv) in rhs.iter_mut().zip(&kv).zip(&mv) {
            *x -= damping.alpha * mv + damping.beta * kv;
        }
    }
    // M has K's pattern (fem): K's analysis, where made, is M's.
    let shared = analysis.as_deref().and_then(Option::clone);
    if let (Some(made), Some(slot)) = (mass.solve_in_place(&mut rhs, fill_order, shared)?, analysis)
    {
        *slot = Some(made);
    }
    state.a.copy_from_slice(&rhs);
    let mut partials = chunks::partials(n);
    let kinetic = 0.5 * mass.form(&state.v, &mut partials);
    let strain = 0.5 * quadratic_form(k, &state.r, &mut partials);
    // kinetic + strain ≥ +0, so adding 0.0 (no compliant preload) keeps
    // its bits.
    let mechanical = kinetic + strain + stored;
    state.initial_mechanical = mechanical;
    state.energy = Energy {
        kinetic,
        strain,
        external_work: 0.0,
        dissipated: 0.0,
        damped: 0.0,
        foundation: 0.0,
        foundation_stored: stored,
        total: mechanical - dot(&state.r, &state.load),
        balance: 0.0,
    };
    Ok(state)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// The preload by the dissection's halves is the whole factor's solve
    /// to the refinement's accuracy: a chain of springs split at its
    /// middle unknown.
    #[test]
    fn a_preload_by_halves_solves_as_the_whole_factor() {
        let n = 21;
        let mut coo = CooMatrix::new(n, n);
        for i in 0..n {
            coo.push(i, i, 2.01);
            if i + 1 < n {
                coo.push(i, i + 1, -1.0);
                coo.push(i + 1, i, -1.0);
            }
        }
        let k = CsrMatrix::from(&coo);
        let mid = n / 2;
        let order: Vec<usize> = (0..mid).chain(mid + 1..n).chain([mid]).collect();
        let halves = [mid, n - mid - 1];
        let b: Vec<f64> = (0..n).map(|i| ((i * 5) % 9) as f64 - 4.0).collect();
        let mut times = SetupTimes::default();
        let split = SplitSingle::analyze(&k, &order, halves)
            .unwrap()
            .expect("the middle unknown separates");
        let mut by_halves = b.clone();
        assert!(split_solve(split, &k, &mut by_halves, &mut times));
        let names: Vec<&str> = times.parts().iter().map(|p| p.0).collect();
        assert_eq!(names, ["preload factor", "preload solve"]);
        let mut whole = b.clone();
        let solver = analyze(&k, &FillOrder::dissection(order), &mut times).unwrap();
        factor_solve(solver, &k, &mut whole, &mut times, false).unwrap();
        let scale = whole.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (x, y) in by_halves.iter().zip(&whole) {
            assert!((x - y).abs() <= 1e-14 * scale, "{x} against {y}");
        }
        assert!(stickslip_linalg::backward_error(&k, &by_halves, &b) <= BACKWARD_ERROR);
    }

    /// Where a half's single factor fails, the preload by halves falls
    /// back to K's whole factor in double, without trying it in single
    /// (whose pivot fails alike), with the double factor's bits and K's
    /// analysis kept: the first half holds [[1, c], [c, 1]] (as below),
    /// joined to the separator by ε, ε² below the pair's determinant
    /// 1 − c² ≈ 2⁻²⁹.
    #[test]
    fn a_preload_whose_half_single_cannot_factorize_is_solved_in_double() {
        let c = 1.0 - 2.0_f64.powi(-30);
        let eps = 1e-5;
        let mut coo = CooMatrix::new(5, 5);
        let entries = [
            (0, 0, 1.0),
            (0, 1, c),
            (1, 1, 1.0),
            (1, 2, -eps),
            (2, 2, 1.0),
            (2, 3, -eps),
            (3, 3, 1.0),
            (3, 4, -0.5),
            (4, 4, 1.0),
        ];
        for (i, j, v) in entries {
            coo.push(i, j, v);
            if i != j {
                coo.push(j, i, v);
            }
        }
        let k = CsrMatrix::from(&coo);
        let order = FillOrder::dissection(vec![0, 1, 3, 4, 2]).with_halves([2, 2]);
        let mut times = SetupTimes::default();
        let split = split_analysis(&k, &order, true).expect("node 2 separates");
        let mut r = vec![1.0, 2.0, 0.5, -1.0, 1.5];
        assert!(!split_solve(split, &k, &mut r.clone(), &mut times));
        let mut double = r.clone();
        let solver = analyze(&k, &order, &mut times).unwrap();
        factor_solve(solver, &k, &mut double, &mut times, false).unwrap();
        let mut kept: SharedAnalysis = None;
        let served = preload(
            &k,
            &order,
            &mut r,
            &mut times,
            true,
            None,
            &mut Some(&mut kept),
        );
        assert_eq!(
            served.unwrap(),
            Served::Double {
                after_single: false
            }
        );
        assert_eq!(r, double);
        assert!(kept.is_some(), "K's analysis kept");
    }

    /// A preload whose K f32 cannot factorize is solved by the double
    /// factor, with its bits: [[1, c], [c, 1]], c = 1 − 2⁻³⁰, is positive
    /// definite (determinant 1 − c² ≈ 2⁻²⁹), but c rounds to 1 in f32.
    #[test]
    fn a_preload_single_precision_cannot_factorize_is_solved_in_double() {
        let c = 1.0 - 2.0_f64.powi(-30);
        let mut coo = CooMatrix::new(2, 2);
        for (i, j, v) in [(0, 0, 1.0), (0, 1, c), (1, 0, c), (1, 1, 1.0)] {
            coo.push(i, j, v);
        }
        let k = CsrMatrix::from(&coo);
        let order = FillOrder::amd();
        let solve = |single: bool| {
            let mut times = SetupTimes::default();
            let mut r = vec![1.0, 2.0];
            let solver = analyze(&k, &order, &mut times).unwrap();
            let served = factor_solve(solver, &k, &mut r, &mut times, single).unwrap();
            assert_eq!(
                served,
                Served::Double {
                    after_single: single
                }
            );
            r
        };
        let (single, double) = (solve(true), solve(false));
        assert_eq!(single, double);
        // K⁻¹(1, 2) = (1 − 2c, 2 − c)/(1 − c²), κ(K) ≈ 2³¹: good to ~1e-6.
        let det = 1.0 - c * c;
        for (x, want) in single.iter().zip([(1.0 - 2.0 * c) / det, (2.0 - c) / det]) {
            assert!((x - want).abs() <= 1e-6 * want.abs(), "{x} against {want}");
        }
    }

    /// A chain of springs, 2 + shift on the diagonal and −1 beside: a
    /// matrix far from its diagonal for a small shift.
    fn chain(n: usize, shift: f64) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n, n);
        for i in 0..n {
            coo.push(i, i, 2.0 + shift);
            if i + 1 < n {
                coo.push(i, i + 1, -1.0);
                coo.push(i + 1, i, -1.0);
            }
        }
        CsrMatrix::from(&coo)
    }

    /// A consistent mass is solved by CG on its diagonal, without a
    /// factorization (no analysis made); a "mass" CG cannot solve in
    /// [`MASS_ITERATIONS`] (a chain with κ(D⁻¹A) ≈ 2.5e4) is factorized, and
    /// the analysis it made is returned. Both to a factor solve's
    /// backward error.
    #[test]
    fn a_consistent_mass_is_solved_by_cg_and_else_factorized() {
        let b: Vec<f64> = (0..400).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        for (shift, factorized) in [(4.0, false), (1e-4, true)] {
            let m = chain(400, shift);
            let mut x = b.clone();
            let made = Mass::Consistent(&m)
                .solve_in_place(&mut x, &FillOrder::amd(), None)
                .unwrap();
            assert_eq!(made.is_some(), factorized, "shift {shift}");
            let eta = stickslip_linalg::backward_error(&m, &x, &b);
            assert!(eta <= 4.0 * BACKWARD_ERROR, "shift {shift}: {eta:e}");
        }
    }
}
