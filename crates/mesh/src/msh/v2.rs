//! MSH 2.2 `$Nodes` and `$Elements`, ASCII and binary.
//!
//! Physical membership is the element's first tag. Gmsh writes an element
//! that is in several physical groups once per group, consecutively and
//! under new element numbers; [`Builder::element`] merges those copies
//! (same type, elementary tag and nodes as the previous element).

use std::collections::HashMap;

use super::build::{nodes_of, unsupported, Builder, Membership};
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
            let (tag, [x, y, z]) = ascii_node(cur)?;
            b.push_node(tag, x, y, z, cur.pos());
        }
    }
    cur.expect_end()?;
    b.finish_nodes(cur, header)
}

/// An ASCII node line's tag and coordinates (`$Nodes` and
/// `$ParametricNodes` alike).
#[inline(always)]
fn ascii_node(cur: &mut Cursor<'_>) -> Result<(u64, [f64; 3])> {
    let tag = cur.u64("a node tag")?;
    let x = cur.f64("a node coordinate")?;
    let y = cur.f64("a node coordinate")?;
    let z = cur.f64("a node coordinate")?;
    Ok((tag, [x, y, z]))
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
            found: format!("{x} {y} {z}"),
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
            let (tag, [x, y, z]) = ascii_node(cur)?;
            let at = cur.pos();
            cur.skip_ws();
            let dp = cur.pos();
            let dim = cur.i32("the dimension of a node's geometric entity")?;
            cur.i32("the tag of a node's geometric entity")?;
            for _ in 0..parameters(cur, dp, dim)? {
                cur.f64("a parametric node coordinate")?;
            }
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
        for _ in 0..n {
            cur.skip_ws();
            let at = cur.pos();
            let tag = cur.u64("an element tag")?;
            let type_id = cur.i32("an element type")?;
            let ntags = cur.u64("the number of element tags")?;
            let (mut phys, mut elementary) = (0i32, 0i32);
            for k in 0..ntags {
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
            let Some(nn) = nodes_of(type_id) else {
                return Err(unsupported(cur, at, tag, type_id));
            };
            for slot in nodes.iter_mut().take(nn) {
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
