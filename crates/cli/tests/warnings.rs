//! Warnings (what runs but is likely not meant) reach the user however
//! the run is made: printed by `check`, by `mesh` and by `run` even with
//! `--quiet` (which silences progress, not warnings), in `run --json`, and
//! in the results file's `warnings` attribute.
//!
//! The nearly degenerate cell: `tests/data/half-annulus-q2.msh`, Gmsh's
//! default quad recombination on a Q2 half-annulus (`half-annulus.py`
//! writes it), leaves element 19 at the top of the outer arc with det J
//! at a node 8.4e-4 of its largest in the cell (its centroid at
//! (0.016780, 1.860008), as Gmsh wrote the nodes).

use std::path::{Path, PathBuf};

mod common;
use common::{root, stickslip};

fn scratch(name: &str) -> PathBuf {
    common::scratch(&format!("warnings-{name}"))
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn annulus_mesh() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/half-annulus-q2.msh")
        .display()
        .to_string()
}

/// A case on the half-annulus: held on its two straight ends, pressed on
/// its inner arc.
fn annulus_case(dir: &Path) -> String {
    let case = format!(
        "[mesh]\nfile = \"{}\"\n\n[material]\nE = 1000.0\nnu = 0.3\nrho = 1.0\nhypothesis = \"plane_strain\"\n\n\
         [[dirichlet]]\ngroup = \"support\"\nux = 0.0\nuy = 0.0\n\n\
         [contact]\ngroup = \"contact\"\npressure = 100.0\nmu = 0.3\neps = 1e-4\n\n\
         [time]\nscheme = \"central_difference\"\ndt = 1e-3\nt_end = 0.003\n\n[output]\nfile = \"a.h5\"\n",
        annulus_mesh()
    );
    let path = dir.join("annulus.toml");
    std::fs::write(&path, case).unwrap();
    path.display().to_string()
}

const DEGENERATE: &str = "1 of the 26 cells are nearly degenerate";
const WORST: &str = "element 19 near (0.016780, 1.860008), 8.4e-4";

/// The `warnings` attribute of a results file.
fn stored(h5: &Path) -> Vec<String> {
    let f = hdf5::File::open(h5).unwrap();
    f.attr("warnings")
        .unwrap()
        .read_raw::<hdf5::types::VarLenUnicode>()
        .unwrap()
        .iter()
        .map(|w| w.as_str().to_string())
        .collect()
}

#[test]
fn a_nearly_degenerate_cell_is_reported_by_mesh_check_and_run() {
    let o = stickslip(&["mesh", &annulus_mesh()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let table = text(&o.stdout);
    assert!(
        table.contains(&format!("  warning: {DEGENERATE}")) && table.contains(WORST),
        "{table}"
    );
    let o = stickslip(&["mesh", &annulus_mesh(), "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let w = j["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1, "{j}");
    assert!(w[0].as_str().unwrap().contains(WORST), "{j}");
    // The paper's mesh has none.
    let slab = root().join("cases/meshes/slab-q2-8x2.msh");
    let o = stickslip(&["mesh", slab.to_str().unwrap(), "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["warnings"], serde_json::json!([]));

    let dir = scratch("degenerate");
    let case = annulus_case(&dir);
    let o = stickslip(&["check", &case]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains(&format!("warning     {DEGENERATE}")),
        "{}",
        text(&o.stdout)
    );
    let h5 = dir.join("a.h5");
    let o = stickslip(&[
        "run",
        &case,
        "-o",
        h5.to_str().unwrap(),
        "--quiet",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains(&format!("warning: {DEGENERATE}")),
        "--quiet prints warnings: {}",
        text(&o.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let w = j["warnings"].as_array().unwrap();
    assert!(w.iter().any(|w| w.as_str().unwrap().contains(WORST)), "{j}");
    let kept = stored(&h5);
    assert_eq!(
        serde_json::json!(kept),
        j["warnings"],
        "the file keeps what --json says"
    );
}

/// The static displacement beyond the part's size (E in the wrong units):
/// printed with --quiet, in --json and in the file; a restart keeps and
/// reports the stored warnings; a calm run stores an empty list.
#[test]
fn warnings_are_printed_with_quiet_and_kept_in_json_and_the_file() {
    let dir = scratch("units");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let case = case.to_str().unwrap();
    let h5 = dir.join("a.h5");
    let out = h5.to_str().unwrap();
    let o = stickslip(&[
        "run",
        case,
        "-o",
        out,
        "--quiet",
        "--json",
        "--set",
        "material.E=1e-3",
        "--set",
        "time.t_end=0.002",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let said = text(&o.stderr);
    assert!(
        said.contains(
            "warning: the initial static displacement, less its mean translation, reaches"
        ),
        "{said}"
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let kept = stored(&h5);
    assert_eq!(kept.len(), 1, "{kept:?}");
    assert!(
        kept[0].starts_with("the initial static displacement, less its mean translation, reaches")
    );
    assert_eq!(j["warnings"], serde_json::json!(kept));
    // A restart says nothing new but reports what the file keeps.
    let o = stickslip(&[
        "run",
        case,
        "--restart",
        out,
        "--quiet",
        "--json",
        "--set",
        "material.E=1e-3",
        "--set",
        "time.t_end=0.004",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["warnings"], serde_json::json!(kept));
    assert_eq!(stored(&h5), kept);

    let calm = dir.join("calm.h5");
    let o = stickslip(&[
        "run",
        case,
        "-o",
        calm.to_str().unwrap(),
        "--quiet",
        "--json",
        "--set",
        "time.t_end=0.002",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("warning"), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["warnings"], serde_json::json!([]));
    assert!(stored(&calm).is_empty());
}

/// `run --restart` of a file that is not there says so (it said "cannot
/// open ... for writing ... check its permissions").
#[test]
fn a_restart_of_a_missing_file_says_it_is_missing() {
    let dir = scratch("missing");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let missing = dir.join("missing.h5");
    let o = stickslip(&[
        "run",
        case.to_str().unwrap(),
        "--restart",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let e = text(&o.stderr);
    assert!(
        e.contains("missing.h5: no such file") && !e.contains("permissions"),
        "{e}"
    );
    assert!(!missing.exists());
}
