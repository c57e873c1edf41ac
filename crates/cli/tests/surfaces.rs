//! Several contact surfaces through the binary: the results name each
//! contact node's surface, the probe and the viewers' files follow, and a
//! node on two surfaces is refused at its line with exit code 2.

mod common;

use std::path::Path;

use common::{bin, probe, scratch, stderr, succeeded};
use hdf5::types::VarLenUnicode;
use stickslip_testkit::case_text::paper_slab_head;

/// The paper's slab (bottom "contact", top "support" on rollers) gripped
/// on both faces for 20 steps, with `extra` appended.
fn case(dir: &Path, extra: &str) -> std::path::PathBuf {
    let text = format!(
        r#"{head}[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "load"
t = [-150.0, 0.0]
[[contact]]
group = "contact"
pressure = 300.0
mu = 0.3
eps = 1e-2
[[contact]]
group = "support"
pressure = 200.0
mu = 0.2
eps = 1e-2
pressure_history = {{ table = [[-1.0, 1.0], [0.0, 1.0], [0.4, 0.0]] }}
{extra}
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.02
"#,
        head = paper_slab_head()
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_results_name_each_nodes_surface() {
    let dir = scratch("surfaces-run");
    let out = dir.join("gripped.h5");
    let o = bin()
        .arg("run")
        .arg(case(&dir, ""))
        .arg("-o")
        .arg(&out)
        .arg("--force")
        .arg("--quiet")
        .output()
        .unwrap();
    succeeded(&o, "run");
    {
        let f = hdf5::File::open(&out).unwrap();
        let nodes = f
            .dataset("contact/nodes")
            .unwrap()
            .read_raw::<i64>()
            .unwrap();
        let surface = f
            .dataset("contact/surface")
            .unwrap()
            .read_raw::<i64>()
            .unwrap();
        let xy = f.dataset("mesh/nodes").unwrap().read_2d::<f64>().unwrap();
        let groups: Vec<String> = f
            .group("contact")
            .unwrap()
            .attr("groups")
            .unwrap()
            .read_raw::<VarLenUnicode>()
            .unwrap()
            .iter()
            .map(|g| g.as_str().to_string())
            .collect();
        assert_eq!(groups, ["contact", "support"]);
        assert_eq!(nodes.len(), surface.len());
        // The bottom (y = 0) is the first surface, the top (y = 1) the
        // second, listed surface by surface.
        for (&n, &k) in nodes.iter().zip(&surface) {
            assert_eq!(xy[[n as usize, 1]], k as f64, "node {n} on surface {k}");
        }
        assert!(surface.windows(2).all(|w| w[0] <= w[1]));
        assert!(surface.contains(&1));
    }
    // The probe along the second surface's group reads its own nodes.
    let o = probe(
        &out,
        &[
            "--along",
            "support",
            "--times",
            "0.02",
            "--field",
            "friction_stress",
        ],
    );
    let text = succeeded(&o, "probe --along support");
    // The top's 17 nodes of the Q2 8 × 2 mesh, with a value at each but
    // the corner (0, 1), which the left end's support holds in x.
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("2e-2,")).collect();
    assert_eq!(rows.len(), 17, "{text}");
    assert_eq!(
        rows.iter().filter(|l| l.ends_with(",NaN")).count(),
        1,
        "{text}"
    );
    // The viewers' contact file shows the surface beside s.
    let o = bin()
        .arg("views")
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    succeeded(&o, "views");
    let xdmf = std::fs::read_to_string(dir.join("gripped.contact.xdmf")).unwrap();
    assert!(xdmf.contains(">gripped.h5:/contact/surface<"), "{xdmf}");
}

/// The loaded right end ("load") shares the corner (8, 0) with the bottom,
/// and that corner slides along both: refused, exit code 2, at the second
/// surface's group line.
#[test]
fn a_node_on_two_surfaces_is_refused_at_its_line() {
    let dir = scratch("surfaces-overlap");
    let extra = "[[contact]]\ngroup = \"load\"\npressure = 10.0\nmu = 0.3\neps = 1e-2\n";
    let path = case(&dir, extra);
    let text = std::fs::read_to_string(&path).unwrap();
    let at = text.match_indices("group = \"load\"").nth(1).unwrap().0;
    let line = text[..at].lines().count() + 1;
    let o = bin().arg("check").arg(&path).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains(&format!("case.toml:{line}:")) && e.contains("carries friction on both surface"),
        "{e}"
    );
}
