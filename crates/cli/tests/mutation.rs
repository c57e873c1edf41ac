//! Bounded mutation testing in the normal suite: tens of thousands of
//! mutated case texts (with and without `--set`) and .msh files (ASCII and
//! binary) go through the readers. Never a panic, and every outcome keeps
//! the readers' promises:
//! * a refused case names, in every problem, the case file (and a line of
//!   it) or the `--set` at fault; an accepted one keeps every promise of
//!   docs/case-file.md, reloads from the text a results file stores to the
//!   same case, and is built into a model (mesh, K, M, initial state) or
//!   refused there by name too;
//! * a refused mesh names a place inside the input; an accepted one keeps
//!   the invariants `Mesh` promises, checked here from its coordinates; the
//!   file read through the streaming reader gives the same mesh or error.
//!
//! The mutations are those of a fuzzer's first stage: byte flips, inserted
//! or deleted bytes, TOML and .msh tokens spliced in, lines duplicated,
//! swapped or dropped, truncation. A fixed-seed xorshift generator keeps the
//! run reproducible; an input that panics or breaks a promise is written
//! next to the target dir and named in the failure. The cargo-fuzz targets
//! in fuzz/ explore the same inputs without a bound.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

use stickslip_case::{Case, History};
use stickslip_mesh::{Location, Mesh};
use stickslip_testkit::workspace_root as root;

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

/// Writes a mutated input next to the target dir, for the failure message.
fn save(name: &str, k: usize, input: &[u8]) -> PathBuf {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mutation-{name}-{k}"));
    std::fs::write(&p, input).unwrap();
    p
}

fn save_and_panic(name: &str, k: usize, input: &[u8], extra: &str) -> ! {
    let p = save(name, k, input);
    panic!(
        "{name}: mutation {k} panicked{extra}; input saved in {}",
        p.display()
    );
}

/// Keeps `found`, the promises input `k` broke (if any), with what it
/// was and where it is saved.
fn note(
    findings: &mut Vec<String>,
    name: &str,
    k: usize,
    input: &[u8],
    what: &str,
    found: &[String],
) {
    if !found.is_empty() {
        let saved = save(name, k, input);
        findings.push(format!(
            "{what} (saved in {}): {}",
            saved.display(),
            found.join("; ")
        ));
    }
}

/// Fails with the first few findings (each naming its saved input) and
/// their count.
fn assert_no_findings(what: &str, findings: &[String]) {
    assert!(
        findings.is_empty(),
        "{} {what}; the first:\n{}",
        findings.len(),
        findings[..findings.len().min(5)].join("\n")
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
    let (mut ok, mut built, mut refused) = (0, 0, 0);
    let mut findings = Vec::new();
    let t0 = Instant::now();
    for k in 0..n {
        let (seed, path) = &seeds[rng.below(seeds.len())];
        let seed = seed.as_bytes();
        let bytes = mutate(&mut rng, seed, &tokens);
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let sets: Vec<String> = (0..rng.below(3))
            .map(|_| sets_pool[rng.below(sets_pool.len())].to_string())
            .collect();
        let file = path.display().to_string();
        let r = catch_unwind(AssertUnwindSafe(|| {
            let r = stickslip_case::load_str(path, &text, &sets);
            if k % 8 == 0 {
                let _ = stickslip_case::restart_changes(&text, seed_str(seed));
            }
            // What `check` and `run` do next: mesh, model, initial state.
            r.map(|case| {
                let model = stickslip_case::prepare(&case).map(|_| ());
                (case, model)
            })
        }));
        let found = match r {
            Ok(Ok((case, model))) => {
                ok += 1;
                let mut found = broken_promises(&case);
                found.extend(reloads_otherwise(&case));
                match model {
                    Ok(()) => built += 1,
                    Err(e) => found.extend(unplaced_lines(&e.0, &file, &text)),
                }
                found
            }
            Ok(Err(e)) => {
                refused += 1;
                unplaced_lines(&e.0, &file, &text)
            }
            Err(_) => save_and_panic("case", k, &bytes, &format!(" with --set {sets:?}")),
        };
        let what = format!("mutation {k} of {file} with --set {sets:?}");
        note(&mut findings, "case", k, &bytes, &what, &found);
    }
    eprintln!(
        "{n} mutated cases in {:.2} s: {ok} accepted ({built} built into a model), \
         {refused} refused with a message",
        t0.elapsed().as_secs_f64()
    );
    assert_no_findings("mutated cases broke a promise", &findings);
    // Both outcomes occur, and most accepted cases become a model: the
    // mutations reach past the first check.
    assert!(
        ok > n / 50 && built > ok / 2 && refused > n / 2,
        "{ok} accepted, {built} built, {refused} refused"
    );
}

fn seed_str(b: &[u8]) -> &str {
    std::str::from_utf8(b).unwrap_or("")
}

/// The lines of an input-error message that do not say where their
/// problem is. Each problem starts with the case file, as `FILE:LINE:COL: `
/// with LINE a line of `text` or as `FILE: `, or with the `--set` it came
/// from (src/error.rs: "the message names the file, the line where there
/// is one"); the list may end with a count of the problems left out.
fn unplaced_lines(msg: &str, file: &str, text: &str) -> Vec<String> {
    if msg.trim().is_empty() {
        return vec!["an empty error message".into()];
    }
    // A problem at the end of a text that ends in a newline is on the
    // empty line after it.
    let lines = text.split('\n').count();
    let placed = |l: &str| {
        if l.starts_with("--set ") || (l.starts_with("and ") && l.contains(" more problems")) {
            return true;
        }
        let Some(rest) = l.strip_prefix(file) else {
            return false;
        };
        if rest.starts_with(": ") {
            return true;
        }
        let mut parts = rest.splitn(4, ':');
        match (parts.next(), parts.next(), parts.next(), parts.next()) {
            (Some(""), Some(line), Some(col), Some(what)) => {
                line.parse::<usize>()
                    .is_ok_and(|l| (1..=lines).contains(&l))
                    && col.parse::<usize>().is_ok_and(|c| c >= 1)
                    && what.starts_with(' ')
            }
            _ => false,
        }
    };
    msg.lines()
        .filter(|l| !placed(l))
        .map(|l| format!("a problem that names no place: {l:?}"))
        .collect()
}

/// What docs/case-file.md promises of an accepted case: every number
/// finite and 0 or of magnitude 1e-100 to 1e100; nu in (-1, 0.5); a
/// contact pressure >= 0 and eps > 0; compression 0 to 9; a traction with
/// either t or pressure; a mesh file that is a file. And what a run needs
/// to mean anything: E, rho, dt and t_end > 0, output.every >= 1.
fn broken_promises(c: &Case) -> Vec<String> {
    let mut numbers = vec![
        ("material.E", c.material.e),
        ("material.nu", c.material.nu),
        ("material.rho", c.material.rho),
        ("time.beta", c.time.beta),
        ("time.gamma", c.time.gamma),
        ("time.dt", c.time.dt),
        ("time.t_end", c.time.t_end),
        ("output.flush_seconds", c.output.flush_seconds),
    ];
    for d in &c.dirichlet {
        numbers.extend(d.ux.map(|x| ("dirichlet ux", x)));
        numbers.extend(d.uy.map(|x| ("dirichlet uy", x)));
    }
    for t in &c.traction {
        numbers.extend(t.t.iter().flatten().map(|&x| ("traction t", x)));
        numbers.extend(t.pressure.map(|x| ("traction pressure", x)));
        match &t.history {
            History::Sin { omega } => numbers.push(("history omega", *omega)),
            History::Table(p) => numbers.extend(p.iter().flatten().map(|&x| ("history table", x))),
            History::Constant | History::Step => {}
        }
    }
    numbers.extend(c.body_force.iter().flatten().map(|&x| ("body_force", x)));
    for ct in c.contact.iter() {
        numbers.extend(
            [
                ("contact.pressure", ct.pressure),
                ("contact.mu", ct.mu.as_ref().map(|m| m.at_rest())),
                ("contact.cn", ct.cn),
                ("contact.mn", ct.mn),
                ("contact.ct", ct.ct),
                ("contact.mt", ct.mt),
            ]
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| (k, v))),
        );
        numbers.push(("contact.eps", ct.eps));
    }
    numbers.extend(
        c.time
            .stick_reduction
            .map(|r| ("time.stick_reduction.dt", r.dt)),
    );
    let mut broken: Vec<String> = numbers
        .into_iter()
        .filter(|&(_, x)| x != 0.0 && !(x.is_finite() && (1e-100..=1e100).contains(&x.abs())))
        .map(|(key, x)| {
            format!("{key} = {x:e} is neither 0 nor finite of magnitude 1e-100 to 1e100")
        })
        .collect();
    let mut promise = |holds: bool, what: &str| {
        if !holds {
            broken.push(what.to_string());
        }
    };
    let m = &c.material;
    promise(m.e > 0.0 && m.rho > 0.0, "E and rho must be > 0");
    promise(m.nu > -1.0 && m.nu < 0.5, "nu must lie in (-1, 0.5)");
    for ct in c.contact.iter() {
        promise(
            ct.pressure.unwrap_or(0.0) >= 0.0,
            "contact.pressure must be >= 0",
        );
        promise(ct.eps > 0.0, "contact.eps must be > 0");
    }
    for t in &c.traction {
        promise(
            t.t.is_some() != t.pressure.is_some(),
            "a traction gives t or pressure, not both or neither",
        );
    }
    promise(
        c.time.dt > 0.0 && c.time.t_end > 0.0,
        "time.dt and time.t_end must be > 0",
    );
    promise(c.output.every != Some(0), "output.every must be >= 1");
    promise(c.output.frames != Some(0), "output.frames must be >= 1");
    promise(
        c.output.interval.is_none_or(|dt| dt > 0.0),
        "output.interval must be > 0",
    );
    promise(
        c.output.compression.is_none_or(|l| l <= 9),
        "output.compression is 0 to 9",
    );
    promise(c.mesh.file.is_file(), "mesh.file must be a file");
    broken
}

/// A results file stores [`Case::source`] and a restart reads it back: the
/// text must load, without the `--set`s it already holds, to the same case
/// (but for where each key was found: a `--set` is a line of it now).
fn reloads_otherwise(c: &Case) -> Option<String> {
    let unplaced = |c: &Case| Case {
        locations: BTreeMap::new(),
        ..c.clone()
    };
    match stickslip_case::load_str(&c.path, &c.source, &[]) {
        Ok(again) if unplaced(&again) == unplaced(c) => None,
        Ok(again) => Some(format!(
            "its source text loads to another case: {again:?} against {c:?}"
        )),
        Err(e) => Some(format!("its source text is refused: {}", e.0)),
    }
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
    let mut findings = Vec::new();
    let file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mutation-msh-current.msh");
    let t0 = Instant::now();
    for k in 0..n {
        let (_, seed) = &seeds[rng.below(seeds.len())];
        let bytes = mutate(&mut rng, seed, MSH_TOKENS);
        // A new file each time: ext4 flushes a file truncated and
        // rewritten to disk (auto_da_alloc), which would slow the loop.
        std::fs::remove_file(&file).ok();
        std::fs::write(&file, &bytes).unwrap();
        let (in_memory, from_file) =
            match catch_unwind(|| (Mesh::from_bytes(&bytes), Mesh::from_file(&file))) {
                Ok(r) => r,
                Err(_) => save_and_panic("msh", k, &bytes, ""),
            };
        let mut found = Vec::new();
        // The file users give is read through a window (`from_file`),
        // the fuzz targets' bytes at once: one reading.
        match (&in_memory, &from_file) {
            (Ok(a), Ok(b)) if a == b => {}
            (Err(a), Err(b)) if a.kind == b.kind && a.location == b.location => {
                if b.path.as_deref() != Some(file.as_path()) {
                    found.push(format!("the error does not name the file: {b}"));
                }
            }
            (a, b) => found.push(format!(
                "read at once and through a file, it gives two results: {:?} / {:?}",
                a.as_ref().map(|_| "a mesh"),
                b.as_ref().map(|_| "a mesh")
            )),
        }
        match in_memory {
            Ok(mesh) => {
                ok += 1;
                found.extend(broken_invariants(&mesh));
            }
            Err(e) => {
                refused += 1;
                if e.to_string().trim().is_empty() {
                    found.push("an empty error message".into());
                }
                found.extend(outside(&e.location, &bytes));
            }
        }
        note(
            &mut findings,
            "msh",
            k,
            &bytes,
            &format!("mutation {k}"),
            &found,
        );
    }
    std::fs::remove_file(&file).ok();
    eprintln!(
        "{n} mutated meshes in {:.2} s: {ok} read, {refused} refused with a message",
        t0.elapsed().as_secs_f64()
    );
    assert_no_findings("mutated meshes broke a promise", &findings);
    // Both outcomes occur: the mutations reach past the first checks.
    assert!(
        ok > n / 100 && refused > n / 4,
        "{ok} read, {refused} refused"
    );
}

/// A place an error names that is not in the input: a line past its last
/// one, a byte past its end.
fn outside(at: &Location, bytes: &[u8]) -> Option<String> {
    let lines = bytes.split(|&b| b == b'\n').count();
    match *at {
        Location::Line(l) if l == 0 || l > lines => {
            Some(format!("line {l} of an input of {lines} lines"))
        }
        Location::Byte(b) if b > bytes.len() => {
            Some(format!("byte {b} of an input of {} bytes", bytes.len()))
        }
        _ => None,
    }
}

/// The invariants `stickslip_mesh::Mesh` promises (its documentation),
/// checked from the coordinates: every node used by a cell; every cell
/// of valid nodes, counter-clockwise with a positive Jacobian at its
/// corners (the cross product of the two sides meeting there); every
/// boundary edge a side of its cell with the cell on its left (so its
/// nodes are consecutive corners of the cell, in the cell's order, and a
/// line3's middle node is that side's); group nodes sorted, unique, valid.
fn broken_invariants(m: &Mesh) -> Vec<String> {
    let mut broken = Vec::new();
    let n = m.nodes.len();
    let per = m.kind.nodes_per_cell();
    if m.node_tags.len() != n || m.cells.len() != m.n_cells() * per {
        return vec!["node tags or cells of the wrong length".into()];
    }
    if m.cells.iter().any(|&i| i >= n) {
        return vec!["a cell with a node that does not exist".into()];
    }
    if m.nodes.iter().flatten().any(|x| !x.is_finite()) {
        broken.push("a node with a coordinate that is not finite".into());
    }
    let mut used = vec![false; n];
    for &i in &m.cells {
        used[i] = true;
    }
    if let Some(i) = used.iter().position(|u| !u) {
        broken.push(format!("node {i} is in no cell"));
    }
    for c in 0..m.n_cells() {
        let cell = m.cell(c);
        let p = |k: usize| m.nodes[cell[k % 4]];
        let turns_left = (0..4).all(|k| {
            let (a, b, prev) = (p(k), p(k + 1), p(k + 3));
            (b[0] - a[0]) * (prev[1] - a[1]) - (b[1] - a[1]) * (prev[0] - a[0]) > 0.0
        });
        if !turns_left {
            broken.push(format!(
                "cell {c} is not counter-clockwise and convex at its corners"
            ));
        }
    }
    for g in &m.groups {
        if g.nodes.windows(2).any(|w| w[0] >= w[1]) || g.nodes.iter().any(|&i| i >= n) {
            broken.push(format!(
                "group {:?}: nodes not sorted, unique and valid",
                g.name
            ));
        }
        for e in &g.edges {
            let side = (e.cell < m.n_cells())
                .then(|| m.cell(e.cell))
                .and_then(|cell| {
                    (0..4)
                        .find(|&k| cell[k] == e.nodes[0] && cell[(k + 1) % 4] == e.nodes[1])
                        .map(|k| (cell, k))
                });
            let mid_ok = match (side, e.mid) {
                (Some((cell, k)), Some(mid)) => cell.len() == 9 && cell[4 + k] == mid,
                (Some((cell, _)), None) => cell.len() == 4,
                (None, _) => false,
            };
            if !mid_ok {
                broken.push(format!(
                    "group {:?}: edge {:?} is not a side of cell {} with the cell on its left",
                    g.name, e.nodes, e.cell
                ));
            }
        }
    }
    broken
}

/// The checks above find what they look for, so that the two tests cannot
/// pass by checking nothing: each broken input here is one promise broken
/// by hand, each sound one an input the readers accept.
#[test]
fn the_checks_find_broken_promises() {
    let (text, path) = &case_seeds()[0];
    let file = path.display().to_string();
    // Messages: placed, and not.
    for good in [
        format!("{file}:3:1: x"),
        format!("{file}: x\n--set a=1: y\nand 3 more problems; fix"),
    ] {
        assert_eq!(unplaced_lines(&good, &file, "a\nb\n"), Vec::<String>::new());
    }
    for bad in [
        "material.nu = 0.5 must lie in (-1, 0.5)".to_string(),
        format!("{file}:4:1: past the end"),
        format!("{file}:2:1: x\nsecond line alone"),
        "other.toml:1:1: x".to_string(),
        " ".to_string(),
    ] {
        assert_eq!(unplaced_lines(&bad, &file, "a\nb\n").len(), 1, "{bad:?}");
    }
    // Cases: the seed keeps every promise; each change breaks one.
    let case = stickslip_case::load_str(path, text, &[]).unwrap();
    assert_eq!(broken_promises(&case), Vec::<String>::new());
    assert_eq!(reloads_otherwise(&case), None);
    let breaks: [fn(&mut Case); 6] = [
        |c| c.material.nu = 0.5,
        |c| c.material.e = 1e101,
        |c| c.output.every = Some(0),
        |c| {
            c.traction[0].history = History::Sin {
                omega: f64::INFINITY,
            }
        },
        |c| c.contact[0].eps = 0.0,
        |c| {
            c.mesh.file.set_extension("absent");
        },
    ];
    for (i, b) in breaks.iter().enumerate() {
        let mut c = case.clone();
        b(&mut c);
        assert_eq!(broken_promises(&c).len(), 1, "break {i}");
    }
    let mut c = case.clone();
    c.source = c.source.replace("eps = 1e-4", "eps = 1e-3");
    assert!(reloads_otherwise(&c).is_some());
    // Meshes: a Q2 mesh as read, then one promise broken at a time.
    let bytes = std::fs::read(root().join("fuzz/seeds/msh/tiny_q9_v22_ascii.msh")).unwrap();
    let mesh = Mesh::from_bytes(&bytes).unwrap();
    assert_eq!(broken_invariants(&mesh), Vec::<String>::new());
    let edged = mesh
        .groups
        .iter()
        .position(|g| !g.edges.is_empty())
        .unwrap();
    let breaks: [fn(&mut Mesh, usize); 4] = [
        // Clockwise.
        |m, _| m.cells[..4].reverse(),
        // A node no cell uses.
        |m, _| {
            m.nodes.push([9.0, 9.0]);
            m.node_tags.push(99);
        },
        // An edge walked the wrong way: the cell on its right.
        |m, g| m.groups[g].edges[0].nodes.reverse(),
        // Another side's middle node.
        |m, g| {
            let e = &mut m.groups[g].edges[0];
            e.mid = e.mid.map(|k| k + 1);
        },
    ];
    for (i, b) in breaks.iter().enumerate() {
        let mut m = mesh.clone();
        b(&mut m, edged);
        assert!(!broken_invariants(&m).is_empty(), "break {i}");
    }
    let lines = bytes.split(|&b| b == b'\n').count();
    assert_eq!(outside(&Location::Line(lines), &bytes), None);
    assert_eq!(outside(&Location::Byte(bytes.len()), &bytes), None);
    for at in [
        Location::Line(0),
        Location::Line(lines + 1),
        Location::Byte(bytes.len() + 1),
    ] {
        assert!(outside(&at, &bytes).is_some(), "{at:?}");
    }
}
