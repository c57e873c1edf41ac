//! `stickslip probe OUT.h5 --along GROUP --times ..` ([`stickslip::probe::along`]).
//!
//! Expected orders come from geometry and DESIGN.md's tangent convention
//! (boundary walked with the body on its left): on a fixture file written
//! here with the hdf5 crate (layout of DESIGN.md "Results", node numbers
//! deliberately scrambled), and on the paper's slab run through the binary.

use std::path::{Path, PathBuf};
use std::process::Command;

use hdf5::types::VarLenUnicode;
use ndarray::{Array1, Array2, Array3};
use stickslip::probe::{along, write_along, AlongArgs, Field};
use stickslip_testkit::{scratch, workspace_root as root};

/// Node index of grid point (gx, gy) of the 4 x 4 fixture grid: a fixed
/// permutation (5 is coprime with 16), so index order is not geometric order.
fn id(gx: usize, gy: usize) -> usize {
    (5 * (gx + 4 * gy) + 3) % 16
}

/// u_x of node i at step k in the fixture.
fn ux(k: usize, i: usize) -> f64 {
    100.0 * k as f64 + i as f64
}

/// A 3 x 3 block of unit Q1 cells without its centre cell (so it has a
/// hole), node spacing 1, cells counter-clockwise. Groups: bottom (y = 0,
/// the contact group; its corner (0, 0) carries no friction, as the
/// slab's), right (x = 3), hole (the inner square), pieces (bottom and top:
/// two chains), body (every node). Three output steps at t = 0, 0.5, 1.
fn write_fixture(path: &Path) {
    let f = hdf5::File::create(path).unwrap();
    let case: VarLenUnicode = "[contact]\ngroup = \"bottom\"\n".parse().unwrap();
    f.new_attr::<VarLenUnicode>()
        .create("case")
        .unwrap()
        .write_scalar(&case)
        .unwrap();
    f.new_attr::<bool>()
        .create("complete")
        .unwrap()
        .write_scalar(&true)
        .unwrap();
    let mut nodes = Array2::<f64>::zeros((16, 2));
    for gy in 0..4 {
        for gx in 0..4 {
            nodes[[id(gx, gy), 0]] = gx as f64;
            nodes[[id(gx, gy), 1]] = gy as f64;
        }
    }
    let mut cells = Vec::new();
    for cy in 0..3 {
        for cx in 0..3 {
            if (cx, cy) == (1, 1) {
                continue;
            }
            for (gx, gy) in [(cx, cy), (cx + 1, cy), (cx + 1, cy + 1), (cx, cy + 1)] {
                cells.push(id(gx, gy) as i64);
            }
        }
    }
    let cells = Array2::from_shape_vec((8, 4), cells).unwrap();
    let m = f.create_group("mesh").unwrap();
    m.new_dataset_builder()
        .with_data(&nodes)
        .create("nodes")
        .unwrap();
    m.new_dataset_builder()
        .with_data(&cells)
        .create("cells")
        .unwrap();
    let g = m.create_group("groups").unwrap();
    let group = |name: &str, pts: &[(usize, usize)]| {
        let mut ids: Vec<i64> = pts.iter().map(|&(x, y)| id(x, y) as i64).collect();
        ids.sort_unstable();
        g.new_dataset_builder()
            .with_data(&Array1::from(ids))
            .create(name)
            .unwrap();
    };
    group("bottom", &[(0, 0), (1, 0), (2, 0), (3, 0)]);
    group("right", &[(3, 0), (3, 1), (3, 2), (3, 3)]);
    group("hole", &[(1, 1), (2, 1), (2, 2), (1, 2)]);
    let mut pieces: Vec<(usize, usize)> = (0..4).map(|x| (x, 0)).collect();
    pieces.extend((0..4).map(|x| (x, 3)));
    group("pieces", &pieces);
    let all: Vec<(usize, usize)> = (0..16).map(|i| (i % 4, i / 4)).collect();
    group("body", &all);

    f.new_dataset_builder()
        .with_data(&Array1::from(vec![0.0, 0.5, 1.0]))
        .create("time")
        .unwrap();
    let disp = Array3::from_shape_fn((3, 16, 2), |(k, i, c)| if c == 0 { ux(k, i) } else { -1.0 });
    for name in ["displacement", "velocity", "acceleration"] {
        f.new_dataset_builder()
            .with_data(&disp)
            .create(name)
            .unwrap();
    }
    let c = f.create_group("contact").unwrap();
    let contact: Vec<i64> = (1..4).map(|x| id(x, 0) as i64).collect();
    c.new_dataset_builder()
        .with_data(&Array1::from(contact))
        .create("nodes")
        .unwrap();
    c.new_dataset_builder()
        .with_data(&Array1::from(vec![1.0, 2.0, 3.0]))
        .create("s")
        .unwrap();
    // σ_T(step k, contact slot j) = 10 k + j.
    let fs = Array2::from_shape_fn((3, 3), |(k, j)| 10.0 * k as f64 + j as f64);
    c.new_dataset_builder()
        .with_data(&fs)
        .create("friction_stress")
        .unwrap();
    c.new_dataset_builder()
        .with_data(&(-&fs))
        .create("slip_velocity")
        .unwrap();
}

fn ids(pts: &[(usize, usize)]) -> Vec<usize> {
    pts.iter().map(|&(x, y)| id(x, y)).collect()
}

#[test]
fn fixture_orders_follow_the_boundary_with_the_body_on_the_left() {
    let dir = scratch("fixture");
    let h5 = dir.join("fixture.h5");
    write_fixture(&h5);

    // The contact group: (0,0) to (3,0) in +x; nearest steps of 0.6, -1, 2
    // are 1 (t = 0.5), 0 and 2, the last two outside [0, 1].
    let a = along(&h5, "bottom", "0.6,-1,2", Field::Ux).unwrap();
    assert_eq!(a.nodes, ids(&[(0, 0), (1, 0), (2, 0), (3, 0)]));
    assert_eq!(a.s, vec![0.0, 1.0, 2.0, 3.0]);
    assert_eq!(a.records, vec![1, 0, 2]);
    assert_eq!(a.t, vec![0.5, 0.0, 1.0]);
    for (i, &k) in a.records.iter().enumerate() {
        let want: Vec<f64> = a.nodes.iter().map(|&n| ux(k, n)).collect();
        assert_eq!(a.values[i], want);
    }
    assert!(
        a.info.contains("t = 0.6: record 1 at t = 0.5"),
        "{}",
        a.info
    );
    assert_eq!(
        a.info.matches("outside the run's [0, 1]").count(),
        2,
        "{}",
        a.info
    );
    assert!(a.info.contains("ordered as /contact/nodes"), "{}", a.info);
    let mut lines = a.csv.lines();
    assert_eq!(lines.next(), Some("t_asked,t,record,node,x,y,s,ux"));
    assert_eq!(
        lines.next().unwrap(),
        format!("6e-1,5e-1,1,{},0e0,0e0,0e0,{:e}", id(0, 0), ux(1, id(0, 0)))
    );
    assert_eq!(a.csv.lines().count(), 1 + 3 * 4);

    // Friction stress: NaN at the corner without friction, σ_T = 10 k + j.
    let a = along(&h5, "bottom", "1", Field::FrictionStress).unwrap();
    assert!(a.values[0][0].is_nan());
    assert_eq!(a.values[0][1..], [20.0, 21.0, 22.0]);
    assert!(
        a.info.contains("1 of the group's nodes carry no friction"),
        "{}",
        a.info
    );
    let a = along(&h5, "bottom", "0.5", Field::SlipVelocity).unwrap();
    assert_eq!(a.values[0][1..], [-10.0, -11.0, -12.0]);

    // The right end, walked upwards (+y), s from (3, 0); only (3, 0) is a
    // contact node (slot 2).
    let a = along(&h5, "right", "0", Field::FrictionStress).unwrap();
    assert_eq!(a.nodes, ids(&[(3, 0), (3, 1), (3, 2), (3, 3)]));
    assert_eq!(a.s, vec![0.0, 1.0, 2.0, 3.0]);
    assert_eq!(a.values[0][0], 2.0);
    assert!(a.values[0][1..].iter().all(|v| v.is_nan()));

    // A closed loop: the hole, with the body on the left, so clockwise,
    // from its node of least x, then least y.
    let a = along(&h5, "hole", "0", Field::Uy).unwrap();
    assert_eq!(a.nodes, ids(&[(1, 1), (1, 2), (2, 2), (2, 1)]));
    assert_eq!(a.s, vec![0.0, 1.0, 2.0, 3.0]);
    assert_eq!(a.values[0], vec![-1.0; 4]);

    // What cannot be walked, and bad arguments.
    let e = along(&h5, "pieces", "0", Field::Ux).unwrap_err().0;
    assert!(e.contains("2 separate pieces"), "{e}");
    let e = along(&h5, "body", "0", Field::Ux).unwrap_err().0;
    assert!(e.contains("not one chain"), "{e}");
    let e = along(&h5, "top", "0", Field::Ux).unwrap_err().0;
    assert!(
        e.contains("no group \"top\"") && e.contains("bottom"),
        "{e}"
    );
    let e = along(&h5, "bottom", "0.1,x", Field::Ux).unwrap_err().0;
    assert!(e.contains("\"x\" is not a number"), "{e}");

    // write_along (what main.rs calls) writes the same CSV to -o.
    let out = dir.join("along.csv");
    write_along(
        &h5,
        &AlongArgs {
            along: Some("hole".into()),
            times: Some("1".into()),
            output: Some(out.clone()),
        },
        Field::Ux,
        false,
    )
    .unwrap();
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        along(&h5, "hole", "1", Field::Ux).unwrap().csv
    );
    let e = write_along(
        &h5,
        &AlongArgs {
            along: Some("hole".into()),
            times: None,
            output: None,
        },
        Field::Ux,
        false,
    )
    .unwrap_err()
    .downcast::<stickslip_case::InputError>()
    .unwrap()
    .0;
    assert!(e.contains("--times"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

fn run_slab(dir: &Path) -> PathBuf {
    let h5 = dir.join("slab.h5");
    let o = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("run")
        .arg(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .arg("-o")
        .arg(&h5)
        .args(["--force", "--quiet", "--set", "time.t_end=0.1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    h5
}

#[test]
fn slab_contact_and_support_quad9() {
    let dir = scratch("slab");
    let h5 = run_slab(&dir);
    // The contact group of the paper's 8 x 2 quad9 slab: 17 nodes on y = 0,
    // from (0, 0) in +x (body above, on the left), s = x.
    let a = along(&h5, "contact", "0.05,0.1", Field::FrictionStress).unwrap();
    let f = hdf5::File::open(&h5).unwrap();
    let nodes = f.dataset("mesh/nodes").unwrap().read_2d::<f64>().unwrap();
    let contact = f
        .dataset("contact/nodes")
        .unwrap()
        .read_raw::<i64>()
        .unwrap();
    let fs = f
        .dataset("contact/friction_stress")
        .unwrap()
        .read_2d::<f64>()
        .unwrap();
    let time = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    assert_eq!(a.nodes.len(), 17);
    for (j, &n) in a.nodes.iter().enumerate() {
        assert_eq!(nodes[[n, 1]], 0.0, "node {n} is on y = 0");
        // Gmsh's transfinite coordinates are exact up to rounding.
        assert!((a.s[j] - nodes[[n, 0]]).abs() < 1e-12, "s = x at node {n}");
        if j > 0 {
            assert!(nodes[[n, 0]] > nodes[[a.nodes[j - 1], 0]]);
        }
    }
    // /contact/nodes is the same sequence without the corner (0, 0), which
    // is held in x (BENCHMARK.md).
    let tail: Vec<i64> = a.nodes[1..].iter().map(|&n| n as i64).collect();
    assert_eq!(tail, contact);
    for (i, &k) in a.records.iter().enumerate() {
        assert!((time[k] - [0.05, 0.1][i]).abs() < 1e-9, "step {k}");
        assert!(a.values[i][0].is_nan());
        for j in 1..17 {
            assert_eq!(a.values[i][j], fs[[k, j - 1]]);
            // |σ_T| ≤ g = μ F_n = 0.3 · 300 (METHOD.md, the friction law).
            assert!(a.values[i][j].abs() <= 90.0 * (1.0 + 1e-12));
        }
    }
    // The top ("support") walked with the body on the left: from (8, 1) in −x.
    let a = along(&h5, "support", "0.1", Field::Ux).unwrap();
    assert_eq!(a.nodes.len(), 17);
    let disp = f
        .dataset("displacement")
        .unwrap()
        .read_dyn::<f64>()
        .unwrap();
    for (j, &n) in a.nodes.iter().enumerate() {
        assert_eq!(nodes[[n, 1]], 1.0);
        assert!((a.s[j] - (8.0 - nodes[[n, 0]])).abs() < 1e-12);
        assert_eq!(a.values[0][j], disp[[a.records[0], n, 0]]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Through the command line: main.rs flattens `probe::AlongArgs` into
/// `probe` and calls `probe::write_along`.
#[test]
fn probe_along_through_the_binary() {
    let dir = scratch("binary");
    let h5 = run_slab(&dir);
    let csv = dir.join("contact.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("probe")
        .arg(&h5)
        .args(["--along", "contact", "--times", "0.1", "--field"])
        .arg("friction_stress")
        .arg("-o")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "stickslip probe --along: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let want = along(&h5, "contact", "0.1", Field::FrictionStress).unwrap();
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), want.csv);
    assert!(String::from_utf8_lossy(&o.stderr).contains("record 100"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Stress fields from the stored displacement and the case's material. At
/// t = 0 the paper's slab is in its static state: pressed by F_n = 300 on
/// its bottom and held on its top, σ_yy = −300 everywhere and σ_xx = σ_xy
/// = 0 (ends free in x but for the left roller, which holds no load);
/// plane strain with ν = 0.3 gives σ_zz = −90 and von Mises √(300² + 90² −
/// 300·90) = √71100. A node's history (`--at`) and the group's values
/// (`--along`) are the same numbers at a later time.
#[test]
fn stress_fields_of_the_slab() {
    let dir = scratch("stress");
    let h5 = run_slab(&dir);
    for (field, want) in [
        (Field::Syy, -300.0),
        (Field::Sxx, 0.0),
        (Field::Sxy, 0.0),
        (Field::VonMises, 71100f64.sqrt()),
    ] {
        let a = along(&h5, "contact", "0", field).unwrap();
        for line in a.csv.lines().skip(1) {
            let v: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
            assert!((v - want).abs() < 1e-9 * 300.0, "{field:?}: {line}");
        }
    }
    let p = stickslip::probe::probe(&h5, "4,0", Field::Sxx, true).unwrap();
    let at: Vec<(f64, f64)> = p
        .table
        .lines()
        .skip(1)
        .map(|l| {
            let mut f = l.split(',').map(|v| v.trim().parse::<f64>().unwrap());
            (f.next().unwrap(), f.next().unwrap())
        })
        .collect();
    let (t, v) = at[at.len() - 1];
    assert!(t > 0.09 && v.abs() > 1e-6, "the slab moves: {t} {v}");
    let a = along(&h5, "contact", &t.to_string(), Field::Sxx).unwrap();
    let node = a
        .csv
        .lines()
        .skip(1)
        .find(|l| l.split(',').nth(4) == Some("4e0"))
        .expect("the node at x = 4");
    let w: f64 = node.rsplit(',').next().unwrap().parse().unwrap();
    assert_eq!(v.to_bits(), w.to_bits(), "{node}");
}
