//! `stickslip views OUT.h5`: the files ParaView, meshio and PyVista open,
//! written beside a results file: `OUT.xdmf` (the body), `OUT.contact.xdmf`
//! (Γ_C as line cells) and `OUT.views.h5` (what they point to,
//! [`crate::views`]), for the records the file holds, of a finished run or
//! of one interrupted or failed midway. With `OUT.stress.h5` beside it
//! (`stickslip stress`, which calls [`write()`] itself) `OUT.xdmf` lists
//! the stresses too.
//!
//! The run writes none of these: their cost grows with the records, and a
//! run of many cheap records paid several times its own time for them
//! (docs/performance.md). The results file is only read; each file is
//! written beside and renamed into place; the views file keeps the views
//! that still hold (a copy of it gets the others), so running the command
//! again after a restart makes only the views the restart changed.

use std::path::{Path, PathBuf};

use hdf5::File;
use stickslip_case::InputError;
use stickslip_mesh::CellKind;

use crate::views::{ContactLine, Layout};
use crate::xdmf::{ContactInfo, XdmfInfo};

/// About the bytes per record the command writes beside the results:
/// the XML of both files (each character of a longer file name adds about
/// ten) and seven views in `OUT.views.h5`, as measured on the paper's slab
/// (docs/performance.md, "The viewers' files").
const BYTES_PER_RECORD: usize = 6500;

/// What [`write()`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Written {
    /// Records listed.
    pub records: usize,
    /// `OUT.contact.xdmf` written (the file has a contact line).
    pub contact: bool,
    /// `OUT.xdmf` lists the stresses of `OUT.stress.h5`.
    pub stress: bool,
    /// Why the contact surface is not shown, where it has friction nodes.
    pub note: Option<String>,
}

/// `stickslip views OUT.h5`: checks that `path` is a results file no run
/// is writing, then writes the viewers' files beside it ([`write()`]).
///
/// # Errors
/// As [`write()`]; an [`InputError`] too for a file that is missing or
/// being written.
pub fn command(path: &Path) -> anyhow::Result<Written> {
    // No run may start on the file while its views are made.
    let (_lock, f) = crate::results_file::open_finished(path, false)?;
    drop(f);
    check_beside(path, "views", &files(path))?;
    write(path)
}

/// The files `stickslip views` writes beside the results file `out`, and
/// the temporary ones it renames into place.
pub(crate) fn files(out: &Path) -> Vec<PathBuf> {
    let xml = [
        crate::xdmf::xdmf_path(out),
        crate::xdmf::contact_xdmf_path(out),
    ];
    let views = crate::views::views_path(out);
    let parts = [&views, &xml[0], &xml[1]].map(|p| part_of(p));
    let mut all = vec![views];
    all.extend(xml);
    all.extend(parts);
    all
}

/// Where `path` is written before it is renamed into place: `path.part`.
pub(crate) fn part_of(path: &Path) -> PathBuf {
    let mut part = path.as_os_str().to_owned();
    part.push(".part");
    PathBuf::from(part)
}

/// What to do where `stickslip COMMAND` cannot write beside the results
/// file `out`: the files must stay beside it (the views name it by file
/// name only), so the way out is a writable copy.
fn elsewhere(out: &Path, command: &str) -> String {
    format!(
        "`stickslip {command}` writes its files beside the results file, which they refer to by \
         name; make that directory writable, or copy {} into a writable directory and run \
         `stickslip {command}` on the copy there",
        out.display()
    )
}

/// Refuses to start `stickslip COMMAND` on the results file `out` where
/// `files`, which it writes beside it, cannot be written: a directory (or
/// a device, FIFO or socket) in the place of one, or a directory this
/// process may not write. Said before any work, naming the path.
///
/// # Errors
/// The [`InputError`] naming the path and what to do.
pub(crate) fn check_beside(out: &Path, command: &str, files: &[PathBuf]) -> Result<(), InputError> {
    for path in files {
        let Ok(meta) = std::fs::symlink_metadata(path) else {
            continue;
        };
        if meta.is_dir() {
            return Err(InputError(format!(
                "{}: a directory of that name is where `stickslip {command}` writes its file for {}; \
                 remove or rename the directory and run this again",
                path.display(),
                out.display()
            )));
        }
        if !meta.is_file() && !meta.file_type().is_symlink() {
            return Err(InputError(format!(
                "{} exists and is not a regular file (a device, FIFO or socket), where \
                 `stickslip {command}` writes its file for {}; remove it and run this again",
                path.display(),
                out.display()
            )));
        }
    }
    use crate::results_file::{foreign_companion, foreign_message, Companion};
    for kind in [Companion::Views, Companion::Stress] {
        if !files.contains(&kind.path(out)) {
            continue;
        }
        if let Some(what) = foreign_companion(out, kind) {
            return Err(InputError(foreign_message(
                out,
                kind,
                &what,
                &format!("`stickslip {command}`"),
            )));
        }
    }
    // The viewers' XML files are replaced whole: one of those names that
    // holds something else (notes, another program's HDF5) is the user's.
    for xml in [
        crate::xdmf::xdmf_path(out),
        crate::xdmf::contact_xdmf_path(out),
    ] {
        if files.contains(&xml) && !is_xdmf_or_empty(&xml) {
            return Err(InputError(format!(
                "{} is not an XDMF file, although named as the viewers' file of {}: \
                 `stickslip {command}` would replace it; move or rename it and run this again",
                xml.display(),
                out.display()
            )));
        }
    }
    named_in_xml(out)?;
    let dir = crate::results_file::dir_of(out);
    if !crate::sys::can_write_in(dir) {
        return Err(InputError(format!(
            "{}: cannot write in the directory {} (read-only, or not yours); {}",
            out.display(),
            dir.display(),
            elsewhere(out, command)
        )));
    }
    Ok(())
}

/// Refuses a results file `out` the XDMF files cannot name
/// ([`crate::results_file::refer_by_name`]).
///
/// # Errors
/// The [`InputError`] saying why and what to do.
fn named_in_xml(out: &Path) -> Result<(), InputError> {
    crate::results_file::refer_by_name(out).map_err(|why| {
        let renamed = crate::results_file::colon_free_name(out);
        InputError(format!(
            "{}: {why}; rename it without ':' (e.g. to {renamed}) and run this again",
            out.display()
        ))
    })
}

/// Whether `path` is empty or starts as an XDMF file does (its first
/// kilobyte holds `<Xdmf`): the viewers' file of some writer, stickslip's
/// or another's, which a viewers' file may replace.
fn is_xdmf_or_empty(path: &Path) -> bool {
    use std::io::Read;
    let Ok(f) = std::fs::File::open(path) else {
        return true;
    };
    let mut head = Vec::with_capacity(1024);
    if f.take(1024).read_to_end(&mut head).is_err() {
        return true;
    }
    head.is_empty() || head.windows(5).any(|w| w == b"<Xdmf")
}

/// Creates (or truncates) `path` beside the results file `out` for
/// `stickslip COMMAND`, before HDF5 or a writer fills it, so that the OS
/// says whether the place or the work failed: HDF5's create writes at
/// once and its error does not say which.
///
/// # Errors
/// [`placed`]'s.
pub(crate) fn create_beside(
    out: &Path,
    command: &str,
    path: &Path,
) -> anyhow::Result<std::fs::File> {
    std::fs::File::create(path).map_err(|e| placed(out, command, path, e))
}

/// Renames `from` to `to` beside the results file `out`.
///
/// # Errors
/// [`placed`]'s, naming `to`.
pub(crate) fn rename_beside(
    out: &Path,
    command: &str,
    from: &Path,
    to: &Path,
) -> anyhow::Result<()> {
    std::fs::rename(from, to).map_err(|e| placed(out, command, to, e))
}

/// `e`, the OS error of creating, renaming or writing `path` beside the
/// results file `out`: [`beside_failed`] (exit 2) where the place must
/// change ([`crate::sys::place_error`]), else [`mid_write`] (exit 1).
pub(crate) fn placed(out: &Path, command: &str, path: &Path, e: std::io::Error) -> anyhow::Error {
    if crate::sys::place_error(&e) {
        beside_failed(out, command, path, e).into()
    } else {
        mid_write(out, command, path, e)
    }
}

/// A failed create or rename of `path` beside the results file `out` (the
/// directory made read-only, or something put in the way, under the
/// command) as the [`InputError`] naming it and what to do.
pub(crate) fn beside_failed(
    out: &Path,
    command: &str,
    path: &Path,
    e: impl std::fmt::Display,
) -> InputError {
    InputError(format!(
        "cannot write {}: {e}; {}",
        path.display(),
        elsewhere(out, command)
    ))
}

/// A failed write into `path` beside the results file `out` once it was
/// created (a full disk, an I/O error): an error of the work (exit 1),
/// naming it and what to do.
pub(crate) fn mid_write(
    out: &Path,
    command: &str,
    path: &Path,
    e: impl std::fmt::Display,
) -> anyhow::Error {
    // HDF5's messages carry a ctime(3) date with its newline.
    let e = e.to_string().replace('\n', "");
    anyhow::anyhow!(
        "cannot write {}: {e}; make room on its disk if it is full, and run `stickslip {command} {}` again",
        path.display(),
        out.display()
    )
}

/// Writes `OUT.views.h5`, `OUT.xdmf` and `OUT.contact.xdmf` for the
/// records of the results file `out` (the views first, so that the XML
/// never names a view that is not there). The caller keeps runs off the
/// file.
///
/// # Errors
/// An [`InputError`] (exit 2) for a file without the datasets a run
/// writes, a disk without room, or a place beside it that cannot take a
/// file (by the OS error of its create or rename:
/// [`crate::sys::place_error`]); other errors (exit 1), naming the file,
/// for a results file that does not read and a write that fails (its
/// start too). Every file is written beside and renamed into place once
/// whole, so a failure leaves none partial.
pub fn write(out: &Path) -> anyhow::Result<Written> {
    let name = out.display().to_string();
    // The views and the XML name the results file by its file name.
    crate::views::file_name(out).map_err(|e| {
        InputError(format!(
            "{e}; rename it (and its files beside it) with a UTF-8 name"
        ))
    })?;
    named_in_xml(out)?;
    let f = File::open(out).map_err(|e| {
        InputError(format!(
            "{name}: cannot open it as HDF5: {e}; give a results file written by `stickslip run`"
        ))
    })?;
    let bad = |what: &str| {
        InputError(format!(
            "{name}: {what}; give a results file written by `stickslip run`"
        ))
    };
    let shape = |path: &str| {
        f.dataset(path)
            .map(|d| d.shape())
            .map_err(|_| bad(&format!("no /{path}")))
    };
    let nodes = shape("mesh/nodes")?;
    let cells = shape("mesh/cells")?;
    // The views and the XML take these shapes as they are.
    if !matches!(nodes[..], [n, 2] if n > 0) {
        return Err(bad(&format!(
            "/mesh/nodes has shape {nodes:?}, expected [n, 2] with n > 0"
        ))
        .into());
    }
    let kind = match f
        .group("mesh")
        .ok()
        .and_then(|g| crate::output::text_attr(&g, "kind").ok())
        .as_deref()
    {
        Some("quad4") => CellKind::Quad4,
        Some("quad9") => CellKind::Quad9,
        other => {
            return Err(bad(&format!(
                "/mesh has cell kind {other:?}, not quad4 or quad9"
            ))
            .into())
        }
    };
    if !matches!(cells[..], [_, k] if k == kind.nodes_per_cell()) {
        return Err(bad(&format!(
            "/mesh/cells has shape {cells:?}, expected [cells, {}] for {} cells",
            kind.nodes_per_cell(),
            kind.name()
        ))
        .into());
    }
    let n_nodes = nodes[0];
    let mut vector_rows = usize::MAX;
    for v in crate::views::VECTORS {
        vector_rows = vector_rows.min(crate::probe::vector_rows(&f, &name, v, n_nodes)?);
    }
    // A record here is a frame: the fields' rows and their contact rows.
    let frames = crate::frames::Frames::read(&f, &name)?;
    let times = frames.time;
    // A run killed between writing /frames and the vectors: list the
    // frames every dataset holds.
    let rows = times.len().min(vector_rows);
    let (contact, note) = contact_line(&f, out)?;
    // The histories' rows the frames name, which every contact field
    // listed must hold.
    let history_rows = frames.row[..rows].iter().max().map_or(0, |&r| r + 1);
    let fields = crate::views::held_contact_fields(
        &f,
        contact.as_ref().map_or(0, |c| c.points.len()),
        history_rows,
    );
    // Files written before it have no /contact/surface: one surface.
    let surface = f.link_exists("contact/surface");
    let (stress, stale) = match stress_name(&f, out, rows) {
        Err(stale) => (None, Some(stale)),
        Ok(name) => (name, None),
    };
    let note = match (note, stale) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    };
    drop(f);

    let need = (rows * BYTES_PER_RECORD) as u64 + (1 << 20);
    if let Some(free) = crate::results_file::free_bytes(out) {
        if free < need {
            return Err(InputError(format!(
                "{}: the viewers' files of {rows} records need about {:.1} MB beside it and its disk \
                 has {:.1} MB free; make room and run this again",
                name,
                need as f64 / 1e6,
                free as f64 / 1e6
            ))
            .into());
        }
    }
    let layout = Layout {
        n_nodes,
        contact: contact.as_ref(),
        fields: &fields,
    };
    let beside = |path: &Path, e: std::io::Error| placed(out, "views", path, e);
    crate::views::update(out, &layout, &frames.row[..rows])?;
    let info = XdmfInfo {
        n_nodes,
        kind,
        n_cells: cells.first().copied().unwrap_or(0),
        times: &times[..rows],
        stress: stress.as_deref(),
    };
    let path = crate::xdmf::xdmf_path(out);
    crate::xdmf::write_xdmf(out, &info).map_err(|e| beside(&path, e))?;
    // A surface of one node has no line to show.
    let line = contact.filter(|c| !c.lines.is_empty());
    let contact_path = crate::xdmf::contact_xdmf_path(out);
    match &line {
        Some(c) => crate::xdmf::write_contact_xdmf(
            out,
            &times[..rows],
            &ContactInfo {
                n_c: c.points.len(),
                n_lines: c.lines.len(),
                surface,
                fields: &fields,
            },
        )
        .map_err(|e| beside(&contact_path, e))?,
        // One of an earlier results file would list other records.
        None => {
            let _ = std::fs::remove_file(&contact_path);
        }
    }
    Ok(Written {
        records: rows,
        contact: line.is_some(),
        stress: stress.is_some(),
        note,
    })
}

/// The contact line of the results file `f`: the friction nodes'
/// coordinates and `/contact/lines`; `None` without friction nodes, and
/// with a note where the file has them but no lines (a file of a version
/// before `/contact/lines`).
fn contact_line(f: &File, out: &Path) -> anyhow::Result<(Option<ContactLine>, Option<String>)> {
    let name = out.display();
    // A damaged file (a dataset of another shape or type, a flipped
    // byte) is the user's input: named, exit 2.
    let unread = |what: &str, e: hdf5::Error| {
        InputError(format!(
            "{name}: cannot read {what}: {e}; the file is damaged: give a results file written \
             by `stickslip run` (or run its case again)"
        ))
    };
    let Ok(nodes) = f.dataset("contact/nodes") else {
        return Ok((None, None));
    };
    let nodes = nodes
        .read_1d::<i64>()
        .map_err(|e| unread("/contact/nodes", e))?;
    let Ok(lines) = f.dataset("contact/lines") else {
        return Ok((
            None,
            Some(format!(
                "{name} has no /contact/lines (a file of an earlier version): {} is not written; \
                 a new run of the case stores them",
                crate::xdmf::contact_xdmf_path(out).display()
            )),
        ));
    };
    let xy = f
        .dataset("mesh/nodes")
        .and_then(|d| d.read_2d::<f64>())
        .map_err(|e| unread("/mesh/nodes", e))?;
    let n_c = nodes.len();
    let point = |&n: &i64| {
        usize::try_from(n)
            .ok()
            .filter(|&n| n < xy.nrows())
            .map(|n| [xy[[n, 0]], xy[[n, 1]]])
    };
    let points: Option<Vec<[f64; 2]>> = nodes.iter().map(point).collect();
    let lines = lines
        .read_2d::<i64>()
        .map_err(|e| unread("/contact/lines", e))?;
    let index = |v: i64| usize::try_from(v).ok().filter(|&i| i < n_c);
    let segments: Option<Vec<[usize; 2]>> = lines
        .rows()
        .into_iter()
        .map(|r| Some([index(r[0])?, index(r[1])?]))
        .collect();
    match (points, segments, lines.ncols()) {
        (Some(points), Some(lines), 2) => Ok((Some(ContactLine { points, lines }), None)),
        _ => Err(InputError(format!(
            "{name}: /contact/nodes or /contact/lines name nodes that are not there; \
             give a results file written by `stickslip run`"
        ))
        .into()),
    }
}

/// The file name of `OUT.stress.h5` beside `out`, if it holds the views of
/// at least `rows` records (one of fewer would leave records without
/// stresses; a run or restart removes it anyway); `Err` with a note where
/// it holds the stresses of other displacements than `out`'s.
fn stress_name(f: &File, out: &Path, rows: usize) -> Result<Option<String>, String> {
    let path = crate::results_file::Companion::Stress.path(out);
    let Some((name, g)) = stress_listed(out, rows) else {
        return Ok(None);
    };
    match of_these_records(f, &g) {
        Some(false) => Err(format!(
            "{} holds the stresses of other displacements than {}'s (a results file copied \
             over it?): they are left out; `stickslip stress {}` forms them anew",
            path.display(),
            out.display(),
            out.display()
        )),
        _ => Ok(Some(name)),
    }
}

/// Whether the stress file `g` was formed from the displacements of the
/// results file `f` (its `last_record_hash` against `f`'s record of that
/// index); `None` where that cannot be told (stress files of earlier
/// versions).
fn of_these_records(f: &File, g: &File) -> Option<bool> {
    let stored = g.attr("last_record_hash").ok()?.read_scalar::<u64>().ok()?;
    let records = g.dataset("von_mises").ok()?.shape().first().copied()?;
    let now = f
        .dataset("displacement")
        .ok()
        .and_then(|u| crate::stress_cmd::last_record_hash(&u, records));
    Some(now == Some(stored))
}

/// [`stress_name`]'s file name, and the file open, where the stress file
/// is these stresses by its name and records.
fn stress_listed(out: &Path, rows: usize) -> Option<(String, File)> {
    use crate::results_file::{foreign_to_read, Companion};
    let path = Companion::Stress.path(out);
    // A file of that name that is not these stresses (another run's
    // results, another file's stresses: `source` names another file, and
    // an earlier version's stresses, without it, are this file's only if
    // nothing says otherwise) is not listed; one a viewer holds open is.
    if foreign_to_read(out, Companion::Stress).is_some() {
        return None;
    }
    let g = File::open(&path).ok()?;
    let ours = crate::views::file_name(out).ok()?;
    if crate::output::text_attr(&g, "source").is_ok_and(|s| s != ours) {
        return None;
    }
    for v in crate::xdmf::STRESS_VIEWS {
        if (g.group(&format!("views/{v}")).ok()?.len() as usize) < rows {
            return None;
        }
    }
    let name = path.file_name()?.to_str()?.to_string();
    Some((name, g))
}

/// The line `stickslip views` closes with: what it wrote for `out` and
/// how to open it.
pub fn summary(out: &Path, w: &Written) -> String {
    let xdmf = crate::xdmf::xdmf_path(out);
    let mut files = xdmf.display().to_string();
    if w.contact {
        files.push_str(&format!(
            " and {}",
            crate::xdmf::contact_xdmf_path(out).display()
        ));
    }
    let stress = if w.stress { ", with the stresses" } else { "" };
    format!(
        "views: {} records in {files}{stress} (pointing into {} and {}); open {} in ParaView \
         (any of its XDMF readers), or read it with meshio.xdmf.TimeSeriesReader or pyvista.read",
        w.records,
        out.display(),
        crate::views::views_path(out).display(),
        xdmf.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A create or rename refused where the place must change is bad
    /// input, exit 2; the disk, a quota, a file-size limit or an I/O error
    /// failing it is the work's, exit 1, naming the file.
    #[test]
    fn the_place_is_bad_input_and_the_writing_a_failure() {
        let (out, path) = (Path::new("d/run.h5"), Path::new("d/run.xdmf"));
        let os = std::io::Error::from_raw_os_error;
        for errno in [
            libc::EACCES,
            libc::EPERM,
            libc::EROFS,
            libc::EISDIR,
            libc::ENOTDIR,
            libc::ENOENT,
        ] {
            let e = placed(out, "views", path, os(errno));
            let input = e.downcast_ref::<InputError>().expect("bad input");
            assert!(
                input.0.contains("cannot write d/run.xdmf")
                    && input.0.contains("writable directory"),
                "{input}"
            );
        }
        for errno in [libc::ENOSPC, libc::EDQUOT, libc::EFBIG, libc::EIO] {
            let e = placed(out, "views", path, os(errno));
            assert!(e.downcast_ref::<InputError>().is_none(), "{e}");
            let e = e.to_string();
            assert!(
                e.contains("cannot write d/run.xdmf") && e.contains("stickslip views d/run.h5"),
                "{e}"
            );
        }
        // A write's error, as the XML writer gives it, is the work's
        // whatever its OS error.
        let written = std::io::Error::new(std::io::ErrorKind::PermissionDenied, os(libc::EACCES));
        assert!(placed(out, "views", path, written)
            .downcast_ref::<InputError>()
            .is_none());
    }
}
