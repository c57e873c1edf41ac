//! A compliant foundation through the binary: the slab dropped onto a
//! floor lands, the results hold the foundation's stored energy, and the
//! ledger closes with it.

mod common;

use common::{scratch, succeeded};
use stickslip_testkit::case_text::paper_slab_head;

/// The paper's slab (mass 8) dropped at 0.5 from 0.01 above a floor of
/// c_n = 1e4: it lands after 0.02 and the floor stores energy while it is
/// pressed; kinetic + strain + stored − initial stays within 1% of the
/// initial ½·8·0.5² = 1 (central difference conserves energy only to
/// O(Δt²), and the touches add their own error: 2.4e-3 measured).
#[test]
fn a_dropped_slab_lands_and_the_ledger_books_the_floor() {
    drop_slab(
        "compliance-run",
        "scheme = \"central_difference\"\ndt = 1e-3",
        &[],
        1e-2,
    );
}

/// The same drop by Newmark ¼, ½ at Δt = 2e-3: the same landing, the floor
/// storing energy, and the ledger at round-off on every step, the touches
/// included: frictionless, the energy-consistent normal force makes each
/// step's ledger exact (docs/results.md, `/energy/balance`). Measured
/// 1.6e-14 of the initial energy; the bound 1e-12 leaves round-off ~60×
/// room and fails on any O(Δt²) or touch error (central difference's is
/// 2.4e-3). The summary counts the Newton iterations.
#[test]
fn a_slab_dropped_by_newmark_lands_and_the_ledger_books_the_floor() {
    drop_slab(
        "compliance-newmark",
        "scheme = \"newmark\"\ndt = 2e-3",
        &["compliance Newton iterations"],
        1e-12,
    );
}

/// The Newmark drop stopped at t = 0.1137 (off the step grid, after the
/// landing) and restarted to 0.2 gives the uninterrupted run's results bit
/// for bit: the energy-consistent normal force's excess, not 0 after the
/// touch, comes from the checkpoint's `normal_excess`.
#[test]
fn a_restarted_newmark_drop_continues_bit_for_bit() {
    let dir = scratch("compliance-restart");
    let case = drop_case(&dir, "scheme = \"newmark\"\ndt = 2e-3");
    let (full, part) = (dir.join("full.h5"), dir.join("part.h5"));
    succeeded(&common::run(&case, &full, &["--quiet", "--force"]), "run");
    let short = ["--quiet", "--force", "--set", "time.t_end=0.1137"];
    succeeded(&common::run(&case, &part, &short), "short run");
    let slot = |f: &hdf5::File| {
        let c = f.group("checkpoint").unwrap();
        let k = c.attr("slot").unwrap().read_scalar::<u8>().unwrap();
        c.group(["a", "b"][k as usize]).unwrap()
    };
    let excess = slot(&hdf5::File::open(&part).unwrap())
        .dataset("normal_excess")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    assert!(excess.iter().any(|&e| e != 0.0), "{excess:?}");
    let o = common::bin()
        .arg("run")
        .arg(&case)
        .arg("--restart")
        .arg(&part)
        .args(["--quiet", "--set", "time.t_end=0.2"])
        .output()
        .unwrap();
    succeeded(&o, "restart");
    let (a, b) = (
        hdf5::File::open(&full).unwrap(),
        hdf5::File::open(&part).unwrap(),
    );
    let bits = |f: &hdf5::File, name: &str| -> Vec<u64> {
        let d = f.dataset(name).unwrap().read_raw::<f64>().unwrap();
        d.iter().map(|x| x.to_bits()).collect()
    };
    for name in [
        "time",
        "energy/kinetic",
        "energy/balance",
        "energy/foundation_stored",
        "contact/normal_stress",
    ] {
        assert_eq!(bits(&a, name), bits(&b, name), "{name}");
    }
    let (sa, sb) = (slot(&a), slot(&b));
    for name in ["velocity", "acceleration", "normal_excess"] {
        let read = |g: &hdf5::Group| g.dataset(name).unwrap().read_raw::<f64>().unwrap();
        let (x, y) = (read(&sa), read(&sb));
        let same = x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits());
        assert!(same && x.len() == y.len(), "checkpoint {name}");
    }
}

/// The drop's case with the `[time]` lines `time` (t_end = 0.2), in `dir`.
fn drop_case(dir: &std::path::Path, time: &str) -> std::path::PathBuf {
    let text = format!(
        r#"{head}[contact]
group = "contact"
law = "compliance"
foundation = {{ point = [0.0, -0.01], normal = [0.0, 1.0] }}
cn = 1e4
mu = 0.0
eps = 1e-3
[initial]
state = "rest"
velocity = [0.0, -0.5]
[time]
{time}
t_end = 0.2
"#,
        head = paper_slab_head()
    );
    let case = dir.join("drop.toml");
    std::fs::write(&case, text).unwrap();
    case
}

/// Runs the drop with the `[time]` lines `time` (t_end = 0.2) and checks
/// it, that the run's summary says each of `said`, and that |balance| stays
/// within `balance_tol` of the initial energy on every record.
fn drop_slab(name: &str, time: &str, said: &[&str], balance_tol: f64) {
    let dir = scratch(name);
    let case = drop_case(&dir, time);
    let out = dir.join("drop.h5");
    let o = common::run(&case, &out, &["--force"]);
    succeeded(&o, "run");
    let said_out = String::from_utf8_lossy(&o.stderr) + String::from_utf8_lossy(&o.stdout);
    for s in said {
        assert!(said_out.contains(s), "no {s:?} in:\n{said_out}");
    }
    let f = hdf5::File::open(&out).unwrap();
    // The checkpoint keeps the Newton count (Newmark's, the one whose
    // summary names it; 0 for central difference) for a restart.
    let c = f.group("checkpoint").unwrap();
    let k = c.attr("slot").unwrap().read_scalar::<u8>().unwrap();
    let newton = c
        .group(["a", "b"][k as usize])
        .unwrap()
        .attr("normal_iterations");
    let newton = newton.unwrap().read_scalar::<u64>().unwrap();
    assert_eq!(newton > 0, !said.is_empty(), "{newton} Newton iterations");
    let read = |name: &str| f.dataset(name).unwrap().read_raw::<f64>().unwrap();
    let (time, stored, kinetic) = (
        read("time"),
        read("energy/foundation_stored"),
        read("energy/kinetic"),
    );
    assert!((kinetic[0] - 1.0).abs() < 1e-12, "{}", kinetic[0]);
    // Nothing stored before the landing at 0.01/0.5 = 0.02.
    let first = time
        .iter()
        .zip(&stored)
        .find(|(_, &s)| s > 0.0)
        .map(|(&t, _)| t)
        .expect("the slab lands");
    assert!((first - 0.02).abs() < 2e-3, "first touch at {first}");
    assert!(stored.iter().any(|&s| s > 0.05), "the floor stores energy");
    let balance = read("energy/balance");
    // f64::max drops NaN: a NaN anywhere must fail, not vanish from `worst`.
    assert!(balance.iter().all(|b| b.is_finite()), "{balance:?}");
    let worst = balance.iter().fold(0.0_f64, |m, b| m.max(b.abs()));
    let initial = kinetic[0] + read("energy/strain")[0] + stored[0];
    assert!(
        worst <= balance_tol * initial,
        "largest |balance| {worst} of initial {initial}"
    );
}

/// Quasi-static increments on a floor: the paper's slab held on its top
/// (rollers) and its left end, its bottom 0.03 inside a floor of c_n =
/// 1e4 (the static start presses it), its end load ramped to t_x = −30
/// over 20 increments (docs/case-file.md's example). The run completes,
/// its summary counts the Newton iterations, the checkpoint keeps them,
/// the floor stores energy at every record, and the ledger closes to
/// round-off (each increment in equilibrium; m_n = 1 and no node leaves
/// the floor, so the trapezoid books the foundation's work exactly:
/// within 1e-9 of the strain energy).
#[test]
fn quasi_static_increments_on_a_floor_report_their_newton_iterations() {
    let dir = scratch("compliance-quasi-static");
    let text = format!(
        r#"{head}[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "load"
t = [-30.0, 0.0]
history = {{ table = [[0.0, 0.0], [1.0, 1.0]] }}
[contact]
group = "contact"
law = "compliance"
foundation = {{ point = [0.0, 0.03], normal = [0.0, 1.0] }}
cn = 1e4
mu = 0.3
eps = 1e-4
[initial]
state = "static"
[time]
scheme = "quasi_static"
dt = 0.05
t_end = 1.0
"#,
        head = paper_slab_head()
    );
    let case = dir.join("floor.toml");
    std::fs::write(&case, text).unwrap();
    let out = dir.join("floor.h5");
    let o = common::run(&case, &out, &["--force"]);
    succeeded(&o, "run");
    let said = String::from_utf8_lossy(&o.stderr) + String::from_utf8_lossy(&o.stdout);
    assert!(said.contains("compliance Newton iterations"), "{said}");
    let f = hdf5::File::open(&out).unwrap();
    let c = f.group("checkpoint").unwrap();
    let k = c.attr("slot").unwrap().read_scalar::<u8>().unwrap();
    let newton = c
        .group(["a", "b"][k as usize])
        .unwrap()
        .attr("normal_iterations")
        .unwrap()
        .read_scalar::<u64>()
        .unwrap();
    assert!(newton > 0);
    let read = |name: &str| f.dataset(name).unwrap().read_raw::<f64>().unwrap();
    let (stored, strain, balance) = (
        read("energy/foundation_stored"),
        read("energy/strain"),
        read("energy/balance"),
    );
    assert_eq!(stored.len(), 21);
    assert!(stored.iter().all(|&s| s > 0.0), "{stored:?}");
    assert!(balance.iter().chain(&strain).all(|x| x.is_finite()));
    let largest = strain.iter().fold(0.0_f64, |m, s| m.max(*s));
    let worst = balance.iter().fold(0.0_f64, |m, b| m.max(b.abs()));
    assert!(
        worst <= 1e-9 * largest,
        "|balance| {worst} of strain {largest}"
    );
}
