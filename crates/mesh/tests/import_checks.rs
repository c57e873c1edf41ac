//! Checks the reader makes beyond the format itself (from a user review of
//! the import): what it drops, what it refuses and what it records. The
//! meshes are small and written inline, each exercising one finding.

mod common;
use common::*;
use stickslip_mesh::{Location, Mesh, MeshError, MeshErrorKind as K};

fn err(s: &str) -> MeshError {
    match parse_str(s) {
        Ok(_) => panic!("bad input was accepted"),
        Err(e) => e,
    }
}

// ---- nodes used by no cell ----

/// Two quad4 cells (tags 1-6) and two nodes no cell uses (9 and 8, one in
/// the middle of the list), node 9 a dimension-0 group of its own as a
/// geometry point saved with Mesh.SaveAll = 1 would be.
const ORPHANS_22: &str = "\
$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
4
0 5 \"pin\"
0 6 \"centre\"
1 1 \"bottom\"
2 2 \"body\"
$EndPhysicalNames
$Nodes
8
1 0 0 0
2 1 0 0
9 5 5 0
3 2 0 0
4 0 1 0
5 1 1 0
6 2 1 0
8 -3 7 0
$EndNodes
$Elements
6
1 15 2 5 1 4
2 15 2 6 2 9
3 1 2 1 1 1 2
4 1 2 1 1 2 3
5 3 2 2 1 1 2 5 4
6 3 2 2 1 2 3 6 5
$EndElements
";

#[test]
fn nodes_in_no_cell_are_dropped() {
    let m = parse_str(ORPHANS_22).unwrap();
    check_invariants(&m);
    assert_eq!(m.source.unused_nodes, 2);
    assert_eq!(m.node_tags, [1, 2, 3, 4, 5, 6]);
    assert_eq!(m.nodes.len(), 6);
    assert_eq!(m.nodes[2], [2.0, 0.0], "tag 3 follows the dropped tag 9");
    assert_eq!(m.cells, [0, 1, 4, 3, 1, 2, 5, 4]);
    // The bounding box is the cells', not the far geometry points'.
    assert_eq!(m.bbox(), [[0.0, 0.0], [2.0, 1.0]]);
    let bottom = m.group("bottom").unwrap();
    let ends: Vec<[usize; 2]> = bottom.edges.iter().map(|e| e.nodes).collect();
    assert_eq!(ends, [[0, 1], [1, 2]]);
    assert_eq!(bottom.nodes, [0, 1, 2]);
    let pin = m.group("pin").unwrap();
    assert_eq!((pin.points.as_slice(), pin.elements), (&[3][..], 1));
    assert_eq!(pin.nodes, [3]);
    // The point on the dropped node leaves its group, which stays (empty).
    let centre = m.group("centre").unwrap();
    assert!(centre.points.is_empty() && centre.nodes.is_empty());
    assert_eq!(centre.elements, 0);
    assert_eq!(m.group("body").unwrap().nodes, [0, 1, 2, 3, 4, 5]);
}

/// The kind a .geo declares each group as, which the messages about an
/// empty group (`check`, `mesh`) name.
#[test]
fn groups_name_their_physical_kind() {
    let m = parse_str(ORPHANS_22).unwrap();
    for (name, kind) in [("pin", "Point"), ("bottom", "Curve"), ("body", "Surface")] {
        assert_eq!(m.group(name).unwrap().physical_kind(), kind, "{name}");
    }
    assert_eq!(
        m.group("centre").unwrap().empty_remedy(),
        "check the entities of its Physical Point in the .geo"
    );
}

#[test]
fn a_mesh_without_unused_nodes_reports_none() {
    let m = load("slab_q9_v41_ascii.msh");
    assert_eq!(m.source.unused_nodes, 0);
}

/// Gmsh 4.1 output with Mesh.SaveAll = 1 (from the user review: the plate
/// with a hole, quad4): the circle's centre (tag 5 at (2, 1)) is saved as
/// a node that no cell uses.
#[test]
fn gmsh_save_all_centre_point_is_dropped() {
    let m = load("hole_q4_saveall_v41_ascii.msh");
    check_invariants(&m);
    assert_eq!(m.source.unused_nodes, 1);
    assert_eq!(m.nodes.len(), 268);
    assert!(!m.node_tags.contains(&5));
    assert!(m.node_tags.windows(2).all(|w| w[0] < w[1]));
}

// ---- quad9 inverted inside ----

/// One quad9 cell on the unit square (Gmsh's node order: corners, mid-sides
/// of (0,1) (1,2) (2,3) (3,0), centre), node `moved` (1-based) put at `at`,
/// given clockwise if `cw`. The element is on line 18.
fn quad9(moved: usize, at: [f64; 2], cw: bool) -> String {
    let mut p = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [0.5, 0.0],
        [1.0, 0.5],
        [0.5, 1.0],
        [0.0, 0.5],
        [0.5, 0.5],
    ];
    p[moved - 1] = at;
    let nodes: String = p
        .iter()
        .enumerate()
        .map(|(i, q)| format!("{} {} {} 0\n", i + 1, q[0], q[1]))
        .collect();
    let conn = if cw {
        "1 4 3 2 8 7 6 5 9"
    } else {
        "1 2 3 4 5 6 7 8 9"
    };
    format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n9\n{nodes}$EndNodes\n\
         $Elements\n1\n7 10 2 1 1 {conn}\n$EndElements\n"
    )
}

#[test]
fn quad9_inverted_by_its_centre_or_a_mid_side_node_is_refused() {
    for (moved, at) in [
        (9, [0.5, 1.4]),  // centre above the top side
        (6, [-0.2, 0.5]), // right mid-side node beyond the left side
        (5, [0.5, 1.3]),  // bottom mid-side node beyond the top side
    ] {
        for cw in [false, true] {
            let e = err(&quad9(moved, at, cw));
            assert_eq!(e.kind, K::InvertedCell { element: 7 }, "{moved} {at:?}");
            assert_eq!(e.location, Location::Line(18));
            assert!(e.to_string().contains("line 18: cell 7 is inverted"), "{e}");
        }
    }
}

#[test]
fn curved_quad9_inside_out_nowhere_is_read() {
    for (moved, at) in [
        (9, [0.5, 0.5]),
        (9, [0.6, 0.4]),
        (6, [1.3, 0.5]),
        (5, [0.5, 0.2]),
    ] {
        for cw in [false, true] {
            let m = parse_str(&quad9(moved, at, cw)).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(m.source.reoriented, usize::from(cw));
        }
    }
}

// ---- one name, several groups ----

#[test]
fn a_name_of_groups_of_two_dimensions_is_ambiguous() {
    // The orphans mesh with its line group renamed "body", like the surface.
    let t = ORPHANS_22.replace("1 1 \"bottom\"", "1 1 \"body\"");
    let m = parse_str(&t).unwrap();
    let e = m.group("body").unwrap_err();
    assert_eq!(
        e.kind,
        K::AmbiguousGroup {
            name: "body".into(),
            groups: vec![(1, 1), (2, 2)],
        }
    );
    let msg = e.to_string();
    assert!(
        msg.contains("\"body\" (dim 1 tag 1, dim 2 tag 2)") && msg.contains("rename"),
        "{msg}"
    );
    // Unique names are found as before; an unknown one is still unknown.
    assert_eq!(m.group("pin").unwrap().dim, 0);
    assert!(matches!(
        m.group("nope").unwrap_err().kind,
        K::UnknownGroup { .. }
    ));
}

// ---- a mesh in another plane ----

/// One quad4 in the xz-plane: flat in xy, so degenerate there, but the
/// cause is the plane. Node 3 (line 8) is the first with the largest |z|.
const XZ_22: &str = "\
$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
4
1 0 0 0
2 2 0 0
3 2 0 1
4 0 0 1
$EndNodes
$Elements
1
1 3 2 1 1 1 2 3 4
$EndElements
";

/// The same in MSH 4.1: node 3's coordinates are on line 13.
const XZ_41: &str = "\
$MeshFormat
4.1 0 8
$EndMeshFormat
$Nodes
1 4 1 4
2 1 0 4
1
2
3
4
0 0 0
2 0 0
2 0 1
0 0 1
$EndNodes
$Elements
1 1 1 1
2 1 3 1
1 1 2 3 4
$EndElements
";

#[test]
fn a_mesh_in_the_xz_plane_is_not_planar_at_its_node() {
    for (t, line) in [(XZ_22, 8), (XZ_41, 13)] {
        let e = err(t);
        assert!(
            matches!(e.kind, K::NotPlanar { node: 3, z, .. } if z == 1.0),
            "{e}"
        );
        assert_eq!(e.location, Location::Line(line), "{e}");
        // Also what a 3-D mesh meets first now: say to mesh in 2-D.
        assert!(e.to_string().contains("mesh it in 2-D (`gmsh -2`)"), "{e}");
    }
}

#[test]
fn binary_not_planar_names_the_node_record() {
    // MSH 2.2 binary node records: i32 tag, 3 f64; put z = 2 into tag 7's.
    let mut b = bytes("slab_q4_v22_bin.msh");
    let data = find(&b, b"$Nodes\n15\n") + 10;
    let rec = data + 28 * 6;
    assert_eq!(b[rec..rec + 4], 7i32.to_le_bytes());
    b[rec + 20..rec + 28].copy_from_slice(&2.0f64.to_le_bytes());
    let e = Mesh::from_bytes(&b).unwrap_err();
    assert!(matches!(e.kind, K::NotPlanar { node: 7, z, .. } if z == 2.0));
    assert_eq!(e.location, Location::Byte(rec));
}

// ---- element order 3 and up ----

#[test]
fn order_3_elements_are_refused_for_their_order() {
    // MSH 2.2: a line4 (type 26) where the first line2 was.
    let t = ORPHANS_22.replace("3 1 2 1 1 1 2\n", "3 26 2 1 1 1 2 3 5\n");
    let e = err(&t);
    assert_eq!(
        e.kind,
        K::UnsupportedOrder {
            element: 3,
            type_id: 26,
            name: "line4",
            order: 3
        }
    );
    assert_eq!(
        e.location,
        Location::Line(line_no(&t, "3 26 2 1 1 1 2 3 5"))
    );
    let msg = e.to_string();
    assert!(
        msg.contains("order 3") && msg.contains("`gmsh -order 1` or `-order 2`"),
        "{msg}"
    );
    assert!(!msg.contains("3-D"), "{msg}");
    // MSH 4.1: a block of quad16 (type 36) cells, located at its header.
    let t = XZ_41.replace("2 0 1\n0 0 1\n", "2 2 0\n0 2 0\n").replace(
        "2 1 3 1\n1 1 2 3 4\n",
        "2 1 36 1\n8 1 2 3 4 1 2 3 4 1 2 3 4 1 2 3 4\n",
    );
    let e = err(&t);
    assert_eq!(
        e.kind,
        K::UnsupportedOrder {
            element: 8,
            type_id: 36,
            name: "quad16",
            order: 3
        }
    );
    assert_eq!(e.location, Location::Line(line_no(&t, "2 1 36 1")));
}

// ---- partitioned meshes ----

/// Gmsh 4.1 output of the slab partitioned in two (`gmsh -part 2`; from the
/// user review), ASCII quad4 and binary quad9.
#[test]
fn partitioned_41_meshes_are_refused_at_their_partitioned_entities() {
    let t = text("slab_q4_part2_v41_ascii.msh");
    let e = Mesh::from_bytes(t.as_bytes()).unwrap_err();
    assert_eq!(e.kind, K::Partitioned);
    assert_eq!(
        e.location,
        Location::Line(line_no(&t, "$PartitionedEntities"))
    );
    let msg = e.to_string();
    assert!(msg.contains("without `-part`"), "{msg}");
    let b = bytes("slab_q9_part2_v41_bin.msh");
    let e = Mesh::from_bytes(&b).unwrap_err();
    assert_eq!(e.kind, K::Partitioned);
    assert_eq!(
        e.location,
        Location::Byte(find(&b, b"$PartitionedEntities"))
    );
}

// ---- MSH 2.2 $ParametricNodes ----

/// Gmsh 4.15 output of a 2 x 1 slab of two quad4 cells with
/// Mesh.SaveParametric = 1 (MSH 2.2 ASCII); the binary twin is the fixture
/// small_q4_param_v22_bin.msh, and small_q4_v22_bin.msh the same mesh
/// saved without parameters.
const PARAM_22: &str = "\
$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
1 1 \"contact\"
2 2 \"body\"
$EndPhysicalNames
$ParametricNodes
6
1 0 0 0 0 1
2 2 0 0 0 2
3 2 1 0 0 3
4 0 1 0 0 4
5 0.9999999999973842 0 0 1 1 0.4999999999986921
6 1.000000000004119 1 0 1 3 0.4999999999979405
$EndParametricNodes
$Elements
4
1 1 2 1 1 1 5
2 1 2 1 1 5 2
3 3 2 2 1 1 5 6 4
4 3 2 2 1 5 2 3 6
$EndElements
";

#[test]
fn msh22_parametric_nodes_are_read_as_nodes() {
    let m = parse_str(PARAM_22).unwrap_or_else(|e| panic!("{e}"));
    check_invariants(&m);
    assert_eq!(m.nodes.len(), 6);
    assert_eq!(m.nodes[4], [0.9999999999973842, 0.0]);
    // The same mesh as its plain $Nodes form (entity and parameters cut).
    let mut plain = String::new();
    let mut in_nodes = false;
    for l in PARAM_22.lines() {
        let l = match l {
            "$ParametricNodes" => {
                in_nodes = true;
                "$Nodes".to_string()
            }
            "$EndParametricNodes" => {
                in_nodes = false;
                "$EndNodes".to_string()
            }
            l if in_nodes && l.split(' ').count() > 1 => {
                l.split(' ').take(4).collect::<Vec<_>>().join(" ")
            }
            l => l.to_string(),
        };
        plain += &l;
        plain.push('\n');
    }
    assert_eq!(parse_str(&plain).unwrap(), m);
    // Binary: records of 36 bytes plus 8 per parameter.
    let b = load("small_q4_param_v22_bin.msh");
    same_mesh(&b, &m, "binary parametric");
    same_mesh(&b, &load("small_q4_v22_bin.msh"), "binary plain");
}

#[test]
fn msh22_parametric_nodes_damaged_are_located() {
    // A node on a "dimension 5" entity.
    let t = PARAM_22.replace(
        "\n6 1.000000000004119 1 0 1 3 ",
        "\n6 1.000000000004119 1 0 5 3 ",
    );
    let e = err(&t);
    assert!(matches!(e.kind, K::Malformed { .. }), "{e}");
    assert_eq!(e.location, Location::Line(16));
    // A curve node without its parameter: its own line is short (read as
    // a stream, the next node's tag stood in for it and the count was off).
    let t = PARAM_22.replace(" 1 3 0.4999999999979405\n", " 1 3\n");
    let e = err(&t);
    assert!(matches!(&e.kind, K::FieldCount { found: 6, .. }), "{e}");
    assert_eq!(
        e.location,
        Location::Line(1 + t.lines().position(|l| l.ends_with(" 1 3")).unwrap())
    );
}

// ---- line groups inside the body ----

#[test]
fn a_line_group_between_two_cells_is_counted_as_interior() {
    // The orphans mesh with a group "mid" on the side 2-5 the cells share.
    let t = ORPHANS_22
        .replace("4\n0 5 \"pin\"", "5\n1 7 \"mid\"\n0 5 \"pin\"")
        .replace("$Elements\n6\n", "$Elements\n7\n7 1 2 7 1 5 2\n");
    let m = parse_str(&t).unwrap_or_else(|e| panic!("{e}"));
    check_invariants(&m);
    let mid = m.group("mid").unwrap();
    assert_eq!(mid.edges.len(), 1);
    assert_eq!(m.interior_edges(mid), 1);
    assert_eq!(m.interior_edges(m.group("bottom").unwrap()), 0);
    assert_eq!(m.interior_edges(m.group("body").unwrap()), 0);
    assert_eq!(m.source.interior_edges.len(), 1);
}

/// Gmsh 4.1 output (from the user review): the slab with an embedded curve
/// `Line{5} In Surface{1}` from (2, 0.5) to (6, 0.5), group "crack".
#[test]
fn an_embedded_curve_group_is_inside_the_body() {
    let m = load("slab_q4_embedded_v41_ascii.msh");
    check_invariants(&m);
    let crack = m.group("crack").unwrap();
    assert_eq!(crack.elements, 16);
    assert_eq!(m.interior_edges(crack), 16);
    for g in ["contact", "load", "support", "left"] {
        assert_eq!(m.interior_edges(m.group(g).unwrap()), 0, "{g}");
    }
}
