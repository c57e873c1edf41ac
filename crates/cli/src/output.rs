//! The HDF5 results writer (DESIGN.md "Results").
//!
//! The file is created with the mesh and the contact surface, then grows by
//! one row per step in every history (`/time`, `/energy/*`, `/solver/*`,
//! `/contact/*`) and by one row per frame (a step whose record carries the
//! fields, [`crate::frames`]) in the fields (`/displacement`, `/velocity`,
//! `/acceleration`) and `/frames/{time,row}`: unlimited first dimension,
//! chunked along time; shuffle + deflate when `compression` is 1-9, none
//! by default. Rows are kept in memory up to the end of a chunk
//! along time and written as one block per dataset (`Pending`), and
//! always before a flush. It is flushed every
//! [`ResultsWriter::flush_every_steps`] appends or
//! [`ResultsWriter::flush_every_secs`] seconds (or when the run says so,
//! with a checkpoint), so a run that stops early leaves a readable file
//! with `complete = false`; [`ResultsWriter::finish`] writes the solver
//! summary and sets `complete`.
//!
//! `/checkpoint` holds the integrator's full state at the last flush
//! ([`ResultsWriter::write_checkpoint`]: the `stickslip_time::Checkpoint`
//! fields and the number of output rows at that moment) in one of two slots,
//! `/checkpoint/a` and `/checkpoint/b`, named by the attribute
//! `/checkpoint.slot` (0 = a, 1 = b): a new checkpoint goes into the other
//! slot, is flushed, and only then becomes the current one, so a `kill -9`
//! in the middle of writing one leaves the previous one intact.
//! [`read_checkpoint`] and [`ResultsWriter::open_append`] continue a file
//! from it (`stickslip run --restart`).

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, ensure, Context, Result};
use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, File, Group, H5Type};
use ndarray::{s, Array1, Array2, ArrayView1, ArrayView2};
use stickslip_time::Checkpoint;

pub use crate::stored::{read_checkpoint, stored_mesh_change, Stored};

use crate::pending::Pending;

/// What the file holds before the first step.
#[derive(Clone, Copy, Debug)]
pub struct Header<'a> {
    /// The case TOML as run (root attribute `case`).
    pub case_source: &'a str,
    /// The mesh (`/mesh/*`).
    pub mesh: &'a stickslip_mesh::Mesh,
    /// Contact node indices along the surface (empty: no `/contact`).
    pub contact_nodes: &'a [usize],
    /// Arc length of each contact node.
    pub contact_s: &'a [f64],
    /// The contact surface's segments between two neighbouring contact
    /// nodes (indices into `contact_nodes`, the body on the left), for
    /// the viewers' line cells (`/contact/lines`).
    pub contact_lines: &'a [[usize; 2]],
    /// The surface of each contact node, an index into `contact_groups`
    /// (`/contact/surface`; empty: not written).
    pub contact_surface: &'a [usize],
    /// The contact surfaces' groups in case order (`/contact` attribute
    /// `groups`).
    pub contact_groups: &'a [String],
}

/// One output step. Vectors are full, `2 * n_nodes` long, interleaved
/// (x, y) per node, or all three empty for a step that is no frame (its
/// histories only); contact arrays are `n_c` long (empty without contact).
#[derive(Clone, Copy, Debug)]
pub struct Record<'a> {
    /// Time.
    pub t: f64,
    /// Displacement r.
    pub displacement: &'a [f64],
    /// Velocity ṙ.
    pub velocity: &'a [f64],
    /// Acceleration r̈.
    pub acceleration: &'a [f64],
    /// Friction stress σ_T along τ at each contact node.
    pub friction_stress: &'a [f64],
    /// Slip velocity v_T along τ at each contact node.
    pub slip_velocity: &'a [f64],
    /// The normal traction at each contact node: the prescribed pressure
    /// p(s, t), or a compliant foundation's c_n δ^{m_n}.
    pub normal_stress: &'a [f64],
    /// 0 stuck, +1 / −1 slipping.
    pub state: &'a [i8],
    /// ½ṙᵀMṙ.
    pub kinetic: f64,
    /// ½rᵀKr.
    pub strain: f64,
    /// Work of the external loads so far.
    pub external_work: f64,
    /// Friction dissipation so far.
    pub dissipated: f64,
    /// Rayleigh damping's dissipation so far (0 without damping).
    pub damped: f64,
    /// A moving foundation's work through friction so far (0 at rest).
    pub foundation: f64,
    /// The energy a compliant foundation stores (0 without one).
    pub foundation_stored: f64,
    /// kinetic + strain + foundation_stored − rᵀR(t) (the paper's Fig. 9).
    pub total: f64,
    /// kinetic + strain + foundation_stored − initial − work +
    /// dissipated + damped − foundation.
    pub balance: f64,
    /// The step that led here.
    pub dt: f64,
    /// Friction iterations of that step.
    pub iterations: u32,
}

/// Written at the end (`/solver` attributes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Summary {
    /// Wall time of the run in seconds.
    pub wall_time_s: f64,
    /// Time steps taken (not only those written).
    pub steps: u64,
    /// Numeric factorizations done.
    pub factorizations: u64,
    /// Critical time step of the explicit scheme, if estimated.
    pub dt_crit: Option<f64>,
    /// Why friction did no work, if it did none (`/solver` attribute
    /// `friction`: "off: ..."; "on" otherwise).
    pub friction_off: Option<String>,
    /// Why the run stopped early, if it did (root attribute `failure`).
    pub failure: Option<String>,
    /// How the steps formed their products with K
    /// (`Integrator::stiffness_product`).
    pub stiffness_product: String,
    /// How the run's sparse Cholesky factors were ordered
    /// (`Integrator::fill_order`); `None` keeps what the file holds (a
    /// restart that factorized nothing).
    pub fill_order: Option<String>,
}

/// Growing datasets: the histories one row per step, the fields and
/// `/frames` one per frame.
#[derive(Debug)]
struct Series {
    time: Dataset,
    displacement: Dataset,
    velocity: Dataset,
    acceleration: Dataset,
    frame_time: Dataset,
    frame_row: Dataset,
    contact: Option<ContactSeries>,
    energy: [Dataset; ENERGY_NAMES.len()],
    dt: Dataset,
    iterations: Dataset,
}

impl Series {
    /// Every history resized to `rows` rows and every field to `frames`
    /// (of `n` nodes and `n_c` contact nodes); all are tried, the first
    /// error returned.
    fn resize(&self, (rows, frames): (usize, usize), n: usize, n_c: usize) -> Result<()> {
        let mut results = Vec::new();
        for d in [&self.time, &self.dt, &self.iterations]
            .into_iter()
            .chain(&self.energy)
        {
            results.push(d.resize(rows));
        }
        for d in [&self.frame_time, &self.frame_row] {
            results.push(d.resize(frames));
        }
        for d in [&self.displacement, &self.velocity, &self.acceleration] {
            results.push(d.resize((frames, n, 2)));
        }
        if let Some(c) = &self.contact {
            for d in [
                &c.friction_stress,
                &c.slip_velocity,
                &c.state,
                &c.normal_stress,
            ] {
                results.push(d.resize((rows, n_c)));
            }
        }
        Ok(results.into_iter().collect::<Result<(), _>>()?)
    }
}

#[derive(Debug)]
struct ContactSeries {
    friction_stress: Dataset,
    slip_velocity: Dataset,
    state: Dataset,
    normal_stress: Dataset,
}

/// Writes one results file as a run goes.
#[derive(Debug)]
pub struct ResultsWriter {
    // Fields drop in this order: the datasets close before the file.
    series: Series,
    file: File,
    n_nodes: usize,
    n_c: usize,
    /// Rows appended, written or still in `pending`.
    rows: usize,
    /// Frames (rows of the fields) appended.
    frames: usize,
    /// Rows and frames on disk at the last flush that succeeded.
    flushed: (usize, usize),
    /// Appended rows not yet in the datasets.
    pending: Pending,
    /// Rows per chunk of the vector fields along time (whole chunks are
    /// allocated in the file).
    block_rows: usize,
    since_flush: usize,
    last_flush: Instant,
    /// Flush after this many appends (default 100).
    pub flush_every_steps: usize,
    /// Flush after this many seconds since the last flush (default 5).
    pub flush_every_secs: f64,
    /// Flush inside [`ResultsWriter::append`] (default true). A run that
    /// checkpoints turns it off and calls [`ResultsWriter::write_checkpoint`]
    /// when [`ResultsWriter::flush_due`] says so.
    pub auto_flush: bool,
}

/// What a run keeps in `/checkpoint` besides the integrator's state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CheckpointExtra {
    /// Output rows in the file that belong to the checkpointed state (rows
    /// written later are dropped on restart).
    pub rows: usize,
    /// Frames (rows of the fields) that belong to it (files written before
    /// the frames: `rows`).
    pub frames: usize,
    /// Wall time spent so far (summed over restarts).
    pub wall_time_s: f64,
    /// Largest |energy balance| so far.
    pub max_balance: f64,
    /// How the state's free DOFs are numbered
    /// (`stickslip_fem::NodeOrder::code`: 0 the mesh file's node order,
    /// 1 grid rows, 2 reverse Cuthill–McKee; files written before the
    /// node orders: 0).
    pub node_order: u8,
}

/// Node order written in `/mesh/cells` attribute `node_order`.
fn node_order(kind: stickslip_mesh::CellKind) -> &'static str {
    match kind {
        stickslip_mesh::CellKind::Quad4 => "quad4: the 4 corners counter-clockwise",
        stickslip_mesh::CellKind::Quad9 => {
            "quad9: the 4 corners counter-clockwise, then the mid-side nodes of edges (0,1), (1,2), \
             (2,3), (3,0), then the centre (Gmsh's and VTK's Quadrilateral_9 order)"
        }
    }
}

pub(crate) fn string_attr(loc: &hdf5::Location, name: &str, value: &str) -> Result<()> {
    let v: VarLenUnicode = value
        .replace('\0', " ")
        .parse()
        .map_err(|e| anyhow::anyhow!("attribute {name}: {e:?}"))?;
    loc.new_attr::<VarLenUnicode>()
        .create(name)?
        .write_scalar(&v)?;
    Ok(())
}

/// A text attribute of a results file, checked to be UTF-8: HDF5 stores
/// bytes, and a damaged file's are not always text (`VarLenUnicode::as_str`
/// does not check them).
///
/// # Errors
/// No such attribute, not a text attribute, or bytes that are not UTF-8.
pub fn text_attr(loc: &hdf5::Location, name: &str) -> Result<String> {
    let v = loc.attr(name)?.read_scalar::<VarLenUnicode>()?;
    match std::str::from_utf8(v.as_bytes()) {
        Ok(text) => Ok(text.to_string()),
        Err(e) => bail!(
            "its attribute {name:?} is not UTF-8 text (byte {}): the file is damaged",
            e.valid_up_to()
        ),
    }
}

fn scalar_attr<T: H5Type>(loc: &hdf5::Location, name: &str, value: T) -> Result<()> {
    loc.new_attr::<T>().create(name)?.write_scalar(&value)?;
    Ok(())
}

/// Deflate level of the growing datasets by default: none. Deflate (after
/// shuffle: HDF5 refuses shuffle after a compression filter,
/// DEPENDENCIES.md §1a) is slower than everything else a run does on the
/// meshes measured, for files 0.7-0.85 of raw: the ignored test
/// `write_speed` (100k nodes, 3 vector fields), levels 1 and 4 about 85 ms
/// per record (57 MB/s), none 1.4 ms; `cargo xtask bench output`
/// (docs/bench-output.csv, 2026-11-24): the paper's case 0.108 s a run at
/// level 4 against 0.038 s with none, a 4,257-node Newmark run 0.91 s
/// against 0.42 s.
/// `output.compression = 1..9` turns it on.
pub const DEFLATE_LEVEL: u8 = 0;

/// The energies files of earlier versions lack (damping, moving and
/// compliant foundations): a restart makes them, their earlier rows 0.
const ADDED_ENERGIES: [&str; 3] = ["damped", "foundation", "foundation_stored"];

/// Names of the `/energy` series, in [`Record`] order.
pub(crate) const ENERGY_NAMES: [&str; 9] = [
    "kinetic",
    "strain",
    "external_work",
    "dissipated",
    "total",
    "balance",
    "damped",
    "foundation",
    "foundation_stored",
];

/// Rows of the histories kept in memory at most before they are written
/// (the chunk of the 1-D series), however rare the frames.
const HISTORY_BLOCK: usize = SERIES_CHUNK;

/// Bytes of rows kept in memory before they are written (a frame larger
/// than this is written as it comes). Each block costs about 15 HDF5
/// writes, which on a small mesh whose every step is a frame cost more
/// than the steps when made at every chunk's end (docs/performance.md).
const PENDING_BYTES: usize = 1 << 20;

/// The growing series of a results file: time, u, v, a, the frames' time
/// and row, the energies, dt and the iterations, and four of the contact
/// (HDF5 keeps up to 1 MiB of each one's chunks in its cache).
const SERIES_COUNT: usize = 4 + 2 + ENERGY_NAMES.len() + 2 + 4;

/// Rows per chunk along time so that a chunk stays within HDF5's default
/// 1 MiB chunk cache (a partly written chunk then stays in memory instead of
/// being re-read and re-compressed on every append).
fn chunk_rows(row_bytes: usize) -> usize {
    (1 << 20) / row_bytes.max(1)
}

/// Shuffle + deflate at `level`, or no filter at level 0.
fn filtered(b: hdf5::DatasetBuilderEmpty, level: u8) -> hdf5::DatasetBuilderEmpty {
    if level == 0 {
        b
    } else {
        b.shuffle().deflate(level.min(9))
    }
}

/// Rows per chunk along time of the 1-D series (`/time`, `/energy/*`,
/// `/solver/*`, `/frames/*`).
pub const SERIES_CHUNK: usize = 1024;

fn series_1d<T: H5Type>(g: &Group, name: &str, level: u8) -> Result<Dataset> {
    Ok(filtered(g.new_dataset::<T>(), level)
        .chunk(SERIES_CHUNK)
        .shape(0..)
        .create(name)?)
}

/// Rows per chunk along time of a contact series of `n` nodes and `size`
/// bytes a value.
pub fn contact_chunk_rows(n: usize, size: usize) -> usize {
    chunk_rows(n * size).clamp(1, 64)
}

fn series_2d<T: H5Type>(g: &Group, name: &str, n: usize, level: u8) -> Result<Dataset> {
    let rows = contact_chunk_rows(n, std::mem::size_of::<T>());
    Ok(filtered(g.new_dataset::<T>(), level)
        .chunk((rows, n))
        .shape((0.., n))
        .create(name)?)
}

/// The name of a physical group's dataset in `/mesh/groups`: '/' (which
/// would make a nested HDF5 path) as '_', and a name HDF5 takes for no
/// link name ("" or ".") as "_"; the dataset's `name` attribute keeps the
/// group's own name.
pub(crate) fn stored_group_name(name: &str) -> String {
    match name {
        "" | "." => "_".to_string(),
        _ => name.replace('/', "_"),
    }
}

/// `base`, or where `taken` (two groups of one name: of two dimensions,
/// unnamed ones "#TAG" of one tag in several, or named so once '/' is
/// replaced) `base#TAG`, `base#DIM.TAG`, then a count after it.
fn free_name(base: &str, (dim, tag): (u8, i32), taken: impl Fn(&str) -> bool) -> String {
    [
        base.to_string(),
        format!("{base}#{tag}"),
        format!("{base}#{dim}.{tag}"),
    ]
    .into_iter()
    .chain((2..).map(|k| format!("{base}#{dim}.{tag}.{k}")))
    .find(|n| !taken(n))
    .expect("a free name")
}

/// [`ResultsWriter::room_needed`] of a file of `n_nodes` nodes, `n_c`
/// contact nodes and `block_rows` rows a chunk of the node vectors, whose
/// state has `n_free` values a vector, less the records not yet flushed.
/// A new run's file has [`vector_chunk_rows`] of them: `stickslip run`
/// and `check` count it before the run, so that a run the disk cannot hold
/// with this room kept is refused at the start rather than stopped part
/// way (near a full disk the records not yet flushed may still stop it).
pub(crate) fn room_kept(n_nodes: usize, n_c: usize, block_rows: usize, n_free: usize) -> u64 {
    // The rows go to the datasets a chunk at a time (whole chunks are
    // allocated), so the next write may take a chunk of every series.
    let frame_bytes = (6 * n_nodes + 2) * 8;
    let fields = block_rows.max(PENDING_BYTES / frame_bytes + 1) * frame_bytes;
    let histories = HISTORY_BLOCK * (4 * n_c + 2 + ENERGY_NAMES.len()) * 8;
    let checkpoint = 5 * n_free * 8;
    (2 * (fields + histories + checkpoint) + (1 << 20)) as u64
}

/// Rows per chunk along time of the node vectors (`/displacement` and the
/// others) of a mesh of `n` nodes: a run's file grows by whole chunks of
/// them. At most 64 KiB a chunk (where a row is smaller), as every flush
/// writes the chunk it ends in whole, however few of its rows are new.
pub fn vector_chunk_rows(n: usize) -> usize {
    ((64 << 10) / (n * 16).max(1)).clamp(1, 16)
}

fn series_3d(g: &Group, name: &str, n: usize, level: u8) -> Result<Dataset> {
    let rows = vector_chunk_rows(n);
    Ok(filtered(g.new_dataset::<f64>(), level)
        .chunk((rows, n, 2))
        .shape((0.., n, 2))
        .create(name)?)
}

/// Rows per chunk along time of a growing dataset (1 if it has no chunks).
fn block_rows(d: &Dataset) -> usize {
    d.chunk()
        .and_then(|c| c.first().copied())
        .unwrap_or(1)
        .max(1)
}

/// Writes `v` into the 1-D dataset `name` of `g`, creating it (contiguous,
/// unfiltered: a checkpoint must be exact and quick) on first use.
fn put_vector<T: H5Type>(g: &Group, name: &str, v: &[T]) -> Result<()> {
    let ds = if g.link_exists(name) {
        let ds = g.dataset(name)?;
        ensure!(
            ds.shape() == [v.len()],
            "checkpoint/{name} has shape {:?}, the state {} values",
            ds.shape(),
            v.len()
        );
        ds
    } else {
        g.new_dataset::<T>().shape(v.len()).create(name)?
    };
    if !v.is_empty() {
        ds.write(ArrayView1::from(v))?;
    }
    Ok(())
}

/// Writes (or rewrites) a scalar attribute.
pub(crate) fn put_scalar<T: H5Type>(loc: &hdf5::Location, name: &str, value: T) -> Result<()> {
    if let Ok(a) = loc.attr(name) {
        let same = a.ndim() == 0
            && a.dtype()
                .and_then(|d| d.to_descriptor())
                .is_ok_and(|d| d == T::type_descriptor());
        if same {
            a.write_scalar(&value)?;
            return Ok(());
        }
        // One of another type or shape (the file changed by another
        // program): written into, it failed (text) or converted the value
        // (an integer dt_crit read 0). Made anew.
        drop(a);
        loc.delete_attr(name)?;
    }
    scalar_attr(loc, name, value)
}

pub(crate) fn get_scalar<T: H5Type>(loc: &hdf5::Location, name: &str) -> Result<T> {
    loc.attr(name)
        .with_context(|| format!("/checkpoint attribute {name} is missing"))?
        .read_scalar::<T>()
        .with_context(|| format!("/checkpoint attribute {name}"))
}

/// The two checkpoint slots.
pub(crate) const SLOTS: [&str; 2] = ["a", "b"];

/// Order of `/checkpoint/energy`.
const ENERGY_ORDER: &str =
    "kinetic, strain, external_work, dissipated, total, balance, damped, foundation, \
     foundation_stored";

/// `/contact/surface` and the attribute `groups`: which surface of the
/// case each contact node is on.
fn write_surfaces(c: &Group, header: &Header) -> Result<()> {
    if header.contact_surface.is_empty() {
        return Ok(());
    }
    ensure!(
        header.contact_surface.len() == header.contact_nodes.len()
            && header
                .contact_surface
                .iter()
                .all(|&k| k < header.contact_groups.len()),
        "contact_surface has {} entries for {} contact nodes and {} surfaces",
        header.contact_surface.len(),
        header.contact_nodes.len(),
        header.contact_groups.len()
    );
    c.new_dataset_builder()
        .with_data(&index_array(header.contact_surface.iter().copied()))
        .create("surface")?;
    let groups: Vec<VarLenUnicode> = header
        .contact_groups
        .iter()
        .map(|g| g.parse::<VarLenUnicode>())
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("a contact group name: {e}"))?;
    c.new_attr::<VarLenUnicode>()
        .shape(groups.len())
        .create("groups")?
        .write(&groups)?;
    Ok(())
}

fn index_array(v: impl ExactSizeIterator<Item = usize>) -> Array1<i64> {
    v.map(|i| i as i64).collect()
}

impl ResultsWriter {
    /// Creates (truncates) `path` and writes everything known before the
    /// first step: root attributes (`program`, `version`, `case`,
    /// `complete = false`), `/mesh`, and `/contact/{nodes,s}` when there is a
    /// contact surface.
    ///
    /// # Errors
    /// File system / HDF5 errors, or contact arrays of different lengths.
    pub fn create(path: &Path, header: &Header) -> Result<ResultsWriter> {
        Self::create_with(path, header, DEFLATE_LEVEL)
    }

    /// [`ResultsWriter::create`] with the deflate level of the growing
    /// datasets: 0 (none) to 9.
    ///
    /// # Errors
    /// As [`ResultsWriter::create`].
    pub fn create_with(path: &Path, header: &Header, compression: u8) -> Result<ResultsWriter> {
        let level = compression.min(9);
        ensure!(
            header.contact_nodes.len() == header.contact_s.len(),
            "contact_nodes has {} entries but contact_s {}",
            header.contact_nodes.len(),
            header.contact_s.len()
        );
        let mesh = header.mesh;
        let n_nodes = mesh.nodes.len();
        ensure!(n_nodes > 0, "the mesh has no nodes");
        // No reuse of freed file space: a compressed chunk rewritten after a
        // flush moves, and with reuse its old place (which the flushed
        // metadata still points to) could be overwritten by later data, so a
        // `kill -9` between flushes would leave flushed rows unreadable
        // (seen as "inflate() failed" on restart). The cost: the space of a
        // partly filled chunk's older copies, one per flush at most.
        let file = File::with_options()
            .with_fcpl(|p| p.file_space_strategy(hdf5::file::FileSpaceStrategy::None))
            .create(path)
            .with_context(|| format!("cannot create {}", path.display()))?;
        let root: &hdf5::Location = &file;
        string_attr(root, "program", "stickslip")?;
        string_attr(root, "version", env!("CARGO_PKG_VERSION"))?;
        string_attr(root, "case", header.case_source)?;
        scalar_attr(root, "complete", false)?;

        let g = file.create_group("mesh")?;
        string_attr(&g, "kind", mesh.kind.name())?;
        let nodes = Array2::from_shape_fn((n_nodes, 2), |(i, k)| mesh.nodes[i][k]);
        g.new_dataset_builder().with_data(&nodes).create("nodes")?;
        let npc = mesh.kind.nodes_per_cell();
        let cells = Array2::from_shape_fn((mesh.n_cells(), npc), |(c, k)| {
            mesh.cells[c * npc + k] as i64
        });
        let ds = g.new_dataset_builder().with_data(&cells).create("cells")?;
        string_attr(&ds, "node_order", node_order(mesh.kind))?;
        let tags: Array1<i64> = mesh.node_tags.iter().map(|&t| t as i64).collect();
        g.new_dataset_builder()
            .with_data(&tags)
            .create("node_tags")?;
        let groups = g.create_group("groups")?;
        for grp in &mesh.groups {
            let name = free_name(&stored_group_name(&grp.name), (grp.dim, grp.tag), |n| {
                groups.link_exists(n)
            });
            let ds = groups
                .new_dataset_builder()
                .with_data(&index_array(grp.nodes.iter().copied()))
                .create(name.as_str())?;
            scalar_attr(&ds, "dim", grp.dim as i64)?;
            scalar_attr(&ds, "tag", grp.tag as i64)?;
            string_attr(&ds, "name", &grp.name)?;
        }

        let n_c = header.contact_nodes.len();
        let contact = if n_c > 0 {
            let c = file.create_group("contact")?;
            c.new_dataset_builder()
                .with_data(&index_array(header.contact_nodes.iter().copied()))
                .create("nodes")?;
            c.new_dataset_builder()
                .with_data(&ArrayView1::from(header.contact_s))
                .create("s")?;
            let lines = Array2::from_shape_fn((header.contact_lines.len(), 2), |(i, k)| {
                header.contact_lines[i][k] as i64
            });
            c.new_dataset_builder().with_data(&lines).create("lines")?;
            write_surfaces(&c, header)?;
            Some(ContactSeries {
                friction_stress: series_2d::<f64>(&c, "friction_stress", n_c, level)?,
                slip_velocity: series_2d::<f64>(&c, "slip_velocity", n_c, level)?,
                state: series_2d::<i8>(&c, "state", n_c, level)?,
                normal_stress: series_2d::<f64>(&c, "normal_stress", n_c, level)?,
            })
        } else {
            None
        };
        let e = file.create_group("energy")?;
        let mut energy = Vec::new();
        for name in ENERGY_NAMES {
            energy.push(series_1d::<f64>(&e, name, level)?);
        }
        let energy: [Dataset; ENERGY_NAMES.len()] =
            energy.try_into().expect("one dataset a series");
        let solver = file.create_group("solver")?;
        let frames = file.create_group("frames")?;
        string_attr(
            &frames,
            "about",
            "the rows of /displacement, /velocity and /acceleration: each one's time and its row of /time \
             (and of the histories /energy/*, /solver/*, /contact/*, written at every step)",
        )?;
        let series = Series {
            time: series_1d::<f64>(&file, "time", level)?,
            displacement: series_3d(&file, "displacement", n_nodes, level)?,
            velocity: series_3d(&file, "velocity", n_nodes, level)?,
            acceleration: series_3d(&file, "acceleration", n_nodes, level)?,
            frame_time: series_1d::<f64>(&frames, "time", level)?,
            frame_row: series_1d::<u64>(&frames, "row", level)?,
            contact,
            energy,
            dt: series_1d::<f64>(&solver, "dt", level)?,
            iterations: series_1d::<u32>(&solver, "iterations", level)?,
        };
        file.flush()?;
        let block_rows = block_rows(&series.displacement);
        Ok(ResultsWriter {
            file,
            series,
            n_nodes,
            n_c,
            rows: 0,
            frames: 0,
            flushed: (0, 0),
            pending: Pending::default(),
            block_rows,
            since_flush: 0,
            last_flush: Instant::now(),
            flush_every_steps: 100,
            flush_every_secs: 5.0,
            auto_flush: true,
        })
    }

    /// The checks [`ResultsWriter::open_append`] makes before it changes
    /// `path`: every series it extends is there and extendible along its
    /// rows (a dataset rewritten by another program, contiguous or of a
    /// fixed size, made the resize fail after it had cut the others back:
    /// records lost). Series a file of an earlier version lacks, which
    /// `open_append` makes, are not asked for.
    ///
    /// # Errors
    /// The [`stickslip_case::InputError`] naming the file, the dataset and
    /// what to do.
    pub fn check_appendable(path: &Path) -> std::result::Result<(), stickslip_case::InputError> {
        let damaged = |what: String| {
            stickslip_case::InputError(format!(
                "--restart {}: {what}: the file is damaged (or was changed by another program); \
                 restart from a copy of the run's own file, or run the case again with -o NEW.h5",
                path.display()
            ))
        };
        let file = File::open(path).map_err(|e| damaged(format!("cannot open it: {e}")))?;
        let mut names: Vec<String> = [
            "time",
            "displacement",
            "velocity",
            "acceleration",
            "solver/dt",
            "solver/iterations",
        ]
        .map(String::from)
        .to_vec();
        names.extend(
            ENERGY_NAMES
                .iter()
                .filter(|n| !ADDED_ENERGIES.contains(n) || file.link_exists(&format!("energy/{n}")))
                .map(|n| format!("energy/{n}")),
        );
        if file.link_exists("frames") {
            names.extend(["frames/time", "frames/row"].map(String::from));
        }
        if file.link_exists("contact") {
            names.extend(
                ["friction_stress", "slip_velocity", "state"].map(|n| format!("contact/{n}")),
            );
            if file.link_exists("contact/normal_stress") {
                names.push("contact/normal_stress".into());
            }
        }
        for name in &names {
            let ds = file
                .dataset(name)
                .map_err(|_| damaged(format!("/{name} is missing")))?;
            let rows_grow = ds
                .space()
                .is_ok_and(|sp| sp.maxdims().first().is_some_and(Option::is_none));
            if !ds.is_chunked() || !rows_grow {
                return Err(damaged(format!(
                    "/{name} cannot grow (it is not a chunked dataset of unlimited rows)"
                )));
            }
        }
        Ok(())
    }

    /// Opens a results file written by [`ResultsWriter::create`] to append
    /// to it after row `rows` and frame `frames` (later rows, written after
    /// the checkpoint, are dropped), marks it `complete = false` and
    /// removes a `failure` attribute. `n_nodes` and `n_c` must match the
    /// file (the same mesh and contact surface). A file written before the
    /// frames (its fields at every row) gets its `/frames`: `/time` and the
    /// rows in order.
    ///
    /// # Errors
    /// HDF5 errors (e.g. the file is open in another program), or a file
    /// whose layout does not match.
    pub fn open_append(
        path: &Path,
        (rows, frames): (usize, usize),
        n_nodes: usize,
        n_c: usize,
    ) -> Result<ResultsWriter> {
        ResultsWriter::check_appendable(path)?;
        let file = File::open_rw(path).with_context(|| {
            format!(
                "cannot open {} for appending (is it open in another program?)",
                path.display()
            )
        })?;
        let ds = |name: &str| -> Result<Dataset> {
            file.dataset(name)
                .with_context(|| format!("{}: /{name} is missing", path.display()))
        };
        let nodes = ds("mesh/nodes")?.shape();
        ensure!(
            nodes.first() == Some(&n_nodes),
            "{} has {} nodes, the case's mesh {n_nodes}: restart with the mesh the run used",
            path.display(),
            nodes.first().copied().unwrap_or(0)
        );
        let contact = if file.link_exists("contact") {
            // Files written before /contact/normal_stress: made here, the
            // resize below gives its rows the fill value 0.
            let normal_stress = if file.link_exists("contact/normal_stress") {
                ds("contact/normal_stress")?
            } else {
                let n = ds("contact/state")?.shape().get(1).copied().unwrap_or(0);
                series_2d::<f64>(&file.group("contact")?, "normal_stress", n, 0)?
            };
            ContactSeries {
                friction_stress: ds("contact/friction_stress")?,
                slip_velocity: ds("contact/slip_velocity")?,
                state: ds("contact/state")?,
                normal_stress,
            }
            .into()
        } else {
            None
        };
        let file_n_c = contact.as_ref().map_or(0, |c: &ContactSeries| {
            c.state.shape().get(1).copied().unwrap_or(0)
        });
        ensure!(
            file_n_c == n_c,
            "{} has {file_n_c} contact nodes, the case {n_c}: restart with the contact group the run used",
            path.display()
        );
        let mut energy = Vec::new();
        for name in ENERGY_NAMES {
            let at = format!("energy/{name}");
            // Files written before damping have no /energy/damped, nor
            // before moving foundations /energy/foundation, nor before
            // compliant ones /energy/foundation_stored: made here, the
            // resize below gives their rows the fill value 0.
            if ADDED_ENERGIES.contains(&name) && !file.link_exists(&at) {
                energy.push(series_1d::<f64>(&file.group("energy")?, name, 0)?);
                continue;
            }
            energy.push(ds(&at)?);
        }
        if !file.link_exists("frames") {
            ensure!(
                frames == rows,
                "{}: the file has no /frames, so its fields are at every row, but its checkpoint \
                 says {frames} frames of {rows} rows: the file is damaged; run the case again",
                path.display()
            );
            // Two numbers a frame: unfiltered whatever the run's level.
            let g = file.create_group("frames")?;
            let t = series_1d::<f64>(&g, "time", 0)?;
            let r = series_1d::<u64>(&g, "row", 0)?;
            let times = ds("time")?.read_slice_1d::<f64, _>(s![..rows])?;
            t.resize(rows)?;
            t.write_slice(&times, s![..rows])?;
            r.resize(rows)?;
            r.write_slice(&(0..rows as u64).collect::<Array1<u64>>(), s![..rows])?;
        }
        let series = Series {
            time: ds("time")?,
            displacement: ds("displacement")?,
            velocity: ds("velocity")?,
            acceleration: ds("acceleration")?,
            frame_time: ds("frames/time")?,
            frame_row: ds("frames/row")?,
            contact,
            energy: energy.try_into().expect("one dataset a series"),
            dt: ds("solver/dt")?,
            iterations: ds("solver/iterations")?,
        };
        let have = series.time.shape().first().copied().unwrap_or(0);
        let have_frames = series.frame_time.shape().first().copied().unwrap_or(0);
        ensure!(
            rows <= have && frames <= have_frames && frames <= rows,
            "{}: cannot continue after row {rows} and frame {frames}, the file has {have} rows \
             and {have_frames} frames",
            path.display()
        );
        // Rows past the checkpoint (written before a crash) are recomputed.
        series.resize((rows, frames), n_nodes, n_c)?;
        file.attr("complete")?.write_scalar(&false)?;
        if file.attr("failure").is_ok() {
            file.delete_attr("failure")?;
        }
        file.flush()?;
        let block_rows = block_rows(&series.displacement);
        Ok(ResultsWriter {
            file,
            series,
            n_nodes,
            n_c,
            rows,
            frames,
            flushed: (rows, frames),
            pending: Pending::default(),
            block_rows,
            since_flush: 0,
            last_flush: Instant::now(),
            flush_every_steps: 100,
            flush_every_secs: 5.0,
            auto_flush: true,
        })
    }

    /// Output rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Frames (rows of the fields) written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Rewrites the root attribute `case` (a restart stores the case it
    /// continued with, so that the next restart compares against it).
    ///
    /// # Errors
    /// HDF5 errors.
    pub fn set_case(&mut self, source: &str) -> Result<()> {
        self.file.delete_attr("case")?;
        string_attr(&self.file, "case", source)
    }

    /// Stores the run's warnings (what runs but is likely not meant) as the
    /// root attribute `warnings`, one string each, replacing any before.
    pub fn set_warnings(&mut self, warnings: &[String]) -> Result<()> {
        if self.file.attr("warnings").is_ok() {
            self.file.delete_attr("warnings")?;
        }
        let v = warnings
            .iter()
            .map(|w| {
                w.replace('\0', " ")
                    .parse::<VarLenUnicode>()
                    .map_err(|e| anyhow::anyhow!("attribute warnings: {e:?}"))
            })
            .collect::<Result<Vec<_>>>()?;
        self.file
            .new_attr::<VarLenUnicode>()
            .shape(v.len())
            .create("warnings")?
            .write_raw(&v)?;
        Ok(())
    }

    /// The warnings the file stores (none where it has no `warnings`
    /// attribute, as files of earlier versions).
    pub fn warnings(&self) -> Vec<String> {
        self.file
            .attr("warnings")
            .and_then(|a| a.read_raw::<VarLenUnicode>())
            .map(|v| v.iter().map(|w| w.as_str().to_string()).collect())
            .unwrap_or_default()
    }

    /// Counts [`ResultsWriter::flush_every_secs`] from `start` (a run's
    /// start, its setup included, rather than the file's creation: what a
    /// crash before the next flush loses is the wall time since then) and
    /// [`ResultsWriter::flush_every_steps`] from the next step (the
    /// initial record is none).
    pub fn flush_clock_from(&mut self, start: Instant) {
        self.last_flush = start;
        self.since_flush = 0;
    }

    /// True when [`ResultsWriter::flush_every_steps`] rows or
    /// [`ResultsWriter::flush_every_secs`] seconds have gone by since the
    /// last flush.
    pub fn flush_due(&self) -> bool {
        self.since_flush >= self.flush_every_steps
            || self.last_flush.elapsed().as_secs_f64() >= self.flush_every_secs
    }

    /// Bytes the file may need before the next flush has written its
    /// records and checkpoint, with room to spare: [`room_kept`] (the
    /// next write's chunks and a checkpoint of `n_free` values a vector,
    /// twice, and 1 MiB for HDF5's own structures) and the records
    /// appended since the last flush, up to what HDF5's chunk caches hold,
    /// which that flush may write again (HDF5 gives cached chunks their
    /// place in the file there: a restart that never flushed wrote 9 MB in
    /// its final flush, after a last check of 4.4 MB). The check before a
    /// run counts [`room_kept`] only: a run it admits on a nearly full
    /// disk may stop near its end, its records kept. A run stops while the
    /// disk has less free (`stickslip run`): on a full disk HDF5's flush
    /// fails half way, and rows flushed before, in a chunk it rewrote, read
    /// as zeros, or the file does not open at all.
    pub fn room_needed(&self, n_free: usize) -> u64 {
        // At most what HDF5's chunk caches hold (1 MiB a series; larger
        // chunks bypass them and are on disk already). A frame's row is
        // among the rows too: its fields only are added per frame.
        let fields = self.row_bytes(true) - self.row_bytes(false);
        let unflushed = (self.frames - self.flushed.1.min(self.frames)) * fields
            + (self.rows - self.flushed.0.min(self.rows)) * self.row_bytes(false);
        let cached = SERIES_COUNT * (1 << 20);
        room_kept(self.n_nodes, self.n_c, self.block_rows, n_free) + unflushed.min(cached) as u64
    }

    /// Whether the next [`ResultsWriter::append`], of a frame if `frame`,
    /// writes its chunk of rows to the file (where
    /// [`ResultsWriter::room_needed`] should be checked, besides before a
    /// flush: HDF5 writes chunks as they fill, not at the flush).
    pub fn append_writes(&self, frame: bool) -> bool {
        self.pending.bytes() + self.row_bytes(frame) >= PENDING_BYTES
            || self.pending.rows() + 1 >= HISTORY_BLOCK
    }

    /// Bytes a record adds to [`Pending`], a frame's if `frame`.
    fn row_bytes(&self, frame: bool) -> usize {
        // time, dt and the energies; friction stress, slip and normal
        // stress a node (f64), its state (i8); the iterations (u32).
        let histories = 8 * (2 + ENERGY_NAMES.len() + 3 * self.n_c) + self.n_c + 4;
        let fields = if frame { 8 * (6 * self.n_nodes + 2) } else { 0 };
        histories + fields
    }

    /// Counts a step toward [`ResultsWriter::flush_due`] without writing a
    /// row (steps between output rows still count, so a checkpoint is taken
    /// every `flush_every_steps` steps).
    pub fn count_step(&mut self) {
        self.since_flush += 1;
    }

    /// Rewrites `/checkpoint` with `cp` and `extra`, then flushes the file:
    /// after this returns, the file on disk holds every row so far and the
    /// state to continue from.
    ///
    /// # Errors
    /// HDF5 errors, or a state whose lengths changed since the last checkpoint.
    pub fn write_checkpoint(&mut self, cp: &Checkpoint, extra: &CheckpointExtra) -> Result<()> {
        let r = self.write_checkpoint_unchecked(cp, extra);
        self.failed_write(r)
    }

    /// What a failed write leaves: the datasets cut back to the rows of the
    /// last flush (a failed flush left rows of fill values, which probe
    /// read as a record of zeros; best effort, as the disk may still be
    /// full), and a message that says what the file keeps and what to do.
    fn failed_write(&mut self, r: Result<()>) -> Result<()> {
        let Err(e) = r else {
            return Ok(());
        };
        let kept = self.flushed;
        // Best effort: the disk may still be full.
        let _ = self.series.resize(kept, self.n_nodes, self.n_c);
        let _ = self.file.flush();
        self.pending.clear();
        (self.rows, self.frames) = kept;
        let kept = kept.0;
        Err(e.context(format!(
            "cannot write to the results file (is the disk full?); it keeps its first {kept} \
             records and the checkpoint of its last flush: make room and continue the run with \
             --restart"
        )))
    }

    fn write_checkpoint_unchecked(
        &mut self,
        cp: &Checkpoint,
        extra: &CheckpointExtra,
    ) -> Result<()> {
        // The rows the checkpoint counts go to the datasets first.
        self.write_pending()?;
        let (cg, slot) = if self.file.link_exists("checkpoint") {
            let cg = self.file.group("checkpoint")?;
            let current: u8 = get_scalar(&cg, "slot")?;
            (cg, 1 - current.min(1))
        } else {
            let cg = self.file.create_group("checkpoint")?;
            string_attr(
                &cg,
                "about",
                "the integrator's state at the last flush (stickslip run --restart continues from it), \
                 in the slot named by the attribute slot (0 = a, 1 = b); vectors on the free DOFs, numbered node by node \
                 in the order the attribute node_order names (0 the mesh file's, 1 the rows of the structured grid, \
                 2 reverse Cuthill-McKee); \
                 rows = output rows that belong to this state",
            )?;
            (cg, 0)
        };
        let name = SLOTS[usize::from(slot)];
        let g = if cg.link_exists(name) {
            cg.group(name)?
        } else {
            cg.create_group(name)?
        };
        put_vector(&g, "displacement", &cp.displacement)?;
        put_vector(&g, "velocity", &cp.velocity)?;
        put_vector(&g, "acceleration", &cp.acceleration)?;
        put_vector(&g, "forces", &cp.forces)?;
        put_vector(&g, "classes", &cp.classes)?;
        // Only where the run carries it (Newmark ¼, ½ on a compliant
        // foundation), so other runs' files are as before.
        if !cp.normal_excess.is_empty() {
            put_vector(&g, "normal_excess", &cp.normal_excess)?;
        }
        let e = &cp.energy;
        let values = [
            e.kinetic,
            e.strain,
            e.external_work,
            e.dissipated,
            e.total,
            e.balance,
            e.damped,
            e.foundation,
            e.foundation_stored,
        ];
        // A slot written before damping holds six values, before moving
        // foundations seven, before compliant ones eight; it keeps them
        // while the values it has no room for are 0.
        let held = g
            .dataset("energy")
            .ok()
            .map_or(values.len(), |d| d.shape().iter().product());
        let kept = match held {
            6..=8 if values[held..].iter().all(|&v| v == 0.0) => held,
            _ => values.len(),
        };
        // A short slot whose run now books one of its missing values (a
        // restart that added damping or a moving foundation) gets every
        // value, in a dataset made anew with the full order.
        if (6..=8).contains(&held) && kept > held {
            g.unlink("energy")?;
        }
        put_vector(&g, "energy", &values[..kept])?;
        let energy = g.dataset("energy")?;
        if energy.attr("order").is_err() {
            string_attr(&energy, "order", ENERGY_ORDER)?;
        }
        put_scalar(&g, "t", cp.t)?;
        put_scalar(&g, "steps", cp.steps)?;
        put_scalar(&g, "initial_mechanical", cp.initial_mechanical)?;
        put_scalar(&g, "reduced_remaining", cp.reduced_remaining)?;
        if let Some((t0, dt, k)) = cp.clock {
            put_scalar(&g, "clock_t0", t0)?;
            put_scalar(&g, "clock_dt", dt)?;
            put_scalar(&g, "clock_steps", k)?;
        }
        put_scalar(&g, "total_iterations", cp.total_iterations)?;
        put_scalar(&g, "factorizations", cp.factorizations)?;
        put_scalar(&g, "normal_iterations", cp.normal_iterations)?;
        put_scalar(&g, "rows", extra.rows as u64)?;
        put_scalar(&g, "frames", extra.frames as u64)?;
        put_scalar(&g, "wall_time_s", extra.wall_time_s)?;
        put_scalar(&g, "max_balance", extra.max_balance)?;
        put_scalar(&g, "node_order", extra.node_order)?;
        // The new slot is complete on disk before it becomes the current one.
        self.file.flush()?;
        put_scalar(&cg, "slot", slot)?;
        self.flush()
    }

    /// Flushes the file to disk.
    ///
    /// # Errors
    /// HDF5 errors.
    pub fn flush(&mut self) -> Result<()> {
        let r = self.write_pending().and_then(|()| Ok(self.file.flush()?));
        self.failed_write(r)?;
        self.flushed = (self.rows, self.frames);
        self.since_flush = 0;
        self.last_flush = Instant::now();
        Ok(())
    }

    /// Writes the rows in [`Pending`] into the datasets: one resize and one
    /// hyperslab write per dataset.
    ///
    /// # Errors
    /// HDF5 errors.
    fn write_pending(&mut self) -> Result<()> {
        let p = &self.pending;
        let m = p.rows();
        if m == 0 {
            return Ok(());
        }
        let (n, n_c) = (self.n_nodes, self.n_c);
        let (k0, k1) = (self.rows - m, self.rows);
        let mf = p.frames();
        let (f0, f1) = (self.frames - mf, self.frames);
        let s = &self.series;
        for (ds, v) in [(&s.time, &p.time), (&s.dt, &p.dt)]
            .into_iter()
            .chain(s.energy.iter().zip(&p.energy))
        {
            ds.resize(k1)?;
            ds.write_slice(ArrayView1::from(&v[..]), s![k0..k1])?;
        }
        s.iterations.resize(k1)?;
        s.iterations
            .write_slice(ArrayView1::from(&p.iterations[..]), s![k0..k1])?;
        if mf > 0 {
            s.frame_time.resize(f1)?;
            s.frame_time
                .write_slice(ArrayView1::from(&p.frame_time[..]), s![f0..f1])?;
            s.frame_row.resize(f1)?;
            s.frame_row
                .write_slice(ArrayView1::from(&p.frame_row[..]), s![f0..f1])?;
            for (ds, v) in [
                (&s.displacement, &p.displacement),
                (&s.velocity, &p.velocity),
                (&s.acceleration, &p.acceleration),
            ] {
                ds.resize((f1, n, 2))?;
                ds.write_slice(
                    ndarray::ArrayView3::from_shape((mf, n, 2), &v[..])?,
                    s![f0..f1, .., ..],
                )?;
            }
        }
        if let Some(c) = &s.contact {
            for (ds, v) in [
                (&c.friction_stress, &p.friction_stress),
                (&c.slip_velocity, &p.slip_velocity),
                (&c.normal_stress, &p.normal_stress),
            ] {
                ds.resize((k1, n_c))?;
                ds.write_slice(ArrayView2::from_shape((m, n_c), &v[..])?, s![k0..k1, ..])?;
            }
            c.state.resize((k1, n_c))?;
            c.state.write_slice(
                ArrayView2::from_shape((m, n_c), &p.state[..])?,
                s![k0..k1, ..],
            )?;
        }
        self.pending.clear();
        Ok(())
    }

    /// Appends one output step to every history, and to the fields when
    /// the record carries them (a frame); kept in memory and written with
    /// its chunk's block, or before the next flush.
    ///
    /// # Errors
    /// HDF5 errors, or slices whose lengths do not match the header.
    pub fn append(&mut self, rec: &Record) -> Result<()> {
        let (n, n_c, k) = (self.n_nodes, self.n_c, self.rows);
        let frame = !rec.displacement.is_empty();
        for (name, v) in [
            ("displacement", rec.displacement),
            ("velocity", rec.velocity),
            ("acceleration", rec.acceleration),
        ] {
            ensure!(
                v.len() == if frame { 2 * n } else { 0 },
                "record {k}: {name} has {} values, expected 2 * {n} nodes (or, with the others, \
                 none for a step that is no frame)",
                v.len()
            );
        }
        for (name, len) in [
            ("friction_stress", rec.friction_stress.len()),
            ("slip_velocity", rec.slip_velocity.len()),
            ("state", rec.state.len()),
            ("normal_stress", rec.normal_stress.len()),
        ] {
            ensure!(
                len == n_c,
                "record {k}: {name} has {len} values, expected {n_c} contact nodes"
            );
        }
        self.pending.push(rec, k);
        self.rows += 1;
        if frame {
            self.frames += 1;
        }
        if self.pending.bytes() >= PENDING_BYTES || self.pending.rows() >= HISTORY_BLOCK {
            self.write_pending()?;
        }
        if self.auto_flush {
            self.since_flush += 1;
            if self.flush_due() {
                self.flush()?;
            }
        }
        Ok(())
    }

    /// Whether the last row appended is a frame (false without rows).
    ///
    /// # Errors
    /// HDF5 errors reading `/frames/row`.
    pub fn last_row_is_frame(&self) -> Result<bool> {
        let Some(last) = self.rows.checked_sub(1) else {
            return Ok(false);
        };
        let row = match self.pending.frame_row.last() {
            Some(&r) => Some(r),
            None if self.frames > 0 => {
                let f = self.frames;
                Some(
                    self.series
                        .frame_row
                        .read_slice_1d::<u64, _>(s![f - 1..f])?[0],
                )
            }
            None => None,
        };
        Ok(row == Some(last as u64))
    }

    /// Writes the fields of `rec` as a frame of the last row appended,
    /// which has none (a record's histories are written once).
    ///
    /// # Errors
    /// HDF5 errors, no row to add it to, or fields whose lengths do not
    /// match the header.
    pub fn frame_last_row(&mut self, rec: &Record) -> Result<()> {
        let r = self.write_frame_of_last_row(rec);
        self.failed_write(r)
    }

    fn write_frame_of_last_row(&mut self, rec: &Record) -> Result<()> {
        let n = self.n_nodes;
        ensure!(self.rows > 0, "no record to add a frame to");
        for v in [rec.displacement, rec.velocity, rec.acceleration] {
            ensure!(
                v.len() == 2 * n,
                "a frame has {} values a field, expected 2 * {n} nodes",
                v.len()
            );
        }
        // The frames before it go first, so that /frames stays in order.
        self.write_pending()?;
        let (f0, f1) = (self.frames, self.frames + 1);
        let s = &self.series;
        s.frame_time.resize(f1)?;
        s.frame_time
            .write_slice(ArrayView1::from(&[rec.t][..]), s![f0..f1])?;
        s.frame_row.resize(f1)?;
        s.frame_row
            .write_slice(ArrayView1::from(&[(self.rows - 1) as u64][..]), s![f0..f1])?;
        for (ds, v) in [
            (&s.displacement, rec.displacement),
            (&s.velocity, rec.velocity),
            (&s.acceleration, rec.acceleration),
        ] {
            ds.resize((f1, n, 2))?;
            ds.write_slice(
                ndarray::ArrayView3::from_shape((1, n, 2), v)?,
                s![f0..f1, .., ..],
            )?;
        }
        self.frames = f1;
        Ok(())
    }

    /// Writes the `/solver` attributes (`wall_time_s`, `steps`,
    /// `factorizations`, `dt_crit` when known), the root attribute `failure`
    /// when the run stopped early, sets root `complete`, and closes the file.
    ///
    /// # Errors
    /// HDF5 errors.
    pub fn finish(mut self, complete: bool, summary: &Summary) -> Result<()> {
        self.write_pending()?;
        let solver = self.file.group("solver")?;
        put_scalar(&solver, "wall_time_s", summary.wall_time_s)?;
        put_scalar(&solver, "steps", summary.steps)?;
        put_scalar(&solver, "factorizations", summary.factorizations)?;
        if solver.attr("friction").is_ok() {
            solver.delete_attr("friction")?;
        }
        let friction = summary
            .friction_off
            .as_ref()
            .map_or("on".to_string(), |why| format!("off: {why}"));
        string_attr(&solver, "friction", &friction)?;
        if let Some(d) = summary.dt_crit {
            put_scalar(&solver, "dt_crit", d)?;
        }
        if solver.attr("stiffness_product").is_ok() {
            solver.delete_attr("stiffness_product")?;
        }
        string_attr(&solver, "stiffness_product", &summary.stiffness_product)?;
        if let Some(order) = &summary.fill_order {
            if solver.attr("fill_order").is_ok() {
                solver.delete_attr("fill_order")?;
            }
            string_attr(&solver, "fill_order", order)?;
        }
        if self.file.attr("failure").is_ok() {
            self.file.delete_attr("failure")?;
        }
        if let Some(f) = &summary.failure {
            string_attr(&self.file, "failure", f)?;
        }
        self.file.attr("complete")?.write_scalar(&complete)?;
        // On disk now; dropping the writer closes the datasets, then the file.
        self.file.flush()?;
        Ok(())
    }
}

impl Drop for ResultsWriter {
    /// A writer dropped without [`ResultsWriter::finish`] (a run that
    /// errors out) still writes the rows appended to it; the file then
    /// says `complete = false`.
    fn drop(&mut self) {
        let _ = self.write_pending();
    }
}

#[cfg(test)]
impl<'a> Record<'a> {
    /// A test's record at `t` with fields `[d, v, a]`, no contact arrays,
    /// every energy 0, Δt 1 and one iteration; a test sets the rest by
    /// struct update.
    pub(crate) fn zeros(t: f64, [d, v, a]: [&'a [f64]; 3]) -> Record<'a> {
        Record {
            t,
            displacement: d,
            velocity: v,
            acceleration: a,
            friction_stress: &[],
            slip_velocity: &[],
            state: &[],
            normal_stress: &[],
            kinetic: 0.0,
            strain: 0.0,
            external_work: 0.0,
            dissipated: 0.0,
            damped: 0.0,
            foundation: 0.0,
            foundation_stored: 0.0,
            total: 0.0,
            balance: 0.0,
            dt: 1.0,
            iterations: 1,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use stickslip_mesh::{CellKind, Edge, Group, Mesh, SourceInfo};

    /// Tests that hold an HDF5 file open or spawn python3 take this lock: a
    /// child forked by one test inherits the file descriptors other tests
    /// have open, and with them HDF5's file lock (EAGAIN on the next open).
    pub(crate) fn h5_lock() -> std::sync::MutexGuard<'static, ()> {
        static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
        LOCK.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Two Q1 cells side by side: nodes 0..6 on a 3 × 2 grid, a contact
    /// line along the bottom (nodes 0, 1, 2).
    pub(crate) fn tiny_mesh() -> Mesh {
        let nodes = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ];
        let edge = |a, b, cell| Edge {
            nodes: [a, b],
            mid: None,
            cell,
        };
        Mesh {
            node_tags: (1..=6).collect(),
            nodes,
            kind: CellKind::Quad4,
            cells: vec![0, 1, 4, 3, 1, 2, 5, 4],
            cell_tags: vec![7, 8],
            groups: vec![
                Group {
                    name: "contact".into(),
                    tag: 1,
                    dim: 1,
                    edges: vec![edge(0, 1, 0), edge(1, 2, 1)],
                    cells: vec![],
                    points: vec![],
                    nodes: vec![0, 1, 2],
                    elements: 2,
                },
                Group {
                    name: "body".into(),
                    tag: 10,
                    dim: 2,
                    edges: vec![],
                    cells: vec![0, 1],
                    points: vec![],
                    nodes: (0..6).collect(),
                    elements: 2,
                },
            ],
            source: SourceInfo::default(),
        }
    }

    /// Values of step k are simple functions of (k, index) so the read-back
    /// can be checked against the same formulas.
    fn u(k: usize, i: usize) -> f64 {
        k as f64 * 100.0 + i as f64 * 0.5
    }

    fn write_file(path: &Path, steps: usize, finish: Option<bool>) {
        let mesh = tiny_mesh();
        let header = Header {
            case_source: "title = \"tiny\"\n",
            mesh: &mesh,
            contact_nodes: &[0, 1, 2],
            contact_s: &[0.0, 1.0, 2.0],
            contact_lines: &[[0, 1], [1, 2]],
            contact_surface: &[0, 0, 1],
            contact_groups: &["bottom".to_string(), "top".to_string()],
        };
        // Compressed, so that the filters' path is the one read back (the
        // default is none: `default_output_is_unfiltered`).
        let mut w = ResultsWriter::create_with(path, &header, 4).unwrap();
        let mut d = vec![0.0; 12];
        let mut v = vec![0.0; 12];
        let mut a = vec![0.0; 12];
        for k in 0..steps {
            for i in 0..12 {
                d[i] = u(k, i);
                v[i] = -u(k, i);
                a[i] = 2.0 * u(k, i);
            }
            let fs = [k as f64, 1.0 + k as f64, 2.0 + k as f64];
            let sv = [0.5 * k as f64, 0.0, -1.0];
            let st: [i8; 3] = [0, 1, -1];
            w.append(&Record {
                friction_stress: &fs,
                slip_velocity: &sv,
                state: &st,
                normal_stress: &sv,
                kinetic: 1.0 + k as f64,
                strain: 2.0 + k as f64,
                external_work: 3.0 + k as f64,
                dissipated: 4.0 + k as f64,
                total: 5.0 + k as f64,
                balance: 6.0 + k as f64,
                dt: 0.1,
                iterations: k as u32 + 1,
                ..Record::zeros(0.1 * k as f64, [&d, &v, &a])
            })
            .unwrap();
        }
        if let Some(c) = finish {
            w.finish(
                c,
                &Summary {
                    wall_time_s: 1.5,
                    steps: 30,
                    factorizations: 2,
                    dt_crit: Some(0.25),
                    failure: (!c).then(|| "iteration cap hit at step 3".to_string()),
                    friction_off: None,
                    stiffness_product: "stencil types".into(),
                    fill_order: Some("nested dissection".into()),
                },
            )
            .unwrap();
        }
    }

    /// A header for `mesh` with no case text, with the tiny mesh's contact
    /// line (nodes 0, 1, 2) or none.
    fn test_header(mesh: &Mesh, contact: bool) -> Header<'_> {
        let (nodes, s, lines): (&[usize], &[f64], &[[usize; 2]]) = if contact {
            (&[0, 1, 2], &[0.0, 1.0, 2.0], &[[0, 1], [1, 2]])
        } else {
            (&[], &[], &[])
        };
        Header {
            case_source: "",
            mesh,
            contact_nodes: nodes,
            contact_s: s,
            contact_lines: lines,
            contact_surface: &[],
            contact_groups: &[],
        }
    }

    fn scratch(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("stickslip-out-{}-{name}.h5", std::process::id()))
    }

    #[test]
    fn three_records_read_back() {
        let _guard = h5_lock();
        let path = scratch("three");
        write_file(&path, 3, Some(true));
        let f = File::open(&path).unwrap();
        let attr_s = |n: &str| {
            f.attr(n)
                .unwrap()
                .read_scalar::<VarLenUnicode>()
                .unwrap()
                .as_str()
                .to_string()
        };
        assert_eq!(attr_s("program"), "stickslip");
        assert_eq!(attr_s("case"), "title = \"tiny\"\n");
        // Each contact node's surface, and the surfaces' groups, as given.
        let surface = f
            .dataset("contact/surface")
            .unwrap()
            .read_raw::<i64>()
            .unwrap();
        assert_eq!(surface, [0, 0, 1]);
        let groups = f.group("contact").unwrap().attr("groups").unwrap();
        let groups: Vec<String> = groups
            .read_raw::<VarLenUnicode>()
            .unwrap()
            .iter()
            .map(|g| g.as_str().to_string())
            .collect();
        assert_eq!(groups, ["bottom", "top"]);
        assert!(f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
        assert!(
            f.attr("failure").is_err(),
            "no failure attribute on a complete run"
        );

        let nodes = f.dataset("mesh/nodes").unwrap().read_2d::<f64>().unwrap();
        assert_eq!(nodes.shape(), &[6, 2]);
        assert_eq!(nodes[[4, 0]], 1.0);
        let cells = f.dataset("mesh/cells").unwrap();
        assert_eq!(
            cells.read_2d::<i64>().unwrap().row(1).to_vec(),
            vec![1, 2, 5, 4]
        );
        assert!(cells.attr("node_order").is_ok());
        assert_eq!(
            f.dataset("mesh/groups/contact")
                .unwrap()
                .read_1d::<i64>()
                .unwrap()
                .to_vec(),
            vec![0, 1, 2]
        );
        assert_eq!(
            f.dataset("mesh/node_tags")
                .unwrap()
                .read_1d::<i64>()
                .unwrap()
                .to_vec(),
            vec![1, 2, 3, 4, 5, 6]
        );

        assert_eq!(
            f.dataset("time")
                .unwrap()
                .read_1d::<f64>()
                .unwrap()
                .to_vec(),
            vec![0.0, 0.1, 0.2]
        );
        let disp = f
            .dataset("displacement")
            .unwrap()
            .read_dyn::<f64>()
            .unwrap();
        assert_eq!(disp.shape(), &[3, 6, 2]);
        // Interleaved input: value i of step k is node i/2, component i%2.
        for k in 0..3 {
            for i in 0..12 {
                assert_eq!(disp[[k, i / 2, i % 2]], u(k, i));
            }
        }
        let vel = f.dataset("velocity").unwrap().read_dyn::<f64>().unwrap();
        assert_eq!(vel[[2, 5, 1]], -u(2, 11));
        let acc = f
            .dataset("acceleration")
            .unwrap()
            .read_dyn::<f64>()
            .unwrap();
        assert_eq!(acc[[1, 3, 0]], 2.0 * u(1, 6));

        assert_eq!(
            f.dataset("contact/nodes")
                .unwrap()
                .read_1d::<i64>()
                .unwrap()
                .to_vec(),
            vec![0, 1, 2]
        );
        assert_eq!(
            f.dataset("contact/s")
                .unwrap()
                .read_1d::<f64>()
                .unwrap()
                .to_vec(),
            vec![0.0, 1.0, 2.0]
        );
        assert_eq!(
            f.dataset("contact/lines")
                .unwrap()
                .read_2d::<i64>()
                .unwrap()
                .iter()
                .copied()
                .collect::<Vec<_>>(),
            vec![0, 1, 1, 2]
        );
        let fs = f
            .dataset("contact/friction_stress")
            .unwrap()
            .read_2d::<f64>()
            .unwrap();
        assert_eq!(fs.shape(), &[3, 3]);
        assert_eq!(fs.row(2).to_vec(), vec![2.0, 3.0, 4.0]);
        let st = f.dataset("contact/state").unwrap().read_2d::<i8>().unwrap();
        assert_eq!(st.row(1).to_vec(), vec![0, 1, -1]);
        assert_eq!(
            f.dataset("contact/slip_velocity")
                .unwrap()
                .read_2d::<f64>()
                .unwrap()[[2, 0]],
            1.0
        );

        for (i, name) in [
            "kinetic",
            "strain",
            "external_work",
            "dissipated",
            "total",
            "balance",
        ]
        .iter()
        .enumerate()
        {
            let e = f
                .dataset(&format!("energy/{name}"))
                .unwrap()
                .read_1d::<f64>()
                .unwrap()
                .to_vec();
            let want: Vec<f64> = (0..3).map(|k| 1.0 + i as f64 + k as f64).collect();
            assert_eq!(e, want, "energy/{name}");
        }
        assert_eq!(
            f.dataset("solver/iterations")
                .unwrap()
                .read_1d::<u32>()
                .unwrap()
                .to_vec(),
            vec![1, 2, 3]
        );
        assert_eq!(
            f.dataset("solver/dt")
                .unwrap()
                .read_1d::<f64>()
                .unwrap()
                .to_vec(),
            vec![0.1; 3]
        );
        let solver = f.group("solver").unwrap();
        assert_eq!(
            solver.attr("steps").unwrap().read_scalar::<u64>().unwrap(),
            30
        );
        assert_eq!(
            solver
                .attr("stiffness_product")
                .unwrap()
                .read_scalar::<VarLenUnicode>()
                .unwrap()
                .as_str(),
            "stencil types"
        );
        assert_eq!(
            solver
                .attr("fill_order")
                .unwrap()
                .read_scalar::<VarLenUnicode>()
                .unwrap()
                .as_str(),
            "nested dissection"
        );
        assert_eq!(
            solver
                .attr("factorizations")
                .unwrap()
                .read_scalar::<u64>()
                .unwrap(),
            2
        );
        assert_eq!(
            solver
                .attr("dt_crit")
                .unwrap()
                .read_scalar::<f64>()
                .unwrap(),
            0.25
        );
        assert_eq!(
            solver
                .attr("wall_time_s")
                .unwrap()
                .read_scalar::<f64>()
                .unwrap(),
            1.5
        );
        // Growing datasets are chunked along time and compressed.
        let d = f.dataset("displacement").unwrap();
        assert_eq!(d.chunk().unwrap()[1..], [6, 2]);
        assert!(
            d.filters().len() >= 2,
            "shuffle + deflate: {:?}",
            d.filters()
        );
        drop(f);
        h5py_check(&path, 3, true);
        std::fs::remove_file(&path).ok();
    }

    /// A restart that factorized nothing (`fill_order` None) keeps the
    /// ordering the file holds; one that did writes its own.
    #[test]
    fn a_restart_keeps_the_stored_fill_order_unless_it_has_one() {
        let _guard = h5_lock();
        let path = scratch("fill-order");
        write_file(&path, 3, Some(true));
        let stored = || {
            File::open(&path)
                .unwrap()
                .group("solver")
                .unwrap()
                .attr("fill_order")
                .unwrap()
                .read_scalar::<VarLenUnicode>()
                .unwrap()
                .as_str()
                .to_string()
        };
        let finish_again = |fill_order: Option<&str>| {
            let w = ResultsWriter::open_append(&path, (3, 3), 6, 3).unwrap();
            let summary = Summary {
                steps: 40,
                fill_order: fill_order.map(Into::into),
                ..Summary::default()
            };
            w.finish(true, &summary).unwrap();
        };
        finish_again(None);
        assert_eq!(stored(), "nested dissection");
        finish_again(Some("AMD"));
        assert_eq!(stored(), "AMD");
        std::fs::remove_file(&path).ok();
    }

    /// Rows go to the datasets in blocks (a chunk's worth, 16 rows for this
    /// mesh, and at every flush): every row appended is in the file, in
    /// order, across chunk ends, flushes between them and a writer dropped
    /// without finish.
    #[test]
    fn buffered_rows_all_reach_the_file() {
        let _guard = h5_lock();
        let path = scratch("blocks");
        let mesh = tiny_mesh();
        let header = test_header(&mesh, true);
        let rows = 41;
        {
            let mut w = ResultsWriter::create(&path, &header).unwrap();
            assert_eq!(w.block_rows, 16);
            w.flush_every_steps = 7;
            w.flush_every_secs = f64::INFINITY;
            for k in 0..rows {
                let d: Vec<f64> = (0..12).map(|i| u(k, i)).collect();
                let fs = [k as f64, -(k as f64), 0.5];
                let st: [i8; 3] = [(k % 3) as i8 - 1, 0, 1];
                w.append(&Record {
                    friction_stress: &fs,
                    slip_velocity: &fs,
                    state: &st,
                    normal_stress: &fs,
                    kinetic: k as f64,
                    dt: 0.5,
                    iterations: k as u32,
                    ..Record::zeros(k as f64, [&d, &d, &d])
                })
                .unwrap();
                if k == 20 {
                    // Flushed rows are readable while the writer goes on.
                    let f = File::open(&path).unwrap();
                    assert_eq!(f.dataset("time").unwrap().shape(), vec![21]);
                }
            }
            // Dropped here after 41 rows, the last flush at 35.
        }
        let f = File::open(&path).unwrap();
        let time = f.dataset("time").unwrap().read_1d::<f64>().unwrap();
        assert_eq!(
            time.to_vec(),
            (0..rows).map(|k| k as f64).collect::<Vec<_>>()
        );
        let d = f
            .dataset("displacement")
            .unwrap()
            .read_dyn::<f64>()
            .unwrap();
        assert_eq!(d.shape(), [rows, 6, 2]);
        for k in 0..rows {
            for i in 0..12 {
                assert_eq!(d[[k, i / 2, i % 2]], u(k, i), "row {k}, value {i}");
            }
        }
        let st = f.dataset("contact/state").unwrap().read_2d::<i8>().unwrap();
        let fs = f
            .dataset("contact/friction_stress")
            .unwrap()
            .read_2d::<f64>()
            .unwrap();
        let it = f
            .dataset("solver/iterations")
            .unwrap()
            .read_1d::<u32>()
            .unwrap();
        for k in 0..rows {
            assert_eq!(st[[k, 0]], (k % 3) as i8 - 1, "row {k}");
            assert_eq!(fs[[k, 1]], -(k as f64), "row {k}");
            assert_eq!(it[k], k as u32, "row {k}");
        }
        assert!(!f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
        drop(f);
        std::fs::remove_file(&path).ok();
    }

    /// A record of the tiny mesh with contact at `t`: fields `[d, v, a]`,
    /// friction stress `fs`, the rest 0.
    fn record_of<'a>(t: f64, [d, v, a]: [&'a [f64]; 3], fs: &'a [f64]) -> Record<'a> {
        Record {
            friction_stress: fs,
            slip_velocity: &[0.0; 3],
            state: &[0; 3],
            normal_stress: &[0.0; 3],
            dt: 0.1,
            ..Record::zeros(t, [d, v, a])
        }
    }

    /// Appends rows `k0..k1` of the tiny mesh with contact, the fields of
    /// row k being `u(k, ·)` on the rows where `frame(k)`.
    fn append_rows(w: &mut ResultsWriter, rows: std::ops::Range<usize>, frame: fn(usize) -> bool) {
        for k in rows {
            let d: Vec<f64> = (0..12).map(|i| u(k, i)).collect();
            let f: &[f64] = if frame(k) { &d } else { &[] };
            let fs = [k as f64; 3];
            w.append(&record_of(0.1 * k as f64, [f, f, f], &fs))
                .unwrap();
        }
    }

    /// The histories grow a row a record, the fields and `/frames` a row a
    /// frame; `/frames/row` names each frame's row, and a restart after
    /// row 7 (frame 3) keeps both in step. Expected values: the rows the
    /// test wrote.
    /// `append_writes` (which the run's check of free disk space relies
    /// on) is true exactly before the appends that write their block.
    /// Expected: a 20 × 20 node grid's frame is 8 (6·400 + 2) = 19,216
    /// bytes and the histories of 3 contact nodes 8 (11 + 9) + 3 + 4 = 167
    /// bytes a row (time, dt and 9 energies, friction stress, slip and
    /// normal stress a node, as f64; the states as i8; the iterations as
    /// u32), which every append adds to the pending rows; so 55 frame rows
    /// reach PENDING_BYTES (⌈1,048,576 / 19,383⌉): rows 54, 109, 164; the
    /// 35 frames left and rows without fields then reach HISTORY_BLOCK
    /// (1,024 rows) at row 164 + 1,024 = 1,188 before 1 MiB.
    #[test]
    fn append_writes_says_which_appends_write() {
        let _guard = h5_lock();
        let path = scratch("append-writes");
        let mesh = stickslip_testkit::grid::rectangle(CellKind::Quad4, 19, 19, [0.0; 2], [1.0; 2]);
        let header = test_header(&mesh, true);
        let mut w = ResultsWriter::create(&path, &header).unwrap();
        w.auto_flush = false;
        let n = 2 * mesh.nodes.len();
        let mut writes = Vec::new();
        for k in 0..1500 {
            let frame = k < 200;
            let predicted = w.append_writes(frame);
            let before = w.pending.bytes();
            let d: Vec<f64> = (0..n).map(|i| u(k, i)).collect();
            let f: &[f64] = if frame { &d } else { &[] };
            w.append(&record_of(0.1 * k as f64, [f, f, f], &[k as f64; 3]))
                .unwrap();
            let wrote = w.pending.rows() == 0;
            assert_eq!(predicted, wrote, "row {k}");
            let row = if frame { 19_216 + 167 } else { 167 };
            assert_eq!(w.row_bytes(frame), row, "row {k}'s bytes foreseen");
            if !wrote {
                assert_eq!(w.pending.bytes() - before, row, "row {k}'s bytes held");
            }
            if wrote {
                writes.push(k);
            }
        }
        assert_eq!(writes, [54, 109, 164, 1188]);
        drop(w);
        std::fs::remove_file(&path).ok();
    }

    /// A slot of seven energy values (a file written before moving
    /// foundations) keeps seven while the foundation's work is 0, and
    /// takes all nine, in `order`, once it is not (a restart that added a
    /// belt), instead of failing on the slot's shape. Expected: the
    /// values the test wrote.
    #[test]
    fn a_short_energy_slot_takes_a_new_value() {
        let _guard = h5_lock();
        let path = scratch("short-slot");
        let mesh = tiny_mesh();
        let header = test_header(&mesh, true);
        let mut w = ResultsWriter::create(&path, &header).unwrap();
        let n = 2 * mesh.nodes.len();
        let mut cp = Checkpoint {
            t: 0.0,
            steps: 0,
            displacement: vec![0.0; n],
            velocity: vec![0.0; n],
            acceleration: vec![0.0; n],
            classes: vec![0; 3],
            forces: vec![0.0; 3],
            energy: stickslip_time::Energy::default(),
            initial_mechanical: 0.0,
            reduced_remaining: 0,
            clock: None,
            total_iterations: 0,
            factorizations: 0,
            normal_iterations: 0,
            normal_excess: Vec::new(),
        };
        let extra = CheckpointExtra::default();
        // Both slots written, then cut to an old file's seven values.
        w.write_checkpoint(&cp, &extra).unwrap();
        w.write_checkpoint(&cp, &extra).unwrap();
        for slot in SLOTS {
            let g = w.file.group(&format!("checkpoint/{slot}")).unwrap();
            g.unlink("energy").unwrap();
            put_vector(&g, "energy", &[1.0; 7]).unwrap();
        }
        let held = |w: &ResultsWriter| -> Vec<f64> {
            let cg = w.file.group("checkpoint").unwrap();
            let slot: u8 = get_scalar(&cg, "slot").unwrap();
            let g = cg.group(SLOTS[usize::from(slot)]).unwrap();
            g.dataset("energy").unwrap().read_raw::<f64>().unwrap()
        };
        cp.energy.kinetic = 2.0;
        w.write_checkpoint(&cp, &extra).unwrap();
        assert_eq!(held(&w), [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        cp.energy.foundation = -3.0;
        w.write_checkpoint(&cp, &extra).unwrap();
        assert_eq!(held(&w), [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -3.0, 0.0]);
        drop(w);
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn frames_and_histories_grow_apart() {
        let _guard = h5_lock();
        let path = scratch("frames");
        let mesh = tiny_mesh();
        let every_third = |k: usize| k.is_multiple_of(3);
        let mut w = ResultsWriter::create(&path, &test_header(&mesh, true)).unwrap();
        append_rows(&mut w, 0..10, every_third);
        assert_eq!((w.rows(), w.frames()), (10, 4));
        w.finish(true, &Summary::default()).unwrap();
        let check = |rows: usize, frame_rows: &[u64]| {
            let f = File::open(&path).unwrap();
            let t = f.dataset("time").unwrap().read_1d::<f64>().unwrap();
            assert_eq!(t.len(), rows);
            let fs = f
                .dataset("contact/friction_stress")
                .unwrap()
                .read_2d::<f64>()
                .unwrap();
            assert_eq!(fs.nrows(), rows);
            assert_eq!(fs[[rows - 1, 0]], (rows - 1) as f64);
            let r = f.dataset("frames/row").unwrap().read_1d::<u64>().unwrap();
            assert_eq!(r.to_vec(), frame_rows);
            let ft = f.dataset("frames/time").unwrap().read_1d::<f64>().unwrap();
            let want: Vec<f64> = frame_rows.iter().map(|&k| 0.1 * k as f64).collect();
            assert_eq!(ft.to_vec(), want);
            let d = f
                .dataset("displacement")
                .unwrap()
                .read_dyn::<f64>()
                .unwrap();
            assert_eq!(d.shape(), [frame_rows.len(), 6, 2]);
            for (j, &k) in frame_rows.iter().enumerate() {
                assert_eq!(d[[j, 5, 1]], u(k as usize, 11), "frame {j}");
            }
        };
        check(10, &[0, 3, 6, 9]);
        // A restart from row 7, frame 3 (rows 7-9 and frame 9 dropped),
        // its frames now on the even rows.
        let mut w = ResultsWriter::open_append(&path, (7, 3), 6, 3).unwrap();
        append_rows(&mut w, 7..12, |k| k.is_multiple_of(2));
        w.finish(true, &Summary::default()).unwrap();
        check(12, &[0, 3, 6, 8, 10]);
        // A file of a version before the frames (its fields at every row)
        // gets its /frames when continued.
        let mut w = ResultsWriter::create(&path, &test_header(&mesh, true)).unwrap();
        append_rows(&mut w, 0..4, |_| true);
        w.finish(true, &Summary::default()).unwrap();
        File::open_rw(&path).unwrap().unlink("frames").unwrap();
        let mut w = ResultsWriter::open_append(&path, (4, 4), 6, 3).unwrap();
        append_rows(&mut w, 4..6, |k| k == 5);
        w.finish(true, &Summary::default()).unwrap();
        check(6, &[0, 1, 2, 3, 5]);
        // Fields of a frame are whole or absent.
        let mut w = ResultsWriter::create(&path, &test_header(&mesh, true)).unwrap();
        let d = [0.0; 12];
        let e = w
            .append(&record_of(0.0, [&d, &[], &d], &[0.0; 3]))
            .unwrap_err();
        assert!(e.to_string().contains("velocity has 0 values"), "{e}");
        drop(w);
        std::fs::remove_file(&path).ok();
    }

    /// The default writes no filter (deflate costs more than the run on the
    /// meshes measured: [`DEFLATE_LEVEL`]).
    #[test]
    fn default_output_is_unfiltered() {
        let _guard = h5_lock();
        let path = scratch("unfiltered");
        let mesh = tiny_mesh();
        let header = test_header(&mesh, false);
        let w = ResultsWriter::create(&path, &header).unwrap();
        w.finish(true, &Summary::default()).unwrap();
        let f = File::open(&path).unwrap();
        let d = f.dataset("displacement").unwrap();
        assert_eq!(d.chunk().unwrap()[1..], [6, 2]);
        assert!(d.filters().is_empty(), "{:?}", d.filters());
        drop(f);
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn unfinished_file_is_readable_and_incomplete() {
        let _guard = h5_lock();
        // A run that dies after flushing keeps the rows written (here the
        // writer is dropped without finish, as when a run errors out).
        let path = scratch("unfinished");
        write_file(&path, 2, None);
        let f = File::open(&path).unwrap();
        assert!(!f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
        assert_eq!(f.dataset("time").unwrap().shape(), vec![2]);
        drop(f);
        h5py_check(&path, 2, false);
        // finish(false) records the failure reason.
        write_file(&path, 1, Some(false));
        let f = File::open(&path).unwrap();
        assert!(!f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
        let why = f
            .attr("failure")
            .unwrap()
            .read_scalar::<VarLenUnicode>()
            .unwrap();
        assert_eq!(why.as_str(), "iteration cap hit at step 3");
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn wrong_lengths_are_errors_not_panics() {
        let _guard = h5_lock();
        let path = scratch("lengths");
        let mesh = tiny_mesh();
        let header = test_header(&mesh, false);
        let mut w = ResultsWriter::create(&path, &header).unwrap();
        let z = vec![0.0; 12];
        let mut rec = Record {
            dt: 0.0,
            iterations: 0,
            ..Record::zeros(0.0, [&z, &z, &z[..10]])
        };
        assert!(w
            .append(&rec)
            .unwrap_err()
            .to_string()
            .contains("acceleration"));
        rec.acceleration = &z;
        w.append(&rec).unwrap();
        w.finish(true, &Summary::default()).unwrap();
        let f = File::open(&path).unwrap();
        assert!(
            !f.link_exists("contact"),
            "no /contact without a contact surface"
        );
        assert_eq!(f.dataset("displacement").unwrap().shape(), vec![1, 6, 2]);
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn flushed_rows_are_readable_while_the_run_goes_on() {
        // What a user sees when peeking at (or inheriting, after a crash) a
        // file mid-run: every flushed row. HDF5's file lock is turned off for
        // the reader only, as h5py users do for a file still being written.
        let _guard = h5_lock();
        let path = scratch("midrun");
        let mesh = tiny_mesh();
        let header = test_header(&mesh, false);
        let mut w = ResultsWriter::create(&path, &header).unwrap();
        w.flush_every_steps = 2;
        w.flush_every_secs = f64::INFINITY;
        let z = vec![0.5; 12];
        for k in 0..2 {
            let rec = Record::zeros(k as f64, [&z, &z, &z]);
            w.append(&rec).unwrap();
        }
        let script = "import sys\ntry:\n import h5py\nexcept ImportError:\n sys.exit(3)\nf = h5py.File(sys.argv[1], 'r')\nprint(f['time'].shape[0], f['displacement'][1, 5, 1], bool(f.attrs['complete']))";
        let out = std::process::Command::new("python3")
            .env("HDF5_USE_FILE_LOCKING", "FALSE")
            .args(["-c", script])
            .arg(&path)
            .output();
        match out {
            Ok(o) if o.status.code() == Some(3) => skip_without("h5py"),
            Ok(o) => assert_eq!(
                String::from_utf8_lossy(&o.stdout).trim(),
                "2 0.5 False",
                "{}",
                String::from_utf8_lossy(&o.stderr)
            ),
            Err(e) => skip_without(&format!("python3 ({e})")),
        }
        w.finish(true, &Summary::default()).unwrap();
        std::fs::remove_file(&path).ok();
    }

    /// Throughput figure, not a check: `cargo test -p stickslip write_speed
    /// -- --ignored --nocapture` (100k nodes, 50 records, 3 vector fields).
    #[test]
    #[ignore]
    fn write_speed() {
        let _guard = h5_lock();
        let (nx, ny) = (316, 316);
        let n = nx * ny;
        let mut mesh = tiny_mesh();
        mesh.nodes = (0..n).map(|i| [(i % nx) as f64, (i / nx) as f64]).collect();
        mesh.node_tags = (1..=n as u64).collect();
        let path = scratch("speed");
        let header = test_header(&mesh, false);
        let mut w = ResultsWriter::create(&path, &header).unwrap();
        let mut d: Vec<f64> = (0..2 * n).map(|i| (i as f64 * 1e-3).sin()).collect();
        let steps = 50;
        let t0 = Instant::now();
        for k in 0..steps {
            d[0] = k as f64;
            let rec = Record::zeros(k as f64, [&d, &d, &d]);
            w.append(&rec).unwrap();
        }
        w.finish(true, &Summary::default()).unwrap();
        let secs = t0.elapsed().as_secs_f64();
        let mb = (steps * 3 * 2 * n * 8) as f64 / 1e6;
        let size = std::fs::metadata(&path).unwrap().len() as f64 / 1e6;
        println!("{n} nodes x {steps} records: {mb:.0} MB of f64 in {secs:.2} s = {:.0} MB/s, {:.1} ms per record, file {size:.0} MB", mb / secs, 1e3 * secs / steps as f64);
        std::fs::remove_file(&path).ok();
    }

    /// Reads the file with h5py, as users do (without h5py: [`skip_without`]).
    fn h5py_check(path: &Path, rows: usize, complete: bool) {
        let script = format!(
            r#"
import sys
try:
    import h5py
except ImportError:
    print("h5py missing"); sys.exit(3)
f = h5py.File(sys.argv[1], "r")
assert f["displacement"].shape == ({rows}, 6, 2), f["displacement"].shape
assert f["displacement"].maxshape == (None, 6, 2)
assert f["displacement"].compression == "gzip" and f["displacement"].shuffle
assert f["contact/friction_stress"].shape == ({rows}, 3)
assert f["contact/state"].dtype == "int8"
assert f["energy/total"].shape == ({rows},)
assert bool(f.attrs["complete"]) == {complete}
assert f.attrs["program"] == "stickslip"
assert f["mesh/cells"].dtype == "int64"
print("ok")
"#,
            complete = if complete { "True" } else { "False" }
        );
        let out = std::process::Command::new("python3")
            .arg("-c")
            .arg(&script)
            .arg(path)
            .output();
        match out {
            Ok(o) if o.status.code() == Some(3) => skip_without("h5py"),
            Ok(o) => assert!(
                o.status.success(),
                "h5py check failed: {}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
            Err(e) => skip_without(&format!("python3 ({e})")),
        }
    }

    /// A check that cannot run for want of `what`: under CI (where `cargo
    /// xtask test` installs python3 and h5py) a failure, elsewhere a skip
    /// said on stderr.
    fn skip_without(what: &str) {
        assert!(
            std::env::var_os("CI").is_none(),
            "{what} is missing here, and CI must run this check: pip install h5py (cargo xtask test installs it)"
        );
        eprintln!("skipped the h5py check: {what} is missing");
    }

    /// Unnamed groups of one tag in three dimensions are all "#1": each
    /// gets a dataset of its own (the third met a name taken twice, and
    /// the run failed with HDF5's "unknown library error").
    #[test]
    fn groups_of_one_name_get_free_dataset_names() {
        let mut taken: Vec<String> = Vec::new();
        for dim in [0, 1, 2, 1] {
            let n = free_name("#1", (dim, 1), |n| taken.iter().any(|t| t == n));
            taken.push(n);
        }
        assert_eq!(taken, ["#1", "#1#1", "#1#2.1", "#1#1.1"]);
        let n = free_name("x", (1, 1), |n| ["x", "x#1", "x#1.1"].contains(&n));
        assert_eq!(n, "x#1.1.2");
    }
}
