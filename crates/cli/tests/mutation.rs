//! Bounded mutation testing in the normal suite (issue 8): tens of
//! thousands of mutated case texts (with and without `--set`) and .msh
//! files (ASCII and binary) go through the readers; every one must give a
//! value or a typed error, never a panic. The cargo-fuzz targets in fuzz/
//! explore the same inputs without a bound.
//!
//! The mutations are those of a fuzzer's first stage: byte flips, inserted
//! or deleted bytes, TOML and .msh tokens spliced in, lines duplicated,
//! swapped or dropped, truncation. A fixed-seed xorshift generator keeps the
//! run reproducible; a panicking input is written next to the target dir and
//! named in the failure.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// xorshift64* (Vigna 2016): reproducible, no dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

const CASE_TOKENS: &[&str] = &[
    "=",
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "\"",
    "'",
    ",",
    ".",
    "\n",
    "#",
    " ",
    "-",
    "+",
    "0",
    "1e309",
    "-1",
    "nan",
    "inf",
    "-inf",
    "1e-400",
    "true",
    "false",
    "\"\"",
    "[]",
    "{}",
    "[[dirichlet]]\n",
    "[[traction]]\n",
    "[contact]\n",
    "[time]\n",
    "[output]\n",
    "[mesh]\n",
    "[material]\n",
    "group = \"body\"\n",
    "history = { table = [] }",
    "history = { sin = { omega = 1e308 } }",
    "history = { table = [[1, 1], [0, 0]] }",
    "stick_reduction = { dt = 0, steps = 0 }",
    "scheme = \"newmark\"\n",
    "mass = \"consistent\"\n",
    "every = 18446744073709551615",
    "max_iterations = -1",
    "compression = 255",
    "t = [1, 2, 3]",
    "E = \"x\"",
    "\u{feff}",
    "\u{00e9}",
    "\u{1f600}",
    "\r\n",
    "\t",
    "\\u0000",
    "\"\"\"",
    "'''",
    "a.b.c = 1\n",
];

const MSH_TOKENS: &[&[u8]] = &[
    b"$MeshFormat\n",
    b"$EndMeshFormat\n",
    b"$Nodes\n",
    b"$EndNodes\n",
    b"$Elements\n",
    b"$EndElements\n",
    b"$PhysicalNames\n",
    b"$Entities\n",
    b"2.2 0 8\n",
    b"4.1 1 8\n",
    b"4.1 0 8\n",
    b"2.2 1 8\n",
    b"\x01\x00\x00\x00",
    b"\xff\xff\xff\xff",
    b"\x00\x00\x00\x80",
    b"-1",
    b"0",
    b"1e308",
    b"nan",
    b"999999999999",
    b"\n",
    b" ",
    b"\"",
    b"10",
    b"3",
    b"9",
];

fn mutate(rng: &mut Rng, seed: &[u8], tokens: &[&[u8]]) -> Vec<u8> {
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = v.len();
        match rng.below(9) {
            0 if n > 0 => {
                let i = rng.below(n);
                v[i] ^= 1 << rng.below(8);
            }
            1 => {
                let i = rng.below(n + 1);
                v.insert(i, rng.next() as u8);
            }
            2 if n > 0 => {
                let i = rng.below(n);
                let len = (1 + rng.below(16)).min(n - i);
                v.drain(i..i + len);
            }
            3 | 4 => {
                let i = rng.below(n + 1);
                let t = tokens[rng.below(tokens.len())];
                v.splice(i..i, t.iter().copied());
            }
            5 => {
                // Duplicate or drop a line.
                let lines: Vec<&[u8]> = v.split(|&b| b == b'\n').collect();
                let k = rng.below(lines.len());
                let mut out: Vec<Vec<u8>> = lines.iter().map(|l| l.to_vec()).collect();
                if rng.below(2) == 0 {
                    out.insert(k, lines[k].to_vec());
                } else {
                    out.remove(k);
                }
                v = out.join(&b'\n');
            }
            6 => {
                // Swap two lines.
                let mut lines: Vec<Vec<u8>> =
                    v.split(|&b| b == b'\n').map(|l| l.to_vec()).collect();
                let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
                lines.swap(a, b);
                v = lines.join(&b'\n');
            }
            7 if n > 0 => v.truncate(rng.below(n)),
            _ => {
                // Replace a digit run by another number.
                if let Some(i) = (0..n)
                    .map(|k| (k + rng.below(n)) % n)
                    .find(|&k| v[k].is_ascii_digit())
                {
                    let t = tokens[rng.below(tokens.len())];
                    v.splice(i..i + 1, t.iter().copied());
                }
            }
        }
    }
    v
}

fn save_and_panic(name: &str, k: usize, input: &[u8], extra: &str) -> ! {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mutation-{name}-{k}"));
    std::fs::write(&p, input).unwrap();
    panic!(
        "{name}: mutation {k} panicked{extra}; input saved in {}",
        p.display()
    );
}

/// The case files (text, and the path they are read as, so that their
/// relative mesh paths resolve and unmutated cases are accepted).
fn case_seeds() -> Vec<(String, PathBuf)> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/slab.toml");
    let mut seeds = vec![(std::fs::read_to_string(&data).unwrap(), data)];
    for e in std::fs::read_dir(root().join("cases/martins-oden")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            seeds.push((std::fs::read_to_string(&p).unwrap(), p));
        }
    }
    seeds
}

#[test]
fn mutated_case_texts_never_panic() {
    let seeds = case_seeds();
    let tokens: Vec<&[u8]> = CASE_TOKENS.iter().map(|t| t.as_bytes()).collect();
    let sets_pool = [
        "time.dt=0",
        "contact.eps=1e-2",
        "dirichlet.0.uy=nan",
        "dirichlet.9.uy=0",
        "traction.0.history={ sin = { omega = 1 } }",
        "x=1",
        "time..dt=1",
        "output.every=0",
        "mesh=1",
        "contact.group.x=1",
        "=",
        "time.stick_reduction.dt=1",
    ];
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let n = 20_000;
    let (mut ok, mut refused) = (0, 0);
    let t0 = Instant::now();
    for k in 0..n {
        let (seed, path) = &seeds[rng.below(seeds.len())];
        let seed = seed.as_bytes();
        let bytes = mutate(&mut rng, seed, &tokens);
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let sets: Vec<String> = (0..rng.below(3))
            .map(|_| sets_pool[rng.below(sets_pool.len())].to_string())
            .collect();
        let r = catch_unwind(AssertUnwindSafe(|| {
            let r = stickslip_case::load_str(path, &text, &sets);
            if k % 8 == 0 {
                let _ = stickslip_case::restart_changes(&text, seed_str(seed));
            }
            r
        }));
        match r {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(e)) => {
                assert!(
                    !e.0.trim().is_empty(),
                    "mutation {k}: an empty error message"
                );
                refused += 1;
            }
            Err(_) => save_and_panic("case", k, &bytes, &format!(" with --set {sets:?}")),
        }
    }
    eprintln!(
        "{n} mutated cases in {:.2} s: {ok} accepted, {refused} refused with a message",
        t0.elapsed().as_secs_f64()
    );
    assert_eq!(ok + refused, n);
    // Both outcomes occur: the mutations reach past the first check.
    assert!(
        ok > n / 50 && refused > n / 2,
        "{ok} accepted, {refused} refused"
    );
}

fn seed_str(b: &[u8]) -> &str {
    std::str::from_utf8(b).unwrap_or("")
}

#[test]
fn mutated_meshes_never_panic() {
    // The small fixtures (ASCII and binary, MSH 2.2 and 4.1) of the fuzz
    // corpus: small inputs put the mutations in every section.
    let dir = root().join("fuzz/seeds/msh");
    let mut seeds: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| std::fs::metadata(p).unwrap().len() < 4096)
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    seeds.sort();
    assert!(
        seeds.iter().any(|(n, _)| n.contains("bin"))
            && seeds.iter().any(|(n, _)| n.contains("ascii")),
        "binary and ASCII seeds"
    );
    let mut rng = Rng(0xd1b5_4a32_d192_ed03);
    let n = 20_000;
    let (mut ok, mut refused) = (0, 0);
    let t0 = Instant::now();
    for k in 0..n {
        let (_, seed) = &seeds[rng.below(seeds.len())];
        let bytes = mutate(&mut rng, seed, MSH_TOKENS);
        match catch_unwind(|| stickslip_mesh::Mesh::from_bytes(&bytes).map(|_| ())) {
            Ok(Ok(())) => ok += 1,
            Ok(Err(e)) => {
                assert!(!e.to_string().is_empty());
                refused += 1;
            }
            Err(_) => save_and_panic("msh", k, &bytes, ""),
        }
    }
    eprintln!(
        "{n} mutated meshes in {:.2} s: {ok} read, {refused} refused with a message",
        t0.elapsed().as_secs_f64()
    );
    assert!(refused > n / 4, "{refused}");
}
