//! Output by simulated time, as a user meets it: a case that says nothing
//! of its output writes its fields (u, v, a) at 200 frames and its
//! histories (time, energy, contact) at every step; `check` says how much
//! that is; a scene whose friction cannot act runs without it and says
//! so.

use std::path::{Path, PathBuf};

mod common;
use common::{check, root, run, scratch, succeeded};

/// The paper's explicit case (500 steps of 1e-3 to 0.5, 85 nodes) in
/// `dir`, its mesh paths absolute and its `[output]` left to the defaults.
fn paper_case(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("cases/martins-oden/cd-step-eps1e-4.toml"))
        .unwrap()
        .replace(
            "\"../meshes/",
            &format!("\"{}/", root().join("cases/meshes").display()),
        );
    let at = text.find("[output]").expect("the paper case has [output]");
    let case = dir.join("slab.toml");
    std::fs::write(&case, &text[..at]).unwrap();
    case
}

fn read_1d<T: hdf5::H5Type>(f: &hdf5::File, name: &str) -> Vec<T> {
    f.dataset(name).unwrap().read_raw::<T>().unwrap()
}

#[test]
fn by_default_200_frames_of_fields_and_every_step_of_histories() {
    let dir = scratch("frames-default");
    let case = paper_case(&dir);
    let said = succeeded(&check(&case, &[]), "check");
    // 200 frames and the initial state; 500 steps and the initial state.
    assert!(
        said.contains("about 201 frames of u, v, a (200 frames over [0, t_end]"),
        "{said}"
    );
    assert!(said.contains("and 501 rows of histories"), "{said}");
    let out = dir.join("slab.h5");
    succeeded(&run(&case, &out, &["--quiet"]), "run");
    let f = hdf5::File::open(&out).unwrap();
    let time: Vec<f64> = read_1d(&f, "time");
    assert_eq!(time.len(), 501);
    for name in [
        "energy/total",
        "solver/dt",
        "solver/iterations",
        "contact/friction_stress",
        "contact/state",
    ] {
        assert_eq!(
            f.dataset(name).unwrap().shape()[0],
            501,
            "{name}: a row a step"
        );
    }
    for name in ["displacement", "velocity", "acceleration"] {
        assert_eq!(f.dataset(name).unwrap().shape(), [201, 85, 2], "{name}");
    }
    // Frame k is the first step at or after k t_end / 200 = 2.5e-3 k: step
    // ceil(2.5 k), so its row of /time is that step and its time the
    // step's (bit for bit: the file's own /time).
    let rows: Vec<u64> = read_1d(&f, "frames/row");
    let want: Vec<u64> = (0..=200).map(|k| (2.5 * k as f64).ceil() as u64).collect();
    assert_eq!(rows, want);
    let frame_time: Vec<f64> = read_1d(&f, "frames/time");
    for (k, (&r, &t)) in rows.iter().zip(&frame_time).enumerate() {
        assert_eq!(t.to_bits(), time[r as usize].to_bits(), "frame {k}");
    }
    assert_eq!(*frame_time.last().unwrap(), 0.5, "the last step is a frame");
    // `check`'s size against the file's: within 10% (HDF5's own
    // structures are estimated).
    let size = said
        .lines()
        .find(|l| l.starts_with("output"))
        .and_then(|l| l.rsplit(", ").next())
        .unwrap();
    let (value, unit) = size.split_once(' ').unwrap();
    let scale = match unit {
        "kB" => 1e3,
        "MB" => 1e6,
        other => panic!("{other}"),
    };
    let said_bytes = value.parse::<f64>().unwrap() * scale;
    let bytes = std::fs::metadata(&out).unwrap().len() as f64;
    assert!(
        (said_bytes - bytes).abs() <= 0.1 * bytes,
        "check said {size}, the file has {bytes} bytes"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn two_rules_for_the_frames_are_refused_where_they_stand() {
    let dir = scratch("frames-two");
    let case = paper_case(&dir);
    let mut text = std::fs::read_to_string(&case).unwrap();
    text.push_str("[output]\nframes = 50\ninterval = 0.1\n");
    std::fs::write(&case, &text).unwrap();
    let line = text.lines().count();
    let o = check(&case, &[]);
    let e = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains(&format!("slab.toml:{line}:"))
            && e.contains("output.interval and output.frames both say"),
        "{e}"
    );
    // A --set of one rule replaces the file's others.
    let said = succeeded(&check(&case, &["output.every=5"]), "check --set");
    assert!(said.contains("about 101 frames"), "{said}");
    std::fs::remove_dir_all(&dir).ok();
}

/// μ = 0: the run says friction was off (its summary, `--json` and
/// `/solver`), counts no stick/slip iteration, and stores no friction
/// stress; Newmark ran 828 iterations in 500 steps on this mesh before.
#[test]
fn a_run_without_friction_says_so() {
    let dir = scratch("frames-mu0");
    let case = paper_case(&dir);
    for scheme in ["central_difference", "newmark"] {
        let out = dir.join(format!("{scheme}.h5"));
        let scheme_set = format!("time.scheme={scheme}");
        let o = run(
            &case,
            &out,
            &["--json", "--set", "contact.mu=0", "--set", &scheme_set],
        );
        let said = succeeded(&o, scheme);
        assert!(
            common::stderr(&o).contains("friction off (contact.mu = 0)"),
            "{}",
            common::stderr(&o)
        );
        let j: serde_json::Value = serde_json::from_str(said.trim()).unwrap();
        assert_eq!(j["friction"], "off: contact.mu = 0", "{j}");
        // One solve (or pass) a step, no iteration besides.
        assert_eq!(j["iterations"], j["steps"], "{j}");
        let f = hdf5::File::open(&out).unwrap();
        let friction = f
            .group("solver")
            .unwrap()
            .attr("friction")
            .unwrap()
            .read_scalar::<hdf5::types::VarLenUnicode>()
            .unwrap();
        assert_eq!(friction.as_str(), "off: contact.mu = 0");
        let stress: Vec<f64> = f
            .dataset("contact/friction_stress")
            .unwrap()
            .read_raw()
            .unwrap();
        assert!(stress.iter().all(|s| s.to_bits() == 0), "{scheme}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `check` counts the frames by the run's own rule: a frame time inside
/// the last step (here 66 · 0.003 = 0.198, in the step from 0.1975 to
/// 0.2) makes that step a frame once, not twice.
#[test]
fn check_counts_the_frames_the_run_writes() {
    let dir = scratch("frames-check-count");
    let case = paper_case(&dir);
    let sets = ["output.interval=0.003", "time.dt=2.5e-3", "time.t_end=0.2"];
    let said = succeeded(&check(&case, &sets), "check");
    assert!(said.contains("about 67 frames of u, v, a"), "{said}");
    let out = dir.join("slab.h5");
    let mut args = vec!["--quiet"];
    for kv in &sets {
        args.extend(["--set", kv]);
    }
    succeeded(&run(&case, &out, &args), "run");
    let f = hdf5::File::open(&out).unwrap();
    let frame_time: Vec<f64> = read_1d(&f, "frames/time");
    assert_eq!(frame_time.len(), 67);
    assert_eq!(*frame_time.last().unwrap(), 0.2);
    std::fs::remove_dir_all(&dir).ok();
}
