//! MSH 2.2 `$Nodes` and `$Elements`, ASCII and binary.
//!
//! Physical membership is the element's first tag. Gmsh writes an element
//! that is in several physical groups once per group, consecutively and
//! under new element numbers; [`Builder::element`] merges those copies
//! (same type, elementary tag and nodes as the previous element).

use std::collections::HashMap;

use super::build::{counted, nodes_of, type_name, unsupported, Builder, Membership};
use super::cursor::{le_f64, le_i32, Cursor, Result};
use crate::MeshErrorKind;

/// `$Nodes`, or `$ParametricNodes` (Mesh.SaveParametric = 1): each node
/// then also has the dimension and tag of its geometric entity and, on a
/// curve or surface, 1 or 2 parametric coordinates, which are skipped.
pub(crate) fn nodes(cur: &mut Cursor<'_>, b: &mut Builder, parametric: bool) -> Result<()> {
    if parametric {
        cur.enter("$ParametricNodes", "$EndParametricNodes");
    } else {
        cur.enter("$Nodes", "$EndNodes");
    }
    cur.skip_ws();
    let header = cur.pos();
    let n = cur.u64("the number of nodes")?;
    cur.counts("nodes", n);
    if parametric {
        parametric_nodes(cur, b, n)?;
    } else if cur.binary {
        cur.end_of_line()?;
        let bytes = cur.check_items(n, 28)?;
        b.nodes.reserve(bytes / 28);
        b.node_tags.reserve(bytes / 28);
        let mut left = n;
        while left > 0 {
            let (start, k) = cur.batch(left, 28)?;
            left -= k as u64;
            let cur = &*cur;
            for (i, rec) in cur.records(start, 28 * k).chunks_exact(28).enumerate() {
                let at = start + 28 * i;
                let tag = binary_tag(cur, at, le_i32(rec))?;
                let xyz = [le_f64(&rec[4..]), le_f64(&rec[12..]), le_f64(&rec[20..])];
                let [x, y, z] = finite_xyz(cur, at + 4, xyz)?;
                b.push_node(tag, x, y, z, at);
            }
        }
    } else {
        // A node line is at least "1 0 0 0\n".
        let cap = cur.capped(n, 8);
        b.nodes.reserve(cap);
        b.node_tags.reserve(cap);
        for _ in 0..n {
            let (at, tag, [x, y, z]) = ascii_node(cur)?;
            cur.line_done(at, 4, || NODE.into())?;
            b.push_node(tag, x, y, z, cur.pos());
        }
    }
    cur.expect_end()?;
    b.finish_nodes(cur, header)
}

const NODE: &str = "a node needs 4 numbers (its tag, x, y and z)";
const PARAMETRIC: &str =
    "a parametric node needs at least 6 numbers (its tag, x, y, z, entity dimension and entity tag)";

/// An ASCII node line's start, tag and coordinates (`$Nodes` and
/// `$ParametricNodes` alike); the caller checks the rest of the line.
#[inline(always)]
fn ascii_node(cur: &mut Cursor<'_>) -> Result<(usize, u64, [f64; 3])> {
    cur.skip_ws();
    let at = cur.pos();
    let tag = cur.u64("a node tag")?;
    let mut xyz = [0.0; 3];
    for (k, v) in xyz.iter_mut().enumerate() {
        cur.need_field(at, 1 + k, || NODE.into())?;
        *v = cur.f64("a node coordinate")?;
    }
    Ok((at, tag, xyz))
}

/// A binary node record's tag, which must not be negative (at byte `at`).
fn binary_tag(cur: &Cursor<'_>, at: usize, raw: i32) -> Result<u64> {
    u64::try_from(raw).map_err(|_| {
        cur.error(
            at,
            MeshErrorKind::Malformed {
                what: format!("node tag {raw} is negative"),
            },
        )
    })
}

/// A binary node record's coordinates, which must be finite (at byte `at`).
fn finite_xyz(cur: &Cursor<'_>, at: usize, xyz: [f64; 3]) -> Result<[f64; 3]> {
    if xyz.iter().all(|v| v.is_finite()) {
        return Ok(xyz);
    }
    let [x, y, z] = xyz;
    Err(cur.error(
        at,
        MeshErrorKind::NotANumber {
            what: "a node coordinate",
            // Debug, not Display: a tiny value would be 300 digits.
            found: format!("{x:?} {y:?} {z:?}"),
        },
    ))
}

/// The records of `$ParametricNodes`: `tag x y z dim entity [u [v]]`,
/// binary as i32, 3 f64, 2 i32 and `dim` f64 (Gmsh writes parameters on
/// curves and surfaces only). Records differ in length: read one by one.
fn parametric_nodes(cur: &mut Cursor<'_>, b: &mut Builder, n: u64) -> Result<()> {
    if cur.binary {
        cur.end_of_line()?;
        // At least tag, x, y, z, dim and entity: 36 bytes a node.
        let cap = cur.check_items(n, 36)? / 36;
        b.nodes.reserve(cap);
        b.node_tags.reserve(cap);
        for _ in 0..n {
            let at = cur.pos();
            let raw = cur.bin_i32()?;
            let tag = binary_tag(cur, at, raw)?;
            let xyz =
                [cur.take::<8>()?, cur.take::<8>()?, cur.take::<8>()?].map(f64::from_le_bytes);
            let [x, y, z] = finite_xyz(cur, at + 4, xyz)?;
            let dp = cur.pos();
            let dim = cur.bin_i32()?;
            cur.bin_i32()?;
            cur.skip(8 * parameters(cur, dp, dim)?)?;
            b.push_node(tag, x, y, z, at);
        }
    } else {
        // A node line is at least "1 0 0 0 0 1\n".
        let cap = cur.capped(n, 12);
        b.nodes.reserve(cap);
        b.node_tags.reserve(cap);
        for _ in 0..n {
            let (line, tag, [x, y, z]) = ascii_node(cur)?;
            let at = cur.pos();
            cur.need_field(line, 4, || PARAMETRIC.into())?;
            let dp = cur.pos();
            let dim = cur.i32("the dimension of a node's geometric entity")?;
            cur.need_field(line, 5, || PARAMETRIC.into())?;
            cur.i32("the tag of a node's geometric entity")?;
            let np = parameters(cur, dp, dim)?;
            let record = || {
                format!(
                    "a parametric node on an entity of dimension {dim} needs {} numbers (its tag, x, y, z, entity dimension, entity tag and {})",
                    6 + np,
                    counted(np as u64, "parametric coordinate")
                )
            };
            for k in 0..np {
                cur.need_field(line, 6 + k, record)?;
                cur.f64("a parametric node coordinate")?;
            }
            cur.line_done(line, 6 + np, record)?;
            b.push_node(tag, x, y, z, at);
        }
    }
    Ok(())
}

/// How many parametric coordinates a node on an entity of dimension `dim`
/// has in MSH 2.2 (Gmsh writes u on curves, u v on surfaces).
fn parameters(cur: &Cursor<'_>, pos: usize, dim: i32) -> Result<usize> {
    match dim {
        0 | 3 => Ok(0),
        1 | 2 => Ok(dim as usize),
        _ => Err(cur.error(
            pos,
            MeshErrorKind::Malformed {
                what: format!("a parametric node's entity dimension is {dim}, not 0 to 3"),
            },
        )),
    }
}

/// Physical tag → membership id, without a Vec per element.
#[derive(Default)]
struct Members {
    last: Option<(i32, Membership)>,
    ids: HashMap<i32, Membership>,
}

impl Members {
    fn get(&mut self, b: &mut Builder, phys: i32) -> Membership {
        if phys == 0 {
            return 0;
        }
        if let Some((p, id)) = self.last {
            if p == phys {
                return id;
            }
        }
        let id = *self
            .ids
            .entry(phys)
            .or_insert_with(|| b.membership(vec![phys]));
        self.last = Some((phys, id));
        id
    }
}

pub(crate) fn elements(cur: &mut Cursor<'_>, b: &mut Builder) -> Result<()> {
    cur.enter("$Elements", "$EndElements");
    let n = cur.u64("the number of elements")?;
    cur.counts("elements", n);
    let mut members = Members::default();
    let mut nodes = [0u64; 9];
    // Mostly cells (Gmsh writes few boundary elements); at least a quad4
    // record each: 20 bytes binary, "1 3 0 1 2 3 4\n" ASCII.
    b.expect_cells(cur, n, 4, if cur.binary { 20 } else { 14 });
    if cur.binary {
        cur.end_of_line()?;
        let mut read: u64 = 0;
        while read < n {
            if cur.at_keyword() {
                return Err(cur.wrong_count(cur.pos()));
            }
            let hp = cur.pos();
            let type_id = cur.bin_i32()?;
            let following = cur.bin_i32()?;
            let ntags = cur.bin_i32()?;
            let (Ok(following), Ok(ntags)) = (u64::try_from(following), usize::try_from(ntags))
            else {
                return Err(cur.error(
                    hp,
                    MeshErrorKind::Malformed {
                        what: "negative element count in a binary element header".into(),
                    },
                ));
            };
            if following == 0 || following > n - read {
                return Err(cur.wrong_count(hp));
            }
            let Some(nn) = nodes_of(type_id) else {
                let first = <[u8; 4]>::try_from(cur.peek(4))
                    .map_or(0, |t| u64::try_from(i32::from_le_bytes(t)).unwrap_or(0));
                return Err(unsupported(cur, hp, first, type_id));
            };
            let size = ntags.checked_add(1 + nn).and_then(|k| k.checked_mul(4));
            let Some(size) = size else {
                return Err(cur.error(
                    hp,
                    MeshErrorKind::Truncated {
                        what: "the $Elements section",
                    },
                ));
            };
            cur.check_items(following, size)?;
            let mut left = following;
            while left > 0 {
                let (start, k) = cur.batch(left, size)?;
                left -= k as u64;
                let cur = &*cur;
                let data = cur.records(start, size * k);
                // Gmsh writes one header per element (k = 1): slice by
                // offsets, not chunks_exact, which divides by `size`.
                for i in 0..k {
                    let rec = &data[size * i..size * (i + 1)];
                    let at = start + size * i;
                    let tag = u64::try_from(le_i32(rec)).map_err(|_| {
                        cur.error(
                            at,
                            MeshErrorKind::Malformed {
                                what: format!("element tag {} is negative", le_i32(rec)),
                            },
                        )
                    })?;
                    let tags = &rec[4..4 + 4 * ntags];
                    let phys = tags.get(..4).map_or(0, le_i32);
                    let elementary = tags.get(4..8).map_or(0, le_i32);
                    for (k, t) in rec[4 + 4 * ntags..].chunks_exact(4).enumerate() {
                        let v = le_i32(t);
                        nodes[k] = u64::try_from(v).map_err(|_| {
                            cur.error(
                                at,
                                MeshErrorKind::MissingNode {
                                    element: tag,
                                    node: i64::from(v),
                                },
                            )
                        })?;
                    }
                    let member = members.get(b, phys);
                    b.element(
                        cur,
                        at,
                        type_id,
                        tag,
                        &nodes[..nn],
                        member,
                        Some(elementary),
                    )?;
                }
            }
            read += following;
        }
    } else {
        const HEAD: &str =
            "an element needs at least 3 numbers (its number, type and number of tags)";
        for _ in 0..n {
            cur.skip_ws();
            let at = cur.pos();
            let tag = cur.u64("an element tag")?;
            cur.need_field(at, 1, || HEAD.into())?;
            let type_id = cur.i32("an element type")?;
            cur.need_field(at, 2, || HEAD.into())?;
            let ntags = cur.u64("the number of element tags")?;
            // The type tells how many node tags follow the tags.
            let Some(nn) = nodes_of(type_id) else {
                return Err(unsupported(cur, at, tag, type_id));
            };
            let fields = 3usize.saturating_add(usize::try_from(ntags).unwrap_or(usize::MAX));
            let record = || {
                format!(
                    "a {} element with {} needs {} numbers (its number, type, number of tags, the tags and {})",
                    type_name(type_id),
                    counted(ntags, "tag"),
                    fields.saturating_add(nn),
                    counted(nn as u64, "node tag")
                )
            };
            let (mut phys, mut elementary) = (0i32, 0i32);
            for k in 0..ntags {
                cur.need_field(at, 3 + k as usize, record)?;
                let (p, v) = cur.i64("an element tag (physical, elementary, ...)")?;
                let v = i32::try_from(v).map_err(|_| {
                    cur.error(
                        p,
                        MeshErrorKind::NotANumber {
                            what: "a 32-bit element tag",
                            found: v.to_string(),
                        },
                    )
                })?;
                match k {
                    0 => phys = v,
                    1 => elementary = v,
                    _ => {}
                }
            }
            for (k, slot) in nodes.iter_mut().take(nn).enumerate() {
                cur.need_field(at, fields + k, record)?;
                let (_, v) = cur.i64("a node tag")?;
                *slot = u64::try_from(v).map_err(|_| {
                    cur.error(
                        at,
                        MeshErrorKind::MissingNode {
                            element: tag,
                            node: v,
                        },
                    )
                })?;
            }
            cur.line_done(at, fields + nn, record)?;
            let member = members.get(b, phys);
            b.element(
                cur,
                at,
                type_id,
                tag,
                &nodes[..nn],
                member,
                Some(elementary),
            )?;
        }
    }
    cur.expect_end()
}
