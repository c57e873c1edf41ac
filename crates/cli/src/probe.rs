//! `stickslip probe OUT.h5 --at X,Y [--field ..] [--csv]`: the time history
//! of one field at the node nearest to a point, read from a results file;
//! and `stickslip probe OUT.h5 --along GROUP --times T1,T2,.. [--field ..]
//! [-o FILE]` ([`along`]): one field along a boundary group at given times.

use std::fmt::Write as _;
use std::path::Path;

use hdf5::File;
use ndarray::s;

use stickslip_case::InputError;

use crate::frames::{checked_rows, Frames};

/// A field that can be probed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Field {
    /// Displacement u_x.
    Ux,
    /// Displacement u_y.
    Uy,
    /// Velocity v_x.
    Vx,
    /// Velocity v_y.
    Vy,
    /// Acceleration a_x.
    Ax,
    /// Acceleration a_y.
    Ay,
    /// Friction stress σ_T along τ (contact nodes only).
    #[value(name = "friction_stress")]
    FrictionStress,
    /// Slip velocity v_T along τ (contact nodes only).
    #[value(name = "slip_velocity")]
    SlipVelocity,
    /// Normal traction pressing the node (contact nodes only).
    #[value(name = "normal_stress")]
    NormalStress,
    /// Stress σ_xx at the node (the average of its cells' values there),
    /// from the stored displacement and the case's material.
    Sxx,
    /// Stress σ_yy at the node.
    Syy,
    /// Shear stress σ_xy at the node.
    Sxy,
    /// Von Mises stress at the node (plane strain: with σ_zz = ν(σ_xx + σ_yy)).
    #[value(name = "von_mises")]
    VonMises,
}

impl Field {
    fn name(self) -> &'static str {
        match self {
            Field::Ux => "ux",
            Field::Uy => "uy",
            Field::Vx => "vx",
            Field::Vy => "vy",
            Field::Ax => "ax",
            Field::Ay => "ay",
            Field::FrictionStress => "friction_stress",
            Field::SlipVelocity => "slip_velocity",
            Field::NormalStress => "normal_stress",
            Field::Sxx => "sxx",
            Field::Syy => "syy",
            Field::Sxy => "sxy",
            Field::VonMises => "von_mises",
        }
    }

    /// The stress component of a stress field: 0, 1, 2 for σ_xx, σ_yy,
    /// σ_xy, 3 for von Mises.
    fn stress(self) -> Option<usize> {
        match self {
            Field::Sxx => Some(0),
            Field::Syy => Some(1),
            Field::Sxy => Some(2),
            Field::VonMises => Some(3),
            _ => None,
        }
    }

    /// A field of the contact nodes only.
    fn on_contact(self) -> bool {
        matches!(
            self,
            Field::FrictionStress | Field::SlipVelocity | Field::NormalStress
        )
    }

    /// The node dataset and component of a node field; `None` for the
    /// contact fields.
    fn node_dataset(self) -> Option<(&'static str, usize)> {
        match self {
            Field::Ux => Some(("displacement", 0)),
            Field::Uy => Some(("displacement", 1)),
            Field::Vx => Some(("velocity", 0)),
            Field::Vy => Some(("velocity", 1)),
            Field::Ax => Some(("acceleration", 0)),
            Field::Ay => Some(("acceleration", 1)),
            _ => None,
        }
    }
}

/// What `probe` prints: `info` says which node was used, `table` holds the
/// history (with `--csv` the info goes to stderr so stdout stays pure CSV).
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// Node index, its coordinates and distance to the point asked for.
    pub info: String,
    /// `t` and the field, one line per output step.
    pub table: String,
    /// The node used (0-based index into /mesh/nodes).
    pub node: usize,
    /// The times.
    pub t: Vec<f64>,
    /// The field's values.
    pub values: Vec<f64>,
}

/// Parses `X,Y`.
fn parse_point(at: &str) -> Result<[f64; 2], InputError> {
    let bad = || {
        InputError(format!(
            "--at {at:?}: expected two numbers X,Y, e.g. --at 8,0"
        ))
    };
    let (x, y) = at.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(bad());
    }
    Ok([x, y])
}

/// Whether `p` lies outside the box `b` ([min, max]) by more than a
/// hundredth of its diagonal: likely a mistyped point, not a node's
/// rounding.
pub(crate) fn off_the_body(b: [[f64; 2]; 2], p: [f64; 2]) -> bool {
    let size = (b[1][0] - b[0][0]).hypot(b[1][1] - b[0][1]);
    let off = (0..2)
        .map(|k| (b[0][k] - p[k]).max(p[k] - b[1][k]).max(0.0))
        .fold(0.0_f64, f64::hypot);
    off > 0.01 * size
}

/// Opens a results file that no run is writing: with HDF5's locking off
/// (HDF5_USE_FILE_LOCKING=FALSE, as `cargo run` sets it) the file opens,
/// but its datasets may be caught between two records.
fn open_results(file: &Path) -> Result<File, InputError> {
    crate::results_file::check_results_path(file)?;
    let name = file.display();
    if crate::results_file::being_written(file) {
        return Err(InputError(format!(
            "{name}: a run is still writing it; wait for the run to end (or stop it: Ctrl-C \
             keeps every step) and probe it then"
        )));
    }
    File::open(file).map_err(|e| {
        InputError(format!(
            "{name}: cannot open it as HDF5: {e}; give a results file written by `stickslip run`, \
             and close any program that is writing it"
        ))
    })
}

/// `/time` (a row a step, the histories'), its rows checked against
/// those of `/contact/friction_stress`, what it is read for
/// ([`checked_rows`]).
pub(crate) fn read_time(f: &File, name: &str) -> Result<Vec<f64>, InputError> {
    checked_rows(f, name, "time", "contact/friction_stress")?;
    f.dataset("time")
        .and_then(|d| d.read_1d::<f64>())
        .map(|t| t.to_vec())
        .map_err(|e| {
            InputError(format!(
                "{name}: cannot read /time: {e}; give a results file written by `stickslip run`"
            ))
        })
}

/// The mesh and material of the run stored in `f` (for the stress
/// fields): cells and coordinates from `/mesh`, E, ν and the hypothesis
/// from the case text the file stores.
pub(crate) fn stored_model(
    f: &File,
    name: &str,
) -> Result<(stickslip_mesh::Mesh, stickslip_fem::Material), InputError> {
    let bad = |what: String| {
        InputError(format!(
            "{name}: {what}; the stress fields need a results file written by `stickslip run`"
        ))
    };
    let nodes = f
        .dataset("mesh/nodes")
        .and_then(|d| d.read_2d::<f64>())
        .map_err(|e| bad(format!("cannot read /mesh/nodes: {e}")))?;
    let cells = f
        .dataset("mesh/cells")
        .and_then(|d| d.read_2d::<i64>())
        .map_err(|e| bad(format!("cannot read /mesh/cells: {e}")))?;
    let kind = match f
        .group("mesh")
        .ok()
        .and_then(|g| crate::output::text_attr(&g, "kind").ok())
        .as_deref()
    {
        Some("quad4") => stickslip_mesh::CellKind::Quad4,
        Some("quad9") => stickslip_mesh::CellKind::Quad9,
        other => {
            return Err(bad(format!(
                "/mesh has cell kind {other:?}, not quad4 or quad9"
            )))
        }
    };
    if nodes.ncols() != 2 || nodes.nrows() == 0 {
        return Err(bad(format!(
            "/mesh/nodes has shape {:?}, expected [n, 2] with n > 0",
            nodes.shape()
        )));
    }
    let n = nodes.nrows();
    if cells.ncols() != kind.nodes_per_cell() || cells.iter().any(|&v| v < 0 || v as usize >= n) {
        return Err(bad("/mesh/cells does not fit /mesh/nodes".into()));
    }
    let mesh = stickslip_mesh::Mesh {
        nodes: nodes.rows().into_iter().map(|r| [r[0], r[1]]).collect(),
        node_tags: (1..=n as u64).collect(),
        kind,
        cells: cells.iter().map(|&v| v as usize).collect(),
        cell_tags: (1..=cells.nrows() as u64).collect(),
        groups: Vec::new(),
        source: Default::default(),
    };
    let case = crate::output::text_attr(f, "case")
        .map_err(|e| bad(format!("cannot read the case it stores: {e:#}")))?;
    let doc: toml::Table = case
        .parse()
        .map_err(|e| bad(format!("the case it stores does not parse: {e}")))?;
    let m = doc.get("material").and_then(|m| m.as_table());
    let num = |k: &str| {
        m.and_then(|m| m.get(k))
            .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let hypothesis = match m.and_then(|m| m.get("hypothesis")).and_then(|h| h.as_str()) {
        None | Some("plane_strain") => stickslip_fem::Hypothesis::PlaneStrain,
        Some("plane_stress") => stickslip_fem::Hypothesis::PlaneStress,
        Some(other) => return Err(bad(format!("its case's material.hypothesis is {other:?}"))),
    };
    let (Some(e), Some(nu)) = (num("E"), num("nu")) else {
        return Err(bad("its case has no material.E and material.nu".into()));
    };
    let material = stickslip_fem::Material::new(e, nu, num("rho").unwrap_or(1.0), hypothesis)
        .map_err(|e| bad(format!("its case's material: {e}")))?;
    Ok((mesh, material))
}

/// The rows of the node vectors `/NAME` (`displacement`, `velocity`,
/// `acceleration`) of `f`, checked to be `[rows, n_nodes, 2]`: the
/// stresses and the views read a row of it as the mesh's node vectors.
///
/// # Errors
/// The dataset missing, or of another shape: an [`InputError`] naming
/// the file.
pub(crate) fn vector_rows(
    f: &File,
    file: &str,
    name: &str,
    n_nodes: usize,
) -> Result<usize, InputError> {
    let shape = f.dataset(name).map(|d| d.shape()).map_err(|e| {
        InputError(format!(
            "{file}: cannot read /{name}: {e}; give a results file written by `stickslip run`"
        ))
    })?;
    match shape[..] {
        [rows, n, 2] if n == n_nodes => Ok(rows),
        _ => Err(InputError(format!(
            "{file}: /{name} has shape {shape:?}, expected [records, {n_nodes}, 2] for the \
             {n_nodes} nodes of /mesh/nodes; the file is damaged or was not written by \
             `stickslip run`: run the case again for a whole one"
        ))),
    }
}

/// Where `f` is a results file of `stickslip run` whose run had no
/// contact surface: the message saying so for a contact field.
fn no_contact(f: &File, name: &str, field: Field) -> Option<InputError> {
    let ours = crate::output::text_attr(f, "program").ok().as_deref() == Some("stickslip");
    (ours && !f.link_exists("contact/nodes")).then(|| {
        InputError(format!(
            "{name}: its run had no contact surface (no [contact] in its case, or no node of it free to slip), \
             so there is no {}; \
             probe a field of the body (ux, uy, vx, vy, ax, ay, sxx, syy, sxy, von_mises), or run a \
             case with a [contact] surface",
            field.name()
        ))
    })
}

/// Component `field` of the stress `s` (von Mises for [`Field::VonMises`]).
fn component(material: &stickslip_fem::Material, s: [f64; 3], field: Field) -> f64 {
    match field.stress() {
        Some(3) => stickslip_fem::von_mises(material, s),
        Some(k) => s[k],
        None => f64::NAN,
    }
}

/// The history of stress field `field` at `node`: its cells' nodes'
/// displacement histories read, the node's stress formed per record
/// ([`stickslip_fem::stress_at_node`], the bits of the nodal average).
fn stress_history(
    f: &File,
    name: &str,
    mesh: &stickslip_mesh::Mesh,
    material: &stickslip_fem::Material,
    node: usize,
    field: Field,
) -> Result<Vec<f64>, InputError> {
    let cells: Vec<usize> = (0..mesh.n_cells())
        .filter(|&c| mesh.cell(c).contains(&node))
        .collect();
    let mut near: Vec<usize> = cells.iter().flat_map(|&c| mesh.cell(c).to_vec()).collect();
    near.sort_unstable();
    near.dedup();
    vector_rows(f, name, "displacement", mesh.nodes.len())?;
    let ds = f
        .dataset("displacement")
        .map_err(|e| InputError(format!("{name}: cannot read /displacement: {e}")))?;
    let mut hist = std::collections::HashMap::new();
    for &v in &near {
        let read = |comp: usize| {
            ds.read_slice_1d::<f64, _>(s![.., v, comp])
                .map(|a| a.to_vec())
                .map_err(|e| InputError(format!("{name}: cannot read /displacement: {e}")))
        };
        hist.insert(v, (read(0)?, read(1)?));
    }
    let records = hist.values().map(|(x, _)| x.len()).min().unwrap_or(0);
    Ok((0..records)
        .map(|k| {
            let s = stickslip_fem::stress_at_node(mesh, material, node, &cells, |v| {
                let (x, y) = &hist[&v];
                [x[k], y[k]]
            });
            component(material, s, field)
        })
        .collect())
}

/// Reads the history of `field` at the node of `file` nearest to `at`.
///
/// # Errors
/// A bad point, a file that is not a stickslip results file, or
/// `friction_stress` asked at a node that is not on the contact surface.
pub fn probe(file: &Path, at: &str, field: Field, csv: bool) -> Result<Probe, InputError> {
    let p = parse_point(at)?;
    let name = file.display().to_string();
    let h5 = |what: &str, e: hdf5::Error| {
        InputError(format!(
            "{name}: {what}: {e}; give a results file written by `stickslip run`"
        ))
    };
    let f = open_results(file)?;
    let nodes = f
        .dataset("mesh/nodes")
        .and_then(|d| d.read_2d::<f64>())
        .map_err(|e| h5("cannot read /mesh/nodes", e))?;
    if nodes.ncols() != 2 || nodes.nrows() == 0 {
        return Err(InputError(format!(
            "{name}: /mesh/nodes has shape {:?}, expected [n, 2] with n > 0",
            nodes.shape()
        )));
    }
    // hypot: squares of a point's coordinates beyond 1e154 overflow, and
    // every node was then as far (inf), the first the nearest.
    let dist = |i: usize| (nodes[[i, 0]] - p[0]).hypot(nodes[[i, 1]] - p[1]);
    let node = (0..nodes.nrows())
        .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
        .expect("n > 0");
    // The node fields are at the frames, the contact's at every step.
    let frame_time = || Frames::read(&f, &name).map(|fr| fr.time);
    let (t, values): (Vec<f64>, Vec<f64>) = match field.node_dataset() {
        None if field.stress().is_some() => {
            let (mesh, material) = stored_model(&f, &name)?;
            let values = stress_history(&f, &name, &mesh, &material, node, field)?;
            (frame_time()?, values)
        }
        None => {
            let contact = f
                .dataset("contact/nodes")
                .and_then(|d| d.read_1d::<i64>())
                .map_err(|e| {
                    no_contact(&f, &name, field).unwrap_or_else(|| {
                        h5("this file has no contact surface (/contact/nodes)", e)
                    })
                })?;
            let Some(j) = contact.iter().position(|&c| c == node as i64) else {
                let nearest = contact
                    .iter()
                    .filter_map(|&c| usize::try_from(c).ok().filter(|&c| c < nodes.nrows()))
                    .min_by(|&a, &b| dist(a).total_cmp(&dist(b)));
                let hint = nearest.map_or(String::new(), |c| {
                    format!(
                        "; the nearest contact node is {c} at ({}, {}): use --at {},{}",
                        nodes[[c, 0]],
                        nodes[[c, 1]],
                        nodes[[c, 0]],
                        nodes[[c, 1]]
                    )
                });
                return Err(InputError(format!(
                    "{name}: node {node} at ({}, {}), nearest to ({}, {}), is not a contact node, so it has no {}{hint}",
                    nodes[[node, 0]], nodes[[node, 1]], p[0], p[1], field.name()
                )));
            };
            let ds = format!("contact/{}", field.name());
            let t = read_time(&f, &name)?;
            let values = f
                .dataset(&ds)
                .and_then(|d| d.read_slice_1d::<f64, _>(s![.., j]))
                .map_err(|e| h5(&format!("cannot read /{ds}"), e))?
                .to_vec();
            (t, values)
        }
        Some((ds, comp)) => {
            vector_rows(&f, &name, ds, nodes.nrows())?;
            let t = frame_time()?;
            let values = f
                .dataset(ds)
                .and_then(|d| d.read_slice_1d::<f64, _>(s![.., node, comp]))
                .map_err(|e| h5(&format!("cannot read /{ds}"), e))?
                .to_vec();
            (t, values)
        }
    };
    let complete = f
        .attr("complete")
        .and_then(|a| a.read_scalar::<bool>())
        .unwrap_or(false);
    let (mut t, mut values) = (t, values);
    let what = if field.on_contact() {
        "output steps"
    } else {
        "frames"
    };
    if values.len() != t.len() {
        if complete {
            return Err(InputError(format!(
                "{name}: /time has {} entries but {} has {}",
                t.len(),
                field.name(),
                values.len()
            )));
        }
        // A run that stopped between writing two datasets (or on a full
        // disk, which left rows it could not cut back): the records both
        // hold.
        let n = t.len().min(values.len());
        t.truncate(n);
        values.truncate(n);
    }
    let mut info = format!(
        "node {node} at ({}, {}), distance {:.3e} from ({}, {}); {} {what}",
        nodes[[node, 0]],
        nodes[[node, 1]],
        dist(node),
        coordinate(p[0]),
        coordinate(p[1]),
        t.len()
    );
    if !complete {
        info.push_str(" (the run did not complete)");
    }
    // A point off the body by more than a hundredth of its size is likely
    // a typo (or the other coordinate order): say so, the history follows.
    let [lo, hi] = stickslip_mesh::bounding_box(nodes.rows().into_iter().map(|r| [r[0], r[1]]));
    if off_the_body([lo, hi], p) {
        let _ = write!(
            info,
            "; note: ({}, {}) lies outside the mesh (x in [{}, {}], y in [{}, {}])",
            coordinate(p[0]),
            coordinate(p[1]),
            lo[0],
            hi[0],
            lo[1],
            hi[1]
        );
    }
    info.push('\n');
    let mut table = String::new();
    if csv {
        let _ = writeln!(table, "t,{}", field.name());
        for (t, v) in t.iter().zip(&values) {
            let _ = writeln!(table, "{t:e},{v:e}");
        }
    } else {
        // Times to as many digits as tell the rows apart (Remark 4.3's
        // reduced steps of 1e-7 read as one time at 7 digits).
        let digits = (6..16)
            .find(|&d| {
                t.windows(2)
                    .all(|w| format!("{:.d$e}", w[0]) != format!("{:.d$e}", w[1]))
            })
            .unwrap_or(16);
        let width = 14.max(digits + 8);
        let _ = writeln!(table, "{:>width$}  {:>14}", "t", field.name());
        for (t, v) in t.iter().zip(&values) {
            let _ = writeln!(table, "{t:>width$.digits$e}  {v:>14.6e}");
        }
    }
    Ok(Probe {
        info,
        table,
        node,
        t,
        values,
    })
}

// ---------------------------------------------------------------------------
// --along GROUP --times T1,T2,..

/// The `--along` arguments of `stickslip probe` (flattened into its clap
/// command by `main.rs`).
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct AlongArgs {
    /// Print the field along this boundary group (a physical line group, e.g.
    /// contact) at the times of --times, as CSV, instead of a history at --at.
    #[arg(long, value_name = "GROUP", conflicts_with = "at")]
    pub along: Option<String>,
    /// With --along: comma-separated times; each uses the nearest frame (u, v, a and the
    /// stresses) or output step (the contact fields).
    #[arg(
        long,
        value_name = "T1,T2,..",
        requires = "along",
        allow_hyphen_values = true
    )]
    pub times: Option<String>,
    /// With --along: write the CSV to this file instead of stdout (an existing one only with
    /// --force; never the results file read).
    #[arg(short = 'o', long = "output", value_name = "FILE", requires = "along")]
    pub output: Option<std::path::PathBuf>,
}

/// A field along a group at a few output steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Along {
    /// Which steps were used for which times (for stderr).
    pub info: String,
    /// `t_asked,t,record,node,x,y,s,FIELD`, one line per (time, node):
    /// `record` is the row of `/time` (0 the initial state), not the
    /// integrator's step.
    pub csv: String,
    /// The group's nodes in order along it.
    pub nodes: Vec<usize>,
    /// Arc length of each node from the first.
    pub s: Vec<f64>,
    /// The record (row of `/time`) used for each asked time.
    pub records: Vec<usize>,
    /// The time of each of those records.
    pub t: Vec<f64>,
    /// `values[i][j]`: the field at record `records[i]`, node `nodes[j]` (NaN for
    /// a contact field at a group node that carries no friction).
    pub values: Vec<Vec<f64>>,
}

/// Parses `T1,T2,..` (at least one finite number).
fn parse_times(times: &str) -> Result<Vec<f64>, InputError> {
    let bad = |why: &str| {
        InputError(format!(
            "--times {times:?}: {why}; give comma-separated times, e.g. --times 0.1,0.25,0.5"
        ))
    };
    let mut out = Vec::new();
    for part in times.split(',') {
        let v: f64 = part
            .trim()
            .parse()
            .map_err(|_| bad(&format!("{:?} is not a number", part.trim())))?;
        if !v.is_finite() {
            return Err(bad(&format!("{v} is not finite")));
        }
        out.push(v);
    }
    Ok(out)
}

/// One edge of a line group as walked: start, end and (quad9) mid-side
/// node.
type Side = (usize, usize, Option<usize>);

/// A line group walked along: its nodes in order with their arc lengths,
/// and its edges in the same order.
struct Walk {
    order: Vec<usize>,
    s: Vec<f64>,
    edges: Vec<Side>,
    closed: bool,
    /// s at the end of the last edge (a closed loop's length).
    length: f64,
}

/// The nodes of a line group in order along it, with their arc lengths.
///
/// The group's edges are recovered from the cells: a cell side is a group
/// edge when it lies on the boundary (no other cell shares it) and all its
/// nodes (the mid-side node too, for quad9) are in the group. Each edge is
/// taken in its cell's counter-clockwise order, so the walk has the body on
/// its left (DESIGN.md's tangent convention). An open chain starts at its
/// free end; a closed loop at its node of least x (then least y), which
/// [`along`] moves to the solver's start on the contact group
/// ([`loop_from_solver_start`]). s is summed over straight segments
/// (through the mid-side node on quad9).
fn order_along(
    name: &str,
    group: &str,
    nodes: &ndarray::Array2<f64>,
    cells: &ndarray::Array2<i64>,
    members: &[i64],
) -> Result<Walk, InputError> {
    use std::collections::{HashMap, HashSet};
    let n = nodes.nrows();
    let bad_index = || {
        InputError(format!(
            "{name}: /mesh/cells or /mesh/groups/{group} holds a node index outside 0..{n}"
        ))
    };
    let index = |v: i64| usize::try_from(v).ok().filter(|&i| i < n);
    let member: HashSet<usize> = members
        .iter()
        .map(|&v| index(v).ok_or_else(bad_index))
        .collect::<Result<_, _>>()?;
    let npc = cells.ncols();
    if npc != 4 && npc != 9 {
        return Err(InputError(format!(
            "{name}: /mesh/cells has {npc} nodes per cell, expected 4 or 9"
        )));
    }
    // Corner pairs of every cell side, counted to find the boundary.
    let mut count: HashMap<(usize, usize), u32> = HashMap::new();
    let mut sides = Vec::with_capacity(4 * cells.nrows());
    for row in cells.rows() {
        let c: Vec<usize> = row
            .iter()
            .map(|&v| index(v).ok_or_else(bad_index))
            .collect::<Result<_, _>>()?;
        for e in 0..4 {
            let (a, b) = (c[e], c[(e + 1) % 4]);
            let mid = (npc == 9).then(|| c[4 + e]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
            sides.push((a, b, mid));
        }
    }
    let mut next: HashMap<usize, (usize, Option<usize>)> = HashMap::new();
    let mut has_incoming: HashSet<usize> = HashSet::new();
    for &(a, b, mid) in &sides {
        let on_boundary = count[&(a.min(b), a.max(b))] == 1;
        let in_group =
            member.contains(&a) && member.contains(&b) && mid.is_none_or(|m| member.contains(&m));
        if on_boundary && in_group {
            if next.insert(a, (b, mid)).is_some() {
                return Err(InputError(format!(
                    "{name}: group {group:?} branches at node {a}; --along needs a single chain of edges"
                )));
            }
            has_incoming.insert(b);
        }
    }
    if next.is_empty() {
        return Err(InputError(format!(
            "{name}: group {group:?} has no boundary edges (is it a line group on the boundary?); \
             --along needs a line group"
        )));
    }
    let least = |ids: &mut dyn Iterator<Item = usize>| {
        ids.min_by(|&a, &b| {
            nodes[[a, 0]]
                .total_cmp(&nodes[[b, 0]])
                .then(nodes[[a, 1]].total_cmp(&nodes[[b, 1]]))
        })
    };
    let starts: Vec<usize> = next
        .keys()
        .copied()
        .filter(|a| !has_incoming.contains(a))
        .collect();
    let start = match starts.len() {
        0 => least(&mut next.keys().copied()).expect("non-empty"),
        1 => starts[0],
        k => {
            return Err(InputError(format!(
                "{name}: group {group:?} is {k} separate pieces; --along needs one chain of edges \
                 (split it into one physical group per piece in Gmsh)"
            )))
        }
    };
    let len =
        |a: usize, b: usize| (nodes[[b, 0]] - nodes[[a, 0]]).hypot(nodes[[b, 1]] - nodes[[a, 1]]);
    let (mut order, mut s) = (vec![start], vec![0.0]);
    let mut edges = Vec::with_capacity(next.len());
    let mut length = 0.0;
    let mut at = start;
    let mut walked = 0;
    while let Some(&(b, mid)) = next.get(&at) {
        edges.push((at, b, mid));
        let s0 = *s.last().expect("non-empty");
        let s_end = match mid {
            Some(m) => {
                order.push(m);
                s.push(s0 + len(at, m));
                s0 + len(at, m) + len(m, b)
            }
            None => s0 + len(at, b),
        };
        walked += 1;
        length = s_end;
        if b == start {
            break;
        }
        order.push(b);
        s.push(s_end);
        at = b;
        if walked > next.len() {
            break;
        }
    }
    if walked != next.len() {
        return Err(InputError(format!(
            "{name}: group {group:?} is not one chain of edges ({walked} of {} edges reached from node {start}); \
             --along needs one chain (split it into one physical group per piece in Gmsh)",
            next.len()
        )));
    }
    let closed = starts.is_empty();
    Ok(Walk {
        order,
        s,
        edges,
        closed,
        length,
    })
}

/// A closed loop of a contact group as the solver walks it: from the node
/// its chain starts at, with the arc length it measures
/// ([`stickslip_fem::boundary_quadrature`]), so that every node, one
/// without friction too, has its s on /contact/s's scale and start.
/// `friction_s` is a node's /contact/s on this group. The solver starts at
/// the group's first edge, which the file does not keep: the start is the
/// corner (the friction node of least /contact/s, or one without friction)
/// whose distance along the walk to that node is nearest its /contact/s;
/// corners lie an edge apart, far beyond the difference between the
/// walk's chords and the arc. `None` where no node of the loop carries
/// friction.
fn loop_from_solver_start(
    group: &str,
    nodes: &ndarray::Array2<f64>,
    walk: &Walk,
    friction_s: impl Fn(usize) -> Option<f64>,
) -> Option<(Vec<usize>, Vec<f64>)> {
    use std::collections::HashMap;
    let at: HashMap<usize, f64> = walk
        .order
        .iter()
        .copied()
        .zip(walk.s.iter().copied())
        .collect();
    let (first, first_s) = walk
        .order
        .iter()
        .filter_map(|&v| friction_s(v).map(|cs| (v, cs)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let ahead = |a: usize| {
        let d = at[&first] - at[&a];
        if d < 0.0 {
            d + walk.length
        } else {
            d
        }
    };
    let k = (0..walk.edges.len())
        .filter(|&k| {
            let a = walk.edges[k].0;
            a == first || friction_s(a).is_none()
        })
        .min_by(|&i, &j| {
            let off = |k: usize| (ahead(walk.edges[k].0) - first_s).abs();
            off(i).total_cmp(&off(j))
        })?;
    // The loop alone, its edges from the start: the solver's sums in the
    // solver's order, so the same bits.
    let mut local: HashMap<usize, usize> = HashMap::new();
    let mut ids = Vec::new();
    let mut id = |v: usize| {
        *local.entry(v).or_insert_with(|| {
            ids.push(v);
            ids.len() - 1
        })
    };
    let edges: Vec<stickslip_mesh::Edge> = walk.edges[k..]
        .iter()
        .chain(&walk.edges[..k])
        .map(|&(a, b, mid)| stickslip_mesh::Edge {
            nodes: [id(a), id(b)],
            mid: mid.map(&mut id),
            cell: 0,
        })
        .collect();
    let kind = if edges.iter().any(|e| e.mid.is_some()) {
        stickslip_mesh::CellKind::Quad9
    } else {
        stickslip_mesh::CellKind::Quad4
    };
    let mesh = stickslip_mesh::Mesh {
        nodes: ids
            .iter()
            .map(|&v| [nodes[[v, 0]], nodes[[v, 1]]])
            .collect(),
        node_tags: (1..=ids.len() as u64).collect(),
        kind,
        cells: Vec::new(),
        cell_tags: Vec::new(),
        groups: vec![stickslip_mesh::Group {
            name: group.to_string(),
            tag: 1,
            dim: 1,
            elements: edges.len(),
            edges,
            cells: Vec::new(),
            points: Vec::new(),
            nodes: (0..ids.len()).collect(),
        }],
        source: Default::default(),
    };
    let chain = stickslip_fem::boundary_quadrature(&mesh, group).ok()?;
    Some(
        chain
            .iter()
            .map(|b| {
                let v = ids[b.node];
                (v, friction_s(v).unwrap_or(b.s))
            })
            .unzip(),
    )
}

/// Whether each node of /contact/nodes carries friction on `group`'s own
/// surface (by /contact/surface); all of them in a file without it (one
/// surface).
fn on_own_surface(f: &File, group: &str, n: usize) -> Vec<bool> {
    let surface = f
        .dataset("contact/surface")
        .and_then(|d| d.read_1d::<i64>())
        .map(|a| a.to_vec());
    let groups = contact_groups(f);
    match surface {
        Ok(surface) if surface.len() == n => surface
            .iter()
            .map(|&k| {
                usize::try_from(k)
                    .ok()
                    .and_then(|k| groups.get(k))
                    .is_some_and(|g| g == group)
            })
            .collect(),
        _ => vec![true; n],
    }
}

/// The contact group of the case stored in the file, if any.
/// The groups of the file's contact surfaces: `/contact`'s attribute
/// `groups`, or in a file written before it the case's `[contact]` group.
fn contact_groups(f: &File) -> Vec<String> {
    if let Ok(groups) = f
        .group("contact")
        .and_then(|c| c.attr("groups"))
        .and_then(|a| a.read_raw::<hdf5::types::VarLenUnicode>())
    {
        return groups.iter().map(|g| g.as_str().to_string()).collect();
    }
    let Some(doc) = crate::output::text_attr(f, "case")
        .ok()
        .and_then(|c| c.parse::<toml::Table>().ok())
    else {
        return Vec::new();
    };
    let group = |t: &toml::Value| t.get("group")?.as_str().map(str::to_string);
    match doc.get("contact") {
        Some(toml::Value::Array(a)) => a.iter().filter_map(group).collect(),
        Some(t) => group(t).into_iter().collect(),
        None => Vec::new(),
    }
}

/// `--along GROUP --times T1,..`: `field` at the nodes of `group`, in order
/// along it (for the contact group: the order of /contact/nodes, the nodes
/// without friction placed by arc length from the same start, a closed
/// loop's too), at the output steps nearest to each time.
///
/// # Errors
/// Bad times, a file that is not a stickslip results file, a group the file
/// does not have or that is not one chain of boundary edges, or a contact
/// field asked along a file without a contact surface.
pub fn along(file: &Path, group: &str, times: &str, field: Field) -> Result<Along, InputError> {
    let asked = parse_times(times)?;
    let name = file.display().to_string();
    let h5 = |what: &str, e: hdf5::Error| {
        InputError(format!(
            "{name}: {what}: {e}; give a results file written by `stickslip run`"
        ))
    };
    let f = open_results(file)?;
    let nodes = f
        .dataset("mesh/nodes")
        .and_then(|d| d.read_2d::<f64>())
        .map_err(|e| h5("cannot read /mesh/nodes", e))?;
    if nodes.ncols() != 2 {
        return Err(InputError(format!(
            "{name}: /mesh/nodes has shape {:?}, expected [n, 2]",
            nodes.shape()
        )));
    }
    // A row of the node vectors is read as the mesh's (the stresses need
    // every node of it).
    if let Some((ds, _)) = field.node_dataset() {
        vector_rows(&f, &name, ds, nodes.nrows())?;
    } else if field.stress().is_some() {
        vector_rows(&f, &name, "displacement", nodes.nrows())?;
    }
    let cells = f
        .dataset("mesh/cells")
        .and_then(|d| d.read_2d::<i64>())
        .map_err(|e| h5("cannot read /mesh/cells", e))?;
    let groups = f
        .group("mesh/groups")
        .map_err(|e| h5("cannot read /mesh/groups", e))?;
    // By the `name` attribute (a dataset's name may differ from its
    // group's: `output::stored_group_name`); files without it by name.
    let stored: Vec<(String, String)> = groups
        .member_names()
        .unwrap_or_default()
        .into_iter()
        .map(|m| {
            let own = groups
                .dataset(&m)
                .ok()
                .and_then(|d| crate::output::text_attr(&d, "name").ok());
            (own.unwrap_or_else(|| m.clone()), m)
        })
        .collect();
    let named: Vec<&String> = stored
        .iter()
        .filter(|(own, _)| own == group)
        .map(|(_, m)| m)
        .collect();
    // Several groups of that name (of several dimensions): as the case
    // refuses such a name, so does --along, naming them.
    if let [_, _, ..] = named[..] {
        let which: Vec<String> = named
            .iter()
            .map(|m| {
                let d = groups.dataset(m).ok();
                let int = |a: &str| {
                    d.as_ref()
                        .and_then(|d| d.attr(a).ok()?.read_scalar::<i64>().ok())
                        .map_or("?".to_string(), |v| v.to_string())
                };
                format!("dim {} tag {}", int("dim"), int("tag"))
            })
            .collect();
        return Err(InputError(format!(
            "{name}: several groups are called {group:?} ({}), so which one is meant is \
             unknown; rename all but one in the .geo and run the case again",
            which.join(", ")
        )));
    }
    let members = match groups.dataset(named.first().map_or(group, |m| m.as_str())) {
        Ok(d) => d
            .read_1d::<i64>()
            .map_err(|e| h5(&format!("cannot read /mesh/groups/{group}"), e))?
            .to_vec(),
        Err(_) => {
            let have: Vec<&str> = stored.iter().map(|(own, _)| own.as_str()).collect();
            let have = have.join(", ");
            return Err(InputError(format!(
                "{name}: no group {group:?} in this file; it has: {have}"
            )));
        }
    };
    let walk = order_along(&name, group, &nodes, &cells, &members)?;
    let (mut order, mut s) = (walk.order.clone(), walk.s.clone());

    let contact_field = field.on_contact();
    let is_contact_group = contact_groups(&f).iter().any(|g| g == group);
    let contact: Option<(Vec<i64>, Vec<f64>)> = if contact_field || is_contact_group {
        let c = f
            .dataset("contact/nodes")
            .and_then(|d| d.read_1d::<i64>())
            .and_then(|c| {
                Ok((
                    c.to_vec(),
                    f.dataset("contact/s")?.read_1d::<f64>()?.to_vec(),
                ))
            });
        match c {
            Ok(c) => Some(c),
            Err(e) if contact_field => {
                return Err(no_contact(&f, &name, field).unwrap_or_else(|| {
                    h5(
                        &format!(
                            "{} needs a contact surface, and this file has none (/contact)",
                            field.name()
                        ),
                        e,
                    )
                }))
            }
            Err(_) => None,
        }
    } else {
        None
    };
    // Position of each ordered node in /contact/nodes.
    let slot = |order: &[usize]| -> Vec<Option<usize>> {
        order
            .iter()
            .map(|&v| {
                contact
                    .as_ref()
                    .and_then(|(c, _)| c.iter().position(|&x| x == v as i64))
            })
            .collect()
    };
    if is_contact_group {
        if let Some((c, cs)) = &contact {
            // A node of the group may carry friction on another surface
            // joined to it, whose s starts elsewhere.
            let own = on_own_surface(&f, group, c.len());
            let friction_s: std::collections::HashMap<usize, f64> = c
                .iter()
                .zip(cs)
                .zip(&own)
                .filter(|(_, &own)| own)
                .filter_map(|((&v, &s), _)| Some((usize::try_from(v).ok()?, s)))
                .collect();
            // A closed loop starts where the solver's chain does.
            if walk.closed {
                if let Some((o, w)) =
                    loop_from_solver_start(group, &nodes, &walk, |v| friction_s.get(&v).copied())
                {
                    (order, s) = (o, w);
                }
            }
            // The order of /contact/nodes: sort by /contact/s where the node
            // carries friction, by the walk's s elsewhere (both are measured
            // from the same end of the same chain).
            let key: Vec<f64> = order
                .iter()
                .zip(&s)
                .map(|(v, &w)| friction_s.get(v).copied().unwrap_or(w))
                .collect();
            let mut idx: Vec<usize> = (0..order.len()).collect();
            idx.sort_by(|&a, &b| key[a].total_cmp(&key[b]));
            order = idx.iter().map(|&i| order[i]).collect();
            s = idx.iter().map(|&i| key[i]).collect();
        }
    }
    let slots = slot(&order);

    // The node fields are at the frames (k: a frame, `row_of[k]` its row of
    // /time), the contact's at every step.
    let (t_all, row_of): (Vec<f64>, Vec<usize>) = if contact_field {
        let t = read_time(&f, &name)?;
        let rows = (0..t.len()).collect();
        (t, rows)
    } else {
        let frames = Frames::read(&f, &name)?;
        (frames.time, frames.row)
    };
    if t_all.is_empty() {
        return Err(InputError(format!(
            "{name}: /time is empty: the run wrote no output step"
        )));
    }
    let (t_first, t_last) = (t_all[0], t_all[t_all.len() - 1]);
    let mut info = format!(
        "{} along {group:?}: {} nodes, s from 0 to {:.6e}{}\n",
        field.name(),
        order.len(),
        s.last().copied().unwrap_or(0.0),
        if is_contact_group {
            " (the contact group: ordered as /contact/nodes)"
        } else {
            ""
        }
    );
    let missing = slots.iter().filter(|x| x.is_none()).count();
    if contact_field && missing > 0 {
        let _ = writeln!(
            info,
            "{missing} of the group's nodes carry no friction (not in /contact/nodes): their {} is nan",
            field.name()
        );
    }
    let (mut records, mut t_used, mut values) = (Vec::new(), Vec::new(), Vec::new());
    for &ta in &asked {
        let k = (0..t_all.len())
            .min_by(|&a, &b| (t_all[a] - ta).abs().total_cmp(&(t_all[b] - ta).abs()))
            .expect("non-empty");
        let _ = write!(
            info,
            "t = {ta}: record {} at t = {} (nearest; off by {:.3e})",
            row_of[k],
            t_all[k],
            (t_all[k] - ta).abs()
        );
        if ta < t_first || ta > t_last {
            let _ = write!(info, "; outside the run's [{t_first}, {t_last}]");
        }
        info.push('\n');
        let row: Vec<f64> = match field.node_dataset() {
            None if field.stress().is_some() => {
                let (mesh, material) = stored_model(&f, &name)?;
                let u: Vec<f64> = f
                    .dataset("displacement")
                    .and_then(|d| d.read_slice_2d::<f64, _>(s![k, .., ..]))
                    .map_err(|e| h5("cannot read /displacement", e))?
                    .iter()
                    .copied()
                    .collect();
                let all = stickslip_fem::nodal_stresses(&mesh, &material, &u);
                order
                    .iter()
                    .map(|&v| {
                        all.get(v)
                            .map_or(f64::NAN, |&st| component(&material, st, field))
                    })
                    .collect()
            }
            Some((ds, comp)) => {
                let all = f
                    .dataset(ds)
                    .and_then(|d| d.read_slice_1d::<f64, _>(s![k, .., comp]))
                    .map_err(|e| h5(&format!("cannot read /{ds}"), e))?;
                order
                    .iter()
                    .map(|&v| all.get(v).copied().unwrap_or(f64::NAN))
                    .collect()
            }
            None => {
                let ds = format!("contact/{}", field.name());
                let all = f
                    .dataset(&ds)
                    .and_then(|d| d.read_slice_1d::<f64, _>(s![k, ..]))
                    .map_err(|e| h5(&format!("cannot read /{ds}"), e))?;
                slots
                    .iter()
                    .map(|j| j.and_then(|j| all.get(j).copied()).unwrap_or(f64::NAN))
                    .collect()
            }
        };
        records.push(row_of[k]);
        t_used.push(t_all[k]);
        values.push(row);
    }
    let complete = f
        .attr("complete")
        .and_then(|a| a.read_scalar::<bool>())
        .unwrap_or(false);
    if !complete {
        info.push_str("(the run did not complete)\n");
    }
    let mut csv = format!("t_asked,t,record,node,x,y,s,{}\n", field.name());
    for (i, &ta) in asked.iter().enumerate() {
        for (j, &v) in order.iter().enumerate() {
            let _ = writeln!(
                csv,
                "{ta:e},{:e},{},{v},{:e},{:e},{:e},{:e}",
                t_used[i],
                records[i],
                nodes[[v, 0]],
                nodes[[v, 1]],
                s[j],
                values[i][j]
            );
        }
    }
    Ok(Along {
        info,
        csv,
        nodes: order,
        s,
        records,
        t: t_used,
        values,
    })
}

/// `stickslip probe FILE --along GROUP --times .. [-o CSV [--force]]`:
/// runs [`along`], prints the step choices on stderr and the CSV on stdout
/// or into `args.output`. An existing CSV file is replaced only with
/// `force`, and never when it is `file` itself (the results read).
///
/// # Errors
/// As [`along`]; `--times` missing; `force` without an output file; the
/// output file existing (without `force`), being the results file, or its
/// place not writable: an [`InputError`]. Writing the output file failing
/// (a full disk): an error naming it, the file as it was. A failed write
/// to stdout or stderr: a [`crate::console::WriteError`] (the CSV is
/// written all the same where only stderr failed).
pub fn write_along(file: &Path, args: &AlongArgs, field: Field, force: bool) -> anyhow::Result<()> {
    let group = args.along.as_deref().unwrap_or_default();
    if force && args.output.is_none() {
        return Err(InputError(format!(
            "--along {group}: --force applies to -o FILE (it lets the CSV replace an existing FILE), \
             and there is no -o; give -o FILE, or leave out --force to print the CSV on stdout"
        ))
        .into());
    }
    let times = args.times.as_deref().ok_or_else(|| {
        InputError(format!(
            "--along {group}: give the times too, e.g. --times 0.1,0.25,0.5"
        ))
    })?;
    // Refused before the reading, which may take a while.
    if let Some(out) = &args.output {
        csv_target(out, file, force)?;
    }
    let a = along(file, group, times, field)?;
    let info = crate::console::err(&a.info);
    match &args.output {
        Some(out) => write_csv(out, &a.csv)?,
        None => crate::console::out(&a.csv)?,
    }
    Ok(info?)
}

/// Writes `csv` into `out` through `out.part`, renamed into place once
/// whole: a write that fails leaves `out` as it was (with `--force` the
/// earlier CSV) and no `.part`. A link at `out` is written through, as
/// before, by writing beside its target.
///
/// # Errors
/// Creating or renaming refused where the place must change
/// ([`crate::sys::place_error`]): an [`InputError`]; any other failure (a
/// full disk, a quota, a file-size limit): an error naming `out`.
fn write_csv(out: &Path, csv: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let linked = std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink());
    let target = match std::fs::canonicalize(out) {
        Ok(t) if linked => t,
        _ => out.to_path_buf(),
    };
    // Written beside and renamed into place as the viewers' XML is: only
    // its create and rename keep their OS error, which says whether the
    // place is at fault.
    crate::xdmf::replace(&target, |w| w.write_all(csv.as_bytes())).map_err(|e| {
        if crate::sys::place_error(&e) {
            InputError(format!(
                "-o {}: cannot write {}: {e}; check the directory exists and is writable, or give \
                 another file with -o",
                out.display(),
                target.display()
            ))
            .into()
        } else {
            anyhow::anyhow!(
                "-o {}: cannot write the CSV: {e} (the file is as it was before); make room on its \
                 disk if it is full, and run this again",
                out.display()
            )
        }
    })
}

/// Refuses `out` as `probe --along`'s CSV file where writing it would lose
/// something: the results file `results` itself (whatever its name: a
/// link or another path to it; even with `force`), an existing file
/// without `force`, or a directory, device, FIFO or socket.
fn csv_target(out: &Path, results: &Path, force: bool) -> Result<(), InputError> {
    use std::os::unix::fs::MetadataExt;
    let name = out.display();
    let Ok(meta) = std::fs::metadata(out) else {
        return Ok(());
    };
    let same_file =
        std::fs::metadata(results).is_ok_and(|r| (r.dev(), r.ino()) == (meta.dev(), meta.ino()));
    if same_file {
        return Err(InputError(format!(
            "-o {name} is the results file being read ({}); write the CSV to another file, e.g. -o {}",
            results.display(),
            out.with_extension("csv").display()
        )));
    }
    if meta.is_dir() {
        return Err(InputError(format!(
            "-o {name} is a directory; give a file in it, e.g. -o {}",
            out.join("along.csv").display()
        )));
    }
    if !meta.is_file() {
        return Err(InputError(format!(
            "-o {name} exists and is not a regular file (a device, FIFO or socket); \
             give a file, or leave out -o to print the CSV on stdout"
        )));
    }
    if !force {
        return Err(InputError(format!(
            "-o {name} already exists; use --force to overwrite it, or -o to write elsewhere"
        )));
    }
    Ok(())
}

/// A coordinate the user gave, as they would write it: in exponent form
/// where plain digits run long (1e200 printed 201 digits).
fn coordinate(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() > 16 {
        format!("{v:e}")
    } else {
        plain
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{Header, Record, ResultsWriter, Summary};

    /// Writes 4 steps for the two-cell mesh of output.rs's tests, with
    /// u_x(node i, step k) = 10 k + i, σ_T(contact j, step k) = k − j.
    fn write(path: &Path) {
        let mesh = crate::output::tests::tiny_mesh();
        let header = Header {
            case_source: "",
            mesh: &mesh,
            contact_nodes: &[0, 1, 2],
            contact_s: &[0.0, 1.0, 2.0],
            contact_lines: &[[0, 1], [1, 2]],
            contact_surface: &[],
            contact_groups: &[],
        };
        let mut w = ResultsWriter::create(path, &header).unwrap();
        for k in 0..4 {
            let d: Vec<f64> = (0..12)
                .map(|i| {
                    if i % 2 == 0 {
                        10.0 * k as f64 + (i / 2) as f64
                    } else {
                        -1.0
                    }
                })
                .collect();
            let v: Vec<f64> = (0..12)
                .map(|i| if i % 2 == 1 { 0.5 * k as f64 } else { 0.0 })
                .collect();
            let fs: Vec<f64> = (0..3).map(|j| k as f64 - j as f64).collect();
            let ns: Vec<f64> = (0..3).map(|j| 300.0 + 10.0 * k as f64 + j as f64).collect();
            w.append(&Record {
                friction_stress: &fs,
                slip_velocity: &[0.0; 3],
                state: &[0; 3],
                normal_stress: &ns,
                dt: 0.25,
                ..Record::zeros(0.25 * k as f64, [&d, &v, &d])
            })
            .unwrap();
        }
        w.finish(true, &Summary::default()).unwrap();
    }

    #[test]
    fn probe_nearest_node_and_fields() {
        let _guard = crate::output::tests::h5_lock();
        let path = std::env::temp_dir().join(format!("stickslip-probe-{}.h5", std::process::id()));
        write(&path);
        // (1.9, 0.2) is nearest to node 2 at (2, 0): distance sqrt(0.01 + 0.04).
        let p = probe(&path, "1.9,0.2", Field::Ux, false).unwrap();
        assert_eq!(p.node, 2);
        assert_eq!(p.t, vec![0.0, 0.25, 0.5, 0.75]);
        assert_eq!(p.values, vec![2.0, 12.0, 22.0, 32.0]);
        assert!(
            p.info.contains("node 2 at (2, 0), distance 2.236e-1"),
            "{}",
            p.info
        );
        assert!(!p.info.contains("outside"), "{}", p.info);
        assert_eq!(
            probe(&path, "2,0", Field::Vy, false).unwrap().values,
            vec![0.0, 0.5, 1.0, 1.5]
        );
        // Far beyond the mesh, where squared distances overflow (every
        // node was at distance inf), and said in exponent form.
        let huge = probe(&path, "1e200,-1e200", Field::Ux, false).unwrap();
        assert!(
            huge.info
                .contains("distance 1.414e200 from (1e200, -1e200)")
                && huge.info.contains("note: (1e200, -1e200) lies outside"),
            "{}",
            huge.info
        );
        let far = probe(&path, "20,0.5", Field::Ux, false).unwrap();
        assert!(
            far.info.contains("note: (20, 0.5) lies outside the mesh"),
            "{}",
            far.info
        );
        // Contact node 1 is index 1 along the surface: σ_T = k − 1.
        let fs = probe(&path, "1,0", Field::FrictionStress, true).unwrap();
        assert_eq!(fs.values, vec![-1.0, 0.0, 1.0, 2.0]);
        assert!(
            fs.table.starts_with("t,friction_stress\n0e0,-1e0\n"),
            "{}",
            fs.table
        );
        // Its normal traction as written: 300 + 10 k + j at row k.
        let ns = probe(&path, "1,0", Field::NormalStress, false).unwrap();
        assert_eq!(ns.values, vec![301.0, 311.0, 321.0, 331.0]);
        // Node 4 at (1, 1) is not on the contact line.
        let e = probe(&path, "1,1", Field::FrictionStress, false)
            .unwrap_err()
            .0;
        assert!(
            e.contains("node 4") && e.contains("not a contact node") && e.contains("--at 1,0"),
            "{e}"
        );
        assert!(probe(&path, "1;1", Field::Ux, false)
            .unwrap_err()
            .0
            .contains("expected two numbers"));
        std::fs::remove_file(&path).ok();
        let e = probe(&path, "0,0", Field::Ux, false).unwrap_err().0;
        assert!(e.contains("no such results file"), "{e}");
    }
}
