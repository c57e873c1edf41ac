//! The XDMF 3 companion of a results file, for ParaView (and meshio).
//!
//! `OUT.xdmf` holds no numbers, only XML that points into `OUT.h5` (by file
//! name: the two files sit side by side and move together): a temporal
//! collection with one uniform grid per output step, each with the mesh
//! (`/mesh/cells`, `/mesh/nodes`) and the node vectors displacement, velocity
//! and acceleration, selected from the `[n_out, n_nodes, 2]` datasets by a
//! HyperSlab (start `k 0 0`, stride `1 1 1`, count `1 n_nodes 2`).
//!
//! HyperSlab is the XDMF model's way to address one row of a larger array;
//! in ParaView (5.11) open the file with the "XDMF Reader" (the "Xdmf3
//! Reader" variants load the mesh but skip HyperSlab vectors); meshio 5.3
//! reads the grids and times but needs a HyperSlab rule added
//! (`tests/xdmf.rs` shows one).
//!
//! Cell node order needs no permutation: quad4 corners counter-clockwise and
//! quad9 as in `stickslip_mesh::GMSH_TO_FEM_QUAD9` are XDMF's (and VTK's)
//! `Quadrilateral` and `Quadrilateral_9` orders.

use std::io::Write;
use std::path::Path;

use stickslip_mesh::CellKind;

/// What the XML needs to know about a results file: its sizes and times.
#[derive(Clone, Copy, Debug)]
pub struct XdmfInfo<'a> {
    /// Rows of `/mesh/nodes`.
    pub n_nodes: usize,
    /// Cell kind of `/mesh/cells`.
    pub kind: CellKind,
    /// Rows of `/mesh/cells`.
    pub n_cells: usize,
    /// `/time`, one entry per output step written so far.
    pub times: &'a [f64],
    /// The file name of `stickslip stress`'s `/stress` [n_out, n_nodes, 3]
    /// and `/von_mises` [n_out, n_nodes], beside the results file: listed
    /// per step too, σ_xx, σ_yy, σ_xy and von Mises as scalars (ParaView
    /// would call a 3-vector's third component "Z").
    pub stress: Option<&'a str>,
}

/// About the bytes of XML per step of a run (2,557 for the slab's `st.h5`;
/// each character of a longer file name adds five).
pub const BYTES_PER_STEP: usize = 2600;

/// The node vectors written per step: (dataset, attribute name).
const VECTORS: [&str; 3] = ["displacement", "velocity", "acceleration"];

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

/// The XML text for the results file named `h5_name` (a file name, no
/// directory).
pub fn xdmf_text(h5_name: &str, info: &XdmfInfo) -> String {
    let mut x = Vec::with_capacity(1024 + info.times.len() * 1600);
    write_xml(&mut x, h5_name, info).expect("writing to memory");
    String::from_utf8(x).expect("the XML is UTF-8")
}

/// [`xdmf_text`] into `x`, grid by grid: a run of a million records has a
/// text of about 1.8 GB, which is never held whole.
fn write_xml(x: &mut impl Write, h5_name: &str, info: &XdmfInfo) -> std::io::Result<()> {
    let h5 = xml_escape(h5_name);
    let (n, n_out, n_cells) = (info.n_nodes, info.times.len(), info.n_cells);
    let npc = info.kind.nodes_per_cell();
    let topology = match info.kind {
        CellKind::Quad4 => "Quadrilateral",
        CellKind::Quad9 => "Quadrilateral_9",
    };
    x.write_all(b"<?xml version=\"1.0\" encoding=\"utf-8\"?>\n")?;
    x.write_all(b"<Xdmf Version=\"3.0\">\n")?;
    x.write_all(b"  <Domain>\n")?;
    x.write_all(
        b"    <Grid Name=\"stickslip\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
    )?;
    for (k, t) in info.times.iter().enumerate() {
        // `{:e}` is Rust's shortest round-trip form: the time read back is
        // the f64 in /time, bit for bit.
        write!(
            x,
            "      <Grid Name=\"step {k}\" GridType=\"Uniform\">\n        <Time Value=\"{t:e}\"/>\n"
        )?;
        write!(
            x,
            "        <Topology TopologyType=\"{topology}\" NumberOfElements=\"{n_cells}\" NodesPerElement=\"{npc}\">\n\
          \x20         <DataItem Dimensions=\"{n_cells} {npc}\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">{h5}:/mesh/cells</DataItem>\n\
          \x20       </Topology>\n\
          \x20       <Geometry GeometryType=\"XY\">\n\
          \x20         <DataItem Dimensions=\"{n} 2\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:/mesh/nodes</DataItem>\n\
          \x20       </Geometry>\n"
        )?;
        for name in VECTORS {
            write!(
                x,
                "        <Attribute Name=\"{name}\" AttributeType=\"Vector\" Center=\"Node\">\n\
              \x20         <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 {n} 2\" Type=\"HyperSlab\">\n\
              \x20           <DataItem Dimensions=\"3 3\" NumberType=\"Int\" Format=\"XML\">{k} 0 0 1 1 1 1 {n} 2</DataItem>\n\
              \x20           <DataItem Dimensions=\"{n_out} {n} 2\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:/{name}</DataItem>\n\
              \x20         </DataItem>\n\
              \x20       </Attribute>\n"
            )?;
        }
        if let Some(file) = info.stress {
            let file = xml_escape(file);
            for (name, c) in [("sxx", 0), ("syy", 1), ("sxy", 2)] {
                write!(
                    x,
                    "        <Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"Node\">\n\
                  \x20         <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 {n} 1\" Type=\"HyperSlab\">\n\
                  \x20           <DataItem Dimensions=\"3 3\" NumberType=\"Int\" Format=\"XML\">{k} 0 {c} 1 1 1 1 {n} 1</DataItem>\n\
                  \x20           <DataItem Dimensions=\"{n_out} {n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{file}:/stress</DataItem>\n\
                  \x20         </DataItem>\n\
                  \x20       </Attribute>\n"
                )?;
            }
            write!(
                x,
                "        <Attribute Name=\"von_mises\" AttributeType=\"Scalar\" Center=\"Node\">\n\
              \x20         <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 {n}\" Type=\"HyperSlab\">\n\
              \x20           <DataItem Dimensions=\"3 2\" NumberType=\"Int\" Format=\"XML\">{k} 0 1 1 1 {n}</DataItem>\n\
              \x20           <DataItem Dimensions=\"{n_out} {n}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{file}:/von_mises</DataItem>\n\
              \x20         </DataItem>\n\
              \x20       </Attribute>\n"
            )?;
        }
        x.write_all(b"      </Grid>\n")?;
    }
    x.write_all(b"    </Grid>\n  </Domain>\n</Xdmf>\n")
}

/// Writes `xdmf_path`, pointing into `h5_path` by its file name only (the
/// two files must sit in the same directory; move them together).
///
/// Call it after the last step is written (and again after a restart), with
/// the times actually in the file: the XML declares `times.len()` rows.
///
/// # Errors
/// `h5_path` without a file name (`InvalidInput`), or the write failing.
pub fn write_xdmf(h5_path: &Path, xdmf_path: &Path, info: &XdmfInfo) -> std::io::Result<()> {
    let name = h5_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "{}: the results path has no UTF-8 file name for the XDMF file to refer to",
                    h5_path.display()
                ),
            )
        })?;
    // Written beside and renamed over: a reader (or a kill -9 mid-write)
    // never meets half a file.
    let tmp = xdmf_path.with_extension("xdmf.part");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
    write_xml(&mut w, name, info)?;
    w.into_inner().map_err(|e| e.into_error())?;
    std::fs::rename(&tmp, xdmf_path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(hay: &str, needle: &str) -> usize {
        hay.matches(needle).count()
    }

    #[test]
    fn one_grid_per_step_with_its_time_and_hyperslab() {
        let times = [0.0, 1e-3, 0.5];
        let x = xdmf_text(
            "slab.h5",
            &XdmfInfo {
                n_nodes: 85,
                kind: CellKind::Quad9,
                n_cells: 16,
                times: &times,
                stress: None,
            },
        );
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
        assert_eq!(count(&x, "slab.h5:/mesh/nodes"), 3);
        // Step 2 of each vector: start (2, 0, 0), count (1, 85, 2) of a
        // [3, 85, 2] dataset.
        assert_eq!(count(&x, ">2 0 0 1 1 1 1 85 2<"), 3);
        assert_eq!(count(&x, "Dimensions=\"3 85 2\""), 9);
        for v in VECTORS {
            assert_eq!(count(&x, &format!("slab.h5:/{v}<")), 3);
        }
        assert_eq!(count(&x, "<Grid"), count(&x, "</Grid>"));
        assert_eq!(count(&x, "<DataItem"), count(&x, "</DataItem>"));
    }

    #[test]
    fn the_file_is_the_text_and_no_part_is_left() {
        let dir = std::env::temp_dir().join(format!("stickslip-xdmf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let info = XdmfInfo {
            n_nodes: 85,
            kind: CellKind::Quad9,
            n_cells: 16,
            times: &[0.0, 0.25, 0.5],
            stress: None,
        };
        let path = dir.join("slab.xdmf");
        write_xdmf(&dir.join("slab.h5"), &path, &info).unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            xdmf_text("slab.h5", &info)
        );
        assert!(!dir.join("slab.xdmf.part").exists());
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
        assert!(!x.contains("a&b"));
    }

    #[test]
    fn refers_to_the_h5_by_file_name_only() {
        let dir = std::env::temp_dir().join(format!("stickslip-xdmf-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let xdmf = dir.join("run.xdmf");
        write_xdmf(
            &dir.join("run.h5"),
            &xdmf,
            &XdmfInfo {
                n_nodes: 4,
                kind: CellKind::Quad4,
                n_cells: 1,
                times: &[0.0, 1.0],
                stress: None,
            },
        )
        .unwrap();
        let x = std::fs::read_to_string(&xdmf).unwrap();
        assert!(x.contains(">run.h5:/displacement<"));
        assert!(!x.contains(&dir.display().to_string()));
        std::fs::remove_dir_all(&dir).ok();
        let e = write_xdmf(
            Path::new("/"),
            &xdmf,
            &XdmfInfo {
                n_nodes: 4,
                kind: CellKind::Quad4,
                n_cells: 1,
                times: &[],
                stress: None,
            },
        )
        .unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    }
}
