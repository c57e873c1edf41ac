//! The XDMF 3 companions of a results file, for ParaView, meshio and
//! PyVista.
//!
//! `OUT.xdmf` (the body) and `OUT.contact.xdmf` (the contact surface Γ_C
//! as line cells) hold no numbers, only XML that points into `OUT.h5` and
//! `OUT.views.h5` by file name (the files sit side by side and move
//! together): each a temporal collection with one uniform grid per record.
//! The body's grid has the mesh (`/mesh/cells`, `/mesh/nodes`) and the
//! node vectors displacement, velocity and acceleration; the contact
//! grid has the friction nodes joined by segments, their arc length `s`
//! and the contact fields the results file holds (friction stress, slip
//! velocity, state and normal stress; files of earlier versions lack the
//! last, and their XML omits it). Every per-record
//! array is a whole dataset of `OUT.views.h5` (a view of one row of the
//! results file, [`crate::views`]), so that no reader needs XDMF's
//! HyperSlab items: ParaView's three XDMF readers, meshio's
//! `TimeSeriesReader` and `pyvista.read` read the files as they are.
//! Two files rather than one grid collection per record: meshio reads one
//! uniform grid per time and PyVista then gives a plain mesh.
//!
//! Cell node order needs no permutation: quad4 corners counter-clockwise and
//! quad9 as in `stickslip_mesh::GMSH_TO_FEM_QUAD9` are XDMF's (and VTK's)
//! `Quadrilateral` and `Quadrilateral_9` orders.

use std::io::Write;
use std::path::{Path, PathBuf};

use stickslip_mesh::CellKind;

use crate::views::{views_path, ContactField, VECTORS};

/// What the XML needs to know about a results file: its sizes and times.
#[derive(Clone, Copy, Debug)]
pub struct XdmfInfo<'a> {
    /// Rows of `/mesh/nodes`.
    pub n_nodes: usize,
    /// Cell kind of `/mesh/cells`.
    pub kind: CellKind,
    /// Rows of `/mesh/cells`.
    pub n_cells: usize,
    /// `/time`, one entry per record written so far.
    pub times: &'a [f64],
    /// The file name of `stickslip stress`'s file beside the results file,
    /// whose views `/views/NAME/K` give σ_xx, σ_yy, σ_xy and von Mises of
    /// record K as scalars (ParaView would call a 3-vector's third
    /// component "Z").
    pub stress: Option<&'a str>,
}

/// What the contact XML needs to know about a results file's contact line.
#[derive(Clone, Copy, Debug)]
pub struct ContactInfo<'a> {
    /// Rows of `/contact/nodes`.
    pub n_c: usize,
    /// Rows of `/contact/lines`.
    pub n_lines: usize,
    /// The file has `/contact/surface`.
    pub surface: bool,
    /// The contact fields the file holds, whose views the XML names
    /// ([`crate::views::held_contact_fields`]).
    pub fields: &'a [ContactField],
}

/// The body's XDMF file of the results file `out`: OUT.xdmf beside it.
pub fn xdmf_path(out: &Path) -> PathBuf {
    out.with_extension("xdmf")
}

/// The contact surface's XDMF file of `out`: OUT.contact.xdmf beside it.
pub fn contact_xdmf_path(out: &Path) -> PathBuf {
    out.with_extension("contact.xdmf")
}

/// Escapes the five XML special characters of a file name.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// The XML of `OUT.xdmf` for the results file named `h5_name` (a file
/// name, no directory).
pub fn xdmf_text(h5_name: &str, info: &XdmfInfo) -> String {
    let mut x = Vec::with_capacity(1024 + info.times.len() * 1400);
    write_body(&mut x, h5_name, info).expect("writing to memory");
    String::from_utf8(x).expect("the XML is UTF-8")
}

/// The XML of `OUT.contact.xdmf` for the results file named `h5_name`
/// and its contact line `info`.
pub fn contact_text(h5_name: &str, times: &[f64], info: &ContactInfo) -> String {
    let mut x = Vec::with_capacity(1024 + times.len() * 1600);
    write_contact(&mut x, h5_name, times, info).expect("writing to memory");
    String::from_utf8(x).expect("the XML is UTF-8")
}

/// The opening of a file: one temporal collection named `name`.
fn open_collection(x: &mut impl Write, name: &str) -> std::io::Result<()> {
    x.write_all(b"<?xml version=\"1.0\" encoding=\"utf-8\"?>\n")?;
    x.write_all(b"<Xdmf Version=\"3.0\">\n  <Domain>\n")?;
    writeln!(
        x,
        "    <Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Temporal\">"
    )
}

fn close_collection(x: &mut impl Write) -> std::io::Result<()> {
    x.write_all(b"    </Grid>\n  </Domain>\n</Xdmf>\n")
}

/// A uniform grid's opening with its time: `{:e}` is Rust's shortest
/// round-trip form, so the time read back is the f64 in /time, bit for bit.
fn open_grid(x: &mut impl Write, k: usize, t: f64) -> std::io::Result<()> {
    write!(
        x,
        "      <Grid Name=\"record {k}\" GridType=\"Uniform\">\n        <Time Value=\"{t:e}\"/>\n"
    )
}

/// A node-centred attribute whose data is the whole dataset `path`.
fn attribute(
    x: &mut impl Write,
    name: &str,
    kind: &str,
    dims: &str,
    number: (&str, u8),
    path: &str,
) -> std::io::Result<()> {
    let (ty, precision) = number;
    write!(
        x,
        "        <Attribute Name=\"{name}\" AttributeType=\"{kind}\" Center=\"Node\">\n\
      \x20         <DataItem Dimensions=\"{dims}\" NumberType=\"{ty}\" Precision=\"{precision}\" Format=\"HDF\">{path}</DataItem>\n\
      \x20       </Attribute>\n"
    )
}

/// A topology and an XY geometry, each one dataset.
fn mesh(
    x: &mut impl Write,
    (topology, n_cells, npc): (&str, usize, usize),
    cells: &str,
    n: usize,
    nodes: &str,
) -> std::io::Result<()> {
    write!(
        x,
        "        <Topology TopologyType=\"{topology}\" NumberOfElements=\"{n_cells}\" NodesPerElement=\"{npc}\">\n\
      \x20         <DataItem Dimensions=\"{n_cells} {npc}\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">{cells}</DataItem>\n\
      \x20       </Topology>\n\
      \x20       <Geometry GeometryType=\"XY\">\n\
      \x20         <DataItem Dimensions=\"{n} 2\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{nodes}</DataItem>\n\
      \x20       </Geometry>\n"
    )
}

/// [`xdmf_text`] into `x`, grid by grid: a run of a million records has a
/// text of about 1.3 GB, which is never held whole.
fn write_body(x: &mut impl Write, h5_name: &str, info: &XdmfInfo) -> std::io::Result<()> {
    let h5 = xml_escape(h5_name);
    let views = xml_escape(&views_name(h5_name));
    let n = info.n_nodes;
    let topology = match info.kind {
        CellKind::Quad4 => "Quadrilateral",
        CellKind::Quad9 => "Quadrilateral_9",
    };
    let cells = (topology, info.n_cells, info.kind.nodes_per_cell());
    let (cells_path, nodes_path) = (format!("{h5}:/mesh/cells"), format!("{h5}:/mesh/nodes"));
    let vector_dims = format!("{n} 3");
    let scalar_dims = n.to_string();
    let stress = info.stress.map(xml_escape);
    open_collection(x, "stickslip")?;
    for (k, &t) in info.times.iter().enumerate() {
        open_grid(x, k, t)?;
        mesh(x, cells, &cells_path, n, &nodes_path)?;
        for name in VECTORS {
            let path = format!("{views}:/{name}/{k}");
            attribute(x, name, "Vector", &vector_dims, ("Float", 8), &path)?;
        }
        if let Some(file) = &stress {
            for name in STRESS_VIEWS {
                let path = format!("{file}:/views/{name}/{k}");
                attribute(x, name, "Scalar", &scalar_dims, ("Float", 8), &path)?;
            }
        }
        x.write_all(b"      </Grid>\n")?;
    }
    close_collection(x)
}

/// The scalars `stickslip stress` gives per record, as its views name
/// them.
pub const STRESS_VIEWS: [&str; 4] = ["sxx", "syy", "sxy", "von_mises"];

/// [`contact_text`] into `x`.
fn write_contact(
    x: &mut impl Write,
    h5_name: &str,
    times: &[f64],
    info: &ContactInfo,
) -> std::io::Result<()> {
    let ContactInfo {
        n_c,
        n_lines,
        surface,
        fields,
    } = *info;
    let h5 = xml_escape(h5_name);
    let views = xml_escape(&views_name(h5_name));
    let (lines, points) = (
        format!("{views}:/contact/lines"),
        format!("{views}:/contact/points"),
    );
    let dims = n_c.to_string();
    open_collection(x, "contact")?;
    for (k, &t) in times.iter().enumerate() {
        open_grid(x, k, t)?;
        mesh(x, ("Polyline", n_lines, 2), &lines, n_c, &points)?;
        let s = format!("{h5}:/contact/s");
        attribute(x, "s", "Scalar", &dims, ("Float", 8), &s)?;
        if surface {
            let path = format!("{h5}:/contact/surface");
            attribute(x, "surface", "Scalar", &dims, ("Int", 8), &path)?;
        }
        for field in fields {
            let number = if field.small {
                ("Int", 1)
            } else {
                ("Float", 8)
            };
            let path = format!("{views}:/contact/{}/{k}", field.name);
            attribute(x, field.name, "Scalar", &dims, number, &path)?;
        }
        x.write_all(b"      </Grid>\n")?;
    }
    close_collection(x)
}

/// The views file's name for the results file named `h5_name`.
fn views_name(h5_name: &str) -> String {
    views_path(Path::new(h5_name)).display().to_string()
}

/// Writes `OUT.xdmf` for the results file `out`, pointing into it and its
/// views by file name only (the files must sit in the same directory; move
/// them together).
///
/// Call it after the views of every record in `info.times` exist
/// ([`crate::views::update`]), with the times actually in the file
/// ([`crate::views_cmd::write`]).
///
/// # Errors
/// `out` without a UTF-8 file name (`InvalidInput`), or the file failing:
/// creating or renaming it with its OS error (which says whether the place
/// is at fault: [`crate::views_cmd::placed`]), writing it with none.
pub fn write_xdmf(out: &Path, info: &XdmfInfo) -> std::io::Result<()> {
    let name = crate::views::file_name(out)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e.to_string()))?;
    replace(&xdmf_path(out), |w| write_body(w, name, info))
}

/// Writes `OUT.contact.xdmf` for the results file `out`: its contact line
/// `info` at `times`, as [`write_xdmf`] (after the views of `info.fields`).
///
/// # Errors
/// As [`write_xdmf`].
pub fn write_contact_xdmf(out: &Path, times: &[f64], info: &ContactInfo) -> std::io::Result<()> {
    let name = crate::views::file_name(out)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e.to_string()))?;
    replace(&contact_xdmf_path(out), |w| {
        write_contact(w, name, times, info)
    })
}

/// Writes `path` beside and renames it over: a reader (or a kill -9
/// mid-write) never meets half a file.
pub(crate) fn replace(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = crate::views_cmd::part_of(path);
    // The write's own errors wrapped, their OS error hidden: only creating
    // and renaming say whether the place is at fault.
    let work = |e: std::io::Error| std::io::Error::new(e.kind(), e);
    let written = std::fs::File::create(&tmp).and_then(|f| {
        let mut w = std::io::BufWriter::new(f);
        write(&mut w).map_err(work)?;
        w.into_inner().map_err(|e| work(e.into_error()))?;
        std::fs::rename(&tmp, path)
    });
    // A failed write or rename (a full disk, a directory at `path`)
    // leaves nothing half written beside the results.
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(hay: &str, needle: &str) -> usize {
        hay.matches(needle).count()
    }

    fn info(times: &[f64]) -> XdmfInfo<'_> {
        XdmfInfo {
            n_nodes: 85,
            kind: CellKind::Quad9,
            n_cells: 16,
            times,
            stress: None,
        }
    }

    #[test]
    fn a_failed_replace_leaves_no_part_file() {
        let dir = std::env::temp_dir().join(format!("stickslip-xdmf-part-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("w.xdmf")).unwrap();
        // The rename onto a directory fails once the part is written.
        let e = replace(&dir.join("w.xdmf"), |w| w.write_all(b"<Xdmf/>")).unwrap_err();
        assert!(!dir.join("w.xdmf.part").exists(), "{e}");
        // So does a write that fails halfway.
        let e = replace(&dir.join("x.xdmf"), |w| {
            w.write_all(b"<Xdmf")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err();
        assert!(!dir.join("x.xdmf.part").exists(), "{e}");
        assert!(!dir.join("x.xdmf").exists(), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Only creating and renaming give their OS error, which says whether
    /// the place is at fault: a write's never reads as the place's.
    #[test]
    fn a_failed_write_is_never_the_place() {
        let dir = std::env::temp_dir().join(format!("stickslip-xdmf-os-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = replace(&dir.join("w.xdmf"), |_| {
            Err(std::io::Error::from_raw_os_error(libc::EACCES))
        })
        .unwrap_err();
        assert!(!crate::sys::place_error(&e), "{e}");
        assert!(e.to_string().contains("Permission denied"), "{e}");
        // A directory missing under it is the place's.
        let e = replace(&dir.join("gone/w.xdmf"), |w| w.write_all(b"<Xdmf/>")).unwrap_err();
        assert!(crate::sys::place_error(&e), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn one_grid_per_record_with_its_time_and_views() {
        let times = [0.0, 1e-3, 0.5];
        let x = xdmf_text("slab.h5", &info(&times));
        assert_eq!(count(&x, "GridType=\"Uniform\""), 3);
        assert_eq!(count(&x, "CollectionType=\"Temporal\""), 1);
        assert!(x.contains("<Time Value=\"0e0\"/>"), "{x}");
        assert!(x.contains("<Time Value=\"1e-3\"/>"), "{x}");
        assert!(x.contains("<Time Value=\"5e-1\"/>"), "{x}");
        assert_eq!(count(&x, "TopologyType=\"Quadrilateral_9\""), 3);
        assert_eq!(
            count(&x, "NumberOfElements=\"16\" NodesPerElement=\"9\""),
            3
        );
        assert_eq!(count(&x, ">slab.h5:/mesh/nodes<"), 3);
        assert_eq!(count(&x, "HyperSlab"), 0);
        // Record 2 of each vector: its own view, three components.
        for v in VECTORS {
            assert_eq!(count(&x, &format!(">slab.views.h5:/{v}/2<")), 1, "{v}");
            assert_eq!(count(&x, &format!("slab.views.h5:/{v}/")), 3, "{v}");
        }
        assert_eq!(count(&x, "Dimensions=\"85 3\""), 9);
        assert_eq!(count(&x, "<Grid"), count(&x, "</Grid>"));
        assert_eq!(count(&x, "<DataItem"), count(&x, "</DataItem>"));
        // Stresses: four scalars per record from the stress file's views.
        let with = xdmf_text(
            "slab.h5",
            &XdmfInfo {
                stress: Some("slab.stress.h5"),
                ..info(&times)
            },
        );
        assert_eq!(count(&with, "slab.stress.h5:/views/"), 12);
        assert!(with.contains(">slab.stress.h5:/views/von_mises/1<"));
    }

    /// The slab's contact line (16 nodes, 15 segments) with every field a
    /// run writes, and `/contact/surface` where `surface`.
    fn contact(surface: bool) -> ContactInfo<'static> {
        ContactInfo {
            n_c: 16,
            n_lines: 15,
            surface,
            fields: &crate::views::CONTACT_FIELDS,
        }
    }

    #[test]
    fn the_contact_file_has_lines_and_the_friction_fields() {
        let x = contact_text("slab.h5", &[0.0, 0.25], &contact(false));
        assert_eq!(count(&x, "GridType=\"Uniform\""), 2);
        assert_eq!(
            count(
                &x,
                "TopologyType=\"Polyline\" NumberOfElements=\"15\" NodesPerElement=\"2\""
            ),
            2
        );
        assert_eq!(count(&x, ">slab.views.h5:/contact/points<"), 2);
        assert_eq!(count(&x, ">slab.h5:/contact/s<"), 2);
        assert!(x.contains(">slab.views.h5:/contact/friction_stress/1<"));
        assert!(x.contains(
            "NumberType=\"Int\" Precision=\"1\" Format=\"HDF\">slab.views.h5:/contact/state/0<"
        ));
        assert_eq!(count(&x, "<DataItem"), count(&x, "</DataItem>"));
        assert_eq!(count(&x, "/contact/surface<"), 0);
        // The normal traction: each record its own view, 16 doubles.
        for k in 0..2 {
            assert_eq!(
                count(
                    &x,
                    &format!(
                        "<Attribute Name=\"normal_stress\" AttributeType=\"Scalar\" Center=\"Node\">\n\
                         \x20         <DataItem Dimensions=\"16\" NumberType=\"Float\" Precision=\"8\" \
                         Format=\"HDF\">slab.views.h5:/contact/normal_stress/{k}<"
                    )
                ),
                1,
                "{x}"
            );
        }
        // A file without it (an earlier version's): the XML names it nowhere.
        let older = ContactInfo {
            fields: &crate::views::CONTACT_FIELDS[..3],
            ..contact(false)
        };
        let y = contact_text("slab.h5", &[0.0, 0.25], &older);
        assert_eq!(count(&y, "normal_stress"), 0);
        assert_eq!(count(&y, "<Attribute "), 2 * 4);
        assert_eq!(count(&y, "<DataItem"), count(&y, "</DataItem>"));
        // With /contact/surface, each record names it once, as 64-bit ints.
        let x = contact_text("slab.h5", &[0.0, 0.25], &contact(true));
        assert_eq!(
            count(
                &x,
                "NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">slab.h5:/contact/surface<"
            ),
            2
        );
        assert_eq!(count(&x, "<DataItem"), count(&x, "</DataItem>"));
    }

    #[test]
    fn the_files_are_the_texts_and_no_part_is_left() {
        let dir = std::env::temp_dir().join(format!("stickslip-xdmf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let times = [0.0, 0.25, 0.5];
        let out = dir.join("slab.h5");
        write_xdmf(&out, &info(&times)).unwrap();
        write_contact_xdmf(&out, &times, &contact(false)).unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join("slab.xdmf")).unwrap(),
            xdmf_text("slab.h5", &info(&times))
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("slab.contact.xdmf")).unwrap(),
            contact_text("slab.h5", &times, &contact(false))
        );
        assert!(!dir.join("slab.xdmf.part").exists());
        assert!(!dir.join("slab.contact.xdmf.part").exists());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn quad4_topology_and_escaped_file_name() {
        let x = xdmf_text(
            "a&b<c>.h5",
            &XdmfInfo {
                n_nodes: 6,
                kind: CellKind::Quad4,
                n_cells: 2,
                times: &[0.0],
                stress: None,
            },
        );
        assert!(x.contains(
            "TopologyType=\"Quadrilateral\" NumberOfElements=\"2\" NodesPerElement=\"4\""
        ));
        assert!(x.contains(">a&amp;b&lt;c&gt;.h5:/mesh/cells<"), "{x}");
        assert!(
            x.contains(">a&amp;b&lt;c&gt;.views.h5:/displacement/0<"),
            "{x}"
        );
        assert!(!x.contains("a&b"));
    }

    #[test]
    fn refers_to_the_h5_by_file_name_only() {
        let dir = std::env::temp_dir().join(format!("stickslip-xdmf-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let small = XdmfInfo {
            n_nodes: 4,
            kind: CellKind::Quad4,
            n_cells: 1,
            times: &[0.0, 1.0],
            stress: None,
        };
        write_xdmf(&dir.join("run.h5"), &small).unwrap();
        let x = std::fs::read_to_string(dir.join("run.xdmf")).unwrap();
        assert!(x.contains(">run.h5:/mesh/nodes<"));
        assert!(x.contains(">run.views.h5:/displacement/1<"));
        assert!(!x.contains(&dir.display().to_string()));
        std::fs::remove_dir_all(&dir).ok();
        let e = write_xdmf(Path::new("/"), &small).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    }
}
