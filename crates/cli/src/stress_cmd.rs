//! `stickslip stress OUT.h5`: a finished run's stress fields in a file
//! beside its results, for ParaView.
//!
//! The run itself writes no stresses (a record is u, v, a and the friction
//! fields; stresses at every node and step would cost a pass over the
//! cells per record, which most runs never read). This command forms them
//! afterwards from `/displacement` and the material of the case the file
//! stores, as `stickslip probe --field sxx` does at one node: at each node
//! the average of its cells' σ = D ε there (`stickslip_fem::nodal_stresses`),
//! into `OUT.stress.h5`: `/stress` [n_frames, n_nodes, 3] (σ_xx, σ_yy,
//! σ_xy) and `/von_mises` [n_frames, n_nodes] (a row per frame, as
//! `/displacement`), with a view of each frame's
//! σ_xx, σ_yy, σ_xy and von Mises under `/views`; and writes the viewers'
//! files as `stickslip views` does, `OUT.xdmf` listing the stresses. The
//! results file is only read: a full disk or a kill leaves it as it was
//! (the stress file is written beside and renamed into place). A new run
//! or a `--restart` on OUT.h5 removes OUT.stress.h5 (it would end where
//! the earlier run ended): run the command again after it.

use std::path::Path;
use std::time::Instant;

use hdf5::File;
use ndarray::{s, Array1, Array2};

use stickslip_case::InputError;

/// Writes the stress datasets of the results file `path` and the viewers'
/// files ([`crate::views_cmd::write`]); returns the records and nodes
/// written, and what the viewers' files hold.
///
/// # Errors
/// An [`InputError`] (exit 2) for a file that is missing, being written,
/// or not a results file of `stickslip run`, for a disk without room for
/// the stresses, and for a place beside it that cannot take the stress
/// file or the viewers' files (a directory in the way, a directory this
/// process may not write: a create or rename that fails by the OS error
/// [`crate::sys::place_error`]). Other errors (exit 1), each naming its
/// file: reading the results file failing (`/displacement` of a damaged
/// file), and writing a file failing (a disk filled meanwhile, a quota, a
/// file-size limit), its start (HDF5's first write) too. Nothing partial
/// is left: the stress file is renamed into place once whole.
pub fn command(
    path: &Path,
    quiet: bool,
) -> anyhow::Result<(usize, usize, crate::views_cmd::Written)> {
    let name = path.display().to_string();
    // No run may start on the file while its stresses are formed.
    let (_lock, f) = crate::results_file::open_finished(path, true)?;
    let target = stress_path(path);
    let part = part_path(path);
    // Refused before the stresses are formed, which may take a while.
    let mut beside = vec![target.clone(), part.clone()];
    beside.extend(crate::views_cmd::files(path));
    crate::views_cmd::check_beside(path, "stress", &beside)?;
    let (mesh, material) = crate::probe::stored_model(&f, &name)?;
    let n_nodes = mesh.nodes.len();
    // Each row is read as the mesh's displacement.
    crate::probe::vector_rows(&f, &name, "displacement", n_nodes)?;
    let u = f.dataset("displacement").map_err(|e| unread(path, e))?;
    // A record here is a frame: the rows of /displacement.
    let times = crate::frames::Frames::read(&f, &name)?.time;
    let rows = times.len().min(u.shape().first().copied().unwrap_or(0));
    let complete = f
        .attr("complete")
        .and_then(|a| a.read_scalar::<bool>())
        .unwrap_or(false);
    if !complete && !quiet {
        say!(
            "stress: note: {name} is of a run that did not complete; its {rows} records get their stresses \
             (a --restart of the run removes them: run this again after it)"
        );
    }
    let old = std::fs::metadata(&target).map_or(0, |m| m.len());
    let need = (rows * n_nodes * 32) as u64 + (1 << 20);
    if let Some(free) = crate::results_file::free_bytes(&target) {
        if free.saturating_add(old) < need {
            return Err(InputError(format!(
                "{}: the stresses of {rows} records need about {:.1} MB and its disk has {:.1} MB free; \
                 make room and run this again",
                target.display(),
                need as f64 / 1e6,
                free as f64 / 1e6
            ))
            .into());
        }
    }
    // Written beside and renamed into place: a failure leaves no half file.
    let written = write_stresses(path, &u, &mesh, &material, rows, quiet)
        .and_then(|()| crate::views_cmd::rename_beside(path, "stress", &part, &target));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&part);
        return Err(e);
    }
    drop((u, f));
    let written = crate::views_cmd::write(path)?;
    Ok((rows, n_nodes, written))
}

/// The stress file of the results file `out`: OUT.stress.h5 beside it.
pub fn stress_path(out: &Path) -> std::path::PathBuf {
    out.with_extension("stress.h5")
}

/// Where [`stress_path`] is written before it is renamed into place.
fn part_path(out: &Path) -> std::path::PathBuf {
    crate::views_cmd::part_of(&stress_path(out))
}

/// A failure to read `/displacement` of the results file `out`: the
/// error of the work (exit 1), naming it, and not the stress file.
fn unread(out: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: cannot read /displacement: {e}; the file may be damaged (h5dump -H shows what HDF5 \
         can read of it): run the case again for a whole one",
        out.display()
    )
}

/// `/stress` and `/von_mises` of `rows` records of `u`, the displacement
/// of the results file `out`, into a new file at [`part_path`], to be
/// renamed to [`stress_path`].
///
/// # Errors
/// Creating the file failing: [`crate::views_cmd::placed`]'s (the place,
/// exit 2, or the disk); reading `u` failing: an error naming `out`;
/// writing into the file failing: an error naming [`stress_path`], the
/// file the user knows.
fn write_stresses(
    out: &Path,
    u: &hdf5::Dataset,
    mesh: &stickslip_mesh::Mesh,
    material: &stickslip_fem::Material,
    rows: usize,
    quiet: bool,
) -> anyhow::Result<()> {
    let part = part_path(out);
    crate::views_cmd::create_beside(out, "stress", &part)?;
    let g = File::create(&part).map_err(|e| write_failed(out, e.into()))?;
    // Whose stresses these are, for the reader (a renamed results file's
    // companion still names the old one).
    let source = crate::views::file_name(out)?;
    crate::output::string_attr(&g, "source", source).map_err(|e| write_failed(out, e))?;
    fill(&g, out, u, mesh, material, rows, quiet)?;
    // Closed before the rename, so that a failure of its last writes is
    // seen here.
    g.close().map_err(|e| write_failed(out, e.into()))
}

/// A failed write into the stress file of the results file `out`: the
/// work's (exit 1), naming [`stress_path`].
fn write_failed(out: &Path, e: anyhow::Error) -> anyhow::Error {
    crate::views_cmd::mid_write(out, "stress", &stress_path(out), format!("{e:#}"))
}

/// [`write_stresses`] into the file `g` it created.
fn fill(
    g: &File,
    out: &Path,
    u: &hdf5::Dataset,
    mesh: &stickslip_mesh::Mesh,
    material: &stickslip_fem::Material,
    rows: usize,
    quiet: bool,
) -> anyhow::Result<()> {
    let n_nodes = mesh.nodes.len();
    let failed = |e: hdf5::Error| write_failed(out, e.into());
    let (stress, mises) = datasets(g, n_nodes, rows).map_err(|e| write_failed(out, e))?;
    let started = Instant::now();
    let mut last = Instant::now();
    for k in 0..rows {
        let row: Vec<f64> = u
            .read_slice_2d::<f64, _>(s![k, .., ..])
            .map_err(|e| unread(out, e))?
            .iter()
            .copied()
            .collect();
        let st = stickslip_fem::nodal_stresses(mesh, material, &row);
        let a = Array2::from_shape_fn((n_nodes, 3), |(i, c)| st[i][c]);
        stress.write_slice(&a, s![k, .., ..]).map_err(failed)?;
        let vm: Array1<f64> = st
            .iter()
            .map(|&s| stickslip_fem::von_mises(material, s))
            .collect();
        mises.write_slice(&vm, s![k, ..]).map_err(failed)?;
        if !quiet && last.elapsed().as_secs() >= 10 {
            last = Instant::now();
            say!(
                "stress: {} of {rows} records, {:.0} s",
                k + 1,
                started.elapsed().as_secs_f64()
            );
        }
    }
    stress_views(g, n_nodes, rows).map_err(failed)?;
    // Which displacements these are: a results file copied over OUT.h5
    // keeps the name `source` gives, not its last record's bits.
    if let Some(hash) = last_record_hash(u, rows) {
        crate::output::put_scalar(g, "last_record_hash", hash).map_err(|e| write_failed(out, e))?;
    }
    g.flush().map_err(failed)
}

/// FNV-1a of the bits of record `rows − 1` of the displacement `u` (None
/// where it does not read): what `views` matches a stress file's
/// `last_record_hash` against.
pub(crate) fn last_record_hash(u: &hdf5::Dataset, rows: usize) -> Option<u64> {
    let row = u
        .read_slice_2d::<f64, _>(s![rows.checked_sub(1)?, .., ..])
        .ok()?;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in row.iter() {
        for b in v.to_bits().to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    Some(h)
}

/// The empty `/stress` and `/von_mises` of `rows` records in `g`.
fn datasets(
    g: &File,
    n_nodes: usize,
    rows: usize,
) -> anyhow::Result<(hdf5::Dataset, hdf5::Dataset)> {
    let stress = g
        .new_dataset::<f64>()
        .chunk((1, n_nodes, 3))
        .shape((rows, n_nodes, 3))
        .create("stress")?;
    let mises = g
        .new_dataset::<f64>()
        .chunk((1, n_nodes))
        .shape((rows, n_nodes))
        .create("von_mises")?;
    let about = "at each node the average of its cells' stress sigma = D eps there, from /displacement \
                 of the results file and the material of its case (stickslip stress); [sigma_xx, sigma_yy, sigma_xy]";
    crate::output::string_attr(&stress, "about", about)?;
    crate::output::string_attr(
        &mises,
        "about",
        "von Mises stress of /stress (plane strain: sigma_zz = nu (sigma_xx + sigma_yy))",
    )?;
    Ok((stress, mises))
}

/// One view per record and scalar for the XDMF readers, in `g` (which
/// goes with the stresses): "." is that file, whatever its name.
fn stress_views(g: &File, n_nodes: usize, rows: usize) -> hdf5::Result<()> {
    let views = g.create_group("views")?;
    for (c, name) in crate::xdmf::STRESS_VIEWS.iter().enumerate() {
        let v = views.create_group(name)?;
        for k in 0..rows {
            if c < 3 {
                crate::views::column_view(&v, ".", "stress", (n_nodes, 3), k, c)?;
            } else {
                crate::views::row_view::<f64>(&v, ".", "von_mises", n_nodes, (k, k))?;
            }
        }
    }
    Ok(())
}
