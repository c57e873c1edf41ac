//! The XDMF companions of a results file that `stickslip views` writes
//! (`src/views_cmd.rs`, `src/xdmf.rs`, `src/views.rs`) read back by the
//! tools users open them with, as shipped: ParaView's three XDMF readers
//! through `pvpython` (Debian's `paraview`), meshio's `TimeSeriesReader`
//! and PyVista (PyPI). `cargo xtask test` installs them, and under CI a
//! missing one fails its test.
//!
//! Each test runs a Q1 and a Q2 case of the paper's slab, writes the
//! viewers' files (`stickslip views`) and forms the stresses (`stickslip
//! stress`, which lists them in OUT.xdmf), and has its reader read
//! `OUT.xdmf` (the body) and `OUT.contact.xdmf` (Γ_C as line cells) at
//! every record. The
//! expected values are h5py's reading of OUT.h5 and OUT.stress.h5, and
//! every array must equal them bit for bit: the XDMF files and the views
//! hold only references, so any difference is a wrong reference. Node
//! vectors come with a third component, which must be 0.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{root, stickslip_ok as stickslip};

fn scratch(name: &str) -> PathBuf {
    common::scratch(&format!("xdmf-{name}"))
}

/// Runs a paper case into `dir/NAME.h5`, writes its viewers' files and
/// forms its stresses; returns the results file.
fn run_case(case: &str, dir: &Path, name: &str, sets: &[&str]) -> PathBuf {
    let out = dir.join(format!("{name}.h5"));
    let case = root().join("cases/martins-oden").join(case);
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "run".as_ref(),
        case.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--force".as_ref(),
        "--quiet".as_ref(),
    ];
    for s in sets {
        args.push("--set".as_ref());
        args.push(s.as_ref());
    }
    stickslip(&args);
    stickslip(&["views".as_ref(), out.as_os_str(), "--quiet".as_ref()]);
    stickslip(&["stress".as_ref(), out.as_os_str(), "--quiet".as_ref()]);
    out
}

/// The two cases every reader reads: the paper's 85-node quad9 slab, every
/// step to t = 0.02 (21 records), and the Q1 16x4 slab (85 nodes, 64
/// quad4 cells), to t = 0.02 at 5 frames (6 records: its fields at steps
/// 0, 4, .., 20 of the 21 rows of its histories, so that its contact views
/// are of rows 0, 4, .., 20).
fn cases(dir: &Path) -> [(PathBuf, &'static str, usize); 2] {
    [
        (
            run_case("cd-step-eps1e-4.toml", dir, "q2", &["time.t_end=0.02"]),
            "quad9",
            21,
        ),
        (
            run_case(
                "cd-step-eps1-q1.toml",
                dir,
                "q1",
                &["time.t_end=0.02", "output.frames=5"],
            ),
            "quad",
            6,
        ),
    ]
}

/// Python (with h5py) that compares what a reader read, `got`, with h5py's
/// reading of the results: `check(tag, h5, part, got)` for part "body"
/// (OUT.xdmf) or "contact" (OUT.contact.xdmf), where `got` has `time`
/// (the reader's times), `points`, `cells` (connectivity, one row per
/// cell) and `arrays` (name → one array per record). Prints one line
/// "ok TAG PART: R records, A arrays, N points".
const COMPARE: &str = r#"
import sys
import numpy as np
import h5py

def expected(h5, part):
    with h5py.File(h5, "r") as f, h5py.File(h5[:-3] + ".stress.h5", "r") as g:
        # A record is a frame: the fields' row k, the histories' row rows[k].
        time = f["frames/time"][:]
        rows = f["frames/row"][:]
        nodes = f["mesh/nodes"][:]
        if part == "body":
            stress = g["stress"][:]
            arrays = {v: f[v][:] for v in ["displacement", "velocity", "acceleration"]}
            for c, name in enumerate(["sxx", "syy", "sxy"]):
                arrays[name] = stress[:, :, c]
            arrays["von_mises"] = g["von_mises"][:]
            return time, nodes, f["mesh/cells"][:], arrays
        contact = f["contact/nodes"][:]
        n_c = len(contact)
        arrays = {v: f["contact/" + v][:][rows] for v in ["friction_stress", "slip_velocity", "state"]}
        if "contact/normal_stress" in f:
            # Files of versions before it lack it, and their XML too.
            arrays["normal_stress"] = f["contact/normal_stress"][:][rows]
        arrays["s"] = np.broadcast_to(f["contact/s"][:], (len(time), n_c))
        if "contact/surface" in f:
            # Each node's surface, as s: one array shown at every record.
            arrays["surface"] = np.broadcast_to(f["contact/surface"][:], (len(time), n_c))
        # /contact/nodes follows the straight contact face node by node, and
        # only its end node is held: each segment joins two neighbours.
        lines = np.array([[i, i + 1] for i in range(n_c - 1)])
        return time, nodes[contact], lines, arrays

def check(tag, h5, part, got):
    time, points, cells, arrays = expected(h5, part)
    assert np.array_equal(np.asarray(got["time"], dtype=float), time), (tag, part, "time", got["time"], time)
    p = np.asarray(got["points"])
    assert np.array_equal(p[:, :2], points), (tag, part, "points")
    assert not p[:, 2:].any(), (tag, part, "z of the points")
    c = np.asarray(got["cells"])
    assert np.array_equal(c, cells), (tag, part, "cells", c[:3], cells[:3])
    assert sorted(got["arrays"]) == sorted(arrays), (tag, part, sorted(got["arrays"]), sorted(arrays))
    for name, want in arrays.items():
        rows = got["arrays"][name]
        assert len(rows) == len(time), (tag, part, name, len(rows))
        for k, a in enumerate(rows):
            a = np.asarray(a)
            if want.ndim == 3:
                # A node vector: (x, y) as stored, z = 0.
                assert a.shape == (want.shape[1], 3), (tag, part, name, k, a.shape)
                assert np.array_equal(a[:, :2], want[k]) and not a[:, 2].any(), (tag, part, name, k)
            else:
                assert np.array_equal(a.reshape(-1), want[k]), (tag, part, name, k, a.reshape(-1)[:4], want[k][:4])
    print(f"ok {tag} {part}: {len(time)} records, {len(arrays)} arrays, {len(points)} points")
"#;

/// Whether `program -c "import MODULES"` runs.
fn imports(program: &str, modules: &str) -> bool {
    Command::new(program)
        .args(["-c", &format!("import {modules}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Whether the reader is here; outside CI a missing one skips its test
/// (saying so), under CI it fails: the test command installs it.
fn present(what: &str, ok: bool, install: &str) -> bool {
    if !ok {
        assert!(
            std::env::var_os("CI").is_none(),
            "{what} is missing: {install} (cargo xtask test installs it)"
        );
        eprintln!("skipped: {what} is not installed ({install})");
    }
    ok
}

/// Runs `python3 -c COMPARE + script args…` from elsewhere than the files
/// (they must be found relative to the XDMF) and returns its stdout.
fn python(script: &str, args: &[&Path]) -> String {
    let o = Command::new("python3")
        .arg("-c")
        .arg(format!("{COMPARE}\n{script}"))
        .args(args)
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "python3 failed:\n{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

/// The lines a reader's check must print for a case of `records` records.
fn oks(tag: &str, records: usize) -> [String; 2] {
    [
        format!("ok {tag} body: {records} records, 7 arrays, 85 points"),
        // s, surface, the three friction fields and the normal stress.
        format!("ok {tag} contact: {records} records, 6 arrays, 16 points"),
    ]
}

fn assert_oks(stdout: &str, tag: &str, records: usize) {
    for line in oks(tag, records) {
        assert!(
            stdout.lines().any(|l| l == line),
            "no `{line}` in:\n{stdout}"
        );
    }
}

/// meshio's stock `TimeSeriesReader`, as PyPI ships it.
const MESHIO: &str = r#"
from meshio.xdmf import TimeSeriesReader
tag, cell_type, h5 = sys.argv[1], sys.argv[2], sys.argv[3]
for part, xdmf, kind in [("body", h5[:-3] + ".xdmf", cell_type), ("contact", h5[:-3] + ".contact.xdmf", "line")]:
    with TimeSeriesReader(xdmf) as r:
        points, cells = r.read_points_cells()
        assert len(cells) == 1 and cells[0].type == kind, [c.type for c in cells]
        got = {"time": [], "points": points, "cells": cells[0].data, "arrays": {}}
        for k in range(r.num_steps):
            t, point_data, cell_data = r.read_data(k)
            assert not cell_data, cell_data
            got["time"].append(t)
            for name, v in point_data.items():
                got["arrays"].setdefault(name, []).append(v)
    check(tag, h5, part, got)
"#;

#[test]
fn meshio_reads_what_h5py_reads_q1_and_q2() {
    if !present(
        "meshio, h5py or numpy",
        imports("python3", "meshio, h5py, numpy"),
        "pip install meshio h5py",
    ) {
        return;
    }
    let dir = scratch("meshio");
    for (h5, cell_type, records) in cases(&dir) {
        let tag = h5.file_stem().unwrap().to_str().unwrap().to_string();
        let out = python(MESHIO, &[Path::new(&tag), Path::new(cell_type), &h5]);
        assert_oks(&out, &tag, records);
    }
    // Moving the files together keeps every reference valid.
    let moved = scratch("meshio-moved");
    for ext in ["h5", "xdmf", "contact.xdmf", "views.h5", "stress.h5"] {
        std::fs::rename(
            dir.join(format!("q1.{ext}")),
            moved.join(format!("q1.{ext}")),
        )
        .unwrap();
    }
    let out = python(
        MESHIO,
        &[Path::new("q1"), Path::new("quad"), &moved.join("q1.h5")],
    );
    assert_oks(&out, "q1", 6);
}

/// PyVista as shipped: `pyvista.read` (the first record) and its reader's
/// time steps (`pyvista.get_reader`), and Warp By Vector on the
/// displacement.
const PYVISTA: &str = r#"
import pyvista as pv
tag, cell_type, h5 = sys.argv[1], sys.argv[2], sys.argv[3]
def cells(grid):
    return np.array([grid.get_cell(i).point_ids for i in range(grid.n_cells)])
for part, xdmf in [("body", h5[:-3] + ".xdmf"), ("contact", h5[:-3] + ".contact.xdmf")]:
    first = pv.read(xdmf)
    assert isinstance(first, pv.UnstructuredGrid), type(first)
    r = pv.get_reader(xdmf)
    got = {"time": list(r.time_values), "points": first.points, "cells": cells(first), "arrays": {}}
    for t in r.time_values:
        r.set_active_time_value(t)
        grid = r.read()
        for name in grid.point_data.keys():
            got["arrays"].setdefault(name, []).append(np.array(grid.point_data[name]))
    for name in first.point_data.keys():
        assert np.array_equal(first.point_data[name], got["arrays"][name][0]), (name, "pyvista.read")
    check(tag, h5, part, got)
    if part == "body":
        # The warped mesh is the nodes plus the displacement (z = 0 + 0).
        warped = grid.warp_by_vector("displacement")
        with h5py.File(h5, "r") as f:
            want = f["mesh/nodes"][:] + f["displacement"][-1]
        assert np.array_equal(warped.points[:, :2], want) and not warped.points[:, 2].any(), "warp"
        print(f"ok {tag} warp")
"#;

#[test]
fn pyvista_reads_what_h5py_reads_q1_and_q2() {
    if !present(
        "pyvista, h5py or numpy",
        imports("python3", "pyvista, h5py, numpy"),
        "pip install pyvista h5py",
    ) {
        return;
    }
    let dir = scratch("pyvista");
    for (h5, cell_type, records) in cases(&dir) {
        let tag = h5.file_stem().unwrap().to_str().unwrap().to_string();
        let out = python(PYVISTA, &[Path::new(&tag), Path::new(cell_type), &h5]);
        assert_oks(&out, &tag, records);
        assert!(out.contains(&format!("ok {tag} warp")), "{out}");
    }
}

/// ParaView's readers of .xdmf files (those its File > Open offers:
/// Xdmf3ReaderS, the one `OpenDataFile` picks, Xdmf3ReaderT and the legacy
/// XDMF Reader), each at every time step, into an .npz for the h5py
/// comparison (Debian's pvpython has numpy but no h5py); and Warp By Vector
/// on the displacement of the last record, as a user would apply it.
const PVPYTHON: &str = r#"
import sys
import numpy as np
from paraview import servermanager as sm
from paraview.simple import OpenDataFile, XDMFReader, Xdmf3ReaderS, Xdmf3ReaderT, WarpByVector
from vtk.numpy_interface import dataset_adapter as dsa
h5, out = sys.argv[1], sys.argv[2]
readers = {
    "XDMF Reader": lambda f: XDMFReader(FileNames=[f]),
    "Xdmf3ReaderS": lambda f: Xdmf3ReaderS(FileName=[f]),
    "Xdmf3ReaderT": lambda f: Xdmf3ReaderT(FileName=[f]),
}
def grid(src, t):
    src.UpdatePipeline(t)
    d = sm.Fetch(src)
    while d.IsA("vtkMultiBlockDataSet"):
        d = d.GetBlock(0)
    return d
res = {"default": np.array([OpenDataFile(h5[:-3] + ".xdmf").GetXMLName()])}
for name, make in readers.items():
    for part, xdmf in [("body", h5[:-3] + ".xdmf"), ("contact", h5[:-3] + ".contact.xdmf")]:
        key = f"{name}|{part}"
        r = make(xdmf)
        r.UpdatePipelineInformation()
        times = list(r.TimestepValues)
        res[f"{key}|time"] = np.array(times)
        for k, t in enumerate(times):
            d = grid(r, t)
            w = dsa.WrapDataObject(d)
            if k == 0:
                res[f"{key}|points"] = np.array(w.Points)
                res[f"{key}|cells"] = np.array([[d.GetCell(i).GetPointId(j) for j in range(d.GetCell(i).GetNumberOfPoints())] for i in range(d.GetNumberOfCells())])
            for a in w.PointData.keys():
                res[f"{key}|array|{a}|{k}"] = np.array(w.PointData[a])
        if part == "body":
            warped = grid(WarpByVector(Input=r, Vectors=["POINTS", "displacement"]), times[-1])
            res[f"{key}|warped"] = np.array(dsa.WrapDataObject(warped).Points)
np.savez(out, **res)
"#;

/// The .npz of [`PVPYTHON`] through [`COMPARE`], one check per reader and
/// part, and the warped points against h5py's nodes + displacement.
const PVPYTHON_COMPARE: &str = r#"
tag, h5, npz = sys.argv[1], sys.argv[2], sys.argv[3]
z = np.load(npz)
print("default reader", z["default"][0])
readers = sorted({k.split("|")[0] for k in z.files if "|" in k})
for name in readers:
    for part in ["body", "contact"]:
        key = f"{name}|{part}"
        got = {"time": z[f"{key}|time"], "points": z[f"{key}|points"], "cells": z[f"{key}|cells"], "arrays": {}}
        n = len(got["time"])
        for a in sorted({k.split("|")[3] for k in z.files if k.startswith(f"{key}|array|")}):
            got["arrays"][a] = [z[f"{key}|array|{a}|{k}"] for k in range(n)]
        check(f"{tag} {name}", h5, part, got)
    with h5py.File(h5, "r") as f:
        want = f["mesh/nodes"][:] + f["displacement"][-1]
    w = z[f"{name}|body|warped"]
    assert np.array_equal(w[:, :2], want) and not w[:, 2].any(), (name, "warp")
    print(f"ok {tag} {name} warp")
"#;

#[test]
fn paraview_readers_read_what_h5py_reads_q1_and_q2() {
    let has = Command::new("pvpython")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !present("pvpython", has, "apt-get install -y paraview")
        || !present(
            "h5py or numpy",
            imports("python3", "h5py, numpy"),
            "pip install h5py",
        )
    {
        return;
    }
    let dir = scratch("paraview");
    let script = dir.join("read.py");
    std::fs::write(&script, PVPYTHON).unwrap();
    for (h5, _, records) in cases(&dir) {
        let tag = h5.file_stem().unwrap().to_str().unwrap().to_string();
        let npz = dir.join(format!("{tag}.npz"));
        let o = Command::new("pvpython")
            .arg("--force-offscreen-rendering")
            .arg(&script)
            .arg(&h5)
            .arg(&npz)
            .current_dir(std::env::temp_dir())
            .output()
            .unwrap();
        assert!(
            o.status.success() && npz.is_file(),
            "pvpython failed:\n{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        let out = python(PVPYTHON_COMPARE, &[Path::new(&tag), &h5, &npz]);
        assert!(
            out.contains("default reader Xdmf3ReaderS"),
            "the reader File > Open picks: {out}"
        );
        for reader in ["XDMF Reader", "Xdmf3ReaderS", "Xdmf3ReaderT"] {
            assert_oks(&out, &format!("{tag} {reader}"), records);
            assert!(out.contains(&format!("ok {tag} {reader} warp")), "{out}");
        }
    }
}

/// `stickslip run -o OUT.h5` writes OUT.h5 only and says how to view it;
/// `stickslip views OUT.h5` writes OUT.xdmf, OUT.contact.xdmf and
/// OUT.views.h5 beside it, one grid and one view per record; a restart
/// removes the XML (it lists the earlier run's records) and keeps the
/// views, to which `views` adds those of the new records.
#[test]
fn views_writes_the_companions_beside_the_h5() {
    let dir = scratch("run");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let h5 = dir.join("slab.h5");
    let (case, h5s) = (case.to_str().unwrap(), h5.to_str().unwrap());
    let run = |more: [&str; 2], t_end: &str| {
        let o = common::stickslip(&["run", case, more[0], more[1], "--set", t_end]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let said = run(["-o", h5s], "time.t_end=0.01");
    assert!(
        said.contains(&format!(
            "view: `stickslip views {h5s}`, then open {} in ParaView",
            dir.join("slab.xdmf").display()
        )),
        "{said}"
    );
    for name in ["slab.xdmf", "slab.contact.xdmf", "slab.views.h5"] {
        assert!(!dir.join(name).exists(), "{name} written by the run");
    }
    let views_cmd = || {
        let o = common::stickslip(&["views", h5s]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let said = views_cmd();
    assert!(said.starts_with("views: 11 records in "), "{said}");
    let grids = |name: &str| {
        std::fs::read_to_string(dir.join(name))
            .unwrap()
            .matches("GridType=\"Uniform\"")
            .count()
    };
    let views = || {
        let f = hdf5::File::open(dir.join("slab.views.h5")).unwrap();
        (
            f.group("displacement").unwrap().len(),
            f.group("contact/state").unwrap().len(),
        )
    };
    assert_eq!(grids("slab.xdmf"), 11);
    assert_eq!(grids("slab.contact.xdmf"), 11);
    assert_eq!(views(), (11, 11));
    let said = run(["--restart", h5s], "time.t_end=0.015");
    assert!(said.contains("restart: removed "), "{said}");
    assert!(!dir.join("slab.xdmf").exists());
    assert!(!dir.join("slab.contact.xdmf").exists());
    assert_eq!(views(), (11, 11));
    views_cmd();
    assert_eq!(grids("slab.xdmf"), 16);
    assert_eq!(grids("slab.contact.xdmf"), 16);
    assert_eq!(views(), (16, 16));
    // The views read what the results file holds, first record and last.
    let f = hdf5::File::open(&h5).unwrap();
    let u = f
        .dataset("displacement")
        .unwrap()
        .read::<f64, ndarray::Ix3>()
        .unwrap();
    let g = hdf5::File::open(dir.join("slab.views.h5")).unwrap();
    for k in [0, 15] {
        let v = g
            .dataset(&format!("displacement/{k}"))
            .unwrap()
            .read_2d::<f64>()
            .unwrap();
        assert_eq!(v.shape(), [85, 3]);
        for i in 0..85 {
            assert_eq!(
                [v[[i, 0]], v[[i, 1]], v[[i, 2]]],
                [u[[k, i, 0]], u[[k, i, 1]], 0.0]
            );
        }
    }
}

/// `stickslip views` refuses, with exit code 2 and what to give instead,
/// a missing file, a file that is not HDF5 (the case), an XDMF named for
/// its results file, and an HDF5 file `stickslip run` did not write.
#[test]
fn views_refuses_what_is_not_a_results_file() {
    let dir = scratch("refuse");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let other = dir.join("other.h5");
    hdf5::File::create(&other).unwrap();
    for (bad, says) in [
        (dir.join("none.h5"), "no such results file"),
        (case, "cannot open it as HDF5"),
        (
            dir.join("slab.xdmf"),
            "give the results file the XDMF is written for",
        ),
        (other, "was not written by `stickslip run`"),
    ] {
        let o = common::stickslip(&["views".as_ref(), bad.as_os_str()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", bad.display());
        assert!(err.contains(says), "{}: {err}", bad.display());
    }
}

/// `stickslip views` on a run's file: refused while the run writes it
/// (exit code 2), and after the run is interrupted (SIGINT) it lists
/// every record the file holds.
#[test]
fn views_waits_for_the_run_and_shows_an_interrupted_one() {
    let dir = scratch("interrupted");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let h5 = dir.join("long.h5");
    // 10⁸ steps, a record every 2,000th: a run that is still going when
    // it is interrupted, however fast the steps, with few records.
    let child = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("run")
        .arg(&case)
        .arg("-o")
        .arg(&h5)
        .args([
            "--quiet",
            "--set",
            "time.t_end=100000",
            "--set",
            "output.every=2000",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !h5.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let o = common::stickslip(&["views".as_ref(), h5.as_os_str()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("a run is writing it"), "{err}");
    assert!(!dir.join("long.xdmf").exists());
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    stickslip(&["views".as_ref(), h5.as_os_str(), "--quiet".as_ref()]);
    let f = hdf5::File::open(&h5).unwrap();
    assert!(!f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
    let rows = f.dataset("time").unwrap().size();
    assert!(rows >= 2, "{rows} records before the signal");
    for name in ["long.xdmf", "long.contact.xdmf"] {
        let xml = std::fs::read_to_string(dir.join(name)).unwrap();
        assert_eq!(xml.matches("GridType=\"Uniform\"").count(), rows, "{name}");
    }
}

/// A results file of a version before `/contact/lines` (made here by
/// removing it): `views` writes the body's files, removes the contact
/// surface's (it would list other records) and says why.
#[test]
fn views_of_a_file_without_contact_lines_shows_the_body() {
    let dir = scratch("old");
    let h5 = run_case("cd-step-eps1e-4.toml", &dir, "old", &["time.t_end=0.005"]);
    assert!(dir.join("old.contact.xdmf").exists());
    hdf5::File::open_rw(&h5)
        .unwrap()
        .unlink("contact/lines")
        .unwrap();
    let o = common::stickslip(&["views".as_ref(), h5.as_os_str(), "--quiet".as_ref()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("has no /contact/lines") && err.contains("old.contact.xdmf is not written"),
        "{err}"
    );
    let xml = std::fs::read_to_string(dir.join("old.xdmf")).unwrap();
    assert_eq!(xml.matches("GridType=\"Uniform\"").count(), 6);
    assert!(!dir.join("old.contact.xdmf").exists());
}

/// The views file beside `h5` holds the views of its `frames` frames and
/// no others: body view k reads frame k of the fields, contact view k the
/// frame's row `/frames/row[k]` of the histories, bit for bit.
fn assert_views_hold_the_frames(h5: &Path, frames: usize) {
    let f = hdf5::File::open(h5).unwrap();
    let rows = f.dataset("frames/row").unwrap().read_raw::<u64>().unwrap();
    assert_eq!(rows.len(), frames);
    let g = hdf5::File::open(h5.with_extension("views.h5")).unwrap();
    let u = f
        .dataset("displacement")
        .unwrap()
        .read::<f64, ndarray::Ix3>()
        .unwrap();
    assert_eq!(g.group("displacement").unwrap().len() as usize, frames);
    for k in 0..frames {
        let v = g
            .dataset(&format!("displacement/{k}"))
            .unwrap()
            .read_2d::<f64>()
            .unwrap();
        let want = u.slice(ndarray::s![k, .., ..]);
        assert_eq!(v.slice(ndarray::s![.., ..2]), want, "displacement/{k}");
    }
    for name in ["friction_stress", "slip_velocity", "normal_stress"] {
        let h = f
            .dataset(&format!("contact/{name}"))
            .unwrap()
            .read_2d::<f64>()
            .unwrap();
        let views = g.group(&format!("contact/{name}")).unwrap();
        assert_eq!(views.len() as usize, frames, "{name}");
        for (k, &r) in rows.iter().enumerate() {
            let v = views
                .dataset(&k.to_string())
                .unwrap()
                .read_1d::<f64>()
                .unwrap();
            let want = h.row(r as usize);
            assert!(
                v.iter().zip(want).all(|(a, b)| a.to_bits() == b.to_bits()),
                "contact/{name}/{k}: not row {r}"
            );
        }
    }
    let state = f.dataset("contact/state").unwrap().read_2d::<i8>().unwrap();
    let views = g.group("contact/state").unwrap();
    assert_eq!(views.len() as usize, frames);
    for (k, &r) in rows.iter().enumerate() {
        let v = views
            .dataset(&k.to_string())
            .unwrap()
            .read_1d::<i8>()
            .unwrap();
        assert_eq!(v, state.row(r as usize), "contact/state/{k}: not row {r}");
    }
    let xml = std::fs::read_to_string(h5.with_extension("contact.xdmf")).unwrap();
    assert_eq!(xml.matches("GridType=\"Uniform\"").count(), frames);
}

/// A restart moves frames to other rows of the histories: it drops the
/// earlier run's last frame, the step shortened to land on its t_end, and
/// its own frames follow the steps at full length. `views` run again
/// points every contact view at its frame's row and drops the views of
/// frames the file no longer holds.
#[test]
fn views_follow_the_frames_a_restart_moves() {
    let dir = scratch("restart-rows");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let step = |h5: &Path, how: &str, sets: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "run".as_ref(),
            case.as_os_str(),
            how.as_ref(),
            h5.as_os_str(),
            "--quiet".as_ref(),
            "--set".as_ref(),
            "time.dt=3e-3".as_ref(),
        ];
        for s in sets {
            args.push("--set".as_ref());
            args.push(s.as_ref());
        }
        stickslip(&args);
        stickslip(&["views".as_ref(), h5.as_os_str(), "--quiet".as_ref()]);
    };
    // 3e-3 steps to t_end = 0.1: 33 of them and one of 1e-3 (row 34), a
    // frame; continued to 0.2 at full length, frame 7 lands on row 39.
    let h5 = dir.join("frames.h5");
    step(&h5, "-o", &["output.frames=7", "time.t_end=0.1"]);
    assert_views_hold_the_frames(&h5, 8);
    step(&h5, "--restart", &["output.frames=7", "time.t_end=0.2"]);
    assert_views_hold_the_frames(&h5, 11);
    // Every step a frame: continued to the checkpoint's time (before the
    // shortened step), the file keeps 34 of its 35 frames.
    let h5 = dir.join("every.h5");
    step(&h5, "-o", &["output.every=1", "time.t_end=0.1"]);
    assert_views_hold_the_frames(&h5, 35);
    step(&h5, "--restart", &["output.every=1", "time.t_end=0.099"]);
    assert_views_hold_the_frames(&h5, 34);
}

/// A views file that holds the frames is left as it is by another
/// `views`: its contact views' rows are read back and found right, so
/// nothing is rebuilt (the file's bytes and time of change stay). A
/// read-back that never found a view right would rebuild them all.
#[test]
fn views_again_leave_a_right_views_file_untouched() {
    let dir = scratch("views-again");
    let case = root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let h5 = dir.join("again.h5");
    stickslip(&[
        "run".as_ref(),
        case.as_os_str(),
        "-o".as_ref(),
        h5.as_os_str(),
        "--quiet".as_ref(),
        "--set".as_ref(),
        "output.frames=7".as_ref(),
    ]);
    let views = dir.join("again.views.h5");
    stickslip(&["views".as_ref(), h5.as_os_str(), "--quiet".as_ref()]);
    let (bytes, changed) = (
        std::fs::read(&views).unwrap(),
        std::fs::metadata(&views).unwrap().modified().unwrap(),
    );
    std::thread::sleep(std::time::Duration::from_millis(20));
    stickslip(&["views".as_ref(), h5.as_os_str(), "--quiet".as_ref()]);
    assert!(
        std::fs::read(&views).unwrap() == bytes,
        "the views file changed"
    );
    assert_eq!(
        std::fs::metadata(&views).unwrap().modified().unwrap(),
        changed,
        "the views file was written again"
    );
}
