//! `cargo xtask bench output`: what a whole run costs, as a user running a
//! parameter sweep sees it (the cost per run), and how much of it is the
//! results file: the release `stickslip run` on the paper's case (central
//! difference, 500 steps) and on a 4,257-node Newmark slab (100 steps), every
//! step written, with deflate off (the default) and at levels 1 and 4, and
//! with only the last step written (the run without its output). Wall time of
//! the process, median and fastest of the rounds (configurations interleaved),
//! and the file's size; a CSV into docs/bench-output.csv (the README quotes
//! it).
//!
//!     cargo xtask bench output [--rounds N]

use std::path::Path;
use std::process::Command;

/// (label, case file, extra `--set`s).
const CASES: [(&str, &str, &[&str]); 2] = [
    (
        "paper slab, central difference, 500 steps",
        "cases/martins-oden/cd-step-eps1e-4.toml",
        &[],
    ),
    (
        "Q2 64x16 slab (4,257 nodes), Newmark, 100 steps",
        "cases/martins-oden/newmark-step.toml",
        &["mesh.file=../meshes/slab-q2-64x16.msh"],
    ),
];

/// (label, `--set`s): what is written.
const SETTINGS: [(&str, &[&str]); 4] = [
    ("every step, no compression (default)", &[]),
    ("every step, deflate 1", &["output.compression=1"]),
    ("every step, deflate 4", &["output.compression=4"]),
    ("last step only", &["output.every=1000000000"]),
];

/// Runs the rounds and prints the table.
///
/// # Errors
/// Bad arguments, a failing build or run.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let mut rounds = 7usize;
    crate::bench::args("bench output", "[--rounds N]", args, |a, it| {
        match a {
            "--rounds" => rounds = crate::bench::integer_arg::<usize>(a, "a number", it)?.max(1),
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    let (exe, dir) = crate::bench::release_stickslip(root, "output")?;
    // times[case][setting]; sizes likewise.
    let mut times = vec![vec![Vec::new(); SETTINGS.len()]; CASES.len()];
    let mut sizes = vec![vec![0u64; SETTINGS.len()]; CASES.len()];
    for round in 0..rounds {
        eprintln!("bench output: round {} of {rounds}", round + 1);
        for (c, (_, case, case_sets)) in CASES.iter().enumerate() {
            for (s, (_, sets)) in SETTINGS.iter().enumerate() {
                let out = dir.join(format!("c{c}-s{s}.h5"));
                let all: Vec<&str> = case_sets.iter().chain(sets.iter()).copied().collect();
                let flags = ["--quiet", "--force"];
                let (o, secs) =
                    crate::bench::timed_run(Command::new(&exe), root, &flags, &out, case, &all)?;
                if !o.status.success() {
                    return Err(format!(
                        "{case} {sets:?} failed: {}",
                        String::from_utf8_lossy(&o.stderr)
                    ));
                }
                times[c][s].push(secs);
                sizes[c][s] = std::fs::metadata(&out).map(|m| m.len()).unwrap_or(0);
            }
        }
    }
    let mut csv = String::from("case,output,median_s,fastest_s,rounds,file_bytes\n");
    println!("\nwall time of `stickslip run` (release), {rounds} interleaved rounds:\n");
    println!(
        "{:<50} {:<38} {:>9} {:>9} {:>11}",
        "case", "output", "median s", "fastest", "file bytes"
    );
    for (c, (label, _, _)) in CASES.iter().enumerate() {
        for (s, (what, _)) in SETTINGS.iter().enumerate() {
            let t = &mut times[c][s];
            t.sort_by(f64::total_cmp);
            let (median, fastest) = (t[t.len() / 2], t[0]);
            println!(
                "{label:<50} {what:<38} {median:>9.3} {fastest:>9.3} {:>11}",
                sizes[c][s]
            );
            csv.push_str(&format!(
                "\"{label}\",\"{what}\",{median:.4},{fastest:.4},{rounds},{}\n",
                sizes[c][s]
            ));
        }
    }
    let path = root.join("docs/bench-output.csv");
    std::fs::write(&path, csv).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}
