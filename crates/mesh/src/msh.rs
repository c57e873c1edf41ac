//! The .msh reader: MSH 2.2 and 4.1, ASCII and binary (`../shared/DEPENDENCIES.md` §2
//! describes the layouts).
//!
//! One pass over the bytes: `$MeshFormat` decides the version and encoding,
//! then each section is parsed where it stands (`$PhysicalNames`,
//! `$Entities`, `$Nodes` or in 2.2 `$ParametricNodes`, `$Elements`; anything
//! else, e.g. `$Periodic` or `$NodeData`, is skipped up to its `$End…`). Elements are mapped to dense
//! node indices and checked as they are read, so `$Nodes` must come before
//! `$Elements` (and `$Entities` before `$Elements` in 4.1), as Gmsh writes them.

mod build;
mod cursor;
mod v2;
mod v4;

use std::fs::File;
use std::path::Path;

use build::Builder;
pub(crate) use cursor::CHUNK;
use cursor::{Cursor, Result, Source};

use crate::{Mesh, MeshError, MeshErrorKind};

/// Reads a mesh held in memory.
pub(crate) fn read(bytes: &[u8]) -> Result<Mesh> {
    parse(Cursor::new(bytes))
}

/// Reads a regular file of `len` bytes through a window of `chunk` bytes
/// (the file is never resident as a whole). An I/O error while reading
/// is reported as such, whatever the parse made of the input ending there.
pub(crate) fn read_file(path: &Path, file: File, len: u64, chunk: usize) -> Result<Mesh> {
    let Ok(len) = usize::try_from(len) else {
        return Err(MeshError::io(path, std::io::Error::other("file too large")));
    };
    let mut cur = Cursor::with_source(Source::File { file, path }, len, chunk);
    let res = parse_with(&mut cur);
    match cur.io_error.take() {
        Some(e) => Err(MeshError::io(path, e)),
        None => res,
    }
}

fn parse(mut cur: Cursor<'_>) -> Result<Mesh> {
    parse_with(&mut cur)
}

fn parse_with(cur: &mut Cursor<'_>) -> Result<Mesh> {
    match cur.token() {
        Some((_, t)) if t == b"$MeshFormat" => {}
        None => return Err(MeshError::new(MeshErrorKind::EmptyFile)),
        _ => return Err(cur.error(0, MeshErrorKind::NotMsh)),
    }
    let (version, binary) = mesh_format(cur)?;
    let mut b = Builder::new(version, binary);
    let mut entities: Option<v4::Entities> = None;
    let mut seen_nodes = false;
    let mut seen_elements = false;
    let mut seen_names = false;
    while let Some((p, t)) = cur.token() {
        let t = &t[..];
        match t {
            // A second one would silently rename groups.
            b"$PhysicalNames" => {
                if seen_names {
                    return Err(out_of_place(cur, p, t, "a second $PhysicalNames section"));
                }
                seen_names = true;
                physical_names(cur, &mut b)?;
            }
            // It could contradict the first (version, ASCII or binary).
            b"$MeshFormat" => {
                return Err(out_of_place(cur, p, t, "a second $MeshFormat section"));
            }
            b"$Entities" if version == "4.1" => {
                if seen_elements || entities.is_some() {
                    return Err(out_of_place(
                        cur,
                        p,
                        t,
                        "$Entities must come once, before $Elements",
                    ));
                }
                entities = Some(v4::entities(cur, &mut b)?);
            }
            // Its entities carry the physical tags of a partitioned mesh, and
            // a split file (Mesh.PartitionSplitMeshFiles) holds only a part of
            // the body: refused rather than read wrong.
            b"$PartitionedEntities" if version == "4.1" => {
                return Err(cur.error(p, MeshErrorKind::Partitioned));
            }
            b"$Nodes" | b"$ParametricNodes" => {
                if seen_nodes {
                    return Err(out_of_place(cur, p, t, "a second $Nodes section"));
                }
                seen_nodes = true;
                if version == "2.2" {
                    v2::nodes(cur, &mut b, t == b"$ParametricNodes")?;
                } else if t == b"$ParametricNodes" {
                    return Err(out_of_place(
                        cur,
                        p,
                        t,
                        "MSH 4.1 gives parametric nodes in $Nodes",
                    ));
                } else {
                    v4::nodes(cur, &mut b)?;
                }
            }
            b"$Elements" => {
                if !seen_nodes {
                    return Err(out_of_place(
                        cur,
                        p,
                        t,
                        "$Nodes (or $ParametricNodes) must come before $Elements",
                    ));
                }
                if seen_elements {
                    return Err(out_of_place(cur, p, t, "a second $Elements section"));
                }
                seen_elements = true;
                if version == "2.2" {
                    v2::elements(cur, &mut b)?;
                } else {
                    v4::elements(cur, &mut b, entities.as_ref())?;
                }
            }
            _ if t.first() == Some(&b'$') && !t.starts_with(b"$End") => skip_section(cur, p, t)?,
            _ => {
                let shown = String::from_utf8_lossy(t.get(..40).unwrap_or(t)).into_owned();
                return Err(cur.error(
                    p,
                    MeshErrorKind::Malformed {
                        what: format!("expected a section keyword such as $Nodes or $Elements, found {shown:?}"),
                    },
                ));
            }
        }
    }
    let end = cur.len();
    if !seen_nodes {
        return Err(cur.error(end, MeshErrorKind::MissingSection { section: "$Nodes" }));
    }
    if !seen_elements {
        return Err(cur.error(
            end,
            MeshErrorKind::MissingSection {
                section: "$Elements",
            },
        ));
    }
    b.finish(cur)
}

fn out_of_place(cur: &Cursor<'_>, pos: usize, t: &[u8], why: &'static str) -> crate::MeshError {
    cur.error(
        pos,
        MeshErrorKind::SectionOrder {
            found: String::from_utf8_lossy(t).into_owned(),
            why,
        },
    )
}

/// `$MeshFormat`: version, file type, data size, and for binary files the
/// integer 1 that tells the byte order.
fn mesh_format(cur: &mut Cursor<'_>) -> Result<(&'static str, bool)> {
    cur.enter("$MeshFormat", "$EndMeshFormat");
    let Some((vp, vt)) = cur.token() else {
        return Err(cur.error(
            cur.pos(),
            MeshErrorKind::Truncated {
                what: "the $MeshFormat section",
            },
        ));
    };
    let version = match &vt[..] {
        b"2.2" => "2.2",
        b"4.1" => "4.1",
        _ => {
            let version = String::from_utf8_lossy(vt.get(..20).unwrap_or(&vt)).into_owned();
            return Err(cur.error(vp, MeshErrorKind::UnsupportedVersion { version }));
        }
    };
    cur.skip_ws();
    let tp = cur.pos();
    let file_type = cur.u64("the file type (0 for ASCII, 1 for binary)")?;
    let data_size = cur.u64("the data size")?;
    let binary = match file_type {
        0 => false,
        1 => true,
        _ => {
            return Err(cur.error(
                tp,
                MeshErrorKind::Malformed {
                    what: format!("file type {file_type} is neither 0 (ASCII) nor 1 (binary)"),
                },
            ))
        }
    };
    if binary {
        cur.binary = true;
        if data_size != 8 {
            return Err(cur.error(tp, MeshErrorKind::UnsupportedDataSize { size: data_size }));
        }
        // Gmsh writes binary files with LF line ends. CR LF here, or a CR
        // before the byte-order integer, means the file went through a
        // text-mode copy, which also put a CR before every 0x0a byte of
        // the data: say so rather than report what the shifted data looks
        // like (an early end, NaN coordinates).
        let eol = cur.pos();
        let crlf = cur.end_of_line()?;
        let p = cur.pos();
        if cur.peek(4) == b"$End" {
            // An ASCII file (its lines at their numbers) flagged binary.
            cur.binary = false;
            return Err(cur.error(p, MeshErrorKind::AsciiInBinary));
        }
        if crlf {
            return Err(cur.error(eol, MeshErrorKind::TextModeTransfer));
        }
        match cur.take::<4>()? {
            [1, 0, 0, 0] => {}
            [b'\r', 1, 0, 0] => return Err(cur.error(p, MeshErrorKind::TextModeTransfer)),
            [0, 0, 0, 1] => return Err(cur.error(p, MeshErrorKind::BigEndian)),
            other => {
                return Err(cur.error(
                    p,
                    MeshErrorKind::Malformed {
                        what: format!(
                        "the byte-order check after $MeshFormat is {other:?}, not the integer 1"
                    ),
                    },
                ))
            }
        }
    }
    if !binary {
        cur.skip_ws();
        // The byte-order integer of a binary file: the file-type says ASCII
        // but binary data follows (reported as a wrong count before).
        if cur.peek(4) == [1, 0, 0, 0] {
            return Err(cur.error(cur.pos(), MeshErrorKind::BinaryInAscii));
        }
    }
    cur.expect_end()?;
    Ok((version, binary))
}

/// `$PhysicalNames` (ASCII in every encoding): `dim tag "name"` lines.
fn physical_names(cur: &mut Cursor<'_>, b: &mut Builder) -> Result<()> {
    cur.enter("$PhysicalNames", "$EndPhysicalNames");
    let n = cur.u64("the number of physical names")?;
    cur.counts("physical names", n);
    // Where each (dim, tag) was named: a second name would silently
    // replace the first (a typo in a tag moves a boundary condition).
    let mut named_at: std::collections::HashMap<(u8, i32), usize> = Default::default();
    for _ in 0..n {
        cur.skip_ws();
        let p = cur.pos();
        let dim = cur.i32("the dimension of a physical group")?;
        let tag = cur.i32("the tag of a physical group")?;
        let dim = match u8::try_from(dim) {
            Ok(d) if d <= 3 => d,
            _ => {
                return Err(cur.error(
                    p,
                    MeshErrorKind::Malformed {
                        what: format!("physical group dimension {dim} is not 0 to 3"),
                    },
                ))
            }
        };
        let name = quoted(cur)?;
        if let Some(&first) = named_at.get(&(dim, tag)) {
            // The same line twice (a copy) names nothing new.
            if b.names.get(&(dim, tag)) == Some(&name) {
                continue;
            }
            return Err(cur.error(
                p,
                MeshErrorKind::DuplicatePhysicalName {
                    dim,
                    tag,
                    name,
                    first: cur.location(first),
                    first_name: b.names.get(&(dim, tag)).cloned().unwrap_or_default(),
                },
            ));
        }
        named_at.insert((dim, tag), p);
        b.names.insert((dim, tag), name);
    }
    cur.expect_end()
}

/// A double-quoted name on the current line.
fn quoted(cur: &mut Cursor<'_>) -> Result<String> {
    cur.skip_ws();
    let start = cur.pos();
    let bad = |cur: &Cursor<'_>| {
        cur.error(
            start,
            MeshErrorKind::Malformed {
                what: "a physical name must be written in double quotes on its line".into(),
            },
        )
    };
    let truncated = |cur: &Cursor<'_>| {
        cur.error(
            start,
            MeshErrorKind::Truncated {
                what: "the $PhysicalNames section",
            },
        )
    };
    match cur.peek_byte() {
        Some(b'"') => cur.advance(1),
        None => return Err(truncated(cur)),
        Some(b'$') => {
            const END: &[u8] = b"$EndPhysicalNames";
            return if cur.peek(END.len()) == END {
                Err(cur.wrong_count(start))
            } else {
                Err(bad(cur))
            };
        }
        Some(_) => return Err(bad(cur)),
    }
    let mut name = Vec::new();
    loop {
        match cur.peek_byte() {
            Some(b'"') => {
                cur.advance(1);
                return Ok(String::from_utf8_lossy(&name).into_owned());
            }
            Some(b'\n') => return Err(bad(cur)),
            Some(c) => {
                name.push(c);
                cur.advance(1);
            }
            None => return Err(truncated(cur)),
        }
    }
}

/// Skips a section the reader does not use, up to `$End<name>` followed by
/// white space or the end of the input.
fn skip_section(cur: &mut Cursor<'_>, pos: usize, keyword: &[u8]) -> Result<()> {
    let name = keyword.get(1..).unwrap_or_default();
    let mut end = Vec::with_capacity(4 + name.len());
    end.extend_from_slice(b"$End");
    end.extend_from_slice(name);
    loop {
        let w = cur.available();
        if w.is_empty() {
            break;
        }
        let Some(k) = w.iter().position(|&c| c == b'$') else {
            let n = w.len();
            cur.advance(n);
            continue;
        };
        cur.advance(k);
        let w = cur.peek(end.len() + 1);
        if w.starts_with(&end) && w.get(end.len()).is_none_or(|c| c.is_ascii_whitespace()) {
            cur.advance(end.len());
            return Ok(());
        }
        cur.advance(1);
    }
    // The keyword is whatever followed a '$', of any length.
    let section = String::from_utf8_lossy(keyword.get(..40).unwrap_or(keyword)).into_owned();
    Err(cur.error(
        pos,
        MeshErrorKind::MissingEnd {
            end: format!("$End{}", section.get(1..).unwrap_or_default()),
            section,
        },
    ))
}

#[cfg(test)]
mod stream_tests;
