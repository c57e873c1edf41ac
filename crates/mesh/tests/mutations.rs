//! Damaged files never make the reader panic: a property test flips bytes,
//! drops and duplicates lines, changes numbers and truncates valid Gmsh
//! files (ASCII and binary, 2.2 and 4.1), and only requires that
//! `Mesh::from_bytes` returns (an `Err`, or `Ok` when the damage happens to
//! leave a valid mesh, e.g. a changed coordinate digit). A panic fails the
//! test. Bounded to a few seconds.

mod common;
use common::*;
use proptest::prelude::*;
use stickslip_mesh::Mesh;

const FILES: [&str; 12] = [
    "hole_q4_v22_ascii.msh",
    "hole_q9_v22_bin.msh",
    "slab_q4_v22_ascii.msh",
    "slab_q4_v22_bin.msh",
    "slab_q4_v41_ascii.msh",
    "slab_q4_v41_bin.msh",
    "slab_q9_v22_ascii.msh",
    "slab_q9_v41_bin.msh",
    "slab_q4_gaps_v41_ascii.msh",
    "slab_q4_gaps_v41_bin.msh",
    "slab_q9_param_v41_bin.msh",
    "slab_q9_param_v41_ascii.msh",
];

#[derive(Debug, Clone)]
enum Damage {
    Flip { at: usize, value: u8 },
    DropLine(usize),
    DuplicateLine(usize),
    Number { which: usize, value: u64 },
    Truncate(usize),
}

fn damage() -> impl Strategy<Value = Damage> {
    let numbers = prop_oneof![
        Just(0u64),
        Just(1),
        Just(u64::MAX),
        Just(1 << 31),
        Just(1_000_000_000_000_000_000),
        0u64..100
    ];
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, value)| Damage::Flip { at, value }),
        any::<usize>().prop_map(Damage::DropLine),
        any::<usize>().prop_map(Damage::DuplicateLine),
        (any::<usize>(), numbers).prop_map(|(which, value)| Damage::Number { which, value }),
        any::<usize>().prop_map(Damage::Truncate),
    ]
}

fn apply(b: &[u8], d: &Damage) -> Vec<u8> {
    let lines = || b.split_inclusive(|&c| c == b'\n');
    match *d {
        Damage::Flip { at, value } => {
            let mut v = b.to_vec();
            let i = at % v.len();
            v[i] ^= value.max(1);
            v
        }
        Damage::DropLine(k) => {
            let n = lines().count();
            lines()
                .enumerate()
                .filter(|(i, _)| *i != k % n)
                .flat_map(|(_, l)| l.iter().copied())
                .collect()
        }
        Damage::DuplicateLine(k) => {
            let n = lines().count();
            lines()
                .enumerate()
                .flat_map(|(i, l)| {
                    if i == k % n {
                        [l, l].concat()
                    } else {
                        l.to_vec()
                    }
                })
                .collect()
        }
        Damage::Number { which, value } => {
            // The which-th run of ASCII digits becomes `value`.
            let runs: Vec<(usize, usize)> = {
                let mut r = Vec::new();
                let mut i = 0;
                while i < b.len() {
                    if b[i].is_ascii_digit() {
                        let s = i;
                        while i < b.len() && b[i].is_ascii_digit() {
                            i += 1;
                        }
                        r.push((s, i));
                    } else {
                        i += 1;
                    }
                }
                r
            };
            let Some(&(s, e)) = runs.get(which % runs.len().max(1)) else {
                return b.to_vec();
            };
            [&b[..s], value.to_string().as_bytes(), &b[e..]].concat()
        }
        Damage::Truncate(at) => b[..at % b.len()].to_vec(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn damaged_files_never_panic(file in 0..FILES.len(), damages in proptest::collection::vec(damage(), 1..4)) {
        let mut b = bytes(FILES[file]);
        for d in &damages {
            if b.is_empty() {
                break;
            }
            b = apply(&b, d);
        }
        let _ = Mesh::from_bytes(&b);
    }
}

/// Every single-byte truncation of a small file is an error, never a panic
/// (a cut file cannot be a complete mesh: the last `$End…` is missing).
#[test]
fn every_truncation_is_an_error() {
    for f in [
        "slab_q4_v22_bin.msh",
        "slab_q4_v41_bin.msh",
        "slab_q4_v41_ascii.msh",
    ] {
        let b = bytes(f);
        // Cutting the final newline still leaves a complete `$EndElements`.
        for n in 0..b.len() - 1 {
            assert!(
                Mesh::from_bytes(&b[..n]).is_err(),
                "{f} cut at {n} was accepted"
            );
        }
    }
}
