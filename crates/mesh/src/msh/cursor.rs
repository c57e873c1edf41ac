//! A position in the input bytes with the two ways of reading MSH data:
//! whitespace-separated ASCII tokens and little-endian binary fields.
//!
//! Nothing here allocates per token; every read is bounds-checked and turns
//! running out of input into [`MeshErrorKind::Truncated`]. Errors carry a byte
//! position that [`Cursor::error`] turns into a line number (ASCII files) or
//! keeps as a byte offset (binary files); counting lines only on the error
//! path keeps the hot loops free of bookkeeping.

use crate::{Location, MeshError, MeshErrorKind};

pub(crate) type Result<T> = std::result::Result<T, MeshError>;

#[derive(Debug)]
pub(crate) struct Cursor<'a> {
    pub(crate) bytes: &'a [u8],
    pub(crate) pos: usize,
    /// Binary file: errors are reported as byte offsets.
    pub(crate) binary: bool,
    /// The section being read and its closing keyword, to tell a wrong count
    /// (the closing keyword comes too early) from a missing `$End…`.
    pub(crate) section: &'static str,
    pub(crate) end: &'static str,
    /// What the section counts, for [`MeshErrorKind::WrongCount`].
    pub(crate) counted: &'static str,
    pub(crate) expected: u64,
}

fn is_ws(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n')
}

/// At most this many characters of a bad field go into an error message.
const SHOW: usize = 40;

impl<'a> Cursor<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Cursor {
            bytes,
            pos: 0,
            binary: false,
            section: "",
            end: "",
            counted: "",
            expected: 0,
        }
    }

    /// Enters a section: a closing keyword found where data is expected is
    /// then reported as a wrong count.
    pub(crate) fn enter(&mut self, section: &'static str, end: &'static str) {
        self.section = section;
        self.end = end;
        self.counted = "entries";
        self.expected = 0;
    }

    /// Sets what the current section's header count promises.
    pub(crate) fn counts(&mut self, counted: &'static str, expected: u64) {
        self.counted = counted;
        self.expected = expected;
    }

    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// The location of byte `pos`: a 1-based line in ASCII files, the byte
    /// offset in binary ones.
    pub(crate) fn location(&self, pos: usize) -> Location {
        if self.binary {
            Location::Byte(pos)
        } else {
            let end = pos.min(self.bytes.len());
            let lines = self
                .bytes
                .get(..end)
                .map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count());
            Location::Line(lines + 1)
        }
    }

    pub(crate) fn error(&self, pos: usize, kind: MeshErrorKind) -> MeshError {
        MeshError::at(self.location(pos), kind)
    }

    pub(crate) fn wrong_count(&self, pos: usize) -> MeshError {
        self.error(
            pos,
            MeshErrorKind::WrongCount {
                section: self.section,
                what: self.counted,
                expected: self.expected,
            },
        )
    }

    pub(crate) fn skip_ws(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !is_ws(b) {
                break;
            }
            self.pos += 1;
        }
    }

    /// The next whitespace-separated token and its start, or `None` at the end.
    pub(crate) fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_ws();
        let start = self.pos;
        while let Some(&b) = self.bytes.get(self.pos) {
            if is_ws(b) {
                break;
            }
            self.pos += 1;
        }
        if self.pos == start {
            None
        } else {
            self.bytes.get(start..self.pos).map(|t| (start, t))
        }
    }

    /// A token where a data field is expected; classifies what else was found.
    fn field(&mut self, _what: &'static str) -> Result<(usize, &'a [u8])> {
        match self.token() {
            None => Err(self.error(
                self.pos,
                MeshErrorKind::Truncated {
                    what: self.section_what(),
                },
            )),
            Some((p, t)) if t.first() == Some(&b'$') => {
                if t == self.end.as_bytes() {
                    Err(self.wrong_count(p))
                } else {
                    Err(self.missing_end(p))
                }
            }
            Some((p, t)) => Ok((p, t)),
        }
    }

    fn section_what(&self) -> &'static str {
        match self.section {
            "$Nodes" => "the $Nodes section",
            "$Elements" => "the $Elements section",
            "$Entities" => "the $Entities section",
            "$PhysicalNames" => "the $PhysicalNames section",
            "$MeshFormat" => "the $MeshFormat section",
            _ => "a section",
        }
    }

    pub(crate) fn missing_end(&self, pos: usize) -> MeshError {
        self.error(
            pos,
            MeshErrorKind::MissingEnd {
                section: self.section.to_string(),
                end: self.end.to_string(),
            },
        )
    }

    fn not_a_number(&self, pos: usize, what: &'static str, tok: &[u8]) -> MeshError {
        let shown = String::from_utf8_lossy(tok.get(..SHOW).unwrap_or(tok)).into_owned();
        self.error(pos, MeshErrorKind::NotANumber { what, found: shown })
    }

    /// An unsigned integer field (counts, tags).
    pub(crate) fn u64(&mut self, what: &'static str) -> Result<u64> {
        let (p, t) = self.field(what)?;
        parse_u64(t).ok_or_else(|| self.not_a_number(p, what, t))
    }

    /// A signed 32-bit field (types, dimensions, entity and physical tags).
    pub(crate) fn i32(&mut self, what: &'static str) -> Result<i32> {
        let (p, t) = self.field(what)?;
        parse_i64(t)
            .and_then(|v| i32::try_from(v).ok())
            .ok_or_else(|| self.not_a_number(p, what, t))
    }

    /// A signed field read as i64 (element node tags in 2.2 ASCII may be any integer).
    pub(crate) fn i64(&mut self, what: &'static str) -> Result<(usize, i64)> {
        let (p, t) = self.field(what)?;
        parse_i64(t)
            .map(|v| (p, v))
            .ok_or_else(|| self.not_a_number(p, what, t))
    }

    /// A finite floating-point field.
    pub(crate) fn f64(&mut self, what: &'static str) -> Result<f64> {
        let (p, t) = self.field(what)?;
        parse_f64(t).ok_or_else(|| self.not_a_number(p, what, t))
    }

    /// Expects the closing keyword of the current section.
    pub(crate) fn expect_end(&mut self) -> Result<()> {
        match self.token() {
            Some((_, t)) if t == self.end.as_bytes() => Ok(()),
            Some((p, t)) if t.first() == Some(&b'$') => Err(self.missing_end(p)),
            // More data than the header promised.
            Some((p, _)) => Err(self.wrong_count(p)),
            None => Err(self.missing_end(self.pos)),
        }
    }

    /// After the ASCII count line of a binary section: skips to just after
    /// the end of the line, where the binary data starts.
    pub(crate) fn end_of_line(&mut self) -> Result<()> {
        while let Some(&b) = self.bytes.get(self.pos) {
            self.pos += 1;
            match b {
                b'\n' => return Ok(()),
                b' ' | b'\t' | b'\r' => {}
                _ => {
                    return Err(self.error(
                        self.pos - 1,
                        MeshErrorKind::Malformed {
                            what: format!(
                                "unexpected data after the count line of {}",
                                self.section
                            ),
                        },
                    ))
                }
            }
        }
        Err(self.error(
            self.pos,
            MeshErrorKind::Truncated {
                what: self.section_what(),
            },
        ))
    }

    /// True when a binary reader about to read a header finds the section's
    /// end instead (`\n$End…`): the header count was too large.
    pub(crate) fn at_keyword(&self) -> bool {
        let rest = self.bytes.get(self.pos..).unwrap_or_default();
        let rest = rest.strip_prefix(b"\n").unwrap_or(rest);
        rest.starts_with(b"$End")
    }

    /// `n` raw bytes of binary data.
    pub(crate) fn take(&mut self, n: usize, _what: &'static str) -> Result<&'a [u8]> {
        match self
            .pos
            .checked_add(n)
            .and_then(|e| self.bytes.get(self.pos..e))
        {
            Some(s) => {
                self.pos += n;
                Ok(s)
            }
            None => Err(self.error(
                self.pos,
                MeshErrorKind::Truncated {
                    what: self.section_what(),
                },
            )),
        }
    }

    /// `count` items of `size` bytes each, checked against the input left
    /// (a count of 10^18 is an error here, never an allocation).
    pub(crate) fn take_items(
        &mut self,
        count: u64,
        size: usize,
        what: &'static str,
    ) -> Result<&'a [u8]> {
        let n = usize::try_from(count)
            .ok()
            .and_then(|c| c.checked_mul(size));
        match n {
            Some(n) => self.take(n, what),
            None => Err(self.error(
                self.pos,
                MeshErrorKind::Truncated {
                    what: self.section_what(),
                },
            )),
        }
    }

    pub(crate) fn bin_i32(&mut self, what: &'static str) -> Result<i32> {
        self.take(4, what).map(le_i32)
    }

    pub(crate) fn bin_u64(&mut self, what: &'static str) -> Result<u64> {
        self.take(8, what).map(le_u64)
    }

    /// Capacity to reserve for `count` items each needing at least
    /// `min_bytes` of input: never more than the input left can hold.
    pub(crate) fn capped(&self, count: u64, min_bytes: usize) -> usize {
        let fit = self.remaining() / min_bytes.max(1);
        usize::try_from(count).map_or(fit, |c| c.min(fit))
    }
}

/// Callers pass slices of exactly 4 or 8 bytes (from `chunks_exact` or `take`).
pub(crate) fn le_i32(b: &[u8]) -> i32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[..4]);
    i32::from_le_bytes(a)
}

pub(crate) fn le_u64(b: &[u8]) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[..8]);
    u64::from_le_bytes(a)
}

pub(crate) fn le_f64(b: &[u8]) -> f64 {
    f64::from_bits(le_u64(b))
}

pub(crate) fn parse_u64(t: &[u8]) -> Option<u64> {
    let digits = t.strip_prefix(b"+").unwrap_or(t);
    if digits.is_empty() || digits.len() > 20 {
        return None;
    }
    let mut v: u64 = 0;
    for &c in digits {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(u64::from(d))?;
    }
    Some(v)
}

pub(crate) fn parse_i64(t: &[u8]) -> Option<i64> {
    match t.strip_prefix(b"-") {
        Some(rest) => {
            let v = parse_u64(rest)?;
            if v <= i64::MAX as u64 + 1 {
                Some((v as i64).wrapping_neg())
            } else {
                None
            }
        }
        None => parse_u64(t).and_then(|v| i64::try_from(v).ok()),
    }
}

/// Decimal floats as Gmsh writes them (`%.16g`); std's parser is exact and
/// fast, and is given the token without copying it.
pub(crate) fn parse_f64(t: &[u8]) -> Option<f64> {
    // Rust also accepts "inf" and "nan"; a coordinate must be finite.
    let v: f64 = std::str::from_utf8(t).ok()?.parse().ok()?;
    v.is_finite().then_some(v)
}
