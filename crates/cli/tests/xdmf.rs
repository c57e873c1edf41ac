//! The XDMF companion file (`src/xdmf.rs`) read back by the tools users
//! open it with: meshio (Python) and ParaView's `pvpython` (Debian's
//! `paraview`; `cargo xtask test` installs both, and under CI a missing one
//! fails its test). Every array they read must equal the one in the
//! .h5 (read here with h5py / the hdf5 crate), bit for bit: the XDMF holds
//! only references, so any difference is a wrong reference.
//!
//! The writer is called directly on the .h5 of a run, so these checks do
//! not depend on when `run` calls it; one test checks that `run` does
//! write `OUT.xdmf` beside `OUT.h5`.

use std::path::{Path, PathBuf};
use std::process::Command;

use stickslip::xdmf;
use stickslip_mesh::CellKind;
use stickslip_testkit::{scratch, workspace_root as root};

/// Runs a paper case into `dir/NAME.h5` and returns that path.
fn run_case(case: &str, dir: &Path, name: &str, sets: &[&str]) -> PathBuf {
    let out = dir.join(format!("{name}.h5"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_stickslip"));
    cmd.arg("run")
        .arg(root().join("cases/martins-oden").join(case))
        .arg("-o")
        .arg(&out)
        .args(["--force", "--quiet"]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let o = cmd.output().unwrap();
    assert!(
        o.status.success(),
        "stickslip run {case} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// Sizes and times of a results file, read with the hdf5 crate.
fn info_of(h5: &Path) -> (usize, CellKind, usize, Vec<f64>) {
    let f = hdf5::File::open(h5).unwrap();
    let nodes = f.dataset("mesh/nodes").unwrap().shape();
    let cells = f.dataset("mesh/cells").unwrap().shape();
    let kind = match cells[1] {
        4 => CellKind::Quad4,
        9 => CellKind::Quad9,
        n => panic!("{n} nodes per cell"),
    };
    let t = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    (nodes[0], kind, cells[0], t)
}

/// Writes `dir/NAME.xdmf` for `dir/NAME.h5` with the writer under test.
fn write_companion(h5: &Path) -> PathBuf {
    let (n_nodes, kind, n_cells, times) = info_of(h5);
    let xdmf = h5.with_extension("xdmf");
    xdmf::write_xdmf(
        h5,
        &xdmf,
        &xdmf::XdmfInfo {
            n_nodes,
            kind,
            n_cells,
            times: &times,
            stress: None,
        },
    )
    .unwrap();
    xdmf
}

fn python_has(modules: &str) -> bool {
    Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .status()
        .is_ok_and(|s| s.success())
}

/// meshio 5.3 reads XDMF 3 temporal collections but not HyperSlab data
/// items (its `_read_data_item` wants a `Format`); the subclass below adds
/// the HyperSlab rule of the XDMF model (first child: start, stride and
/// count per dimension; second child: the source) and leaves everything
/// else (grid discovery, topology names, times, centring) to meshio.
const MESHIO_CHECK: &str = r#"
import sys
import numpy as np
import h5py
from meshio.xdmf import TimeSeriesReader

class Reader(TimeSeriesReader):
    def _read_data_item(self, item):
        if item.get("ItemType") == "HyperSlab":
            sel, src = list(item)
            start, stride, count = self._read_data_item(sel).reshape(3, -1)
            full = self._read_data_item(src)
            assert list(full.shape) == [int(d) for d in src.get("Dimensions").split()]
            idx = tuple(slice(a, a + s * c, s) for a, s, c in zip(start, stride, count))
            dims = [int(d) for d in item.get("Dimensions").split()]
            return full[idx].reshape(dims)
        return super()._read_data_item(item)

xdmf, h5, cell_type = sys.argv[1], sys.argv[2], sys.argv[3]
with h5py.File(h5, "r") as f, Reader(xdmf) as r:
    points, cells = r.read_points_cells()
    assert np.array_equal(points, f["mesh/nodes"][:]), "points"
    assert len(cells) == 1 and cells[0].type == cell_type, [c.type for c in cells]
    assert np.array_equal(cells[0].data, f["mesh/cells"][:]), "cells"
    time = f["time"][:]
    assert r.num_steps == len(time), (r.num_steps, len(time))
    n = points.shape[0]
    for k in range(r.num_steps):
        t, point_data, cell_data = r.read_data(k)
        assert t == time[k], (k, t, time[k])
        assert sorted(point_data) == ["acceleration", "displacement", "velocity"], sorted(point_data)
        for name, v in point_data.items():
            assert np.array_equal(v.reshape(n, 2), f[name][k]), (name, k)
    print(f"ok {r.num_steps} steps {n} nodes {cells[0].type}")
"#;

/// Reads the XDMF with meshio and compares every array with h5py; returns
/// meshio's summary line, or None (skipped) without meshio/h5py outside CI.
fn meshio_check(xdmf: &Path, h5: &Path, cell_type: &str) -> Option<String> {
    if !python_has("meshio, h5py, numpy") {
        assert!(
            std::env::var_os("CI").is_none(),
            "meshio/h5py missing: pip install meshio h5py (cargo xtask test installs them)"
        );
        eprintln!("skipped: meshio or h5py is not installed (pip install meshio h5py)");
        return None;
    }
    let o = Command::new("python3")
        .arg("-c")
        .arg(MESHIO_CHECK)
        .arg(xdmf)
        .arg(h5)
        .arg(cell_type)
        // From elsewhere: the .h5 must be found relative to the .xdmf.
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "meshio check of {} failed:\n{}{}",
        xdmf.display(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    Some(String::from_utf8_lossy(&o.stdout).trim().to_string())
}

#[test]
fn meshio_reads_the_same_arrays_as_h5py_quad9_and_quad4() {
    let dir = scratch("meshio");
    // The paper's 85-node quad9 slab, every step to t = 0.05 (51 records).
    let h5 = run_case("cd-step-eps1e-4.toml", &dir, "q2", &["time.t_end=0.05"]);
    let x = write_companion(&h5);
    if let Some(s) = meshio_check(&x, &h5, "quad9") {
        assert_eq!(s, "ok 51 steps 85 nodes quad9");
    }
    // The Q1 16x4 slab (85 nodes too, 64 quad4 cells), every 5th step.
    let h5 = run_case(
        "cd-step-eps1-q1.toml",
        &dir,
        "q1",
        &["time.t_end=0.05", "output.every=5"],
    );
    let x = write_companion(&h5);
    if let Some(s) = meshio_check(&x, &h5, "quad") {
        assert!(s.starts_with("ok ") && s.ends_with(" nodes quad"), "{s}");
    }
    // Moving both files together keeps the reference valid.
    let moved = scratch("meshio-moved");
    std::fs::rename(&h5, moved.join("q1.h5")).unwrap();
    std::fs::rename(&x, moved.join("q1.xdmf")).unwrap();
    meshio_check(&moved.join("q1.xdmf"), &moved.join("q1.h5"), "quad");
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&moved).ok();
}

/// ParaView's "XDMF Reader" (vtkXdmfReader), through pvpython: the number
/// of time steps, their values, the cell type (VTK_BIQUADRATIC_QUAD = 28),
/// the point count and the displacement at the last step. (ParaView 5.11's
/// "Xdmf3 Reader" variants do not evaluate HyperSlab data items: they load
/// the mesh and skip the vectors with "Skipping unrecognized array type".)
const PVPYTHON_CHECK: &str = r#"
import sys, json, struct
from paraview.simple import XDMFReader
from paraview import servermanager as sm
r = XDMFReader(FileNames=[sys.argv[1]])
r.UpdatePipelineInformation()
times = list(r.TimestepValues)
r.UpdatePipeline(times[-1])
d = sm.Fetch(r)
if d.IsA("vtkMultiBlockDataSet"):
    d = d.GetBlock(0)
pd = d.GetPointData()
# Floats as their IEEE bits, so the JSON round trip cannot round them.
bits = lambda v: struct.unpack("<q", struct.pack("<d", v))[0]
disp = pd.GetArray("displacement")
print(json.dumps({
    "times": [bits(t) for t in times],
    "points": d.GetNumberOfPoints(),
    "cells": d.GetNumberOfCells(),
    "cell_type": d.GetCellType(0),
    "arrays": sorted(pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())),
    "components": disp.GetNumberOfComponents(),
    "disp": [[bits(v) for v in disp.GetTuple(i)] for i in range(d.GetNumberOfPoints())],
    "xy": [[bits(v) for v in d.GetPoint(i)[:2]] for i in range(d.GetNumberOfPoints())],
}))
"#;

#[test]
fn paraview_loads_the_xdmf() {
    let has_pvpython = Command::new("pvpython")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_pvpython {
        // Under CI the test command has installed it: its absence is a
        // failure, not a pass.
        assert!(
            std::env::var_os("CI").is_none(),
            "pvpython is missing: apt-get install -y paraview (cargo xtask test installs it)"
        );
        eprintln!("skipped: pvpython is not installed (apt-get install -y paraview)");
        return;
    }
    let dir = scratch("paraview");
    let h5 = run_case("cd-step-eps1e-4.toml", &dir, "q2", &["time.t_end=0.02"]);
    let x = write_companion(&h5);
    let script = dir.join("check.py");
    std::fs::write(&script, PVPYTHON_CHECK).unwrap();
    let o = Command::new("pvpython")
        .arg("--force-offscreen-rendering")
        .arg(&script)
        .arg(&x)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "pvpython failed:\n{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let line = stdout.lines().last().unwrap_or_default();
    let j: serde_json::Value =
        serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {stdout}"));

    let f = hdf5::File::open(&h5).unwrap();
    let time = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    let nodes = f.dataset("mesh/nodes").unwrap().read_2d::<f64>().unwrap();
    let disp = f
        .dataset("displacement")
        .unwrap()
        .read_dyn::<f64>()
        .unwrap();
    let float = |v: &serde_json::Value| f64::from_bits(v.as_i64().unwrap() as u64);
    let times: Vec<f64> = j["times"].as_array().unwrap().iter().map(float).collect();
    assert_eq!(times, time, "ParaView's time steps are /time");
    assert_eq!(j["points"], 85);
    assert_eq!(j["cells"], 16);
    assert_eq!(j["cell_type"], 28, "VTK_BIQUADRATIC_QUAD");
    // VTK vectors have 3 components: the reader pads (x, y) with z = 0.
    assert_eq!(j["components"], 3);
    assert_eq!(
        j["arrays"],
        serde_json::json!(["acceleration", "displacement", "velocity"])
    );
    let last = time.len() - 1;
    for i in 0..85 {
        for c in 0..2 {
            assert_eq!(float(&j["xy"][i][c]), nodes[[i, c]], "node {i}");
            assert_eq!(
                float(&j["disp"][i][c]),
                disp[[last, i, c]],
                "displacement of node {i} at the last step"
            );
        }
        assert_eq!(float(&j["disp"][i][2]), 0.0);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `stickslip run -o OUT.h5` writes `OUT.xdmf` beside it (issue 9). This
/// fails until run.rs calls `xdmf::write_xdmf` after the last step.
#[test]
fn run_writes_the_xdmf_beside_the_h5() {
    let dir = scratch("run");
    let h5 = run_case("cd-step-eps1e-4.toml", &dir, "slab", &["time.t_end=0.01"]);
    let x = dir.join("slab.xdmf");
    assert!(
        x.is_file(),
        "stickslip run -o {} wrote no {}",
        h5.display(),
        x.display()
    );
    if let Some(s) = meshio_check(&x, &h5, "quad9") {
        assert_eq!(s, "ok 11 steps 85 nodes quad9");
    }
    std::fs::remove_dir_all(&dir).ok();
}
