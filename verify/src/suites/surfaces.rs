//! Several contact surfaces and a pressure that changes: the strip gripped
//! between two surfaces against its half on a symmetry support, the plain
//! pressure against a uniform profile and a constant history, and the
//! friction oscillator's block let go by a pressure ramped down.

use std::path::Path;

use stickslip_contact::ContactSurface;
use stickslip_fem::{Dirichlet, Hypothesis, Material, Traction};
use stickslip_mesh::CellKind;
use stickslip_testkit::{add_point_group, rectangle, sdof, Slab};
use stickslip_time::{History, Integrator, Settings};

use super::analytic::SCHEMES;
use crate::report::{max_or_nan, Report};
use crate::Options;

/// Runs the checks.
pub fn run(root: &Path, opts: &Options, r: &mut Report) {
    mirror(opts, r);
    plain_pressure(root, opts, r);
    ramp_down(r);
}

/// Strip length, half height, end traction, pressure, μ, ε.
const L: f64 = 8.0;
const H: f64 = 1.0;
const END: f64 = -150.0;
const P: f64 = 300.0;
const MU: f64 = 0.3;
const EPS: f64 = 1e-2;

/// The strip [0, L] × [−H, H] gripped on its top and bottom faces (`full`)
/// or its upper half [0, L] × [0, H] on a symmetry support u_y = 0 at
/// y = 0: both held in x at the right end, the left end loaded by a step
/// traction along x, the faces pressed by P with friction μ, ε.
fn strip(full: bool) -> Result<Slab, String> {
    let (ny, origin, height) = if full {
        (4, [0.0, -H], 2.0 * H)
    } else {
        (2, [0.0, 0.0], H)
    };
    let mut mesh = rectangle(CellKind::Quad9, 8, ny, origin, [L, height]);
    let material =
        Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).map_err(|e| e.to_string())?;
    let mut conditions = vec![Dirichlet::new("right", 0, 0.0)];
    if full {
        // The mid-plane node of the held end: by symmetry u_y = 0 there,
        // which keeps the frictionless static solve (Remark 4.1) regular.
        let mid = mesh
            .nodes
            .iter()
            .position(|p| (p[0] - L).abs() < 1e-12 && p[1].abs() < 1e-12)
            .ok_or("the strip has a node at (L, 0)")?;
        add_point_group(&mut mesh, "mid", &[mid]);
        conditions.push(Dirichlet::new("mid", 1, 0.0));
    } else {
        conditions.push(Dirichlet::new("bottom", 1, 0.0));
    }
    let mut tractions = vec![
        ("left", Traction::Vector([END, 0.0]), History::Step),
        ("top", Traction::Pressure(P), History::Constant),
    ];
    if full {
        tractions.push(("bottom", Traction::Pressure(P), History::Constant));
    }
    let mut slab = Slab::assemble(
        mesh,
        &material,
        &conditions,
        &tractions,
        Some(("top", P, MU, EPS)),
    )
    .map_err(|e| e.to_string())?;
    if full {
        let bottom = ContactSurface::from_group(&slab.mesh, &slab.model.dofs, "bottom", P, MU, EPS)
            .map_err(|e| e.to_string())?;
        let top = slab.contact.take().ok_or("the strip has its top surface")?;
        slab.contact = Some(ContactSurface::join(vec![bottom, top]).map_err(|e| e.to_string())?);
    }
    Ok(slab)
}

/// Largest |u_half − u_full| over the half's nodes and every step (u_y
/// and u_x alike: the mirror image of the upper half is the lower half).
fn mirror_error(scheme: stickslip_time::Scheme, t_end: f64) -> Result<f64, String> {
    let (half, full) = (strip(false)?, strip(true)?);
    let settings = Settings::new(scheme, 1e-3, t_end);
    let mut a = half
        .integrator(settings.clone())
        .map_err(|e| e.to_string())?;
    let mut b = full.integrator(settings).map_err(|e| e.to_string())?;
    let pairs: Vec<(usize, usize)> = half
        .mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(i, p)| {
            full.node_at(p[0], p[1])
                .map(|j| (i, j))
                .map_err(|e| e.to_string())
        })
        .collect::<Result<_, _>>()?;
    let u = |s: &Slab, i: &Integrator, node: usize, c: usize| {
        s.dof(node, c).map_or(0.0, |d| i.displacement()[d])
    };
    let mut worst: f64 = 0.0;
    while !a.done() {
        a.step().map_err(|e| e.to_string())?;
        b.step().map_err(|e| e.to_string())?;
        for &(i, j) in &pairs {
            for c in 0..2 {
                let d = (u(&half, &a, i, c) - u(&full, &b, j, c)).abs();
                worst = max_or_nan([worst, d]);
            }
        }
    }
    Ok(worst)
}

fn mirror(opts: &Options, r: &mut Report) {
    let t_end = if opts.quick { 0.1 } else { 0.5 };
    for (name, scheme) in SCHEMES {
        let case = format!("gripped strip = half strip {name}");
        match mirror_error(scheme, t_end) {
            Ok(e) => r.at_most(
                &case,
                &format!("max |u_half − u_full| to t = {t_end}"),
                e,
                1e-9,
                "mirror symmetry about y = 0",
            ),
            Err(e) => r.holds(&case, "runs", e, "runs", false),
        }
    }
}

/// The bits of every displacement and friction stress of two runs, step by
/// step: the first step where they differ, or `None`.
fn first_difference(mut a: Integrator, mut b: Integrator) -> Result<Option<u64>, String> {
    let n_c = a.contact().map_or(0, |c| c.len());
    let (mut sa, mut sb) = (vec![0.0; n_c], vec![0.0; n_c]);
    while !a.done() {
        a.step().map_err(|e| e.to_string())?;
        b.step().map_err(|e| e.to_string())?;
        a.friction_stress(&mut sa);
        b.friction_stress(&mut sb);
        let same = |x: &[f64], y: &[f64]| {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())
        };
        if !same(a.displacement(), b.displacement()) || !same(&sa, &sb) {
            return Ok(Some(a.steps()));
        }
    }
    Ok(None)
}

/// A paper case with its `[contact]` table extended by the lines `extra`
/// (its own `pressure = ..` line left out when `extra` gives one).
fn variant(root: &Path, file: &str, extra: &str, t_end: f64) -> Result<Integrator, String> {
    let path = crate::cases_dir(root).join(file);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let own_pressure = extra.contains("pressure =");
    let text: String = text
        .lines()
        .filter(|l| !(own_pressure && l.trim_start().starts_with("pressure =")))
        .map(|l| format!("{l}\n"))
        .collect();
    let text = text.replacen("[contact]", &format!("[contact]\n{extra}"), 1);
    let case = stickslip_case::load_str(&path, &text, &[format!("time.t_end={t_end}")])
        .map_err(|e| e.to_string())?;
    let scene = stickslip_case::assemble(&case).map_err(|e| e.to_string())?;
    scene.integrator().map_err(|e| e.to_string())
}

fn plain_pressure(root: &Path, opts: &Options, r: &mut Report) {
    let t_end = if opts.quick { 0.05 } else { 0.5 };
    // θ = 1 and a factor 1 multiply exactly; pressure 600 with a factor
    // ½ gives μ·600·½ = μ·300 and 600·½ = 300 exactly (a power of two
    // scales without rounding).
    let variants = [
        (
            "uniform profile 1",
            "pressure_profile = { table = [[0.0, 1.0], [8.0, 1.0]] }",
        ),
        (
            "history table of 1",
            "pressure_history = { table = [[-1.0, 1.0], [1.0, 1.0]] }",
        ),
        (
            "pressure 600, profile ½",
            "pressure_profile = { table = [[0.0, 0.5]] }\npressure = 600.0",
        ),
        (
            "foundation at rest",
            "foundation_velocity = 0.0\nfoundation_history = { sin = { omega = 3.0 } }",
        ),
    ];
    for file in ["cd-step-eps1e-2.toml", "newmark-step.toml"] {
        for (what, extra) in variants {
            let case = format!("{} {what}", file.trim_end_matches(".toml"));
            let result = (|| {
                first_difference(
                    variant(root, file, "", t_end)?,
                    variant(root, file, extra, t_end)?,
                )
            })();
            match result {
                Ok(d) => r.holds(
                    &case,
                    &format!("u and σ_T bits, every step to t = {t_end}"),
                    d.map_or("identical".into(), |s| format!("differ at step {s}")),
                    "identical to the plain pressure",
                    d.is_none(),
                ),
                Err(e) => r.holds(&case, "runs", e, "runs", false),
            }
        }
    }
}

/// The friction oscillator (m = 1, k = 100, g₀ = 1) under a step force P,
/// its pressure ramped down as θ(t) = 1 − t/T: stuck while friction can
/// hold P, it slips when g₀θ(t) falls below P − kx (the static balance),
/// at t* = T(1 − P/g₀) where x, the creep of the stuck block at
/// ε(P − kx)/g, is negligible: about 3e-6 by t*, at ε = 1e-5, which moves
/// the onset by kxT/g₀ ≈ 3e-4, under half a step. P = 0.5005 puts t* =
/// 0.4995 in the middle of a step of 1e-3, so the check is that the first
/// slipping step is the one holding t* (its middle within Δt/2 of t*).
/// (A much smaller ε is no better: at Δt = 1e-3 the first steps' stuck
/// velocity, set by the frictionless r̈₀ of Remark 4.1, exceeds it.)
fn ramp_down(r: &mut Report) {
    let (p, t_ramp, dt) = (0.5005, 1.0, 1e-3);
    let expected = t_ramp * (1.0 - p / sdof::G);
    for (name, scheme) in SCHEMES {
        let case = format!("pressure ramped down {name}");
        let result = (|| -> Result<f64, String> {
            let mut i = sdof::integrator(p, 1e-5, scheme, dt, 0.8).map_err(|e| e.to_string())?;
            i.set_pressure_histories(&[History::Table(vec![(0.0, 1.0), (t_ramp, 0.0)])])
                .map_err(|e| e.to_string())?;
            while !i.done() {
                i.step().map_err(|e| e.to_string())?;
                if !i.classes()[0].is_stuck() {
                    return Ok(i.time() - 0.5 * dt);
                }
            }
            Err("the block never slipped".into())
        })();
        match result {
            Ok(t) => r.close(
                &case,
                "middle of the first slipping step",
                t,
                expected,
                "g₀(1 − t*/T) = P: the step holding t*",
                0.5 * dt,
            ),
            Err(e) => r.holds(&case, "slips", e, "slips", false),
        }
    }
}
