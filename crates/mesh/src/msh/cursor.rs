//! A position in the input with the two ways of reading MSH data:
//! whitespace-separated ASCII tokens and little-endian binary fields.
//!
//! The input is seen through a window of 1 MiB that is refilled as the reader
//! moves on ([`Source`]), so a file is never resident as a whole: the reader's
//! memory target (peak below twice the `Mesh`, `cargo xtask bench mesh`)
//! leaves no room for the file's bytes next to the mesh. Positions are
//! absolute byte offsets in the input. Nothing here allocates per token; every
//! read is bounds-checked and turns running out of input into
//! [`MeshErrorKind::Truncated`]. Errors carry a byte position that
//! [`Cursor::error`] turns into a line number (ASCII files) or keeps as a byte
//! offset (binary files); lines are counted only on the error path (re-reading
//! the file when the window has moved past the position), which keeps the hot
//! loops free of bookkeeping.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

use crate::{Location, MeshError, MeshErrorKind};

pub(crate) type Result<T> = std::result::Result<T, MeshError>;

/// Window size: refills (a copy of the unread tail and a `read`) are rare,
/// and the window is small next to a mesh worth streaming; the read's time
/// hardly depends on it (docs/performance.md).
pub(crate) const CHUNK: usize = 1 << 20;

/// Where the bytes come from.
#[derive(Debug)]
pub(crate) enum Source<'a> {
    /// Input already in memory (`Mesh::from_bytes`), copied into the window
    /// piece by piece like a file so both take the same code paths.
    Memory { data: &'a [u8], next: usize },
    /// A regular file of known length; `path` is re-read to count lines for
    /// an error behind the window.
    File { file: File, path: &'a Path },
}

#[derive(Debug)]
pub(crate) struct Cursor<'a> {
    src: Source<'a>,
    /// The window: input bytes `base .. base + filled` are `buf[..filled]`.
    buf: Vec<u8>,
    filled: usize,
    base: usize,
    /// Read position, relative to `buf`.
    i: usize,
    /// Input length (the file's length when opened); reads stop there.
    len: usize,
    /// Bytes taken from the source so far (absolute end of the window).
    read: usize,
    /// First I/O error of the source; the input ends there, and the caller
    /// reports this error instead of whatever the parse made of the end.
    pub(crate) io_error: Option<io::Error>,
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

#[inline]
fn is_ws(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n')
}

/// At most this many characters of a bad field go into an error message.
const SHOW: usize = 40;

/// Exact powers of ten for the fast float path (10^22 is the largest exact one).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

impl<'a> Cursor<'a> {
    /// A cursor over bytes in memory.
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self::with_source(
            Source::Memory {
                data: bytes,
                next: 0,
            },
            bytes.len(),
            CHUNK,
        )
    }

    /// A cursor over `len` bytes of `src`, read `chunk` bytes at a time.
    pub(crate) fn with_source(src: Source<'a>, len: usize, chunk: usize) -> Self {
        let chunk = chunk.clamp(16, len.max(16));
        Cursor {
            src,
            buf: vec![0; chunk],
            filled: 0,
            base: 0,
            i: 0,
            len,
            read: 0,
            io_error: None,
            binary: false,
            section: "",
            end: "",
            counted: "",
            expected: 0,
        }
    }

    /// The absolute read position.
    #[inline]
    pub(crate) fn pos(&self) -> usize {
        self.base + self.i
    }

    /// The input length.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Drops the window before `keep` (relative), then reads until at least
    /// `want` bytes follow the read position or the input ends. Returns
    /// false when no byte could be added. Relative indices held by the caller
    /// shift down by `keep`.
    #[cold]
    #[inline(never)]
    fn refill(&mut self, keep: usize, want: usize) -> bool {
        let keep = keep.min(self.i);
        if keep > 0 {
            self.buf.copy_within(keep..self.filled, 0);
            self.base += keep;
            self.i -= keep;
            self.filled -= keep;
        }
        let need = self.i.saturating_add(want);
        if need > self.buf.len() {
            // One token or record larger than the window (only in odd
            // files): grow geometrically, so a long token is not read
            // byte by byte.
            let grown = need.max(2 * self.buf.len());
            self.buf
                .resize(grown.min(self.len - self.base).max(self.buf.len()), 0);
        }
        let before = self.filled;
        while self.filled - self.i < want && self.filled < self.buf.len() && self.read < self.len {
            let room = (self.buf.len() - self.filled).min(self.len - self.read);
            let dst = &mut self.buf[self.filled..self.filled + room];
            let n = match &mut self.src {
                Source::Memory { data, next } => {
                    let src = data.get(*next..*next + room).unwrap_or_default();
                    dst[..src.len()].copy_from_slice(src);
                    *next += src.len();
                    src.len()
                }
                Source::File { file, .. } => loop {
                    match file.read(dst) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        Err(e) => {
                            self.io_error.get_or_insert(e);
                            break 0;
                        }
                    }
                },
            };
            if n == 0 {
                // The file shrank or failed: the input ends here.
                self.len = self.read;
                break;
            }
            self.filled += n;
            self.read += n;
        }
        self.filled > before
    }

    /// Makes up to `n` bytes from the read position available (fewer only
    /// at the end of the input) and returns them.
    #[inline]
    pub(crate) fn peek(&mut self, n: usize) -> &[u8] {
        if self.filled - self.i < n {
            self.refill(self.i, n);
        }
        let e = self.filled.min(self.i + n);
        &self.buf[self.i..e]
    }

    /// The bytes from the read position to the end of the window, refilled
    /// first if empty; empty only at the end of the input.
    pub(crate) fn available(&mut self) -> &[u8] {
        if self.i == self.filled {
            self.refill(self.i, 1);
        }
        &self.buf[self.i..self.filled]
    }

    #[inline]
    pub(crate) fn peek_byte(&mut self) -> Option<u8> {
        if self.i == self.filled && !self.refill(self.i, 1) {
            return None;
        }
        self.buf.get(self.i).copied()
    }

    /// Moves on by `n` bytes already seen through [`Cursor::peek`].
    #[inline]
    pub(crate) fn advance(&mut self, n: usize) {
        self.i = (self.i + n).min(self.filled);
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
        self.len.saturating_sub(self.pos())
    }

    /// The location of byte `pos`: a 1-based line in ASCII files, the byte
    /// offset in binary ones.
    pub(crate) fn location(&self, pos: usize) -> Location {
        if self.binary {
            return Location::Byte(pos);
        }
        let end = pos.min(self.len);
        let newlines = |b: &[u8]| b.iter().filter(|&&c| c == b'\n').count();
        let lines = match &self.src {
            Source::Memory { data, .. } => data.get(..end).map_or(0, newlines),
            Source::File { path, .. } => {
                // The window may have moved past `pos`: count from the start
                // of the file again (error path only).
                let mut n = 0;
                let mut left = end;
                if let Ok(f) = File::open(path) {
                    let mut f = f.take(end as u64);
                    let mut piece = vec![0u8; 1 << 16];
                    while left > 0 {
                        match f.read(&mut piece) {
                            Ok(0) => break,
                            Ok(k) => {
                                n += newlines(&piece[..k]);
                                left -= k.min(left);
                            }
                            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                            Err(_) => break,
                        }
                    }
                }
                n
            }
        };
        Location::Line(lines + 1)
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

    fn truncated(&self, pos: usize) -> MeshError {
        self.error(
            pos,
            MeshErrorKind::Truncated {
                what: self.section_what(),
            },
        )
    }

    #[inline]
    pub(crate) fn skip_ws(&mut self) {
        loop {
            while let Some(&b) = self.buf[..self.filled].get(self.i) {
                if !is_ws(b) {
                    return;
                }
                self.i += 1;
            }
            if !self.refill(self.i, 1) {
                return;
            }
        }
    }

    /// The next whitespace-separated token as (absolute start, relative
    /// start, relative end), or `None` at the end.
    #[inline]
    fn token_range(&mut self) -> Option<(usize, usize, usize)> {
        self.skip_ws();
        let mut start = self.i;
        loop {
            while let Some(&b) = self.buf[..self.filled].get(self.i) {
                if is_ws(b) {
                    break;
                }
                self.i += 1;
            }
            if self.i < self.filled {
                break;
            }
            // The token may go on past the window.
            let old = self.base;
            let more = self.refill(start, 1);
            start -= self.base - old;
            if !more {
                break;
            }
        }
        (self.i > start).then(|| (self.base + start, start, self.i))
    }

    /// The next whitespace-separated token and its start, or `None` at the end.
    pub(crate) fn token(&mut self) -> Option<(usize, Vec<u8>)> {
        self.token_range()
            .map(|(p, s, e)| (p, self.buf[s..e].to_vec()))
    }

    /// A token where a data field is expected; classifies what else was found.
    fn field(&mut self) -> Result<(usize, usize, usize)> {
        match self.token_range() {
            None => Err(self.truncated(self.pos())),
            Some((p, s, e)) if self.buf[s] == b'$' => {
                if &self.buf[s..e] == self.end.as_bytes() {
                    Err(self.wrong_count(p))
                } else {
                    Err(self.missing_end(p))
                }
            }
            Some(r) => Ok(r),
        }
    }

    fn section_what(&self) -> &'static str {
        match self.section {
            "$Nodes" => "the $Nodes section",
            "$ParametricNodes" => "the $ParametricNodes section",
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
        // Control bytes are no text: binary data under an ASCII header.
        if !self.binary && tok.iter().any(|&c| c < 0x20 || c == 0x7f) {
            return self.error(pos, MeshErrorKind::BinaryInAscii);
        }
        let shown = String::from_utf8_lossy(tok.get(..SHOW).unwrap_or(tok)).into_owned();
        self.error(pos, MeshErrorKind::NotANumber { what, found: shown })
    }

    /// Parses the next field with `parse`, or says what it is instead.
    fn parsed<T>(
        &mut self,
        what: &'static str,
        parse: fn(&[u8]) -> Option<T>,
    ) -> Result<(usize, T)> {
        let (p, s, e) = self.field()?;
        let t = &self.buf[s..e];
        match parse(t) {
            Some(v) => Ok((p, v)),
            None => Err(self.not_a_number(p, what, t)),
        }
    }

    /// The fast path of the integer fields: after optional whitespace, a
    /// plain decimal of 1 to `max` digits (so it cannot overflow) followed by
    /// whitespace inside the window. Returns the value and the digit count,
    /// leaving the position on the first digit; `None` sends the caller to
    /// the general path, which gives the same value or the error.
    #[inline]
    fn plain_digits(&mut self, from: usize, max: usize) -> Option<(u64, usize)> {
        let w = self.buf.get(from..self.filled)?;
        let mut v = 0u64;
        let mut k = 0;
        while let Some(&c) = w.get(k) {
            let d = c.wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            if k == max {
                return None;
            }
            v = v * 10 + u64::from(d);
            k += 1;
        }
        (k > 0 && w.get(k).is_some_and(|&c| is_ws(c))).then_some((v, k))
    }

    /// An unsigned integer field (counts, tags).
    #[inline]
    pub(crate) fn u64(&mut self, what: &'static str) -> Result<u64> {
        self.skip_ws();
        if let Some((v, k)) = self.plain_digits(self.i, 19) {
            self.i += k;
            return Ok(v);
        }
        self.parsed(what, parse_u64).map(|(_, v)| v)
    }

    /// A signed 32-bit field (types, dimensions, entity and physical tags).
    pub(crate) fn i32(&mut self, what: &'static str) -> Result<i32> {
        self.parsed(what, |t| parse_i64(t).and_then(|v| i32::try_from(v).ok()))
            .map(|(_, v)| v)
    }

    /// A signed field read as i64 (element node tags in 2.2 ASCII may be any integer).
    #[inline]
    pub(crate) fn i64(&mut self, what: &'static str) -> Result<(usize, i64)> {
        self.skip_ws();
        let neg = self.buf[..self.filled].get(self.i) == Some(&b'-');
        if let Some((v, k)) = self.plain_digits(self.i + usize::from(neg), 18) {
            let p = self.pos();
            self.i += k + usize::from(neg);
            // At most 18 digits: fits, and -0 is 0 as in `parse_i64`.
            let v = v as i64;
            return Ok((p, if neg { -v } else { v }));
        }
        self.parsed(what, parse_i64)
    }

    /// A finite floating-point field.
    #[inline]
    pub(crate) fn f64(&mut self, what: &'static str) -> Result<f64> {
        self.skip_ws();
        if let Some((v, k)) = self.fast_f64() {
            self.i += k;
            return Ok(v);
        }
        self.parsed(what, parse_f64).map(|(_, v)| v)
    }

    /// Clinger's fast path for the decimals Gmsh writes (`%.16g` without an
    /// exponent): `[-]digits[.digits]` with at most 19 digits whose value
    /// `m` is at most 2^53, followed by whitespace inside the window. Then
    /// `m` and `10^f` are exact doubles and one correctly rounded division
    /// gives the correctly rounded value, the same as std's parser; anything
    /// else (more digits, exponents, '+', garbage) goes to std's parser.
    #[inline]
    fn fast_f64(&self) -> Option<(f64, usize)> {
        let w = self.buf.get(self.i..self.filled)?;
        let neg = w.first() == Some(&b'-');
        let mut k = usize::from(neg);
        let (mut m, mut digits, mut frac) = (0u64, 0usize, None::<usize>);
        while let Some(&c) = w.get(k) {
            let d = c.wrapping_sub(b'0');
            if d <= 9 {
                if digits == 19 {
                    return None;
                }
                m = m * 10 + u64::from(d);
                digits += 1;
            } else if c == b'.' && frac.is_none() {
                frac = Some(digits);
            } else {
                break;
            }
            k += 1;
        }
        if digits == 0 || !w.get(k).is_some_and(|&c| is_ws(c)) || m > 1 << 53 {
            return None;
        }
        let f = frac.map_or(0, |at| digits - at);
        let v = m as f64 / *POW10.get(f)?;
        Some((if neg { -v } else { v }, k))
    }

    /// Expects the closing keyword of the current section.
    pub(crate) fn expect_end(&mut self) -> Result<()> {
        match self.token_range() {
            Some((_, s, e)) if &self.buf[s..e] == self.end.as_bytes() => Ok(()),
            Some((p, s, _)) if self.buf[s] == b'$' => Err(self.missing_end(p)),
            // More data than the header promised.
            Some((p, _, _)) => Err(self.wrong_count(p)),
            None => Err(self.missing_end(self.pos())),
        }
    }

    /// Skips blanks (space, tab, CR) without leaving the line; true when
    /// another field follows on it. ASCII records are one line each, so a
    /// field missing here is reported on its line instead of being taken
    /// from the next record (which would shift every record after it).
    #[inline]
    pub(crate) fn more_on_line(&mut self) -> bool {
        // Fast path, as Gmsh writes: one space, then a field or the line end
        // (4.1 element lines end in " \n"), inside the window.
        if let Some(&[a, c]) = self.buf[..self.filled].get(self.i..self.i + 2) {
            match (a, c) {
                (b'\n', _) | (b' ', b'\n') => return false,
                (b' ', c) if !is_ws(c) => {
                    self.i += 1;
                    return true;
                }
                _ => {}
            }
        }
        loop {
            match self.peek_byte() {
                Some(b' ' | b'\t' | b'\r') => self.i += 1,
                Some(b'\n') | None => return false,
                Some(_) => return true,
            }
        }
    }

    /// Before field `found` (0-based) of the one-line record at `at`: the
    /// field must be on the record's line. `record` says what the record
    /// needs; it is built on the error path only.
    #[inline]
    pub(crate) fn need_field(
        &mut self,
        at: usize,
        found: usize,
        record: impl FnOnce() -> String,
    ) -> Result<()> {
        if self.more_on_line() {
            Ok(())
        } else if self.peek_byte().is_none() {
            Err(self.truncated(self.pos()))
        } else {
            Err(self.field_count(at, record(), found))
        }
    }

    /// After the `found` fields of the one-line record at `at`: nothing but
    /// blanks may follow on its line.
    #[inline]
    pub(crate) fn line_done(
        &mut self,
        at: usize,
        found: usize,
        record: impl FnOnce() -> String,
    ) -> Result<()> {
        if !self.more_on_line() {
            return Ok(());
        }
        let mut found = found;
        while self.more_on_line() {
            found += 1;
            while self.peek_byte().is_some_and(|b| !is_ws(b)) {
                self.i += 1;
            }
        }
        Err(self.field_count(at, record(), found))
    }

    #[cold]
    fn field_count(&self, at: usize, record: String, found: usize) -> MeshError {
        self.error(at, MeshErrorKind::FieldCount { record, found })
    }

    /// After the ASCII count line of a binary section: skips to just after
    /// the end of the line, where the binary data starts. Returns whether
    /// the line ended with CR LF (see `mesh_format`).
    pub(crate) fn end_of_line(&mut self) -> Result<bool> {
        let mut cr = false;
        while let Some(b) = self.peek_byte() {
            self.i += 1;
            cr = match b {
                b'\n' => return Ok(cr),
                b'\r' => true,
                b' ' | b'\t' => false,
                _ => {
                    return Err(self.error(
                        self.pos() - 1,
                        MeshErrorKind::Malformed {
                            what: format!(
                                "unexpected data after the count line of {}",
                                self.section
                            ),
                        },
                    ))
                }
            };
        }
        Err(self.truncated(self.pos()))
    }

    /// True when a binary reader about to read a header finds the section's
    /// end instead (`\n$End…`): the header count was too large.
    pub(crate) fn at_keyword(&mut self) -> bool {
        let rest = self.peek(5);
        let rest = rest.strip_prefix(b"\n").unwrap_or(rest);
        rest.starts_with(b"$End")
    }

    /// `N` raw bytes of binary data.
    #[inline]
    pub(crate) fn take<const N: usize>(&mut self) -> Result<[u8; N]> {
        let p = self.pos();
        match self.peek(N).try_into() {
            Ok(a) => {
                self.i += N;
                Ok(a)
            }
            Err(_) => Err(self.truncated(p)),
        }
    }

    /// The byte length of `count` items of `size` bytes if the input left
    /// holds them (a count of 10^18 is an error here, never an allocation).
    pub(crate) fn check_items(&self, count: u64, size: usize) -> Result<usize> {
        usize::try_from(count)
            .ok()
            .and_then(|c| c.checked_mul(size))
            .filter(|&n| n <= self.remaining())
            .ok_or_else(|| self.truncated(self.pos()))
    }

    /// Skips `n` bytes of binary data.
    pub(crate) fn skip(&mut self, n: usize) -> Result<()> {
        let p = self.pos();
        if n > self.remaining() {
            return Err(self.truncated(p));
        }
        let mut left = n;
        loop {
            let step = left.min(self.filled - self.i);
            self.i += step;
            left -= step;
            if left == 0 {
                return Ok(());
            }
            if !self.refill(self.i, left.min(self.buf.len())) {
                return Err(self.truncated(p));
            }
        }
    }

    /// The next run of whole records of `size` bytes, at most `left` of them
    /// and at least one: returns (absolute start, count) and moves past them;
    /// [`Cursor::records`] gives their bytes until the next read. Callers
    /// check the whole run with [`Cursor::check_items`] first, so that a
    /// short input is reported where the run starts.
    pub(crate) fn batch(&mut self, left: u64, size: usize) -> Result<(usize, usize)> {
        let size = size.max(1);
        if self.filled - self.i < size {
            self.refill(self.i, size);
            if self.filled - self.i < size {
                return Err(self.truncated(self.pos()));
            }
        }
        let k = if left == 1 {
            // MSH 2.2 binary: one record per header, no division.
            1
        } else {
            usize::try_from(left)
                .unwrap_or(usize::MAX)
                .min((self.filled - self.i) / size)
        };
        let at = self.pos();
        self.i += k * size;
        Ok((at, k))
    }

    /// `len` bytes from absolute position `at`, which the last
    /// [`Cursor::batch`] passed.
    pub(crate) fn records(&self, at: usize, len: usize) -> &[u8] {
        let s = at - self.base;
        &self.buf[s..s + len]
    }

    pub(crate) fn bin_i32(&mut self) -> Result<i32> {
        self.take::<4>().map(i32::from_le_bytes)
    }

    pub(crate) fn bin_u64(&mut self) -> Result<u64> {
        self.take::<8>().map(u64::from_le_bytes)
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
