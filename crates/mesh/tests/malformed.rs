//! Every malformed-input class gets its own typed error, located by line
//! (ASCII) or byte offset (binary). Each test damages a Gmsh-written fixture
//! in one known place and expects exactly that place back.

mod common;
use common::*;
use stickslip_mesh::{Location, Mesh, MeshError, MeshErrorKind as K};

fn err_bytes(b: &[u8]) -> MeshError {
    match Mesh::from_bytes(b) {
        Ok(_) => panic!("damaged input was accepted"),
        Err(e) => e,
    }
}

fn err(s: &str) -> MeshError {
    err_bytes(s.as_bytes())
}

/// The error of `fixture` with its first line `line` replaced by `by`,
/// which must be located at the line `at` of the damaged text (the
/// replaced line where None: where the fix is).
fn line_err(fixture: &str, line: &str, by: &str, at: Option<&str>) -> MeshError {
    let t = replace_line(&text(fixture), line, by);
    err_at_line(&t, at.unwrap_or(by))
}

/// The error of `t`, which must be located at its first line equal to `at`.
fn err_at_line(t: &str, at: &str) -> MeshError {
    let e = err(t);
    assert_eq!(e.location, Location::Line(line_no(t, at)), "{e}");
    e
}

/// The error of damaged binary input, which must be located at byte `at`.
fn byte_err(b: &[u8], at: usize) -> MeshError {
    let e = err_bytes(b);
    assert_eq!(e.location, Location::Byte(at), "{e}");
    e
}

/// A count that does not match what follows it.
fn wrong_count(section: &'static str, what: &'static str, expected: u64) -> K {
    K::WrongCount {
        section,
        what,
        expected,
    }
}

const Q4_22: &str = "slab_q4_v22_ascii.msh";
const Q4_41: &str = "slab_q4_v41_ascii.msh";

// ---- truncated file ----

#[test]
fn truncated_ascii() {
    let t = text(Q4_41);
    let keep = line_no(&t, "$Nodes") + 3; // header, first block header, first tag
    let lines: Vec<&str> = t.lines().collect();
    // Whole lines, then the first 3 characters ("0 0") of the next one.
    let cut = lines[..keep].join("\n") + "\n" + &lines[keep][..3];
    let e = err(&cut);
    assert!(matches!(e.kind, K::Truncated { .. }), "{e}");
    assert_eq!(e.location, Location::Line(keep + 1));
}

#[test]
fn truncated_binary() {
    let b = bytes("slab_q4_v22_bin.msh");
    let data = find(&b, b"$Nodes\n15\n") + 10;
    // 5 whole 28-byte node records and 3 bytes: the 15 records do not fit.
    let e = byte_err(&b[..data + 28 * 5 + 3], data);
    assert!(matches!(e.kind, K::Truncated { .. }), "{e}");
}

// ---- missing $End… ----

#[test]
fn missing_end_ascii() {
    let e = line_err(Q4_22, "$EndNodes", "", Some("$Elements"));
    assert_eq!(
        e.kind,
        K::MissingEnd {
            section: "$Nodes".into(),
            end: "$EndNodes".into()
        }
    );
}

#[test]
fn missing_end_binary() {
    let mut b = bytes("slab_q4_v41_bin.msh");
    let at = find(&b, b"$EndElements");
    b[at + 11] = b'X';
    let e = byte_err(&b, at);
    assert!(
        matches!(&e.kind, K::MissingEnd { end, .. } if end == "$EndElements"),
        "{e}"
    );
}

#[test]
fn skipped_section_without_end() {
    let t = text(Q4_22) + "$Comments\nno end\n";
    let e = err_at_line(&t, "$Comments");
    assert!(
        matches!(&e.kind, K::MissingEnd { section, .. } if section == "$Comments"),
        "{e}"
    );
}

// ---- wrong counts ----

#[test]
fn wrong_counts_ascii() {
    // Too many nodes declared: reported where the nodes end; too few: at
    // the first node past the count; $Elements declaring 20 of the 21
    // elements: at the last block (8 quads), which takes the sum past it.
    let past = "15 5.999999999998746 0.6874999999984586 0";
    let e = line_err(Q4_22, "15", "16", Some("$EndNodes"));
    assert_eq!(e.kind, wrong_count("$Nodes", "nodes", 16));
    let e = line_err(Q4_22, "15", "14", Some(past));
    assert_eq!(e.kind, wrong_count("$Nodes", "nodes", 14));
    let e = line_err(Q4_41, "6 21 1 21", "6 20 1 21", Some("2 1 3 8"));
    assert_eq!(e.kind, wrong_count("$Elements", "elements", 20));
}

#[test]
fn wrong_count_binary() {
    let mut b = bytes("slab_q4_v22_bin.msh");
    let at = find(&b, b"$Elements\n21\n") + 10;
    b[at + 1] = b'2'; // 21 -> 22
    let e = byte_err(&b, find(&b, b"\n$EndElements"));
    assert_eq!(e.kind, wrong_count("$Elements", "elements", 22));
}

#[test]
fn huge_counts_are_errors_not_allocations() {
    // 10^18 nodes in a binary 2.2 file: more than the input holds.
    let b = bytes("slab_q4_v22_bin.msh");
    let at = find(&b, b"$Nodes\n15\n") + 7;
    let mut huge = b[..at].to_vec();
    huge.extend_from_slice(b"1000000000000000000");
    huge.extend_from_slice(&b[at + 2..]);
    let e = byte_err(&huge, at + 20);
    assert!(matches!(e.kind, K::Truncated { .. }), "{e}");
    // And in a 4.1 ASCII header: the blocks hold 15, not 10^18.
    let e = line_err(Q4_41, "9 15 1 15", "9 1000000000000000000 1 15", None);
    assert_eq!(
        e.kind,
        wrong_count("$Nodes", "nodes", 1_000_000_000_000_000_000)
    );
}

// ---- non-numeric field ----

#[test]
fn non_numeric_ascii() {
    for (fixture, line, by, found) in [
        (Q4_22, "5 1.999999999995288 0 0", "5 1.99x 0 0", "1.99x"),
        (Q4_41, "14 1 5 13 12", "14 1 5 six 12", "six"),
    ] {
        let e = line_err(fixture, line, by, None);
        assert!(
            matches!(&e.kind, K::NotANumber { found: f, .. } if f == found),
            "{e}"
        );
    }
}

#[test]
fn non_numeric_binary() {
    let mut b = bytes("slab_q4_v22_bin.msh");
    let data = find(&b, b"$Nodes\n15\n") + 10;
    let x = data + 28 * 2 + 4; // x of the third node
    b[x..x + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let e = byte_err(&b, x);
    assert!(matches!(e.kind, K::NotANumber { .. }), "{e}");
}

// ---- element referencing a missing node ----

/// The 2.2 binary fixture and its first quad4 element record.
fn v22_bin_first_quad4() -> (Vec<u8>, Record) {
    let b = bytes("slab_q4_v22_bin.msh");
    let r = *v22_bin_elements(&b)
        .iter()
        .find(|r| r.type_id == 3)
        .unwrap();
    (b, r)
}

#[test]
fn missing_node_ascii() {
    let e = line_err(
        Q4_22,
        "14 3 2 10 1 1 5 13 12",
        "14 3 2 10 1 1 5 13 99",
        None,
    );
    assert_eq!(
        e.kind,
        K::MissingNode {
            element: 14,
            node: 99
        }
    );
}

#[test]
fn missing_node_binary() {
    let (mut b, r) = v22_bin_first_quad4();
    let last = r.offset + 4 * (1 + r.ntags + 3);
    b[last..last + 4].copy_from_slice(&999i32.to_le_bytes());
    let e = byte_err(&b, r.offset);
    assert!(matches!(e.kind, K::MissingNode { node: 999, .. }), "{e}");
}

// ---- unknown physical group (4.1: an entity $Entities does not list) ----

#[test]
fn unknown_entity_ascii() {
    let e = line_err(Q4_41, "2 1 3 8", "2 7 3 8", None);
    assert_eq!(e.kind, K::UnknownEntity { dim: 2, tag: 7 });
}

fn block_header(dim: i32, tag: i32, ty: i32, n: u64) -> Vec<u8> {
    [
        &dim.to_le_bytes()[..],
        &tag.to_le_bytes(),
        &ty.to_le_bytes(),
        &n.to_le_bytes(),
    ]
    .concat()
}

#[test]
fn unknown_entity_binary() {
    let mut b = bytes("slab_q4_v41_bin.msh");
    let at = find(&b, &block_header(2, 1, 3, 8));
    b[at + 4] = 7;
    let e = byte_err(&b, at);
    assert_eq!(e.kind, K::UnknownEntity { dim: 2, tag: 7 });
}

// ---- unsupported element type ----

#[test]
fn unsupported_element_ascii() {
    let e = line_err(Q4_41, "2 1 3 8", "2 1 5 8", None);
    // Element 14 is the first of that block in the fixture.
    assert_eq!(
        e.kind,
        K::UnsupportedElement {
            element: 14,
            type_id: 5,
            name: "hex8"
        }
    );
}

#[test]
fn unsupported_element_binary() {
    let (mut b, r) = v22_bin_first_quad4();
    b[r.header..r.header + 4].copy_from_slice(&4i32.to_le_bytes());
    let e = byte_err(&b, r.header);
    assert!(
        matches!(
            e.kind,
            K::UnsupportedElement {
                type_id: 4,
                name: "tet4",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn mixed_quad4_quad9_refused() {
    let e = line_err(
        Q4_22,
        "15 3 2 10 1 12 13 11 4",
        "15 10 2 10 1 12 13 11 4 5 6 7 8 9",
        None,
    );
    assert!(
        matches!(&e.kind, K::NotQuads { found } if found.contains("quad4 and quad9")),
        "{e}"
    );
}

// ---- unsupported version, big-endian, data size ----

#[test]
fn unsupported_version() {
    for v in ["3", "4.0", "2.1"] {
        // Located at line 2, the version's.
        let e = line_err(Q4_22, "2.2 0 8", &format!("{v} 0 8"), None);
        assert_eq!(e.kind, K::UnsupportedVersion { version: v.into() });
    }
}

#[test]
fn big_endian_binary() {
    let mut b = bytes("slab_q4_v41_bin.msh");
    let at = find(&b, b"4.1 1 8\n") + 8;
    assert_eq!(&b[at..at + 4], &[1, 0, 0, 0]);
    b[at..at + 4].copy_from_slice(&[0, 0, 0, 1]);
    assert_eq!(byte_err(&b, at).kind, K::BigEndian);
}

#[test]
fn unsupported_data_size() {
    let mut b = bytes("slab_q4_v41_bin.msh");
    let at = find(&b, b"4.1 1 8\n");
    b[at + 6] = b'4';
    let e = byte_err(&b, at + 4);
    assert_eq!(e.kind, K::UnsupportedDataSize { size: 4 });
}

// ---- checks: degenerate cells, boundary elements off the cells ----

#[test]
fn degenerate_cells() {
    // A repeated corner (zero-length side) and a bow-tie (crossed sides).
    for bad in ["16 3 2 10 1 5 6 6 13", "16 3 2 10 1 5 14 6 13"] {
        let e = line_err(Q4_22, "16 3 2 10 1 5 6 14 13", bad, None);
        assert_eq!(e.kind, K::DegenerateCell { element: 16 }, "{bad}");
    }
}

#[test]
fn boundary_element_not_on_a_cell_edge() {
    // 5-14 is a diagonal of cell 16 (5 6 14 13), not a side.
    let e = line_err(Q4_22, "3 1 2 1 1 5 6", "3 1 2 1 1 5 14", None);
    assert_eq!(
        e.kind,
        K::EdgeNotOnCell {
            element: 3,
            group: "contact".into()
        }
    );
}

#[test]
fn line_order_mismatch() {
    let e = line_err(Q4_22, "3 1 2 1 1 5 6", "3 8 2 1 1 5 6 1", None);
    assert_eq!(
        e.kind,
        K::OrderMismatch {
            element: 3,
            line: "line3",
            cells: "quad4"
        }
    );
}

#[test]
fn no_cells() {
    let t = text(Q4_22);
    let cut: Vec<&str> = t
        .lines()
        .filter(|l| l.split_whitespace().nth(1) != Some("3") || l.split_whitespace().count() != 9)
        .collect();
    let t = replace_line(&(cut.join("\n") + "\n"), "21", "13");
    let e = err(&t);
    assert_eq!(e.kind, K::NoCells);
    assert_eq!(e.location, Location::Nowhere);
}

/// A mesh drawn in a plane z = const other than 0 reads, z dropped (it
/// was refused at its first node).
#[test]
fn a_plane_at_constant_z_reads() {
    let flat = text(Q4_22);
    // Node lines of $Nodes (tag x y z) with z given by `z(tag)`.
    let at = |z: &dyn Fn(u64) -> String| -> String {
        flat.lines()
            .map(|l| {
                let f: Vec<&str> = l.split(' ').collect();
                if f.len() == 4 && f.iter().all(|v| v.parse::<f64>().is_ok()) && l.ends_with(" 0") {
                    format!("{} {} {} {}", f[0], f[1], f[2], z(f[0].parse().unwrap()))
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    };
    let a = Mesh::from_bytes(flat.as_bytes()).unwrap();
    // At z = 0.5; at z = 1e6 with one ulp of noise on every other node.
    for shifted in [
        at(&|_| "0.5".into()),
        at(&|t| {
            if t % 2 == 0 {
                "1e6".into()
            } else {
                "1000000.0000000001".into()
            }
        }),
    ] {
        assert_ne!(shifted, flat);
        let b = Mesh::from_bytes(shifted.as_bytes()).unwrap();
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.cells, b.cells);
    }
    // One node off by 1e-9 (beyond the rounding of an extent of 8): that
    // node is named, not another.
    let e = err(&at(&|t| if t == 1 { "1e-9".into() } else { "0".into() }));
    assert!(matches!(e.kind, K::NotPlanar { node: 1, .. }), "{e}");
}

#[test]
fn not_planar() {
    // Located at the node's line, where the fix is.
    let e = line_err(
        Q4_22,
        "9 6.000000000002768 1.375000000000173 0",
        "9 6.000000000002768 1.375000000000173 0.5",
        None,
    );
    assert!(matches!(e.kind, K::NotPlanar { node: 9, z, .. } if z == 0.5));
    // Rounding-level z (1e-14 of an 8-long mesh) is accepted.
    let t = replace_line(
        &text(Q4_22),
        "9 6.000000000002768 1.375000000000173 0",
        "9 6.000000000002768 1.375000000000173 1e-14",
    );
    assert!(Mesh::from_bytes(t.as_bytes()).is_ok());
}

#[test]
fn duplicate_node_tag() {
    let t = text("slab_q4_gaps_v41_ascii.msh");
    let t = replace_line(&t, "106", "103");
    let e = err(&t);
    assert_eq!(e.kind, K::DuplicateNode { tag: 103 });
    // The second 103, where the fix is, not the $Nodes header: after
    // $Nodes come the header, a block header, 103, its coordinates, the
    // next block header and the duplicate.
    let second = line_no(&t, "$Nodes") + 6;
    assert_eq!(t.lines().nth(second - 1), Some("103"));
    assert_eq!(e.location, Location::Line(second));
}

#[test]
fn duplicate_node_tag_22_ascii_and_binary() {
    // Sparse tags (a table index): node 9's line repeats tag 5.
    let t = text("slab_q4_gaps_v22_ascii.msh");
    let nodes = line_no(&t, "$Nodes");
    let lines: Vec<&str> = t.lines().collect();
    let (l5, l9) = (lines[nodes + 5], lines[nodes + 9]);
    let tag5 = l5.split(' ').next().unwrap();
    let dup = format!("{tag5} {}", l9.split_once(' ').unwrap().1);
    let t = replace_line(&t, l9, &dup);
    let e = err(&t);
    assert_eq!(
        e.kind,
        K::DuplicateNode {
            tag: tag5.parse().unwrap()
        }
    );
    assert_eq!(e.location, Location::Line(nodes + 10));
    // Binary: the 8th record takes the 3rd one's tag.
    let mut b = bytes("slab_q4_gaps_v22_bin.msh");
    let data = find(&b, b"$Nodes\n15\n") + 10;
    let third: [u8; 4] = b[data + 28 * 2..data + 28 * 2 + 4].try_into().unwrap();
    b[data + 28 * 7..data + 28 * 7 + 4].copy_from_slice(&third);
    let e = byte_err(&b, data + 28 * 7);
    assert!(matches!(e.kind, K::DuplicateNode { .. }), "{e}");
    // MSH 4.1 binary: the second block's tag (after the 32-byte header, a
    // 20-byte block header, a tag and 24 bytes of coordinates, and the next
    // block header) takes the first one's.
    let mut b = bytes("slab_q4_gaps_v41_bin.msh");
    let first = find(&b, b"$Nodes\n") + 7 + 32 + 20;
    let second = first + 8 + 24 + 20;
    let tag: [u8; 8] = b[first..first + 8].try_into().unwrap();
    b[second..second + 8].copy_from_slice(&tag);
    let e = byte_err(&b, second);
    assert_eq!(
        e.kind,
        K::DuplicateNode {
            tag: u64::from_le_bytes(tag)
        }
    );
}

// ---- file structure ----

#[test]
fn not_an_msh_file() {
    let e = err("hello\n");
    assert_eq!(e.kind, K::NotMsh);
    assert_eq!(e.location, Location::Line(1));
    // An empty file is not "not a mesh file": it is empty.
    for empty in [&b""[..], b"\n", b"  \r\n\t\n"] {
        let e = err_bytes(empty);
        assert_eq!(e.kind, K::EmptyFile);
        assert_eq!(e.location, Location::Nowhere);
    }
}

#[test]
fn sections_out_of_order_or_missing() {
    let t = text(Q4_22);
    let (n0, n1) = (t.find("$Nodes").unwrap(), t.find("$Elements").unwrap());
    let swapped = format!("{}{}{}", &t[..n0], &t[n1..], &t[n0..n1]);
    let e = err_at_line(&swapped, "$Elements");
    assert!(
        matches!(&e.kind, K::SectionOrder { found, .. } if found == "$Elements"),
        "{e}"
    );
    let e = err(&t[..n1]);
    assert_eq!(
        e.kind,
        K::MissingSection {
            section: "$Elements"
        }
    );
}

/// Sections the reader does not use are skipped, whatever they hold.
#[test]
fn unused_sections_are_skipped() {
    let t = text(Q4_41);
    let extra = "$Comments\nanything $Nodes 1 2 3\n$EndComments\n$NodeData\n1\n\"u\"\n1\n0.0\n3\n0\n1\n15\n1 0.5\n$EndNodeData\n$Periodic\n0\n$EndPeriodic\n";
    let at = t.find("$Elements").unwrap();
    let with = format!("{}{}{}", &t[..at], extra, &t[at..]) + extra;
    same_mesh(
        &Mesh::from_bytes(with.as_bytes()).unwrap(),
        &load(Q4_41),
        "with extra sections",
    );
}

#[test]
fn file_errors_name_the_file_and_line() {
    let dir = std::env::temp_dir().join(format!("stickslip-mesh-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.msh");
    std::fs::write(&p, replace_line(&text(Q4_22), "2.2 0 8", "3 0 8")).unwrap();
    let e = Mesh::from_file(&p).unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("{}:2: MSH version 3", p.display())),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    let e = Mesh::from_file(dir.join("none.msh")).unwrap_err();
    assert!(matches!(e.kind, K::Io(_)));
}

// ---- ASCII records are whole lines ----

/// The message of `e`, which must be a [`K::FieldCount`] with `found`
/// numbers on the line.
fn short_or_long(e: MeshError, found: usize) -> String {
    assert!(
        matches!(&e.kind, K::FieldCount { found: f, .. } if *f == found),
        "{e}"
    );
    e.to_string()
}

/// The error of `fixture` with its line `line` cut after its last blank:
/// one number short, reported at the cut line.
fn cut_last_number(fixture: &str, line: &str) -> MeshError {
    let cut = line.trim_end().rsplit_once(' ').unwrap().0;
    line_err(fixture, line.trim_end(), cut, None)
}

/// One number too few or too many on an element line is reported there,
/// with what the line needs; read as a stream of numbers, the records after
/// it shifted and gave a wrong geometric diagnosis (a "degenerate" cell).
#[test]
fn element_line_with_a_number_missing_or_extra() {
    // MSH 4.1: a quad4 line is its tag and 4 node tags.
    let msg = short_or_long(line_err(Q4_41, "14 1 5 13 12", "14 1 5 13", None), 4);
    assert!(
        msg.contains("a quad4 element needs 5 numbers (its tag and 4 node tags), this line has 4")
            && msg.contains("re-export the mesh from Gmsh"),
        "{msg}"
    );
    short_or_long(line_err(Q4_41, "14 1 5 13 12", "14 1 5 13 12 7", None), 6);
    // The last element before $EndElements.
    let t = text(Q4_41);
    let last = t.lines().nth(line_no(&t, "$EndElements") - 2).unwrap();
    short_or_long(cut_last_number(Q4_41, last), 4);
    // MSH 2.2: number, type, number of tags, the tags, the node tags.
    let q4 = "14 3 2 10 1 1 5 13 12";
    let msg = short_or_long(line_err(Q4_22, q4, "14 3 2 10 1 1 5 13", None), 8);
    assert!(
        msg.contains("a quad4 element with 2 tags needs 9 numbers"),
        "{msg}"
    );
    short_or_long(line_err(Q4_22, q4, "14 3 2 10 1 1 5 13 12 9", None), 10);
    short_or_long(line_err(Q4_22, q4, "14 3", None), 2);
    // quad9 (the review's q2short.msh): a node tag missing.
    let q9 = "slab_q9_v22_ascii.msh";
    let t = text(q9);
    let line = t
        .lines()
        .find(|l| l.split(' ').nth(1) == Some("10") && l.split_whitespace().count() == 14)
        .unwrap();
    let msg = short_or_long(cut_last_number(q9, line), 13);
    assert!(
        msg.contains("a quad9 element with 2 tags needs 14 numbers"),
        "{msg}"
    );
}

/// Node lines, block headers and section headers too.
#[test]
fn node_and_header_lines_with_a_number_missing_or_extra() {
    // MSH 2.2: tag x y z.
    let node = "5 1.999999999995288 0 0";
    short_or_long(line_err(Q4_22, node, "5 1.999999999995288 0", None), 3);
    short_or_long(line_err(Q4_22, node, "5 1.999999999995288 0 0 0", None), 5);
    // MSH 4.1: the tags one a line, then x y z one node a line.
    let xyz = "1.999999999995288 0 0";
    short_or_long(line_err(Q4_41, xyz, "1.999999999995288 0", None), 2);
    let t = text(Q4_41).replacen("\n5\n6\n7\n", "\n5 6\n6\n7\n", 1);
    short_or_long(err_at_line(&t, "5 6"), 2);
    // An entity line (curve 1: bounding box, 1 physical tag, 2 points).
    let t = text(Q4_41);
    let line = t.lines().find(|l| l.starts_with("1 0 0 0 8 0 0 ")).unwrap();
    let long = format!("{} 5", line.trim_end());
    let msg = short_or_long(line_err(Q4_41, line.trim_end(), &long, None), 13);
    assert!(msg.contains("a curve entity needs"), "{msg}");
    // A block header and a section header.
    short_or_long(line_err(Q4_41, "0 1 15 1", "0 1 15", None), 3);
    short_or_long(line_err(Q4_41, "6 21 1 21", "6 21 1 21 0", None), 5);
}

/// ASCII files with CR LF line ends (written on Windows) are legitimate:
/// CR is a blank, not a field, on a record's line.
#[test]
fn ascii_with_crlf_line_ends() {
    for name in [Q4_22, Q4_41, "slab_q9_param_v41_ascii.msh"] {
        let t = text(name).replace('\n', "\r\n");
        same_mesh(&err_free(&t), &load(name), name);
    }
}

fn err_free(t: &str) -> Mesh {
    Mesh::from_bytes(t.as_bytes()).unwrap_or_else(|e| panic!("{e}"))
}

// ---- sections given twice ----

#[test]
fn second_physical_names_or_mesh_format_refused() {
    // A second $PhysicalNames renamed group 4 ("support" became "other").
    let t = text(Q4_22) + "$PhysicalNames\n1\n1 4 \"other\"\n$EndPhysicalNames\n";
    let e = err(&t);
    assert!(
        matches!(&e.kind, K::SectionOrder { found, .. } if found == "$PhysicalNames"),
        "{e}"
    );
    let second = t.match_indices("$PhysicalNames").nth(1).unwrap().0;
    let line = 1 + t[..second].matches('\n').count();
    assert_eq!(e.location, Location::Line(line));
    // A second $MeshFormat was skipped whatever it said.
    let t = text(Q4_41) + "$MeshFormat\n2.2 1 8\n$EndMeshFormat\n";
    let e = err(&t);
    assert!(
        matches!(&e.kind, K::SectionOrder { found, .. } if found == "$MeshFormat"),
        "{e}"
    );
    assert_eq!(e.location, Location::Line(t.lines().count() - 2));
}

// ---- binary files copied in text mode ----

/// A binary file whose LF were turned into CR LF (a text-mode copy) is
/// reported as such, at the end of the $MeshFormat line; it was reported as
/// cut short, or as NaN coordinates.
#[test]
fn binary_with_crlf_line_ends() {
    for name in ["slab_q4_v22_bin.msh", "slab_q4_v41_bin.msh"] {
        let b = bytes(name);
        let mut crlf = Vec::with_capacity(b.len() * 2);
        for &c in &b {
            if c == b'\n' {
                crlf.push(b'\r');
            }
            crlf.push(c);
        }
        let e = byte_err(&crlf, find(&crlf, b" 8\r\n") + 2);
        assert_eq!(e.kind, K::TextModeTransfer, "{name}: {e}");
        assert!(e.to_string().contains("binary mode"), "{e}");
        // Only the byte-order integer shifted by a CR.
        let mut b = b.clone();
        let at = find(&b, b" 8\n") + 3;
        b.insert(at, b'\r');
        let e = byte_err(&b, at);
        assert_eq!(e.kind, K::TextModeTransfer, "{name}: {e}");
    }
}

/// Values quoted in messages are short: a bad binary coordinate is shown in
/// exponent form, not as 300 decimals.
#[test]
fn bad_binary_coordinates_are_quoted_short() {
    for name in ["slab_q4_v22_bin.msh", "slab_q4_v41_bin.msh"] {
        let mut b = bytes(name);
        // The first node's coordinates: after the 2.2 count line and tag,
        // or the 4.1 headers and the block's one tag.
        let x = if name.contains("v22") {
            find(&b, b"$Nodes\n15\n") + 10 + 4
        } else {
            find(&b, b"$Nodes\n") + 7 + 32 + 20 + 8
        };
        b[x..x + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        b[x + 16..x + 24].copy_from_slice(&f64::MIN_POSITIVE.to_le_bytes());
        let e = err_bytes(&b);
        let K::NotANumber { found, .. } = &e.kind else {
            panic!("{name}: {e}")
        };
        assert!(found.len() < 40, "{name}: {found}");
        assert!(found.contains("2.2250738585072014e-308"), "{name}: {found}");
    }
}

/// Other values quoted in messages: a huge z in exponent form, a long
/// section keyword cut.
#[test]
fn long_values_are_quoted_short() {
    let t = replace_line(
        &text(Q4_22),
        "9 6.000000000002768 1.375000000000173 0",
        "9 6.000000000002768 1.375000000000173 1e300",
    );
    let e = err(&t);
    assert!(e.to_string().contains("has z = 1e300,"), "{e}");
    let t = text(Q4_22) + "$" + &"A".repeat(300) + "\n1 2 3\n";
    let e = err(&t);
    assert!(e.to_string().len() < 300, "{e}");
    assert!(matches!(e.kind, K::MissingEnd { .. }), "{e}");
}

// ---- a group named twice ----

/// A (dim, tag) named twice was read with the last name: `1 3 "left"`, a
/// typo for `1 4`, silently moved "left" onto group 3. Refused at the
/// repeat, naming the line of the first name.
#[test]
fn a_group_named_twice_is_refused_at_the_repeat() {
    let t = replace_line(&text(Q4_22), "1 4 \"support\"", "1 3 \"left\"");
    let e = err_at_line(&t, "1 3 \"left\"");
    assert_eq!(
        e.kind,
        K::DuplicatePhysicalName {
            dim: 1,
            tag: 3,
            name: "left".into(),
            first: Location::Line(line_no(&t, "1 3 \"load\"")),
            first_name: "load".into(),
        }
    );
    let msg = e.to_string();
    assert!(
        msg.contains("line 8 already named it \"load\"") && msg.contains("wrong tag"),
        "{msg}"
    );
    // The same line twice names nothing new: read (a case naming the
    // group the copy replaced then finds it missing, by name); in a binary
    // file a repeat with another name is refused at byte offsets.
    let t = replace_line(&text(Q4_22), "1 4 \"support\"", "1 3 \"load\"");
    let mesh = Mesh::from_bytes(t.as_bytes()).expect("a copied line is harmless");
    assert!(mesh.group("load").is_ok() && mesh.group("support").is_err());
    let b = bytes("slab_q4_v41_bin.msh");
    let at = find(&b, b"1 4 \"support\"");
    let mut dup = b.clone();
    dup[at + 2] = b'3';
    let e = byte_err(&dup, at);
    assert!(
        matches!(&e.kind, K::DuplicatePhysicalName { first: Location::Byte(f), .. }
            if *f == find(&b, b"1 3 \"load\"")),
        "{e}"
    );
    // One name on groups of different dimensions stays readable (Gmsh
    // allows it; `Mesh::group` asks which one is meant).
    let t = replace_line(&text(Q4_22), "1 4 \"support\"", "2 4 \"load\"");
    assert!(Mesh::from_bytes(t.as_bytes()).is_ok());
}

// ---- the encoding $MeshFormat declares, against the content ----

/// A binary file whose file-type says ASCII was "$MeshFormat declares 0
/// entries"; an ASCII file flagged binary, "the byte-order check ... is
/// [36, 69, 110, 100]". Both now say the header does not match the data.
#[test]
fn an_encoding_that_does_not_match_the_content_is_named() {
    for name in ["slab_q4_v22_bin.msh", "slab_q4_v41_bin.msh"] {
        let mut b = bytes(name);
        let at = find(&b, b" 1 8\n");
        b[at + 1] = b'0';
        let e = err_bytes(&b);
        assert_eq!(e.kind, K::BinaryInAscii, "{name}: {e}");
        // The byte-order integer starts line 3.
        assert_eq!(e.location, Location::Line(3), "{name}");
        assert!(
            e.to_string().contains("re-export the mesh from Gmsh"),
            "{e}"
        );
        // Without the integer: the binary node data, where a count was due.
        let int = find(&b, &[1, 0, 0, 0, b'\n']);
        b.drain(int..int + 5);
        let e = err_bytes(&b);
        assert_eq!(e.kind, K::BinaryInAscii, "{name}: {e}");
    }
    for name in [Q4_22, Q4_41] {
        let t = text(name).replacen(" 0 8\n", " 1 8\n", 1);
        let e = err(&t);
        assert_eq!(e.kind, K::AsciiInBinary, "{name}: {e}");
        assert_eq!(e.location, Location::Line(3), "{name}");
        // Its lines ending in CR LF: still ASCII, not a text-mode copy.
        let e = err(&t.replace('\n', "\r\n"));
        assert_eq!(e.kind, K::AsciiInBinary, "{name}: {e}");
    }
}

// ---- paths that are no regular file ----

/// `stickslip mesh /tmp` said only "Is a directory (os error 21)", and a
/// device was read whole before parsing (`/dev/zero`: without bound).
/// Both are refused before anything is read, naming the path.
#[test]
fn directories_and_devices_are_refused_before_reading() {
    let dir = std::env::temp_dir();
    let e = Mesh::from_file(&dir).unwrap_err();
    assert_eq!(e.kind, K::IsDirectory, "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("{}: is a directory", dir.display())),
        "{e}"
    );
    assert!(e.to_string().contains("give the .msh file"), "{e}");
    // /dev/null reads as empty, which was "the file is empty"; /dev/zero
    // never ends (not read here: without the check it would fill memory).
    let e = Mesh::from_file("/dev/null").unwrap_err();
    assert_eq!(e.kind, K::NotRegularFile, "{e}");
    assert!(
        e.to_string().starts_with("/dev/null: not a regular file"),
        "{e}"
    );
}
