//! Clockwise cells are re-oriented counter-clockwise and counted. The
//! clockwise files are made here by reversing cells of Gmsh fixtures; since
//! the reversal keeps node 0 (corners 0 3 2 1, quad9 mid-side nodes 7 6 5 4,
//! centre 8) and is its own inverse, the result must equal the original mesh.

mod common;
use common::*;
use stickslip_mesh::Mesh;

const REVERSE9: [usize; 9] = [0, 3, 2, 1, 7, 6, 5, 4, 8];

fn reversed(nodes: &[&str]) -> Vec<String> {
    let perm: &[usize] = if nodes.len() == 9 {
        &REVERSE9
    } else {
        &REVERSE9[..4]
    };
    perm.iter().map(|&i| nodes[i].to_string()).collect()
}

/// MSH 2.2 ASCII: reverses every other cell line (`tag type ntags tags… nodes`).
fn reverse_v22(text: &str, type_id: &str) -> (String, usize) {
    let mut count = 0;
    let mut cell = 0;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            if f.len() > 3
                && f[1] == type_id
                && f.len()
                    == 3 + f[2].parse::<usize>().unwrap_or(99) + if type_id == "3" { 4 } else { 9 }
            {
                cell += 1;
                if cell % 2 == 1 {
                    count += 1;
                    let k = 3 + f[2].parse::<usize>().unwrap();
                    let mut g: Vec<String> = f[..k].iter().map(|s| s.to_string()).collect();
                    g.extend(reversed(&f[k..]));
                    return g.join(" ");
                }
            }
            l.to_string()
        })
        .collect();
    (out.join("\n") + "\n", count)
}

/// MSH 4.1 ASCII: reverses all cells of the dim-2 blocks (`tag nodes…`),
/// walking `$Elements` block by block.
fn reverse_v41(text: &str) -> (String, usize) {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut i = lines.iter().position(|l| l == "$Elements").unwrap() + 1;
    let blocks: usize = lines[i].split_whitespace().next().unwrap().parse().unwrap();
    i += 1;
    let mut count = 0;
    for _ in 0..blocks {
        let h: Vec<usize> = lines[i]
            .split_whitespace()
            .map(|f| f.parse().unwrap())
            .collect();
        i += 1;
        for _ in 0..h[3] {
            if h[0] == 2 {
                let f: Vec<&str> = lines[i].split_whitespace().collect();
                let mut g = vec![f[0].to_string()];
                g.extend(reversed(&f[1..]));
                lines[i] = g.join(" ");
                count += 1;
            }
            i += 1;
        }
    }
    (lines.join("\n") + "\n", count)
}

fn check(original: &str, edited: &str, expected: usize) {
    let m = Mesh::from_bytes(edited.as_bytes()).unwrap();
    assert!(expected > 0);
    assert_eq!(m.source.reoriented, expected);
    same_mesh(&m, &load(original), original);
    check_invariants(&m);
}

#[test]
fn clockwise_quad4_cells_are_reoriented() {
    let (t, n) = reverse_v22(&text("slab_q4_v22_ascii.msh"), "3");
    assert_eq!(n, 4, "every other of the 8 cells");
    check("slab_q4_v22_ascii.msh", &t, n);
    let (t, n) = reverse_v41(&text("hole_q4_v41_ascii.msh"));
    check("hole_q4_v41_ascii.msh", &t, n);
}

#[test]
fn clockwise_quad9_cells_are_reoriented() {
    let (t, n) = reverse_v22(&text("slab_q9_v22_ascii.msh"), "10");
    assert_eq!(n, 4);
    check("slab_q9_v22_ascii.msh", &t, n);
    let (t, n) = reverse_v41(&text("hole_q9_v41_ascii.msh"));
    check("hole_q9_v41_ascii.msh", &t, n);
}

#[test]
fn clockwise_binary_cells_are_reoriented() {
    let mut b = bytes("slab_q4_v22_bin.msh");
    let quads: Vec<Record> = v22_bin_elements(&b)
        .into_iter()
        .filter(|r| r.type_id == 3)
        .collect();
    for r in &quads {
        // Swap corners 1 and 3.
        let n = r.offset + 4 * (1 + r.ntags);
        let (a, c) = (n + 4, n + 12);
        for k in 0..4 {
            b.swap(a + k, c + k);
        }
    }
    let m = Mesh::from_bytes(&b).unwrap();
    assert_eq!(m.source.reoriented, quads.len());
    same_mesh(&m, &load("slab_q4_v22_bin.msh"), "binary");
}
