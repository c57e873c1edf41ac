//! `OUT.views.h5`: one dataset per record and field, each a view of one
//! row of the results file's `[n_out, …]` datasets, for the XDMF files to
//! point to.
//!
//! A view is an HDF5 virtual dataset: it holds no numbers, only the
//! mapping "row k of `/displacement` in OUT.h5", which the HDF5 library
//! resolves on read (every reader built on HDF5 ≥ 1.10 does: ParaView,
//! h5py under meshio, VTK under PyVista). XDMF readers then see plain
//! datasets, where the XDMF way to address one row of a larger array (a
//! HyperSlab data item) is read by ParaView's legacy reader only; and the
//! `[n_out, n, 2]` datasets stay as h5py scripts read them.
//!
//! The node vectors are viewed as `[n, 3]` with z = 0 (HDF5's fill value
//! of the unmapped third column): VTK vectors have three components, and
//! ParaView's Warp By Vector offers only 3-component arrays. The source is
//! named by file name only: HDF5 looks for it beside the views file, so
//! the files move together.
//!
//! `stickslip views` writes the file (and `stickslip stress` through it),
//! not the run: HDF5 creates a dataset, virtual or plain, far more slowly
//! than a run writes a record, and six views a record made a run of many
//! cheap records several times slower (docs/performance.md).
//!
//! An update keeps the views that still hold and makes only the others:
//! a body view names a frame's row of the fields, which no run moves, but
//! a contact view names the frame's row of the histories, and a restart
//! moves those (it drops the earlier run's last frame, so the frames
//! after it fall on other rows). So each contact view keeps the row it
//! maps in its attribute `row`, which is compared with `/frames/row`; a
//! view of another row, without the attribute, or of a frame the file no
//! longer holds, is replaced or dropped. A views file that is not this
//! results file's (its attribute `source` names the results file: a
//! renamed or copied one's), cannot be read back or belongs to other sizes
//! is made anew; a file of that name that holds results of its own is
//! refused before ([`crate::results_file::foreign_companion`]).

use std::path::{Path, PathBuf};

use hdf5::{File, Hyperslab, Selection};
use ndarray::Array2;
use stickslip_mesh::Mesh;

/// The body's node vectors, as the results file names them.
pub const VECTORS: [&str; 3] = ["displacement", "velocity", "acceleration"];

/// A per-node history under `/contact` that `OUT.contact.xdmf` shows, one
/// view a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ContactField {
    /// Its name under `/contact`, in the results file and the views file.
    pub name: &'static str,
    /// Stored as i8 (the state), else f64.
    pub small: bool,
}

/// The contact fields a run writes, in the order the XDMF lists them.
pub const CONTACT_FIELDS: [ContactField; 4] = [
    ContactField {
        name: "friction_stress",
        small: false,
    },
    ContactField {
        name: "slip_velocity",
        small: false,
    },
    ContactField {
        name: "state",
        small: true,
    },
    ContactField {
        name: "normal_stress",
        small: false,
    },
];

/// The [`CONTACT_FIELDS`] the results file `f` holds for its `n_c` contact
/// nodes down to row `rows - 1`: files of versions before
/// `/contact/normal_stress` lack it. A view of a dataset that is not there
/// reads as HDF5's fill value, so the views and the XML list only these.
pub fn held_contact_fields(f: &File, n_c: usize, rows: usize) -> Vec<ContactField> {
    CONTACT_FIELDS
        .into_iter()
        .filter(|c| {
            f.dataset(&format!("contact/{}", c.name))
                .is_ok_and(|d| matches!(d.shape()[..], [r, n] if r >= rows && n == n_c))
        })
        .collect()
}

/// The views file of the results file `out`: OUT.views.h5 beside it.
pub fn views_path(out: &Path) -> PathBuf {
    out.with_extension("views.h5")
}

/// The segments of the contact surface between two friction nodes
/// `nodes` (mesh indices, as `/contact/nodes`) that are neighbours on a
/// side of the dimension-1 group `group`, as indices into `nodes`,
/// oriented as the group's edges (the body on the left): a quad9 side
/// gives two (corner, mid-side, corner). A segment with a node that
/// carries no friction (its tangential motion held) is left out, since
/// the fields have no value there. The run stores them as
/// `/contact/lines`, since the results file keeps the group's nodes but
/// not its edges.
pub fn contact_lines(mesh: &Mesh, group: &str, nodes: &[usize]) -> Vec<[usize; 2]> {
    let mut index = std::collections::HashMap::with_capacity(nodes.len());
    for (i, &n) in nodes.iter().enumerate() {
        index.insert(n, i);
    }
    let mut lines = Vec::new();
    if let Ok(g) = mesh.group(group) {
        for e in &g.edges {
            let chain: Vec<usize> = match e.mid {
                Some(m) => vec![e.nodes[0], m, e.nodes[1]],
                None => e.nodes.to_vec(),
            };
            for w in chain.windows(2) {
                if let (Some(&a), Some(&b)) = (index.get(&w[0]), index.get(&w[1])) {
                    lines.push([a, b]);
                }
            }
        }
    }
    lines
}

/// The contact surface as the viewers' line cells: the friction nodes'
/// coordinates, in the order of `/contact/nodes`, and `/contact/lines`.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactLine {
    /// Coordinates of `/contact/nodes`.
    pub points: Vec<[f64; 2]>,
    /// Segments: pairs of indices into `points`.
    pub lines: Vec<[usize; 2]>,
}

/// What the views of one results file are views of.
#[derive(Clone, Copy, Debug)]
pub struct Layout<'a> {
    /// Rows of `/mesh/nodes`.
    pub n_nodes: usize,
    /// The contact surface's line, if the case has friction nodes.
    pub contact: Option<&'a ContactLine>,
    /// The contact fields the results file holds ([`held_contact_fields`]).
    pub fields: &'a [ContactField],
}

/// Makes `OUT.views.h5` hold the views of the frames of the results file
/// `out`, and no others: frame k's node vectors are row k of
/// `/displacement` and the others, its contact fields row `rows[k]` of
/// `/contact/*` (its row of `/time`; `rows` has one entry a frame). Views
/// that already say so are kept, the others made.
///
/// The file is written beside, as `OUT.views.h5.part` (a copy of the views
/// file where it has views to keep), and renamed into place: a failure
/// midway leaves the views file as it was, or none, and no `.part`.
///
/// # Errors
/// `out` without a UTF-8 file name; the place beside `out` refusing the
/// file (an [`InputError`](stickslip_case::InputError), exit 2); writing
/// it failing (an error naming the views file, exit 1).
pub fn update(out: &Path, layout: &Layout, frame_rows: &[usize]) -> anyhow::Result<()> {
    let source = file_name(out)?;
    let path = views_path(out);
    let n_c = layout.contact.map_or(0, |c| c.points.len());
    // A file whose views cannot be read back is made anew.
    let kept = File::open(&path)
        .ok()
        .filter(|f| matching(f, source, layout.n_nodes, n_c))
        .and_then(|f| changes(&f, layout, frame_rows).ok());
    if kept
        .as_ref()
        .is_some_and(|c| c.stale.is_empty() && !c.missing)
    {
        return Ok(());
    }
    let part = crate::views_cmd::part_of(&path);
    let stale = kept.as_ref().map(|c| &c.stale[..]);
    let written = write_aside(out, &part, stale, layout, frame_rows)
        .and_then(|()| crate::views_cmd::rename_beside(out, "views", &part, &path));
    if written.is_err() {
        let _ = std::fs::remove_file(&part);
    }
    written
}

/// How a views file departs from the views of its results file's frames.
struct Changes {
    /// Views to remove: past the last frame, or of a row that is no
    /// longer their frame's.
    stale: Vec<String>,
    /// Some frame lacks a view (stale ones included).
    missing: bool,
}

/// [`Changes`] of the views file `f` of `source` against the views of
/// `frame_rows`.
fn changes(f: &File, layout: &Layout, frame_rows: &[usize]) -> hdf5::Result<Changes> {
    let rows = frame_rows.len();
    let mut groups: Vec<(String, bool)> = VECTORS.iter().map(|v| (v.to_string(), false)).collect();
    let n_c = layout.contact.map_or(0, |c| c.points.len());
    if n_c > 0 && f.group("contact").is_ok() {
        groups.extend(
            layout
                .fields
                .iter()
                .map(|c| (format!("contact/{}", c.name), true)),
        );
    }
    let mut c = Changes {
        stale: Vec::new(),
        missing: false,
    };
    for (name, by_history) in groups {
        let Ok(g) = f.group(&name) else {
            c.missing = true;
            continue;
        };
        let mut good = 0;
        for member in g.member_names()? {
            let Ok(k) = member.parse::<usize>() else {
                continue;
            };
            let holds = k < rows
                && (!by_history || viewed_row(&g.dataset(&member)?) == Some(frame_rows[k]));
            if holds {
                good += 1;
            } else {
                c.stale.push(format!("{name}/{member}"));
            }
        }
        c.missing |= good < rows;
    }
    Ok(c)
}

/// The row the view `ds` maps, from its attribute `row` ([`row_view`]'s;
/// a view written without it is made again).
fn viewed_row(ds: &hdf5::Dataset) -> Option<usize> {
    let row = ds.attr("row").and_then(|a| a.read_scalar::<u64>()).ok()?;
    usize::try_from(row).ok()
}

/// [`update`]'s file at `part`: a copy of the views file without its
/// `stale` views (where given), or a new one, with the views it lacks
/// added.
fn write_aside(
    out: &Path,
    part: &Path,
    stale: Option<&[String]>,
    layout: &Layout,
    frame_rows: &[usize],
) -> anyhow::Result<()> {
    let source = file_name(out)?;
    let path = views_path(out);
    let mut file = crate::views_cmd::create_beside(out, "views", part)?;
    let failed =
        |e: anyhow::Error| crate::views_cmd::mid_write(out, "views", &path, format!("{e:#}"));
    let f = if let Some(stale) = stale {
        std::fs::File::open(&path)
            .and_then(|mut from| std::io::copy(&mut from, &mut file))
            .map_err(|e| failed(e.into()))?;
        drop(file);
        let f = File::open_rw(part).map_err(|e| failed(e.into()))?;
        for view in stale {
            f.unlink(view).map_err(|e| failed(e.into()))?;
        }
        f
    } else {
        drop(file);
        create(part, source, layout).map_err(failed)?
    };
    add(&f, source, layout, frame_rows).map_err(|e| failed(e.into()))?;
    // Closed before the rename, so that a failure of its last writes is
    // seen here.
    f.close().map_err(|e| failed(e.into()))
}

/// Adds to the views file `f` the views of `frame_rows` it lacks.
fn add(f: &File, source: &str, layout: &Layout, frame_rows: &[usize]) -> hdf5::Result<()> {
    let rows = frame_rows.len();
    let n_c = layout.contact.map_or(0, |c| c.points.len());
    for name in VECTORS {
        let g = f.group(name)?;
        for k in 0..rows {
            if !g.link_exists(&k.to_string()) {
                vector_view(&g, source, name, layout.n_nodes, k)?;
            }
        }
    }
    if n_c > 0 && f.group("contact").is_ok() {
        for field in layout.fields {
            let src = format!("contact/{}", field.name);
            // A views file made before the results file held the field (a
            // restart of an older file adds /contact/normal_stress) gets
            // its group now.
            let g = match f.group(&src) {
                Ok(g) => g,
                Err(_) => f.create_group(&src)?,
            };
            for (k, &r) in frame_rows.iter().enumerate() {
                if g.link_exists(&k.to_string()) {
                    continue;
                }
                if field.small {
                    row_view::<i8>(&g, source, &src, n_c, (k, r))?;
                } else {
                    row_view::<f64>(&g, source, &src, n_c, (k, r))?;
                }
            }
        }
    }
    f.flush()
}

/// `out`'s file name, by which the views and the XML refer to it.
pub(crate) fn file_name(out: &Path) -> anyhow::Result<&str> {
    out.file_name().and_then(|n| n.to_str()).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the results path has no UTF-8 file name for the views and XDMF files to refer to",
            out.display()
        )
    })
}

/// Whether `f` is a views file of `source` with these sizes.
fn matching(f: &File, source: &str, n_nodes: usize, n_c: usize) -> bool {
    let size = |name: &str| f.attr(name).and_then(|a| a.read_scalar::<u64>()).ok();
    crate::output::text_attr(f, "source").ok().as_deref() == Some(source)
        && size("n_nodes") == Some(n_nodes as u64)
        && size("n_contact") == Some(n_c as u64)
        && VECTORS.iter().all(|v| f.group(v).is_ok())
}

/// A new, empty views file for `source` (the contact line's points and
/// segments written whole: they are the mesh's, not a record's).
fn create(path: &Path, source: &str, layout: &Layout) -> anyhow::Result<File> {
    let f = File::create(path)?;
    crate::output::string_attr(
        &f,
        "about",
        "views (HDF5 virtual datasets) of one frame each of the results file named by `source`, \
         for OUT.xdmf and OUT.contact.xdmf; /NAME/K is row K of /NAME there (frame K), node vectors with z = 0; \
         /contact/NAME/K is row /frames/row[K] of /contact/NAME there (the histories' row of frame K)",
    )?;
    crate::output::string_attr(&f, "source", source)?;
    let n_c = layout.contact.map_or(0, |c| c.points.len());
    f.new_attr::<u64>()
        .create("n_nodes")?
        .write_scalar(&(layout.n_nodes as u64))?;
    f.new_attr::<u64>()
        .create("n_contact")?
        .write_scalar(&(n_c as u64))?;
    for name in VECTORS {
        f.create_group(name)?;
    }
    if let Some(c) = layout.contact.filter(|c| !c.points.is_empty()) {
        let g = f.create_group("contact")?;
        let points = Array2::from_shape_fn((c.points.len(), 2), |(i, k)| c.points[i][k]);
        g.new_dataset_builder()
            .with_data(&points)
            .create("points")?;
        let lines = Array2::from_shape_fn((c.lines.len(), 2), |(i, k)| c.lines[i][k] as i64);
        g.new_dataset_builder().with_data(&lines).create("lines")?;
    }
    Ok(f)
}

/// The source extent a view of row `k` names: one row more than it needs.
/// The hdf5 crate stores a selection that covers its whole extent as
/// "all", and a view of "all" of a one-row extent would read the whole
/// source once the run has written more rows.
fn rows_past(k: usize) -> usize {
    k + 2
}

/// `g/k`: row k of the `[rows, n, 2]` dataset `src` of `source` as `[n, 3]`.
fn vector_view(g: &hdf5::Group, source: &str, src: &str, n: usize, k: usize) -> hdf5::Result<()> {
    let row = Selection::from(Hyperslab::from((k..k + 1, 0..n, 0..2)));
    let cols = Selection::from(Hyperslab::from((0..n, 0..2)));
    g.new_dataset::<f64>()
        .shape((n, 3))
        .fill_value(0.0)
        .virtual_map(source, src, (rows_past(k), n, 2), row, (n, 3), cols)
        .create(k.to_string().as_str())?;
    Ok(())
}

/// `g/k`: row `r` of the `[rows, n]` dataset `src` of `source`, for
/// `(k, r)`.
pub(crate) fn row_view<T: hdf5::H5Type>(
    g: &hdf5::Group,
    source: &str,
    src: &str,
    n: usize,
    (k, r): (usize, usize),
) -> hdf5::Result<()> {
    let row = Selection::from(Hyperslab::from((r..r + 1, 0..n)));
    let view = g
        .new_dataset::<T>()
        .shape(n)
        .virtual_map(source, src, (rows_past(r), n), row, n, ..)
        .create(k.to_string().as_str())?;
    // The row kept beside the mapping, for an update to compare with the
    // frames: the mapping's hyperslab read back through hdf5-metno fails
    // to convert ("blocks can not overlap").
    view.new_attr::<u64>()
        .create("row")?
        .write_scalar(&(r as u64))?;
    Ok(())
}

/// `g/k`: column `c` of row k of the `[rows, n, m]` dataset `src` of
/// `source`, as `[n]`.
pub(crate) fn column_view(
    g: &hdf5::Group,
    source: &str,
    src: &str,
    (n, m): (usize, usize),
    k: usize,
    c: usize,
) -> hdf5::Result<()> {
    let sel = Selection::from(Hyperslab::from((k..k + 1, 0..n, c..c + 1)));
    g.new_dataset::<f64>()
        .shape(n)
        .virtual_map(source, src, (rows_past(k), n, m), sel, n, ..)
        .create(k.to_string().as_str())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad9_sides_give_two_segments_and_held_nodes_none() {
        // Two quad9 cells side by side along y = 0; the contact group is
        // their bottom sides, nodes 0-4-1 and 1-9-10.
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n1 1 \"contact\"\n$EndPhysicalNames\n\
                    $Nodes\n15\n1 0 0 0\n2 2 0 0\n3 2 1 0\n4 0 1 0\n5 1 0 0\n6 2 0.5 0\n7 1 1 0\n8 0 0.5 0\n9 1 0.5 0\n\
                    10 3 0 0\n11 4 0 0\n12 4 1 0\n13 3 1 0\n14 4 0.5 0\n15 3 0.5 0\n$EndNodes\n\
                    $Elements\n4\n1 8 2 1 1 1 2 5\n2 8 2 1 1 2 11 10\n3 10 2 0 1 1 2 3 4 5 6 7 8 9\n4 10 2 0 1 2 11 12 3 10 14 13 6 15\n$EndElements\n";
        let mesh = Mesh::from_bytes(text.as_bytes()).unwrap();
        let g = mesh.group("contact").unwrap();
        let mut nodes = g.nodes.clone();
        // Along the face: x = 0, 1, 2, 3, 4.
        nodes.sort_by(|&a, &b| mesh.nodes[a][0].total_cmp(&mesh.nodes[b][0]));
        let mut lines = contact_lines(&mesh, "contact", &nodes);
        lines.sort();
        assert_eq!(lines, [[0, 1], [1, 2], [2, 3], [3, 4]]);
        // The node at x = 0 held: its segment goes, the others stay.
        let mut lines = contact_lines(&mesh, "contact", &nodes[1..]);
        lines.sort();
        assert_eq!(lines, [[0, 1], [1, 2], [2, 3]]);
    }
}
