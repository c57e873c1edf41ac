//! What a restart reads of a results file: its `/checkpoint` (the
//! integrator's state at the last flush, the rows and frames that belong
//! to it), the case it stores, and whether its mesh is the case's.

use std::path::Path;

use anyhow::{bail, ensure, Context, Result};
use hdf5::{File, Group, H5Type};
use ndarray::s;
use stickslip_time::{Checkpoint, Energy};

use crate::output::{get_scalar, text_attr, CheckpointExtra, SLOTS};

/// A results file's `/checkpoint` and what a restart needs besides.
#[derive(Clone, Debug, PartialEq)]
pub struct Stored {
    /// The integrator's state.
    pub checkpoint: Checkpoint,
    /// Rows, frames, wall time, largest balance.
    pub extra: CheckpointExtra,
    /// The case TOML as run (root attribute `case`).
    pub case_source: String,
    /// Root attribute `complete`.
    pub complete: bool,
    /// `/time`, the first `extra.rows` entries.
    pub times: Vec<f64>,
}

fn get_vector<T: H5Type>(g: &Group, name: &str) -> Result<Vec<T>> {
    let ds = g
        .dataset(name)
        .with_context(|| format!("/checkpoint/{name} is missing"))?;
    if ds.size() == 0 {
        return Ok(Vec::new());
    }
    Ok(ds.read_raw::<T>()?)
}

/// Reads `/checkpoint`, the case and `complete` of a results file.
///
/// # Errors
/// The file cannot be opened, was not written by `stickslip run`, or has no
/// checkpoint (written before any flush, or by a version without restart).
pub fn read_checkpoint(path: &Path) -> Result<Stored> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let program = text_attr(&file, "program").unwrap_or_default();
    ensure!(
        program == "stickslip",
        "{} was not written by stickslip run (no program = \"stickslip\" attribute)",
        path.display()
    );
    let case_source = text_attr(&file, "case").with_context(|| {
        format!(
            "{}: cannot read the case it stores; start a new run instead of restarting",
            path.display()
        )
    })?;
    let complete = file.attr("complete")?.read_scalar::<bool>()?;
    if !file.link_exists("checkpoint") {
        bail!(
            "{} holds no checkpoint (the run stopped before its first flush); run the case again",
            path.display()
        );
    }
    let cg = file.group("checkpoint")?;
    let slot: u8 = get_scalar(&cg, "slot")?;
    let g = cg
        .group(SLOTS[usize::from(slot).min(1)])
        .context("/checkpoint: the current slot is missing")?;
    let e: Vec<f64> = get_vector(&g, "energy")?;
    // Six in files written before damping (damped = 0 then), seven before
    // moving foundations (foundation = 0 then), eight before compliant
    // foundations (their stored energy 0 then, and set again from the
    // displacement on restore).
    ensure!(
        (6..=9).contains(&e.len()),
        "/checkpoint/energy has {} values, expected 9",
        e.len()
    );
    let checkpoint = Checkpoint {
        t: get_scalar(&g, "t")?,
        steps: get_scalar(&g, "steps")?,
        displacement: get_vector(&g, "displacement")?,
        velocity: get_vector(&g, "velocity")?,
        acceleration: get_vector(&g, "acceleration")?,
        classes: get_vector(&g, "classes")?,
        forces: get_vector(&g, "forces")?,
        energy: Energy {
            kinetic: e[0],
            strain: e[1],
            external_work: e[2],
            dissipated: e[3],
            damped: e.get(6).copied().unwrap_or(0.0),
            foundation: e.get(7).copied().unwrap_or(0.0),
            foundation_stored: e.get(8).copied().unwrap_or(0.0),
            total: e[4],
            balance: e[5],
        },
        initial_mechanical: get_scalar(&g, "initial_mechanical")?,
        reduced_remaining: get_scalar(&g, "reduced_remaining")?,
        // Absent in files written before the drift-free clock: the
        // restart then starts a new run of steps at t.
        clock: if g.attr("clock_t0").is_ok() {
            Some((
                get_scalar(&g, "clock_t0")?,
                get_scalar(&g, "clock_dt")?,
                get_scalar(&g, "clock_steps")?,
            ))
        } else {
            None
        },
        total_iterations: get_scalar(&g, "total_iterations")?,
        factorizations: get_scalar(&g, "factorizations")?,
        // Absent in files written before the compliant Newmark step.
        normal_iterations: if g.attr("normal_iterations").is_ok() {
            get_scalar(&g, "normal_iterations")?
        } else {
            0
        },
        // Absent in files written before the energy-consistent normal
        // force, and where the run does not carry it.
        normal_excess: if g.link_exists("normal_excess") {
            get_vector(&g, "normal_excess")?
        } else {
            Vec::new()
        },
    };
    // The clock's steps are read back as they are: one of another value
    // (a file changed by another program) moved the restart's times, and
    // the run blew up blaming its Δt.
    if let Some((t0, dt, k)) = checkpoint.clock {
        let on_clock = t0 + k as f64 * dt;
        ensure!(
            dt > 0.0 && (on_clock - checkpoint.t).abs() <= 0.5 * dt,
            "/checkpoint: its clock (t0 = {t0}, dt = {dt}, {k} steps: t = {on_clock}) does not \
             reach its t = {}: the file is damaged; restart from a copy of the run's own file, \
             or run the case again",
            checkpoint.t
        );
    }
    let rows = get_scalar::<u64>(&g, "rows")? as usize;
    let extra = CheckpointExtra {
        rows,
        // Absent in files written before the frames: the fields at every
        // row.
        frames: if g.attr("frames").is_ok() {
            get_scalar::<u64>(&g, "frames")? as usize
        } else {
            rows
        },
        wall_time_s: get_scalar(&g, "wall_time_s")?,
        max_balance: get_scalar(&g, "max_balance")?,
        // Absent in files of versions before the node orders: the mesh's.
        node_order: if g.attr("node_order").is_ok() {
            get_scalar(&g, "node_order")?
        } else {
            0
        },
    };
    let time = file.dataset("time")?;
    let n = time.shape().first().copied().unwrap_or(0);
    ensure!(
        extra.rows <= n && extra.rows >= 1 && extra.frames <= extra.rows && extra.frames >= 1,
        "/checkpoint says {} rows and {} frames but /time has {n} rows: the file is damaged; \
         run the case again",
        extra.rows,
        extra.frames
    );
    let times = time.read_slice_1d::<f64, _>(s![..extra.rows])?.to_vec();
    // A file whose /time was damaged (rows never written read as the fill
    // value 0) would be continued with a wrong history.
    let rising = times.windows(2).all(|w| w[0] < w[1]);
    let last = times.last().copied().unwrap_or(0.0);
    ensure!(
        rising && last <= checkpoint.t,
        "/time's first {} rows do not rise to the checkpoint's t = {} (they end at {last}): \
         the file is damaged; run the case again",
        extra.rows,
        checkpoint.t
    );
    Ok(Stored {
        checkpoint,
        extra,
        case_source,
        complete,
        times,
    })
}

/// How the mesh stored in a results file differs from `mesh`, if it does
/// (a restart must continue on the mesh the run started on: the case
/// names the mesh file, and the file may have changed since).
///
/// # Errors
/// The file's `/mesh` cannot be read.
pub fn stored_mesh_change(path: &Path, mesh: &stickslip_mesh::Mesh) -> Result<Option<String>> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let g = file.group("mesh")?;
    let kind = text_attr(&g, "kind")?;
    if kind != mesh.kind.name() {
        return Ok(Some(format!(
            "the stored mesh's cells are {kind}, the mesh's now {}",
            mesh.kind.name()
        )));
    }
    let nodes = g.dataset("nodes")?;
    let cells = g.dataset("cells")?;
    let npc = mesh.kind.nodes_per_cell();
    if nodes.shape() != [mesh.nodes.len(), 2] || cells.shape() != [mesh.n_cells(), npc] {
        return Ok(Some(format!(
            "the stored mesh has {} nodes and {} cells, the mesh now {} and {}",
            nodes.shape().first().copied().unwrap_or(0),
            cells.shape().first().copied().unwrap_or(0),
            mesh.nodes.len(),
            mesh.n_cells()
        )));
    }
    let stored = nodes.read_2d::<f64>()?;
    if let Some(i) = (0..mesh.nodes.len())
        .find(|&i| (0..2).any(|k| stored[[i, k]].to_bits() != mesh.nodes[i][k].to_bits()))
    {
        return Ok(Some(format!(
            "node {i} was at ({}, {}) and is now at ({}, {})",
            stored[[i, 0]],
            stored[[i, 1]],
            mesh.nodes[i][0],
            mesh.nodes[i][1]
        )));
    }
    let stored = cells.read_2d::<i64>()?;
    if let Some(c) = (0..mesh.n_cells())
        .find(|&c| (0..npc).any(|k| stored[[c, k]] != mesh.cells[c * npc + k] as i64))
    {
        return Ok(Some(format!(
            "cell {c} has other nodes than in the stored mesh"
        )));
    }
    Ok(None)
}
