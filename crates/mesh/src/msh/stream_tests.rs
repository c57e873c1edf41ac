//! The window of [`Cursor`] must not change any result: every fixture of
//! `tests/data` (real Gmsh output, all four encodings) and many damaged
//! copies of them are read whole and through windows of a few bytes, from
//! memory and from a file, and must give the same `Mesh` or the same error
//! at the same line or byte. The reference is the whole-input read, whose
//! results the integration tests in `tests/` pin against Gmsh.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use super::cursor::{parse_f64, parse_i64, parse_u64, Cursor, Source};
use super::{parse, read, read_file};
use crate::{Mesh, MeshError};

/// Window sizes that put refills at every kind of place (inside tokens,
/// binary records, keywords), up to one larger than any fixture.
const CHUNKS: [usize; 6] = [16, 17, 23, 64, 1000, 1 << 20];

fn fixtures() -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut v: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/data")
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "msh").then(|| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                (name, std::fs::read(&p).unwrap())
            })
        })
        .collect();
    v.sort();
    assert!(v.len() >= 20, "fixtures missing from {}", dir.display());
    v
}

fn from_memory(bytes: &[u8], chunk: usize) -> Result<Mesh, MeshError> {
    parse(Cursor::with_source(
        Source::Memory {
            data: bytes,
            next: 0,
        },
        bytes.len(),
        chunk,
    ))
}

/// A file name no other test (they run in parallel) uses.
fn temp_path(tag: &str) -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let k = NEXT.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!(
        "stickslip-mesh-{}-{k}-{tag}.msh",
        std::process::id()
    ))
}

fn from_file(bytes: &[u8], chunk: usize, tag: &str) -> Result<Mesh, MeshError> {
    let path = temp_path(tag);
    std::fs::write(&path, bytes).unwrap();
    let file = std::fs::File::open(&path).unwrap();
    let r = read_file(&path, file, bytes.len() as u64, chunk);
    std::fs::remove_file(&path).unwrap();
    r
}

/// Same mesh or same error (kind and location) for every window size.
fn check_same(name: &str, bytes: &[u8], files: bool) {
    let whole = read(bytes);
    for chunk in CHUNKS {
        let m = from_memory(bytes, chunk);
        assert_eq!(m, whole, "{name}: window {chunk} (memory) differs");
        if files {
            let f = from_file(bytes, chunk, &format!("{chunk}"));
            assert_eq!(f, whole, "{name}: window {chunk} (file) differs");
        }
    }
}

#[test]
fn fixtures_read_the_same_through_any_window() {
    for (name, bytes) in fixtures() {
        // The fixtures must be valid meshes except the refused ones.
        let ok = read(&bytes).is_ok();
        let refused = ["tri", "q8", "part"].iter().any(|r| name.contains(r));
        assert_eq!(ok, !refused, "{name}");
        check_same(&name, &bytes, true);
    }
}

/// Damaged copies: cut short, a byte changed, a line dropped, a digit
/// changed; the error (or mesh) must not depend on the window.
#[test]
fn damaged_fixtures_fail_the_same_through_any_window() {
    let mut errors = 0;
    for (name, bytes) in fixtures() {
        let n = bytes.len();
        // Deterministic spread of positions over the whole file.
        let positions: Vec<usize> = (1..24).map(|k| k * n / 24).collect();
        for &p in &positions {
            let mut variants = vec![bytes[..p].to_vec()];
            for b in [b'x', b'$', b'\n', b' ', 0u8, 0xff] {
                let mut v = bytes.clone();
                v[p] = b;
                variants.push(v);
            }
            // Drop the line holding p.
            let s = bytes[..p]
                .iter()
                .rposition(|&c| c == b'\n')
                .map_or(0, |k| k + 1);
            let e = bytes[p..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(n, |k| p + k + 1);
            variants.push([&bytes[..s], &bytes[e..]].concat());
            for v in variants {
                errors += usize::from(read(&v).is_err());
                // Files for a sample only: they cost a write each.
                check_same(&name, &v, p == positions[5] || p == positions[17]);
            }
        }
    }
    // The mutations must mostly be caught, or this test checks little.
    assert!(errors > 1000, "only {errors} damaged copies were refused");
}

/// A token far longer than the window (a damaged file) makes the window
/// grow and is reported as the whole-input read reports it.
#[test]
fn token_longer_than_the_window() {
    let (_, bytes) = fixtures()
        .into_iter()
        .find(|(n, _)| n == "slab_q4_v41_ascii.msh")
        .unwrap();
    let text = String::from_utf8(bytes).unwrap();
    let at = text.find("$Nodes").unwrap();
    let at = at + text[at..].find('\n').unwrap() + 1;
    let long = "7".repeat(300_000) + "x";
    let broken = format!("{}{long} {}", &text[..at], &text[at..]);
    let whole = read(broken.as_bytes());
    assert!(whole.is_err());
    check_same("long token", broken.as_bytes(), true);
}

/// An error far behind the window (a boundary line checked at the end of
/// the read) still gets its exact line, counted again from the file.
#[test]
fn line_of_an_error_behind_the_window() {
    let (_, bytes) = fixtures()
        .into_iter()
        .find(|(n, _)| n == "slab_q4_v41_ascii.msh")
        .unwrap();
    let text = String::from_utf8(bytes).unwrap();
    // Move the first element of the first line2 block ("1 1 1 4": entity
    // dim 1, tag 1, type 1, 4 elements) off the cell edges: nodes 1 and 3
    // are two corners of the slab, not the ends of one cell side.
    let block = text.find("\n1 1 1 4\n").unwrap() + "\n1 1 1 4\n".len();
    let line_end = block + text[block..].find('\n').unwrap();
    let fields: Vec<&str> = text[block..line_end].split_whitespace().collect();
    assert_eq!(
        fields.len(),
        3,
        "expected a line2 element: {:?}",
        &text[block..line_end]
    );
    let broken = format!("{}{} 1 3{}", &text[..block], fields[0], &text[line_end..]);
    let want_line = text[..block].matches('\n').count() + 1;
    let whole = read(broken.as_bytes()).unwrap_err();
    assert_eq!(whole.location, crate::Location::Line(want_line), "{whole}");
    let f = from_file(broken.as_bytes(), 16, "behind").unwrap_err();
    assert_eq!(f, whole);
}

/// The fast paths of the number fields give std's values bit for bit, and
/// send everything else to the general path.
#[test]
fn number_fast_paths_agree_with_the_general_parsers() {
    let mut tokens: Vec<String> = [
        "0",
        "-0",
        "1",
        "-1",
        "007",
        "1.",
        ".5",
        "-.5",
        ".",
        "-",
        "+1",
        "+1.5",
        "1e5",
        "1.5E-3",
        "inf",
        "nan",
        "1.2.3",
        "0x10",
        "9007199254740992",
        "9007199254740993",
        "0.9589589589588192",
        "3.968000000015329",
        "-3.968000000015329",
        "1234567890123456789",
        "12345678901234567890",
        "123456789012345678901",
        "0.0000000000000000001",
        "0.00000000000000000001",
        "18446744073709551615",
        "18446744073709551616",
        "-9223372036854775808",
        "-9223372036854775809",
        "999999999999999999",
        "-999999999999999999",
        "1.7976931348623157e308",
        "12a",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    // Decimals as Gmsh writes them (%.16g), from a simple generator.
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    for _ in 0..20_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let v = (x >> 11) as f64 / (1u64 << 53) as f64 * 10f64.powi((x % 9) as i32 - 4);
        tokens.push(format!("{v}"));
        tokens.push(format!("{:.15}", -v));
        tokens.push(format!("{}", x % 1_000_000_007));
    }
    for t in &tokens {
        // Each token twice: followed by white space (fast path possible)
        // and last in the input (general path).
        let text = format!("{t} {t}");
        let mut c = Cursor::new(text.as_bytes());
        let mut d = Cursor::new(text.as_bytes());
        let mut e = Cursor::new(text.as_bytes());
        for _ in 0..2 {
            let f = c.f64("x").ok().map(f64::to_bits);
            assert_eq!(f, parse_f64(t.as_bytes()).map(f64::to_bits), "f64 {t:?}");
            assert_eq!(d.u64("x").ok(), parse_u64(t.as_bytes()), "u64 {t:?}");
            assert_eq!(
                e.i64("x").ok().map(|(_, v)| v),
                parse_i64(t.as_bytes()),
                "i64 {t:?}"
            );
        }
    }
}
