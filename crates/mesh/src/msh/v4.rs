//! MSH 4.1 `$Entities`, `$Nodes` and `$Elements`, ASCII and binary.
//!
//! Physical membership lives in `$Entities` (entity → physical tags); an
//! element block names its entity. In binary files every `size_t` of the
//! format is a little-endian u64 and every `int` an i32.

use std::collections::HashMap;

use super::build::{nodes_of, unsupported, Builder, Membership};
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
    for c in &mut counts {
        *c = if cur.binary {
            cur.bin_u64()?
        } else {
            cur.u64("an entity count")?
        };
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
                tag = cur.i32("an entity tag")?;
                for _ in 0..if dim == 0 { 3 } else { 6 } {
                    cur.f64("an entity coordinate")?;
                }
                let np = cur.u64("a number of physical tags")?;
                for _ in 0..np {
                    phys.push(cur.i32("a physical tag")?);
                }
                if dim > 0 {
                    let nb = cur.u64("a number of bounding entities")?;
                    for _ in 0..nb {
                        cur.i32("a bounding entity tag")?;
                    }
                }
            }
            let id = b.membership(phys.clone());
            map.insert((dim as i32, tag), id);
        }
    }
    cur.expect_end()?;
    Ok(map)
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
    for v in &mut h {
        *v = if cur.binary {
            cur.bin_u64()?
        } else {
            cur.u64(what)?
        };
    }
    Ok((at, h[0], h[1]))
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
        let a = [cur.i32(what)?, cur.i32(what)?, cur.i32(what)?];
        Ok((at, a, cur.u64(what)?))
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
                                found: format!("{x} {y} {z}"),
                            },
                        ));
                    }
                    let tag = b.node_tags.get(i).copied().unwrap_or(0);
                    b.push_xyz(x, y, z, tag, start + size * j);
                    i += 1;
                }
            }
        } else {
            for _ in 0..n {
                let t = cur.u64("a node tag")?;
                b.push_tag(t, cur.pos());
            }
            for i in 0..n as usize {
                let x = cur.f64("a node coordinate")?;
                let y = cur.f64("a node coordinate")?;
                let z = cur.f64("a node coordinate")?;
                let at = cur.pos();
                for _ in 0..extra {
                    cur.f64("a parametric node coordinate")?;
                }
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
            for _ in 0..n {
                cur.skip_ws();
                let ep = cur.pos();
                let tag = cur.u64("an element tag")?;
                for slot in nodes.iter_mut().take(nn) {
                    *slot = cur.u64("a node tag")?;
                }
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
