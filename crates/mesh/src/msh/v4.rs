//! MSH 4.1 `$Entities`, `$Nodes` and `$Elements`, ASCII and binary.
//!
//! Physical membership lives in `$Entities` (entity → physical tags); an
//! element block names its entity. In binary files every `size_t` of the
//! format is a little-endian u64 and every `int` an i32.

use std::collections::HashMap;

use super::build::{counted, nodes_of, type_name, unsupported, Builder, Membership};
use super::cursor::{le_f64, le_u64, Cursor, Result};
use crate::MeshErrorKind;

/// (entity dimension, entity tag) → membership id.
pub(crate) type Entities = HashMap<(i32, i32), Membership>;

pub(crate) fn entities(cur: &mut Cursor<'_>, b: &mut Builder) -> Result<Entities> {
    cur.enter("$Entities", "$EndEntities");
    if cur.binary {
        cur.end_of_line()?;
    }
    let mut counts = [0u64; 4];
    if !cur.binary {
        cur.skip_ws();
    }
    let at = cur.pos();
    const COUNTS: &str = "the $Entities header needs 4 numbers (the numbers of points, curves, surfaces and volumes)";
    for (k, c) in counts.iter_mut().enumerate() {
        *c = if cur.binary {
            cur.bin_u64()?
        } else {
            if k > 0 {
                cur.need_field(at, k, || COUNTS.into())?;
            }
            cur.u64("an entity count")?
        };
    }
    if !cur.binary {
        cur.line_done(at, 4, || COUNTS.into())?;
    }
    cur.counts(
        "entities",
        counts.iter().fold(0u64, |a, &c| a.saturating_add(c)),
    );
    let mut map = Entities::new();
    let mut phys = Vec::new();
    for (dim, &count) in counts.iter().enumerate() {
        for _ in 0..count {
            if cur.binary && cur.at_keyword() {
                return Err(cur.wrong_count(cur.pos()));
            }
            phys.clear();
            let tag;
            if cur.binary {
                tag = cur.bin_i32()?;
                // A point has x y z, other entities a bounding box.
                cur.skip(if dim == 0 { 24 } else { 48 })?;
                let np = cur.bin_u64()?;
                for _ in 0..cur.check_items(np, 4)? / 4 {
                    phys.push(cur.bin_i32()?);
                }
                if dim > 0 {
                    let nb = cur.bin_u64()?;
                    let bytes = cur.check_items(nb, 4)?;
                    cur.skip(bytes)?;
                }
            } else {
                // One entity a line; `k` counts the numbers read on it.
                let record = || entity_record(dim);
                cur.skip_ws();
                let at = cur.pos();
                tag = cur.i32("an entity tag")?;
                let mut k = 1;
                for _ in 0..if dim == 0 { 3 } else { 6 } {
                    cur.need_field(at, k, record)?;
                    cur.f64("an entity coordinate")?;
                    k += 1;
                }
                cur.need_field(at, k, record)?;
                let np = cur.u64("a number of physical tags")?;
                k += 1;
                for _ in 0..np {
                    cur.need_field(at, k, record)?;
                    phys.push(cur.i32("a physical tag")?);
                    k += 1;
                }
                if dim > 0 {
                    cur.need_field(at, k, record)?;
                    let nb = cur.u64("a number of bounding entities")?;
                    k += 1;
                    for _ in 0..nb {
                        cur.need_field(at, k, record)?;
                        cur.i32("a bounding entity tag")?;
                        k += 1;
                    }
                }
                cur.line_done(at, k, record)?;
            }
            let id = b.membership(phys.clone());
            map.insert((dim as i32, tag), id);
        }
    }
    cur.expect_end()?;
    Ok(map)
}

fn entity_record(dim: usize) -> String {
    if dim == 0 {
        "a point entity needs its tag, x, y, z, the number of physical tags and those tags".into()
    } else {
        let kind = ["point", "curve", "surface", "volume"]
            .get(dim)
            .unwrap_or(&"");
        format!("a {kind} entity needs its tag, 6 bounding-box coordinates, the number of physical tags and those tags, the number of bounding entities and their tags")
    }
}

/// Reads a 4.1 section header of four size_t: blocks, items, min tag, max tag.
fn header(cur: &mut Cursor<'_>, what: &'static str) -> Result<(usize, u64, u64)> {
    if cur.binary {
        // Binary data starts right after the keyword's line; blank-looking
        // bytes (0x09, 0x0a, 0x20) are data there.
        cur.end_of_line()?;
    } else {
        cur.skip_ws();
    }
    let at = cur.pos();
    let mut h = [0u64; 4];
    for (k, v) in h.iter_mut().enumerate() {
        *v = if cur.binary {
            cur.bin_u64()?
        } else {
            if k > 0 {
                cur.need_field(at, k, || header_record(what))?;
            }
            cur.u64(what)?
        };
    }
    if !cur.binary {
        cur.line_done(at, 4, || header_record(what))?;
    }
    Ok((at, h[0], h[1]))
}

fn header_record(what: &str) -> String {
    format!("{what} needs 4 numbers (the number of blocks, the number of entries, the smallest and the largest tag)")
}

/// A block header: three ints and a size_t.
fn block(cur: &mut Cursor<'_>, what: &'static str) -> Result<(usize, [i32; 3], u64)> {
    if cur.binary {
        if cur.at_keyword() {
            return Err(cur.wrong_count(cur.pos()));
        }
        let at = cur.pos();
        let a = [cur.bin_i32()?, cur.bin_i32()?, cur.bin_i32()?];
        Ok((at, a, cur.bin_u64()?))
    } else {
        cur.skip_ws();
        let at = cur.pos();
        let record = || {
            format!("{what} needs 4 numbers (entity dimension, entity tag, type or parametric flag, and the number of entries)")
        };
        let mut a = [0i32; 3];
        for (k, v) in a.iter_mut().enumerate() {
            if k > 0 {
                cur.need_field(at, k, record)?;
            }
            *v = cur.i32(what)?;
        }
        cur.need_field(at, 3, record)?;
        let n = cur.u64(what)?;
        cur.line_done(at, 4, record)?;
        Ok((at, a, n))
    }
}

pub(crate) fn nodes(cur: &mut Cursor<'_>, b: &mut Builder) -> Result<()> {
    cur.enter("$Nodes", "$EndNodes");
    let (at, nblocks, total) = header(cur, "the $Nodes header")?;
    cur.counts("nodes", total);
    let cap = cur.capped(total, if cur.binary { 32 } else { 8 });
    b.nodes.reserve(cap);
    b.node_tags.reserve(cap);
    let mut seen: u64 = 0;
    for _ in 0..nblocks {
        let (bp, [dim, _tag, parametric], n) = block(cur, "a node block header")?;
        seen = seen.saturating_add(n);
        if seen > total {
            return Err(cur.wrong_count(bp));
        }
        // Parametric nodes carry `dim` more coordinates (u, or u v, ...).
        let extra = match (parametric, dim) {
            (0, 0..=3) => 0,
            (1, 0..=3) => dim as usize,
            _ => {
                return Err(cur.error(
                    bp,
                    MeshErrorKind::Malformed {
                        what: format!(
                        "node block with entity dimension {dim} and parametric flag {parametric}"
                    ),
                    },
                ))
            }
        };
        let first = b.node_tags.len();
        if cur.binary {
            cur.check_items(n, 8)?;
            let mut left = n;
            while left > 0 {
                let (start, k) = cur.batch(left, 8)?;
                left -= k as u64;
                let tags = cur.records(start, 8 * k);
                for (j, t) in tags.chunks_exact(8).enumerate() {
                    b.push_tag(le_u64(t), start + 8 * j);
                }
            }
            let size = 8 * (3 + extra);
            cur.check_items(n, size)?;
            let (mut left, mut i) = (n, first);
            while left > 0 {
                let (start, k) = cur.batch(left, size)?;
                left -= k as u64;
                let cur = &*cur;
                for (j, rec) in cur.records(start, size * k).chunks_exact(size).enumerate() {
                    let (x, y, z) = (le_f64(rec), le_f64(&rec[8..]), le_f64(&rec[16..]));
                    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                        return Err(cur.error(
                            start + size * j,
                            MeshErrorKind::NotANumber {
                                what: "a node coordinate",
                                // Debug, not Display: a tiny value would be 300 digits.
                                found: format!("{x:?} {y:?} {z:?}"),
                            },
                        ));
                    }
                    let tag = b.node_tags.get(i).copied().unwrap_or(0);
                    b.push_xyz(x, y, z, tag, start + size * j);
                    i += 1;
                }
            }
        } else {
            // Gmsh writes the block's tags one a line, then its
            // coordinates one node a line.
            const TAG: &str = "a node tag line needs 1 number";
            for _ in 0..n {
                cur.skip_ws();
                let line = cur.pos();
                let t = cur.u64("a node tag")?;
                cur.line_done(line, 1, || TAG.into())?;
                b.push_tag(t, cur.pos());
            }
            let record = || {
                if extra == 0 {
                    "a node coordinate line needs 3 numbers (x, y and z)".to_string()
                } else {
                    format!(
                        "a parametric node coordinate line needs {} numbers (x, y, z and {})",
                        3 + extra,
                        counted(extra as u64, "parametric coordinate")
                    )
                }
            };
            for i in 0..n as usize {
                cur.skip_ws();
                let line = cur.pos();
                let x = cur.f64("a node coordinate")?;
                cur.need_field(line, 1, record)?;
                let y = cur.f64("a node coordinate")?;
                cur.need_field(line, 2, record)?;
                let z = cur.f64("a node coordinate")?;
                let at = cur.pos();
                for k in 0..extra {
                    cur.need_field(line, 3 + k, record)?;
                    cur.f64("a parametric node coordinate")?;
                }
                cur.line_done(line, 3 + extra, record)?;
                let tag = b.node_tags.get(first + i).copied().unwrap_or(0);
                b.push_xyz(x, y, z, tag, at);
            }
        }
    }
    if seen != total {
        return Err(cur.wrong_count(at));
    }
    cur.expect_end()?;
    b.finish_nodes(cur, at)
}

pub(crate) fn elements(
    cur: &mut Cursor<'_>,
    b: &mut Builder,
    entities: Option<&Entities>,
) -> Result<()> {
    cur.enter("$Elements", "$EndElements");
    let (at, nblocks, total) = header(cur, "the $Elements header")?;
    cur.counts("elements", total);
    let mut seen: u64 = 0;
    let mut nodes = [0u64; 9];
    for _ in 0..nblocks {
        let (bp, [dim, entity, type_id], n) = block(cur, "an element block header")?;
        seen = seen.saturating_add(n);
        if seen > total {
            return Err(cur.wrong_count(bp));
        }
        let member = match entities {
            None => 0,
            Some(map) => match map.get(&(dim, entity)) {
                Some(&m) => m,
                None => {
                    return Err(cur.error(bp, MeshErrorKind::UnknownEntity { dim, tag: entity }))
                }
            },
        };
        let Some(nn) = nodes_of(type_id) else {
            let first = peek_tag(cur);
            return Err(unsupported(cur, bp, first, type_id));
        };
        let type_dim = match nn {
            1 => 0,
            2 | 3 => 1,
            _ => 2,
        };
        if type_dim != dim {
            let name = type_name(type_id);
            return Err(cur.error(
                bp,
                MeshErrorKind::BlockDimension {
                    name,
                    type_dim,
                    dim,
                    tag: entity,
                },
            ));
        }
        if nn >= 4 {
            let min_bytes = if cur.binary {
                8 * (1 + nn)
            } else {
                2 * (1 + nn)
            };
            b.expect_cells(cur, n, nn, min_bytes);
        }
        if cur.binary {
            let size = 8 * (1 + nn);
            cur.check_items(n, size)?;
            let mut left = n;
            while left > 0 {
                let (start, k) = cur.batch(left, size)?;
                left -= k as u64;
                let cur = &*cur;
                for (i, rec) in cur.records(start, size * k).chunks_exact(size).enumerate() {
                    let tag = le_u64(rec);
                    for (slot, t) in nodes.iter_mut().zip(rec[8..].chunks_exact(8)) {
                        *slot = le_u64(t);
                    }
                    b.element(
                        cur,
                        start + size * i,
                        type_id,
                        tag,
                        &nodes[..nn],
                        member,
                        None,
                    )?;
                }
            }
        } else {
            let record = || {
                format!(
                    "a {} element needs {} numbers (its tag and {})",
                    type_name(type_id),
                    1 + nn,
                    counted(nn as u64, "node tag")
                )
            };
            for _ in 0..n {
                cur.skip_ws();
                let ep = cur.pos();
                let tag = cur.u64("an element tag")?;
                for (k, slot) in nodes.iter_mut().take(nn).enumerate() {
                    cur.need_field(ep, 1 + k, record)?;
                    *slot = cur.u64("a node tag")?;
                }
                cur.line_done(ep, 1 + nn, record)?;
                b.element(cur, ep, type_id, tag, &nodes[..nn], member, None)?;
            }
        }
    }
    if seen != total {
        return Err(cur.wrong_count(at));
    }
    cur.expect_end()
}

/// The tag of the first element of a block, for an error message.
fn peek_tag(cur: &mut Cursor<'_>) -> u64 {
    if cur.binary {
        <[u8; 8]>::try_from(cur.peek(8)).map_or(0, u64::from_le_bytes)
    } else {
        cur.token()
            .and_then(|(_, t)| super::cursor::parse_u64(&t))
            .unwrap_or(0)
    }
}
