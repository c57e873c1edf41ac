//! `stickslip stress OUT.h5`: a finished run's stress fields into
//! OUT.stress.h5, listed in OUT.xdmf; the results file is only read. Expected values: the paper's slab at t = 0 is in its static
//! state, pressed by F_n = 300 on its bottom and held on its top: σ_yy =
//! −300 at every node, σ_xx = σ_xy = 0, and plane strain with ν = 0.3 gives
//! von Mises √(300² + 90² − 300·90) = √71100. Later rows are checked
//! against `probe --along` (the same nodal average, formed independently of
//! this command's loop).

use std::path::PathBuf;
use std::process::{Command, Output};

use stickslip::probe::{along, Field};
use stickslip_testkit::{scratch, workspace_root as root};

fn stickslip(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args(args)
        .output()
        .unwrap()
}

/// [`stickslip`], which must succeed.
fn stickslip_ok(args: &[&str]) {
    let o = stickslip(args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The paper's slab case run to `t_end` into a new scratch directory
/// `name`: (the directory, the case, the results file).
fn run_slab(name: &str, t_end: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = scratch(name);
    let h5 = dir.join("slab.h5");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let t_end = format!("time.t_end={t_end}");
    stickslip_ok(&[
        "run",
        case.to_str().unwrap(),
        "-o",
        h5.to_str().unwrap(),
        "--quiet",
        "--set",
        &t_end,
    ]);
    (dir, case, h5)
}

#[test]
fn stress_fields_go_into_the_file_and_its_xdmf() {
    let (dir, case, h5) = run_slab("slab", "0.1");
    let out = h5.to_str().unwrap().to_string();
    let before = std::fs::read(&h5).unwrap();
    stickslip_ok(&["stress", &out]);
    assert_eq!(
        std::fs::read(&h5).unwrap(),
        before,
        "the results file is only read"
    );

    let g = hdf5::File::open(dir.join("slab.stress.h5")).unwrap();
    let stress = g
        .dataset("stress")
        .unwrap()
        .read::<f64, ndarray::Ix3>()
        .unwrap();
    let mises = g.dataset("von_mises").unwrap().read_2d::<f64>().unwrap();
    drop(g);
    let f = hdf5::File::open(&h5).unwrap();
    let rows = f.dataset("time").unwrap().size();
    assert_eq!(stress.shape(), [rows, 85, 3]);
    assert_eq!(mises.shape(), [rows, 85]);
    for v in 0..85 {
        let s = [stress[[0, v, 0]], stress[[0, v, 1]], stress[[0, v, 2]]];
        for (got, want) in s.iter().zip([0.0, -300.0, 0.0]) {
            assert!((got - want).abs() < 1e-9 * 300.0, "node {v}: {s:?}");
        }
        assert!((mises[[0, v]] - 71100f64.sqrt()).abs() < 1e-9 * 300.0);
    }
    // The last row against probe --along at the same step, bit for bit.
    let t_last = f.dataset("time").unwrap().read_1d::<f64>().unwrap()[rows - 1];
    drop(f);
    for (field, comp) in [(Field::Sxx, 0), (Field::Syy, 1), (Field::Sxy, 2)] {
        let a = along(&h5, "contact", &t_last.to_string(), field).unwrap();
        for line in a.csv.lines().skip(1) {
            let cols: Vec<&str> = line.split(',').collect();
            let node: usize = cols[3].parse().unwrap();
            let v: f64 = cols[7].parse().unwrap();
            assert_eq!(
                v.to_bits(),
                stress[[rows - 1, node, comp]].to_bits(),
                "{field:?} at node {node}"
            );
        }
    }
    let xml = std::fs::read_to_string(dir.join("slab.xdmf")).unwrap();
    for name in ["sxx", "syy", "sxy", "von_mises"] {
        let attr = format!("<Attribute Name=\"{name}\" AttributeType=\"Scalar\"");
        assert_eq!(xml.matches(&attr).count(), rows, "{name}");
    }
    assert_eq!(xml.matches(">slab.stress.h5:/views/").count(), 4 * rows);
    // Each record's view is that record's column of /stress.
    let g = hdf5::File::open(dir.join("slab.stress.h5")).unwrap();
    let last = format!("views/syy/{}", rows - 1);
    let syy = g.dataset(&last).unwrap().read_1d::<f64>().unwrap();
    for v in 0..85 {
        assert_eq!(
            syy[v].to_bits(),
            stress[[rows - 1, v, 1]].to_bits(),
            "{last}"
        );
    }
    drop(g);
    // Again: the same file, not a bigger one.
    let size = std::fs::metadata(dir.join("slab.stress.h5")).unwrap().len();
    stickslip_ok(&["stress", &out, "--quiet"]);
    assert_eq!(
        std::fs::metadata(dir.join("slab.stress.h5")).unwrap().len(),
        size
    );

    // A restart ends the run elsewhere: the stresses are removed, and the
    // command writes them again.
    stickslip_ok(&[
        "run",
        case.to_str().unwrap(),
        "--restart",
        &out,
        "--quiet",
        "--set",
        "time.t_end=0.12",
    ]);
    assert!(!dir.join("slab.stress.h5").exists());
    assert!(!dir.join("slab.xdmf").exists());
    // `stickslip views` lists the records without stresses.
    stickslip_ok(&["views", &out, "--quiet"]);
    let xml = std::fs::read_to_string(dir.join("slab.xdmf")).unwrap();
    assert!(!xml.contains("von_mises") && xml.contains(">slab.views.h5:/displacement/120<"));

    // Bad input: no file, not a results file.
    for bad in [dir.join("none.h5"), case.clone()] {
        let o = stickslip(&["stress", bad.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// While `stickslip stress` reads a results file (its shared lock, held
/// here by the library call it makes), a run's `--force` or `--restart` on
/// the file is refused: a `--force` run would remove the file under it
/// and then get the old run's stresses beside its own results.
#[test]
fn runs_keep_out_while_the_stresses_are_read() {
    let (_, case, h5) = run_slab("shared", "0.05");
    let out = h5.to_str().unwrap().to_string();
    let lock = stickslip::results_file::RunLock::shared(&h5).unwrap();
    for args in [
        vec![
            "run",
            case.to_str().unwrap(),
            "-o",
            &out,
            "--force",
            "--quiet",
        ],
        vec![
            "run",
            case.to_str().unwrap(),
            "--restart",
            &out,
            "--quiet",
            "--set",
            "time.t_end=0.06",
        ],
    ] {
        let o = stickslip(&args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(h5.exists(), "{args:?}: the file is still there");
    }
    // probe reads alongside.
    stickslip_ok(&["probe", &out, "--at", "8,0"]);
    drop(lock);
    stickslip_ok(&[
        "run",
        case.to_str().unwrap(),
        "-o",
        &out,
        "--force",
        "--quiet",
    ]);
}

/// Another run's results copied over OUT.h5 (same name, same number of
/// records) leave OUT.stress.h5 holding the stresses of other
/// displacements: `views` listed them in OUT.xdmf, so a viewer showed the
/// first run's stresses on the second's motion. Now they are left out
/// with a note saying so, until `stress` forms them anew.
#[test]
fn views_leave_out_the_stresses_of_other_displacements() {
    let (dir, case, h5) = run_slab("stale-stress", "0.1");
    let out = h5.to_str().unwrap().to_string();
    stickslip_ok(&["stress", &out]);
    let other = dir.join("other.h5");
    stickslip_ok(&[
        "run",
        case.to_str().unwrap(),
        "-o",
        other.to_str().unwrap(),
        "--quiet",
        "--set",
        "time.t_end=0.1",
        "--set",
        "contact.mu=0.1",
    ]);
    std::fs::copy(&other, &h5).unwrap();
    let xdmf = dir.join("slab.xdmf");
    let o = stickslip(&["views", &out]);
    let said = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{said}");
    assert!(
        said.contains("slab.stress.h5 holds the stresses of other displacements")
            && said.contains("stickslip stress"),
        "{said}"
    );
    assert!(!std::fs::read_to_string(&xdmf)
        .unwrap()
        .contains("von_mises"));
    stickslip_ok(&["stress", &out]);
    let o = stickslip(&["views", &out]);
    let said = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success() && !said.contains("note"), "{said}");
    assert!(std::fs::read_to_string(&xdmf)
        .unwrap()
        .contains("von_mises"));
}
