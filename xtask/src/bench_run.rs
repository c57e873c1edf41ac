//! `cargo xtask bench run`: whole `stickslip run` processes on the slab
//! ladder, as a user pays for them: start-up, mesh, setup, steps, output.
//!
//! The first rung is the paper's two cases as shipped (mesh, Δt, t_end,
//! every step written). Each other rung is a mesh of the paper's slab (the committed ones, and larger
//! ones Gmsh writes into target/bench/run/ from cases/slab.geo), run with
//! the paper's scene (cases/martins-oden/cd-step-eps1e-4.toml and
//! newmark-step.toml): central difference for 1,000 steps at 0.9 of the
//! rung's critical step (from `stickslip check --json`), Newmark for 100
//! steps (20 from 200k DOFs, none from 1M) at 5x that step; the full fields
//! written at 11 records of the run (output.every), as a user of a long run
//! sets it. Each results file is removed after its run.
//!
//! The peers (`bench_peers.rs`, bench/README.md): each run is also made,
//! interleaved with ours, by a numpy/scipy process (bench/scipy_run.py:
//! scikit-fem's K and M, the same scheme in numpy) and a FEniCSx one
//! (bench/fenicsx_run.py: DOLFINx 0.11, Newton by PETSc SNES for Newmark),
//! each reading the case file and the mesh and writing its results file.
//! The FEniCSx peer is installed into a venv (target/bench/fenicsx) when
//! it is missing, saying so. Before anything is timed, one run of each
//! peer on each of its runs is compared with one of ours
//! (bench/peer_check.py: displacements at every common record, to 1e-8 of
//! the largest); a peer that differs stops the bench with an error. Both
//! run the rungs up to 260k DOFs, the FEniCSx one the structured ones only
//! (its row-sum lumped mass is HRZ's on rectangular cells only): the paper
//! mesh, q2-64x16, q1-128x32, q1-352x88, q2-352x88 and q1-708x177; the
//! 500k and the two 1M rungs (one unstructured, as the issue's whole-run
//! target names it) are ours alone. The table and the CSV give each
//! peer's median, its ratio to ours (peer / ours) and its agreement;
//! ours are run with `--json`, and a second table and the CSV's
//! `setup_s` and `setup_parts` give the median of each part of our setup
//! (mesh read, assembly, preload, critical step, operators, ...).
//! `--peers scipy,fenicsx` or `none` chooses them; by default both, and
//! none when `--against` compares another binary.
//!
//! Small runs are repeated: a run of ours of a few milliseconds is at the
//! mercy of the scheduler and of caches a shared host keeps evicting
//! (docs/performance.md, "Start-up and small runs"). Each run is made once untimed before the rounds (files
//! and the binary in the page cache), which also says how long it takes;
//! each round then makes it as many times as fill [`ROUND_SECONDS`] (at
//! most [`MAX_REPEATS`], at least once), ours and `--against`'s
//! alternately, each peer likewise by its checked run's time. The medians
//! are over every timed run; the CSV's `samples` column counts ours.
//!
//! With `--against EXE`, every run is also made with that binary (for
//! instance a build of an earlier commit), interleaved round by round, and
//! the table gives the ratio of the medians: a change measured run against
//! run on one machine at one time. A whole ladder (no --rungs, --only or
//! --max-dofs; at least 3 rounds) also writes docs/bench-run.csv, the
//! table the README quotes. `--against-env K=V` (repeatable) makes
//! the second runs with that environment (with this binary unless
//! `--against` names another).
//!
//!     cargo xtask bench run [--rounds N] [--max-dofs N] [--rungs NAME,...]
//!         [--against EXE] [--against-env K=V]... [--only cd|newmark]
//!         [--peers scipy,fenicsx|none]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Seconds of runs a round makes of each run, at least: a run of 20 ms is
/// made 25 times a round, one of 0.1 s 5 times, anything of 0.5 s or
/// more once.
const ROUND_SECONDS: f64 = 0.5;

/// The most times a round makes one run.
const MAX_REPEATS: usize = 25;

/// How many times a round makes a run that takes `secs`.
fn repeats(secs: f64) -> usize {
    if secs.is_finite() && secs > 0.0 {
        ((ROUND_SECONDS / secs).ceil() as usize).clamp(1, MAX_REPEATS)
    } else {
        1
    }
}

/// (name, mesh file relative to the root or a Gmsh rung, DOFs roughly).
struct Rung {
    name: &'static str,
    /// `None`: a committed mesh; `Some((order, nx, ny, structured))`: Gmsh.
    gmsh: Option<(u32, u32, u32, bool)>,
    committed: &'static str,
    dofs: u64,
    /// The paper's cases as they are shipped (their Δt, t_end and output).
    paper: bool,
}

impl Rung {
    /// Whether every cell is a rectangle (the committed slabs and Gmsh's
    /// structured ones).
    fn structured(&self) -> bool {
        self.gmsh.is_none_or(|g| g.3)
    }
}

const RUNGS: [Rung; 9] = [
    Rung {
        name: "paper q2-8x2",
        gmsh: None,
        committed: "cases/meshes/slab-q2-8x2.msh",
        dofs: 148,
        paper: true,
    },
    Rung {
        name: "q2-64x16",
        gmsh: None,
        committed: "cases/meshes/slab-q2-64x16.msh",
        dofs: 8_352,
        paper: false,
    },
    Rung {
        name: "q1-128x32",
        gmsh: None,
        committed: "cases/meshes/slab-q1-128x32.msh",
        dofs: 8_352,
        paper: false,
    },
    Rung {
        name: "q1-352x88",
        gmsh: Some((1, 352, 88, true)),
        committed: "",
        dofs: 62_392,
        paper: false,
    },
    Rung {
        name: "q2-352x88",
        gmsh: Some((2, 352, 88, true)),
        committed: "",
        dofs: 248_688,
        paper: false,
    },
    Rung {
        name: "q1-708x177",
        gmsh: Some((1, 708, 177, true)),
        committed: "",
        dofs: 251_517,
        paper: false,
    },
    Rung {
        name: "q1-unstructured-500k",
        gmsh: Some((1, 1315, 329, false)),
        committed: "",
        dofs: 500_000,
        paper: false,
    },
    Rung {
        name: "q1-unstructured-1m",
        gmsh: Some((1, 1860, 465, false)),
        committed: "",
        dofs: 1_000_000,
        paper: false,
    },
    Rung {
        name: "q1-1416x354",
        gmsh: Some((1, 1416, 354, true)),
        committed: "",
        dofs: 1_004_298,
        paper: false,
    },
];

/// Runs the ladder and prints the table.
///
/// # Errors
/// Bad arguments, a failing build, mesh or run.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let mut rounds = 3usize;
    let mut max_dofs = u64::MAX;
    let mut against: Option<PathBuf> = None;
    let mut only: Option<String> = None;
    let mut rungs: Option<Vec<String>> = None;
    let mut against_env: Vec<(String, String)> = Vec::new();
    let mut peer_names: Option<Vec<String>> = None;
    let usage = "[--rounds N] [--max-dofs N] [--rungs NAME,...] [--against EXE] [--against-env K=V]... [--only cd|newmark] [--peers scipy,fenicsx|none]";
    crate::bench::args("bench run", usage, args, |a, it| {
        match a {
            "--rounds" => rounds = crate::bench::integer_arg::<usize>(a, "a number", it)?.max(1),
            "--max-dofs" => max_dofs = crate::bench::integer_arg(a, "a number of DOFs", it)?,
            "--against" => {
                let p = it.next().ok_or("--against needs a stickslip binary")?;
                against = Some(std::fs::canonicalize(p).map_err(|e| format!("{p}: {e}"))?);
            }
            "--against-env" => {
                let kv = it.next().ok_or("--against-env needs KEY=VALUE")?;
                let (k, v) = kv
                    .split_once('=')
                    .ok_or_else(|| format!("--against-env {kv}: expected KEY=VALUE"))?;
                against_env.push((k.to_string(), v.to_string()));
            }
            "--rungs" => {
                let list = it.next().ok_or("--rungs needs names, comma-separated")?;
                let names: Vec<String> = list.split(',').map(str::to_string).collect();
                if let Some(bad) = names
                    .iter()
                    .find(|n| RUNGS.iter().all(|r| r.name != n.as_str()))
                {
                    let known: Vec<&str> = RUNGS.iter().map(|r| r.name).collect();
                    return Err(format!(
                        "--rungs: no rung named {bad:?}; the rungs are {}",
                        known.join(", ")
                    ));
                }
                rungs = Some(names);
            }
            "--only" => only = Some(it.next().ok_or("--only needs cd or newmark")?.clone()),
            "--peers" => {
                let list = it.next().ok_or("--peers needs scipy,fenicsx or none")?;
                peer_names = Some(if list == "none" {
                    Vec::new()
                } else {
                    list.split(',').map(str::to_string).collect()
                });
            }
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    let (exe, dir) = crate::bench::release_stickslip(root, "run")?;
    let mut exes = vec![exe.clone()];
    if against.is_some() || !against_env.is_empty() {
        exes.push(against.clone().unwrap_or_else(|| exe.clone()));
    }
    let compared = exes.len() == 2;
    // The peers by default when no other binary is compared.
    let peer_names = peer_names.unwrap_or_else(|| {
        if compared {
            Vec::new()
        } else {
            vec!["scipy".into(), "fenicsx".into()]
        }
    });
    let peers = crate::bench_peers::peers(root, &peer_names)?;

    let full = rungs.is_none() && only.is_none() && max_dofs == u64::MAX;
    // The runs: (label, case, sets, which peers run it).
    let mut runs: Vec<(String, &'static str, Vec<String>, Vec<bool>)> = Vec::new();
    let chosen = |r: &Rung| rungs.as_ref().is_none_or(|n| n.iter().any(|n| n == r.name));
    for rung in RUNGS.iter().filter(|r| r.dofs <= max_dofs && chosen(r)) {
        let mesh = match rung.gmsh {
            None => root.join(rung.committed),
            Some(g) => gmsh_mesh(root, &dir, rung.name, g)?,
        };
        let dt_crit = dt_crit(&exe, root, &mesh)?;
        let cd_dt = 0.9 * dt_crit;
        let mesh_set = format!("mesh.file={}", mesh.display());
        let fits: Vec<bool> = peers
            .iter()
            .map(|p| p.fits(rung.dofs, rung.structured()))
            .collect();
        if only.as_deref() != Some("newmark") {
            let steps = 1000.0;
            runs.push((
                format!("{} cd", rung.name),
                "cases/martins-oden/cd-step-eps1e-4.toml",
                if rung.paper {
                    Vec::new()
                } else {
                    vec![
                        mesh_set.clone(),
                        format!("time.dt={cd_dt:e}"),
                        format!("time.t_end={:e}", steps * cd_dt),
                        "output.every=100".into(),
                    ]
                },
                fits.clone(),
            ));
        }
        let nm_steps = match rung.dofs {
            d if d >= 1_000_000 => 0.0,
            d if d >= 200_000 => 20.0,
            _ => 100.0,
        };
        if nm_steps > 0.0 && only.as_deref() != Some("cd") {
            let dt = 5.0 * cd_dt;
            runs.push((
                format!("{} newmark", rung.name),
                "cases/martins-oden/newmark-step.toml",
                if rung.paper {
                    Vec::new()
                } else {
                    vec![
                        mesh_set,
                        format!("time.dt={dt:e}"),
                        format!("time.t_end={:e}", nm_steps * dt),
                        format!("output.every={}", (nm_steps as u64 / 10).max(1)),
                    ]
                },
                fits,
            ));
        }
    }
    let (checks, peer_secs) = check_peers(root, &exe, &dir, &peers, &runs)?;
    // Ours (and --against's) once each, untimed: warm caches, and the
    // time that sets the repeats.
    let run_exe = |r: usize, e: usize, case: &str, sets: &[String]| {
        let out = dir.join(format!("r{r}-e{e}.h5"));
        let mut cmd = Command::new(&exes[e]);
        if e == 1 {
            cmd.envs(against_env.iter().map(|(k, v)| (k, v)));
        }
        let flags = ["--quiet", "--force", "--json"];
        let result = crate::bench::timed_run(cmd, root, &flags, &out, case, sets);
        for ext in ["h5", "xdmf"] {
            let _ = std::fs::remove_file(out.with_extension(ext));
        }
        result
    };
    let mut repeats_of = Vec::with_capacity(runs.len());
    for (r, (_, case, sets, _)) in runs.iter().enumerate() {
        let mut ours = f64::NAN;
        for e in 0..exes.len() {
            let (o, secs) = run_exe(r, e, case, sets)?;
            if e == 0 && o.status.success() {
                ours = secs;
            }
        }
        let mut n = vec![repeats(ours); exes.len()];
        n.extend(peer_secs[r].iter().map(|&s| repeats(s)));
        repeats_of.push(n);
    }
    // times[run][exe, then peer]
    let mut times = vec![vec![Vec::new(); exes.len() + peers.len()]; runs.len()];
    // Our runs' setup parts, per run and round (the run's --json summary).
    let mut setups: Vec<Vec<Vec<(String, f64)>>> = vec![Vec::new(); runs.len()];
    for round in 0..rounds {
        eprintln!("bench run: round {} of {rounds}", round + 1);
        for (r, (label, case, sets, fits)) in runs.iter().enumerate() {
            for _ in 0..repeats_of[r][0] {
                for e in 0..exes.len() {
                    let (o, secs) = run_exe(r, e, case, sets)?;
                    if !o.status.success() {
                        // One failed run (a full disk, a shared host's hiccup)
                        // leaves the others' figures standing.
                        eprintln!(
                            "bench run: {label} ({}) failed, left out of its median: {}",
                            exes[e].display(),
                            String::from_utf8_lossy(&o.stderr).trim()
                        );
                        continue;
                    }
                    times[r][e].push(secs);
                    if e == 0 {
                        setups[r].push(setup_parts(&String::from_utf8_lossy(&o.stdout)));
                    }
                }
            }
            for (p, peer) in peers.iter().enumerate().filter(|(p, _)| fits[*p]) {
                for _ in 0..repeats_of[r][exes.len() + p] {
                    let out = dir.join(format!("r{r}-{}.h5", peer.name));
                    let (o, secs) = crate::bench::timed(peer.command(root, &out, case, sets))?;
                    let _ = std::fs::remove_file(&out);
                    if o.status.success() {
                        times[r][exes.len() + p].push(secs);
                    } else {
                        eprintln!(
                            "bench run: {label} ({} peer) failed, left out of its median: {}",
                            peer.name,
                            String::from_utf8_lossy(&o.stderr).trim()
                        );
                    }
                }
            }
        }
    }
    let median = |t: &mut Vec<f64>| {
        t.sort_by(f64::total_cmp);
        t.get(t.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let mut csv = String::from("run,median_s,fastest_s,rounds,samples,setup_s,setup_parts");
    if compared {
        csv.push_str(",against_median_s,ratio");
    }
    for peer in &peers {
        let p = peer.name;
        csv.push_str(&format!(",{p}_median_s,{p}_ratio,{p}_check"));
    }
    csv.push('\n');
    println!(
        "\nwall time of whole `stickslip run` processes (release), medians over {rounds} interleaved rounds \
         (short runs repeated within a round, `samples`):\n"
    );
    print!(
        "{:<32} {:>10} {:>10} {:>7}",
        "run", "median s", "fastest", "samples"
    );
    for peer in &peers {
        print!(" {:>12} {:>8}", format!("{} s", peer.name), "/ ours");
    }
    if compared {
        print!(" {:>12} {:>8}", "against s", "ratio");
        println!(
            "\n(against: {} {})",
            exes[1].display(),
            against_env
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
    } else {
        println!();
    }
    let mut setup_lines = Vec::new();
    let mut measured = Vec::with_capacity(runs.len());
    for (r, (label, _, _, fits)) in runs.iter().enumerate() {
        let m = median(&mut times[r][0]);
        let fastest = times[r][0].first().copied().unwrap_or(f64::NAN);
        let samples = times[r][0].len();
        print!("{label:<32} {m:>10.4} {fastest:>10.4} {samples:>7}");
        let parts = median_parts(&setups[r], median);
        let setup = parts
            .iter()
            .find(|(n, _)| n == "setup")
            .map_or(f64::NAN, |p| p.1);
        let listed: Vec<String> = parts
            .iter()
            .filter(|(n, _)| n != "setup")
            .map(|(n, s)| format!("{n}={s:.3}"))
            .collect();
        csv.push_str(&format!(
            "{label},{m:.5},{fastest:.5},{rounds},{samples},{setup:.4},{}",
            listed.join(";")
        ));
        setup_lines.push(format!("{label:<32} {setup:>8.3}  {}", listed.join(" ")));
        let (rung, scheme) = label.rsplit_once(' ').unwrap_or((label, ""));
        let mut run = crate::bench_targets::Measured {
            rung,
            scheme,
            dofs: RUNGS.iter().find(|g| g.name == rung).map_or(0, |g| g.dofs),
            median: m,
            setup,
            ratios: Vec::new(),
        };
        let mut peer_csv = String::new();
        for p in 0..peers.len() {
            if fits[p] {
                let mp = median(&mut times[r][exes.len() + p]);
                run.ratios.push((peers[p].name, mp / m));
                print!(" {mp:>12.4} {:>8.1}", mp / m);
                peer_csv.push_str(&format!(",{mp:.5},{:.2},{:.1e}", mp / m, checks[r][p]));
            } else {
                print!(" {:>12} {:>8}", "-", "-");
                peer_csv.push_str(",,,");
            }
        }
        if compared {
            let ma = median(&mut times[r][1]);
            print!(" {ma:>12.4} {:>8.3}", m / ma);
            csv.push_str(&format!(",{ma:.5},{:.4}", m / ma));
        }
        csv.push_str(&peer_csv);
        println!();
        csv.push('\n');
        measured.push(run);
    }
    println!("\nour setup (median s of each part over the rounds; the run's --json summary):\n");
    println!("{:<32} {:>8}  parts", "run", "setup s");
    for line in &setup_lines {
        println!("{line}");
    }
    let verdicts = crate::bench_targets::verdicts(&measured);
    if !verdicts.is_empty() {
        println!("\nthe whole-run targets this bench measured (bench_targets.rs):\n");
        for line in &verdicts {
            println!("{line}");
        }
        println!();
    }
    let path = root.join("target/bench/run.csv");
    std::fs::write(&path, &csv).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    // A whole ladder of both schemes is the table the docs quote.
    if full && rounds >= 3 {
        let docs = root.join("docs/bench-run.csv");
        std::fs::write(&docs, &csv).map_err(|e| format!("{}: {e}", docs.display()))?;
        println!("and {}", docs.display());
    }
    Ok(())
}

/// A figure per run and peer: `[run][peer]`.
type PerPeer = Vec<Vec<f64>>;

/// The setup of a run's `--json` summary: ("setup", setup_s), then each
/// of `setup_parts` (mesh_read, assembly, preload_factor, ...); empty
/// where the summary has none (an older binary).
fn setup_parts(stdout: &str) -> Vec<(String, f64)> {
    let number = |s: &str| -> Option<f64> {
        let end = s
            .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
            .unwrap_or(s.len());
        s[..end].parse().ok()
    };
    let mut out = Vec::new();
    let Some(setup) = stdout
        .find("\"setup_s\":")
        .and_then(|i| number(&stdout[i + 10..]))
    else {
        return out;
    };
    out.push(("setup".to_string(), setup));
    if let Some(i) = stdout.find("\"setup_parts\":{") {
        let body = &stdout[i + 15..];
        let body = &body[..body.find('}').unwrap_or(body.len())];
        for entry in body.split(',') {
            if let Some((k, v)) = entry.split_once(':') {
                if let Some(v) = number(v.trim()) {
                    out.push((k.trim().trim_matches('"').to_string(), v));
                }
            }
        }
    }
    out
}

/// Each part's median over the rounds, in the first round's order.
fn median_parts(
    rounds: &[Vec<(String, f64)>],
    median: impl Fn(&mut Vec<f64>) -> f64,
) -> Vec<(String, f64)> {
    let Some(first) = rounds.first() else {
        return Vec::new();
    };
    first
        .iter()
        .map(|(name, _)| {
            let mut v: Vec<f64> = rounds
                .iter()
                .filter_map(|r| r.iter().find(|(n, _)| n == name).map(|p| p.1))
                .collect();
            (name.clone(), median(&mut v))
        })
        .collect()
}

/// Each peer's agreement with stickslip on each run it makes
/// (`checks[run][peer]`, NaN where it does not run it), before anything is
/// timed: one run of each, their results files compared; and how long
/// that run of each peer took (NaN where none was made).
///
/// # Errors
/// A run that fails, or a peer that differs by more than 1e-8: the bench
/// stops there and says which.
fn check_peers(
    root: &Path,
    exe: &Path,
    dir: &Path,
    peers: &[crate::bench_peers::Peer],
    runs: &[(String, &'static str, Vec<String>, Vec<bool>)],
) -> Result<(PerPeer, PerPeer), String> {
    let mut checks = vec![vec![f64::NAN; peers.len()]; runs.len()];
    let mut secs = checks.clone();
    for (r, (label, case, sets, fits)) in runs.iter().enumerate() {
        if !fits.contains(&true) {
            continue;
        }
        let ours = dir.join(format!("check-r{r}.h5"));
        let flags = ["--quiet", "--force"];
        let (o, _) = crate::bench::timed_run(Command::new(exe), root, &flags, &ours, case, sets)?;
        if !o.status.success() {
            return Err(format!(
                "{label}: stickslip failed: {}",
                String::from_utf8_lossy(&o.stderr).trim()
            ));
        }
        for (p, peer) in peers.iter().enumerate().filter(|(p, _)| fits[*p]) {
            let theirs = dir.join(format!("check-r{r}-{}.h5", peer.name));
            let (o, took) = crate::bench::timed(peer.command(root, &theirs, case, sets))?;
            secs[r][p] = took;
            if !o.status.success() {
                return Err(format!(
                    "{label}: the {} peer failed: {}",
                    peer.name,
                    String::from_utf8_lossy(&o.stderr).trim()
                ));
            }
            let rel = crate::bench_peers::check(root, &ours, &theirs).map_err(|e| {
                format!(
                    "{label}: the {} peer disagrees with stickslip, so it is not timed: {e}",
                    peer.name
                )
            })?;
            eprintln!(
                "bench run: {label}: the {} peer agrees to {rel:.1e}",
                peer.name
            );
            checks[r][p] = rel;
            let _ = std::fs::remove_file(&theirs);
        }
        for ext in ["h5", "xdmf"] {
            let _ = std::fs::remove_file(ours.with_extension(ext));
        }
    }
    Ok((checks, secs))
}

/// The rung's mesh, written by Gmsh from cases/slab.geo unless it is there.
fn gmsh_mesh(
    root: &Path,
    dir: &Path,
    name: &str,
    (order, nx, ny, structured): (u32, u32, u32, bool),
) -> Result<PathBuf, String> {
    let out = dir.join(format!("{name}.msh"));
    if out.is_file() {
        return Ok(out);
    }
    crate::python::ensure_python_modules(&[("gmsh", "gmsh")])?;
    eprintln!("bench run: meshing {name} with Gmsh");
    let script = format!(
        "import gmsh, sys\n\
         gmsh.initialize(['', '-setnumber', 'nx', '{nx}', '-setnumber', 'ny', '{ny}', '-setnumber', 'structured', '{s}'])\n\
         gmsh.option.setNumber('General.Terminal', 0)\n\
         gmsh.open(sys.argv[1])\n\
         gmsh.model.mesh.generate(2)\n\
         gmsh.model.mesh.setOrder({order})\n\
         gmsh.option.setNumber('Mesh.Binary', 1)\n\
         gmsh.write(sys.argv[2])\n\
         gmsh.finalize()\n",
        s = u8::from(structured)
    );
    let status = Command::new(crate::python::python())
        .args(["-c", &script])
        .arg(root.join("cases/slab.geo"))
        .arg(&out)
        .status()
        .map_err(|e| format!("cannot start python: {e}"))?;
    if !status.success() {
        return Err(format!("Gmsh failed on {name} ({status})"));
    }
    Ok(out)
}

/// The central-difference critical step of the paper's scene on `mesh`,
/// as `stickslip check` prints it ("dt_crit     1.234567e-3 (...").
fn dt_crit(exe: &Path, root: &Path, mesh: &Path) -> Result<f64, String> {
    let o = Command::new(exe)
        .current_dir(root)
        .args(["check", "cases/martins-oden/cd-step-eps1e-4.toml"])
        .args(["--set", &format!("mesh.file={}", mesh.display())])
        .args(["--set", "time.allow_unstable=true"])
        .output()
        .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
    let text = String::from_utf8_lossy(&o.stdout);
    text.lines()
        .find_map(|l| l.strip_prefix("dt_crit"))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| {
            format!(
                "stickslip check printed no dt_crit:\n{text}{}",
                String::from_utf8_lossy(&o.stderr)
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The repeats a round makes: ⌈0.5 s / t⌉ between 1 and 25, so that a
    /// round spends at least half a second on a run where it can.
    #[test]
    fn short_runs_are_repeated_to_fill_half_a_second() {
        assert_eq!(repeats(0.012), 25); // ⌈41.7⌉, capped
        assert_eq!(repeats(0.021), 24); // ⌈23.8⌉
        assert_eq!(repeats(0.1), 5);
        assert_eq!(repeats(0.3), 2); // ⌈1.67⌉
        assert_eq!(repeats(0.5), 1);
        assert_eq!(repeats(8.0), 1);
        // No timed run (it failed, or no peer made one): once.
        assert_eq!(repeats(f64::NAN), 1);
    }

    /// The rungs each peer runs, as the module doc lists them.
    #[test]
    fn the_setup_parts_are_read_from_the_json_summary() {
        let stdout = r#"{"status":"complete","setup_parts":{"assembly":1.5,"mesh_read":0.25,"other":0.01},"setup_s":1.76,"step_s":0.0066}"#;
        assert_eq!(
            setup_parts(stdout),
            vec![
                ("setup".to_string(), 1.76),
                ("assembly".to_string(), 1.5),
                ("mesh_read".to_string(), 0.25),
                ("other".to_string(), 0.01)
            ]
        );
        assert!(setup_parts("not json").is_empty());
    }

    #[test]
    fn the_peers_run_the_rungs_the_doc_names() {
        let runs = |name| -> Vec<&str> {
            let peer = crate::bench_peers::installed(name);
            RUNGS
                .iter()
                .filter(|r| peer.fits(r.dofs, r.structured()))
                .map(|r| r.name)
                .collect()
        };
        let structured = [
            "paper q2-8x2",
            "q2-64x16",
            "q1-128x32",
            "q1-352x88",
            "q2-352x88",
            "q1-708x177",
        ];
        assert_eq!(runs("scipy"), structured);
        assert_eq!(runs("fenicsx"), structured);
    }
}
