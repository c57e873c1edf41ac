//! `/contact/normal_stress` (docs/results.md): the prescribed pressure
//! p·θ(t) on the paper's law, the foundation's c_n δ on a compliant one.

mod common;

use common::{bin, scratch, succeeded};
use stickslip_testkit::case_text::paper_slab_head;

/// Runs `text` and returns (`/time`, `/contact/normal_stress` row by row).
fn run(name: &str, text: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let dir = scratch(name);
    let case = dir.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let out = dir.join("out.h5");
    let o = bin()
        .args(["run", "--force", "--quiet", "-o"])
        .arg(&out)
        .arg(&case)
        .output()
        .unwrap();
    succeeded(&o, "run");
    let f = hdf5::File::open(&out).unwrap();
    let time = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    let normal = f
        .dataset("contact/normal_stress")
        .unwrap()
        .read_2d::<f64>()
        .unwrap();
    let rows = normal.rows().into_iter().map(|r| r.to_vec()).collect();
    (time, rows)
}

/// The paper's slab pressed by 300 with the history θ(t) = 1 + t (a table
/// from (0, 1) to (1, 2)): every node's row is 300·(1 + t), to round-off.
#[test]
fn a_prescribed_pressure_is_recorded_with_its_history() {
    let text = format!(
        r#"{head}[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[contact]
group = "contact"
pressure = 300.0
pressure_history = {{ table = [[0.0, 1.0], [1.0, 2.0]] }}
mu = 0.3
eps = 1e-2
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.02
"#,
        head = paper_slab_head()
    );
    let (time, rows) = run("normal-stress-pressure", &text);
    assert_eq!(time.len(), 21);
    for (t, row) in time.iter().zip(&rows) {
        assert_eq!(row.len(), 16);
        for p in row {
            assert!((p - 300.0 * (1.0 + t)).abs() < 1e-9, "t = {t}: {p}");
        }
    }
}

/// The slab pressed by 300 on its top onto a floor of c_n = 1e4 from the
/// static preload: at t = 0 every bottom node's c_n δ balances the 300
/// (uniform compression), to 1e-6 of it, and so it stays at every row,
/// the preload an equilibrium of either scheme (Newmark's rows are the
/// traction at the displacement its Newton solve ended at).
#[test]
fn a_compliant_floor_records_its_traction() {
    for scheme in ["central_difference", "newmark"] {
        compliant_floor(scheme);
    }
}

fn compliant_floor(scheme: &str) {
    let text = format!(
        r#"{head}[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "support"
pressure = 300.0
history = "constant"
[contact]
group = "contact"
law = "compliance"
foundation = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}
cn = 1e4
mu = 0.3
eps = 1e-3
[time]
scheme = "{scheme}"
dt = 1e-3
t_end = 0.01
"#,
        head = paper_slab_head()
    );
    let (_, rows) = run(&format!("normal-stress-compliance-{scheme}"), &text);
    assert_eq!(rows.len(), 11, "{scheme}");
    for row in &rows {
        assert_eq!(row.len(), 17);
        for p in row {
            assert!((p - 300.0).abs() < 1e-6 * 300.0, "{scheme}: {row:?}");
        }
    }
}
