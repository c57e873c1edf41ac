//! Time per step of both schemes on the slab ladder with what it is compared
//! with in the same run: STREAM triad bandwidth against the bytes one explicit
//! step moves; for Newmark the time of one forward+back solve with the factor
//! of A₀; the scipy peer (bench/peer.py, `--peer`) on the paper's 85-node mesh
//! and the generated rungs of ≥ 100k DOFs, which reads the problem this
//! process dumps (target/bench/peer/), assembles K and M on the dumped mesh
//! with scikit-fem and checks them against ours (≤ 1e-10), checks its state
//! after a few steps against ours (≤ 1e-8) and times its own steps; peak
//! memory: VmHWM of the whole process (`peak_rss`) and of the run after setup
//! (`peak_run`, VmHWM reset through clear_refs), each over what the run must
//! hold (`matrix_bytes` + `factor_bytes` + `vector_bytes`).
//!
//!     cargo run -p stickslip-time --example bench_step [-- --quick] [-- --max-dofs N] [-- --peer]
//!
//! Every rung runs in its own process (`--case NAME`) so that its peak RSS
//! (VmHWM) is the rung's; the parent prints a table and writes
//! target/bench/step.csv. Meshes: the committed slab ladder
//! (cases/meshes) and larger structured slabs built here in code.

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use stickslip_contact::ContactSurface;
use stickslip_fem::Model;
use stickslip_mesh::Mesh;
use stickslip_testkit::{meshes_dir, paper_material, structured_slab, workspace_root, Slab};
use stickslip_time::stability::critical_step;
use stickslip_time::{Dynamics, History, Integrator, Load, Scheme, Settings};

fn mesh_named(name: &str) -> Mesh {
    // "gen-q1-NXxNY" / "gen-q2-NXxNY" are built here; others are files.
    if let Some(rest) = name.strip_prefix("gen-") {
        let (order, size) = rest.split_once('-').expect("gen-qK-NXxNY");
        let (nx, ny) = size.split_once('x').expect("NXxNY");
        return structured_slab(nx.parse().unwrap(), ny.parse().unwrap(), order == "q2");
    }
    // A path to a .msh file (e.g. a Gmsh slab from generate.py
    // --bench-out); "gmsh-qK-NXxNY[-fileorder]": the Gmsh slab `cargo
    // xtask bench step` writes into target/bench/gmsh; else a committed
    // mesh by name.
    let path = if name.ends_with(".msh") {
        PathBuf::from(name)
    } else if let Some(rest) = name.strip_prefix("gmsh-") {
        gmsh_file(rest.trim_end_matches("-fileorder"))
    } else {
        meshes_dir().join(format!("{name}.msh"))
    };
    Mesh::from_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The Gmsh slab "qK-NXxNY" as `cargo xtask bench step` writes it
/// (generate.py --bench-out target/bench/gmsh: Gmsh's numbering and
/// coordinates, not snapped).
fn gmsh_file(size: &str) -> PathBuf {
    workspace_root()
        .join("target/bench/gmsh")
        .join(format!("slab-{size}-bin.msh"))
}

/// Gmsh's own Q2 slab of the 249k rung, in the node order the solver
/// picks (the grid's) and in the file's (`STICKSLIP_DOF_ORDER=mesh`): what
/// a user's mesh costs, beside the generator's slab.
const GMSH_RUNGS: [&str; 2] = ["gmsh-q2-352x88", "gmsh-q2-352x88-fileorder"];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A memory figure of this process from /proc/self/status ("VmHWM:" the
/// peak resident set, "VmRSS:" the current one), bytes.
fn status_bytes(key: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb * 1024.0)
}

/// Peak resident memory of this process (VmHWM), bytes.
fn peak_rss() -> f64 {
    status_bytes("VmHWM:")
}

/// Resets VmHWM to the current RSS (Linux clear_refs "5"), so that a later
/// [`peak_rss`] is the peak of what ran since. False if refused.
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Streams `v` as little-endian f64 through a small buffer (not a
/// whole-file buffer, tens of MB for K's columns from 250k DOFs).
fn write_f64(path: &std::path::Path, v: &[f64]) {
    write_le(path, v.iter().map(|x| x.to_le_bytes()));
}

fn write_i64(path: &std::path::Path, v: &[usize]) {
    write_le(path, v.iter().map(|&x| (x as i64).to_le_bytes()));
}

fn write_le(path: &std::path::Path, words: impl Iterator<Item = [u8; 8]>) {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for b in words {
        w.write_all(&b).unwrap();
    }
    w.flush().unwrap();
}

/// Writes what bench/peer.py needs into `dir`: K and M (CSR: row offsets,
/// column indices as little-endian i64, values as f64), the lumped mass,
/// the constant load, the loads with their histories, the contact nodes
/// (free DOFs, tangent, w·g) and the scheme's parameters (meta.json).
#[allow(clippy::too_many_arguments)]
fn dump_problem(
    dir: &std::path::Path,
    model: &Model,
    contact: &ContactSurface,
    loads: &[Load],
    scheme: &str,
    dt: f64,
    check_steps: usize,
) {
    std::fs::create_dir_all(dir).unwrap();
    let k = &model.stiffness;
    write_i64(&dir.join("indptr.i64"), k.row_offsets());
    write_i64(&dir.join("indices.i64"), k.col_indices());
    write_f64(&dir.join("k.f64"), k.values());
    let m = model.mass.as_ref().expect("Model::new assembles M");
    assert!(m.pattern() == k.pattern(), "M has K's pattern");
    write_f64(&dir.join("m.f64"), m.values());
    write_f64(&dir.join("lumped.f64"), &model.lumped_mass);
    write_f64(&dir.join("constant.f64"), &model.dirichlet_load);
    let mut histories = Vec::new();
    for (l, load) in loads.iter().enumerate() {
        write_f64(&dir.join(format!("load{l}.f64")), &load.vector);
        histories.push(match load.history {
            History::Constant => "\"constant\"",
            History::Step => "\"step\"",
            _ => panic!("the bench's loads are constant or step"),
        });
    }
    let dof = |d: Option<usize>| d.map_or(-1, |i| i as i64).to_string();
    let list = |f: &dyn Fn(&stickslip_contact::ContactNode) -> String| {
        contact.nodes.iter().map(f).collect::<Vec<_>>().join(",")
    };
    let json = format!(
        "{{\"scheme\": \"{scheme}\", \"n\": {}, \"nnz\": {}, \"dt\": {dt:e}, \"beta\": {}, \"gamma\": {}, \
         \"eps\": {:e}, \"check_steps\": {check_steps}, \"histories\": [{}], \
         \"contact_dof_x\": [{}], \"contact_dof_y\": [{}], \"contact_tx\": [{}], \"contact_ty\": [{}], \
         \"contact_wg\": [{}]}}\n",
        k.nrows(),
        k.nnz(),
        if scheme == "cd" { 0.0 } else { 0.25 },
        0.5,
        contact.law.eps,
        histories.join(", "),
        list(&|c| dof(c.dofs[0])),
        list(&|c| dof(c.dofs[1])),
        list(&|c| format!("{:e}", c.tangent[0])),
        list(&|c| format!("{:e}", c.tangent[1])),
        list(&|c| format!("{:e}", c.force_scale())),
    );
    std::fs::write(dir.join("meta.json"), json).unwrap();
}

/// Writes the mesh for bench/peer.py's own assembly (scikit-fem): node
/// coordinates (x, y per node), each cell's four corners (counter-clockwise;
/// a Q2 cell's other nodes are its edges' midpoints and its centre), our
/// free DOF of each full DOF 2·node + component (−1: fixed), and the
/// element order and material (mesh.json).
fn dump_mesh(dir: &std::path::Path, mesh: &Mesh, model: &Model) {
    std::fs::create_dir_all(dir).unwrap();
    write_f64(
        &dir.join("nodes.f64"),
        &mesh.nodes.iter().flatten().copied().collect::<Vec<_>>(),
    );
    let per = mesh.kind.nodes_per_cell();
    let corners: Vec<usize> = mesh
        .cells
        .chunks(per)
        .flat_map(|c| c[..4].to_vec())
        .collect();
    write_i64(&dir.join("cells.i64"), &corners);
    let free =
        (0..model.dofs.n_full()).map(|d| model.dofs.free_of_full(d).map_or(-1, |f| f as i64));
    write_le(&dir.join("free.i64"), free.map(i64::to_le_bytes));
    let m = paper_material();
    let order = if per == 9 { 2 } else { 1 };
    std::fs::write(
        dir.join("mesh.json"),
        format!(
            "{{\"order\": {order}, \"young\": {:e}, \"poisson\": {:e}, \"density\": {:e}, \"plane\": \"strain\"}}\n",
            m.youngs_modulus, m.poisson_ratio, m.density
        ),
    )
    .unwrap();
}

/// One STREAM triad a = b + s c on the rayon pool, bytes per second (3 ×
/// 8 bytes per entry, the STREAM convention).
fn triad(a: &mut [f64], b: &[f64], c: &[f64]) -> f64 {
    use rayon::prelude::*;
    let t = Instant::now();
    a.par_chunks_mut(65536)
        .zip(b.par_chunks(65536))
        .zip(c.par_chunks(65536))
        .for_each(|((a, b), c)| {
            for i in 0..a.len() {
                a[i] = b[i] + 3.0 * c[i];
            }
        });
    let bw = 24.0 * a.len() as f64 / t.elapsed().as_secs_f64();
    std::hint::black_box(&a);
    bw
}

/// The explicit step against STREAM in the same moments: `blocks` times the
/// best of three triads over 20M entries, then `steps` steps. A shared host's
/// STREAM switches between levels with its other tenants' work while our
/// step's bandwidth hardly moves (docs/performance.md), so a single STREAM
/// figure would decide the percentage. Returns the highest triad (what the
/// memory delivers when the host lets it: the `stream_bw` the percentage is
/// taken of), the median triad and the median over the blocks of the step's
/// bandwidth over the triad just before it.
fn paired_stream(i: &mut Integrator, bytes: f64, steps: usize, blocks: usize) -> (f64, f64, f64) {
    let n = 20_000_000;
    let (mut a, b, c) = (vec![0.0_f64; n], vec![1.0_f64; n], vec![2.0_f64; n]);
    let (mut triads, mut ratios) = (Vec::new(), Vec::new());
    for _ in 0..blocks {
        let bw = (0..3).map(|_| triad(&mut a, &b, &c)).fold(0.0, f64::max);
        let t = Instant::now();
        for _ in 0..steps {
            i.step().unwrap();
        }
        let step = t.elapsed().as_secs_f64() / steps as f64;
        triads.push(bw);
        ratios.push(bytes / step / bw);
    }
    let max = triads.iter().copied().fold(0.0, f64::max);
    (max, median(triads), median(ratios))
}

/// One rung: prints a RESULT line. With `dump`, first writes the problem
/// and the state after a few steps for bench/peer.py.
fn run_case(scheme: &str, name: &str, steps: usize, repeats: usize, dump: Option<PathBuf>) {
    // The process before any of the run's data: code, libraries, the
    // runtime, which the run's own figure leaves out.
    let rss_base = status_bytes("VmRSS:");
    let t_setup = Instant::now();
    let Slab {
        mesh,
        model,
        contact,
        loads,
    } = Slab::paper(mesh_named(name), 1e-4, History::Step, true).unwrap();
    let contact = contact.expect("the paper's slab has friction");
    let explicit = scheme == "cd";
    if let Some(dir) = &dump {
        dump_mesh(dir, &mesh, &model);
    }
    drop(mesh);
    let n = model.dofs.n_free();
    let nnz = model.stiffness.nnz();
    let n_c = contact.len();
    let newmark_dt = 5e-3;
    // Long enough on small meshes for nodes to slip (the friction branches
    // are then part of the check); a few steps on large ones.
    let check_steps = if n < 50_000 { 2000 } else { 10 };
    // Newmark's hardware figure first, so that its matrix and factor are
    // gone before the run (the run's peak is the run's).
    let solve = if explicit {
        None
    } else {
        // One forward+back solve with a factor of A₀ (fem's wrapper: the
        // same ordering, the model's, and faer supernodal Cholesky as the
        // step's).
        let a0 = model.combined(0.5 * newmark_dt, 1.0 / (0.5 * newmark_dt));
        let mut chol = stickslip_linalg::SparseCholesky::analyze(&a0, &model.fill_order).unwrap();
        chol.factorize(&a0).unwrap();
        let mut x = vec![1.0; n];
        let mut times = Vec::new();
        for _ in 0..repeats.max(5) {
            x.fill(1.0);
            let t = Instant::now();
            chol.solve_in_place(&mut x);
            times.push(t.elapsed().as_secs_f64());
        }
        Some(median(times))
    };
    let dt = if explicit {
        0.9 * critical_step(&model.stiffness, &model.lumped_mass)
    } else {
        newmark_dt
    };
    if let Some(dir) = &dump {
        dump_problem(dir, &model, &contact, &loads, scheme, dt, check_steps);
    }
    // The model's matrices move into the integrator: one copy of K and M.
    // STICKSLIP_NO_STENCILS set: K (and M) as the mesh allows without
    // stencil types (the comparison).
    let dynamics = Dynamics::from_model_owned(model)
        .with_stencils(std::env::var_os("STICKSLIP_NO_STENCILS").is_none());
    let settings = if explicit {
        Settings::new(Scheme::CentralDifference, dt, 1e9)
    } else {
        Settings::new(
            Scheme::Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
            dt,
            1e9,
        )
    };
    let pool = rayon::ThreadPoolBuilder::new().build().unwrap();
    let mut i = pool.install(|| Integrator::new(dynamics, Some(contact), loads, settings).unwrap());
    let setup = t_setup.elapsed().as_secs_f64();
    let peak_setup = peak_rss();
    let reset = reset_peak_rss();
    let rss_start = status_bytes("VmRSS:");
    let run = |i: &mut Integrator, k: usize| {
        for _ in 0..k {
            i.step().unwrap();
        }
    };
    if let Some(dir) = &dump {
        // The peer starts from the same initial state (Remark 4.1) and
        // checks its state after a few steps against ours.
        write_f64(&dir.join("r0.f64"), i.displacement());
        write_f64(&dir.join("v0.f64"), i.velocity());
        write_f64(&dir.join("a0.f64"), i.acceleration());
        // The most nodes slipping at once during the check steps.
        let slipping = pool.install(|| {
            let mut most = 0;
            for _ in 0..check_steps {
                i.step().unwrap();
                most = most.max(i.classes().iter().filter(|c| !c.is_stuck()).count());
            }
            most
        });
        write_f64(&dir.join("r_check.f64"), i.displacement());
        write_f64(&dir.join("v_check.f64"), i.velocity());
        std::fs::write(
            dir.join("check.json"),
            format!("{{\"slipping\": {slipping}}}\n"),
        )
        .unwrap();
        // The timed run is another process, without the dump: a process
        // that has written it may start the run holding several MB more,
        // which its peak would count (docs/performance.md).
        return;
    }
    // Warm-up: the thread pool and the factor of the normal Δt.
    let per_step = pool.install(|| {
        let t = Instant::now();
        run(&mut i, 2);
        let first = t.elapsed().as_secs_f64();
        let mut times = Vec::new();
        for _ in 0..repeats {
            let t = Instant::now();
            run(&mut i, steps);
            times.push(t.elapsed().as_secs_f64() / steps as f64);
        }
        (median(times), first)
    });
    let slipping = i.classes().iter().filter(|c| !c.is_stuck()).count();
    // Before the STREAM arrays exist.
    let peak_run = if reset { peak_rss() } else { f64::NAN };
    let peak = peak_rss().max(peak_setup);
    // What the run must hold: the matrices it streams or factorizes, the
    // factor, and the integrator's free-DOF vectors (r, ṙ, r̈, R and their
    // new values, b, two scratch, the lumped mass, the constant load, the
    // bench's two loads: 14 of n f64; explicit: the next predictor, 15).
    let vectors = if explicit { 15.0 } else { 14.0 } * 8.0 * n as f64;
    let csr = 16.0 * nnz as f64 + 8.0 * (n + 1) as f64;
    let (matrix, factor) = if explicit {
        (i.explicit_matrix_bytes() as f64, 0.0)
    } else {
        // K and M (each a CSR with its own pattern), A₀'s values while it
        // is factorized (on K's pattern), the factor's values.
        (2.0 * csr + 8.0 * nnz as f64, 8.0 * i.factor_len() as f64)
    };
    let need = matrix + factor + vectors;
    let memory = format!(
        "peak_rss={peak:.0} peak_run={peak_run:.0} rss_start={rss_start:.0} rss_base={rss_base:.0} matrix_bytes={matrix:.0} \
         factor_bytes={factor:.0} vector_bytes={vectors:.0} peak_run_over_need={:.3} run_own_over_need={:.3} peak_over_need={:.3}",
        peak_run / need,
        (peak_run - rss_base) / need,
        peak / need
    );
    let extra = if explicit {
        // Bytes a step must move (Integrator::explicit_bytes_per_step).
        let bytes = i.explicit_bytes_per_step() as f64;
        let (bw, bw_median, paired) = pool.install(|| paired_stream(&mut i, bytes, steps, 9));
        let stencils = i.explicit_stencils().unwrap_or(0);
        format!(
            "stencil_types={stencils} bytes_per_step={bytes:.0} stream_bw={bw:.4e} step_bw={:.4e} pct_stream={:.1} stream_bw_median={bw_median:.4e} pct_stream_paired={:.1}",
            bytes / per_step.0,
            100.0 * bytes / per_step.0 / bw,
            100.0 * paired
        )
    } else {
        let solve = solve.expect("timed above");
        format!(
            "solve={solve:.4e} step_over_solve={:.2} factor_len={} factorizations={} w_len={} reach_len={}",
            per_step.0 / solve,
            i.factor_len(),
            i.factorizations(),
            i.paths_len().0,
            i.paths_len().1
        )
    };
    println!(
        "RESULT scheme={scheme} mesh={name} dofs={n} nnz={nnz} contact_nodes={n_c} steps={steps} repeats={repeats} \
         step={:.4e} first2={:.4e} setup={setup:.3e} slipping={slipping} {memory} {extra}",
        per_step.0, per_step.1,
    );
}

/// Pairs of ours and the peer's timings on the rungs below 1000 DOFs
/// (the first pair is the row's own `step` and `peer_step`).
const PAIRS: usize = 5;

/// Rungs the scipy peer runs on (both schemes where the ladder has them):
/// the paper's 85-node mesh and the generated rungs of ≥ 100k DOFs up to
/// 1M (Q1 and Q2).
const PEER_MESHES: [&str; 6] = [
    "slab-q2-8x2",
    "gen-q1-708x177",
    "gen-q1-1416x354",
    "gen-q2-352x88",
    "gen-q2-500x125",
    "gen-q2-708x177",
];

/// A value of a `key=value` row.
fn field(row: &str, key: &str) -> Option<f64> {
    text(row, key)?.parse().ok()
}

/// A row's text field (`scheme`, `mesh`).
fn text<'a>(row: &'a str, key: &str) -> Option<&'a str> {
    row.split_whitespace()
        .find_map(|kv| kv.strip_prefix(key)?.strip_prefix('='))
}

/// The bench's targets (README, "Speed per step") against this run's
/// rows, each with its figures and a verdict for this run alone (one run
/// meeting a target does not make it met on a shared host: the README
/// weighs the runs).
fn print_targets(rows: &[String]) {
    let verdict = |ok: bool| if ok { "met" } else { "NOT met" };
    let of = |scheme: &str| {
        rows.iter()
            .filter(move |r| text(r, "scheme") == Some(scheme))
            .collect::<Vec<_>>()
    };
    let (cd, newmark) = (of("cd"), of("newmark"));
    let dofs = |r: &&String| field(r, "dofs").unwrap_or(0.0);
    println!("targets in this run:");
    // The largest explicit rungs (the 1M slabs), against the run's highest
    // triad.
    let largest = cd.iter().map(dofs).fold(0.0, f64::max);
    let top: Vec<(&str, f64)> = cd
        .iter()
        .filter(|r| dofs(r) == largest)
        .filter_map(|r| Some((text(r, "mesh")?, field(r, "pct_stream_run")?)))
        .collect();
    if !top.is_empty() {
        let figures: Vec<String> = top.iter().map(|(m, p)| format!("{m} {p:.1}%")).collect();
        println!(
            "  explicit step >= 50% of the run's highest STREAM triad on the largest mesh: {} -- {}",
            figures.join(", "),
            verdict(top.iter().all(|(_, p)| *p >= 50.0))
        );
    }
    if let Some(step) = cd
        .iter()
        .find(|r| text(r, "mesh") == Some("gen-q1-1416x354"))
        .and_then(|r| field(r, "step"))
    {
        println!(
            "  1000 steps of the 1M-DOF Q1 slab under 30 s: {:.2} s -- {}",
            1000.0 * step,
            verdict(1000.0 * step < 30.0)
        );
    }
    // A quantity over the rungs of 100k DOFs and more.
    let large = |rs: &[&String], value: &dyn Fn(&str) -> Option<f64>| -> Vec<f64> {
        rs.iter()
            .filter(|r| dofs(r) >= 1e5)
            .filter_map(|r| value(r))
            .collect()
    };
    let most = |v: Vec<f64>| (!v.is_empty()).then(|| v.into_iter().fold(0.0, f64::max));
    let least = |v: Vec<f64>| (!v.is_empty()).then(|| v.into_iter().fold(f64::INFINITY, f64::min));
    let worst = |rs: &[&String], key: &str| most(large(rs, &|r| field(r, key)));
    if let Some(w) = worst(&newmark, "step_over_solve") {
        println!(
            "  Newmark step <= 2.5 forward+back solves from 100k DOFs: at most {w:.2} -- {}",
            verdict(w <= 2.5)
        );
    }
    // From the times, not the rounded ratio column.
    let ratio = |rs: &[&String]| {
        least(large(rs, &|r| {
            Some(field(r, "peer_step")? / field(r, "step")?)
        }))
    };
    if let (Some(c), Some(n)) = (ratio(&cd), ratio(&newmark)) {
        println!(
            "  >= 5x the scipy peer per step from 100k DOFs: central difference at least {c:.2}x, Newmark at least {n:.2}x -- {}",
            verdict(c >= 5.0 && n >= 5.0)
        );
    }
    let paper: Vec<String> = [("central difference", &cd), ("Newmark", &newmark)]
        .iter()
        .filter_map(|(name, rs)| {
            let r = rs
                .iter()
                .find(|r| dofs(r) < 1000.0 && field(r, "peer_over_ours").is_some())?;
            Some((
                name,
                field(r, "peer_over_ours")?,
                field(r, "peer_over_ours_paired").unwrap_or(f64::NAN),
            ))
        })
        .map(|(name, first, paired)| {
            format!(
                "{name} {first:.1}x (median of the pairs {paired:.2}x) -- {}",
                verdict(paired >= 50.0)
            )
        })
        .collect();
    if !paper.is_empty() {
        println!("  >= 50x the peer on the paper mesh: {}", paper.join("; "));
    }
    let all: Vec<&String> = cd.iter().chain(&newmark).copied().collect();
    if let Some(w) = worst(&all, "peak_run_over_need") {
        println!(
            "  peak memory of the run <= 1.5x matrix + factor + vectors from 100k DOFs: at most {w:.2} -- {}",
            verdict(w <= 1.5)
        );
    }
}

/// Runs bench/peer.py on a dumped rung; returns " peer_step=… peer_over_ours=…
/// peer_check=…" (or " peer=failed"). Large rungs take fewer peer steps:
/// scipy's step is slow enough that a few give a stable median.
fn run_peer(
    root: &std::path::Path,
    dir: &std::path::Path,
    row: &str,
    scheme: &str,
    steps: usize,
    repeats: usize,
) -> String {
    let big = field(row, "dofs").unwrap_or(0.0) > 50_000.0;
    let steps = match (big, scheme) {
        (false, _) => steps,
        (true, "cd") => 20,
        (true, _) => 5,
    };
    match peer_fields(root, dir, steps, repeats) {
        Some(fields) => {
            let ours = field(row, "step").unwrap_or(f64::NAN);
            let theirs = field(&fields, "peer_step").unwrap_or(f64::NAN);
            format!(" {fields} peer_over_ours={:.1}", theirs / ours)
        }
        None => " peer=failed".into(),
    }
}

/// The fields of the peer's `PEER` line for the problem dumped in `dir`
/// (`None`, said on stderr, if it fails).
fn peer_fields(
    root: &std::path::Path,
    dir: &std::path::Path,
    steps: usize,
    repeats: usize,
) -> Option<String> {
    let python = std::env::var("PYTHON")
        .ok()
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "python3".into());
    let out = Command::new(&python)
        .arg(root.join("bench/peer.py"))
        .arg(dir)
        .args([
            "--steps",
            &steps.to_string(),
            "--repeats",
            &repeats.min(5).to_string(),
        ])
        .output();
    let out = match out {
        Ok(o) => o,
        Err(e) => {
            eprintln!("peer: cannot run {python}: {e}");
            return None;
        }
    };
    let text = String::from_utf8_lossy(&out.stdout);
    match text.lines().find(|l| l.starts_with("PEER ")) {
        Some(l) if out.status.success() => Some(l.trim_start_matches("PEER ").to_string()),
        _ => {
            eprintln!(
                "peer on {}: failed:\n{}{}",
                dir.display(),
                text,
                String::from_utf8_lossy(&out.stderr)
            );
            None
        }
    }
}

/// What `--help` prints, and an unknown argument with it.
const USAGE: &str = "usage: bench_step [--quick] [--peer] [--max-dofs N]   the whole ladder
       bench_step --case cd|newmark MESH STEPS REPEATS [--dump DIR]   one rung
       bench_step --targets CSV   the targets of a run already written
MESH: gen-q1-NXxNY, gen-q2-NXxNY (built here), gmsh-qK-NXxNY[-fileorder],
a .msh path, or a committed mesh's name (cases/meshes)";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--help" || a == "-h") {
        println!("{USAGE}");
        return;
    }
    let fail = |what: String| -> ! {
        eprintln!("bench_step: {what}\n{USAGE}");
        std::process::exit(2);
    };
    // The targets of a run already written (docs/bench-step.csv).
    if let Some(k) = args.iter().position(|a| a == "--targets") {
        let Some(path) = args.get(k + 1) else {
            eprintln!("--targets needs the CSV a bench run wrote (docs/bench-step.csv)");
            std::process::exit(2);
        };
        let csv = match std::fs::read_to_string(path) {
            Ok(csv) => csv,
            Err(e) => {
                eprintln!("{path}: {e}");
                std::process::exit(2);
            }
        };
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let rows: Vec<String> = lines
            .map(|l| {
                header
                    .iter()
                    .zip(l.split(','))
                    .filter(|(_, v)| !v.is_empty())
                    .map(|(h, v)| format!("{h}={v}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect();
        print_targets(&rows);
        return;
    }
    if let Some(k) = args.iter().position(|a| a == "--case") {
        let [scheme, name, steps, repeats] = std::array::from_fn(|j| args.get(k + 1 + j));
        let (Some(scheme), Some(name), Some(steps), Some(repeats)) = (scheme, name, steps, repeats)
        else {
            fail("--case needs a scheme, a mesh, steps and repeats".into())
        };
        if scheme != "cd" && scheme != "newmark" {
            fail(format!("--case {scheme}: the scheme is cd or newmark"));
        }
        let count = |what: &str, v: &str| -> usize {
            match v.parse() {
                Ok(n) if n > 0 => n,
                _ => fail(format!("{what} {v:?}: expected a whole number above 0")),
            }
        };
        let (steps, repeats) = (count("steps", steps), count("repeats", repeats));
        let dump = args
            .iter()
            .position(|a| a == "--dump")
            .map(|k| PathBuf::from(&args[k + 1]));
        run_case(scheme, name, steps, repeats, dump);
        return;
    }
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--quick" | "--peer" => {}
            "--max-dofs" => match rest.next().map(|v| v.parse::<f64>()) {
                Some(Ok(v)) if v > 0.0 => {}
                _ => fail("--max-dofs needs a number of DOFs above 0".into()),
            },
            other => fail(format!("unknown argument {other:?}")),
        }
    }
    let quick = args.iter().any(|a| a == "--quick");
    let peer = args.iter().any(|a| a == "--peer");
    let max_dofs: f64 = args
        .iter()
        .position(|a| a == "--max-dofs")
        .and_then(|k| args.get(k + 1)?.parse().ok())
        .unwrap_or(f64::INFINITY);
    // (scheme, mesh, approximate DOFs, steps per repeat, repeats)
    let mut ladder: Vec<(&str, String, f64, usize, usize)> = Vec::new();
    for m in [
        "slab-q2-8x2",
        "slab-q1-32x8",
        "slab-q1-128x32",
        "slab-q2-64x16",
    ] {
        // At least ~0.1 s per repeat: a repeat of a few ms overstates the
        // paper mesh's explicit step while the core's clock and caches
        // settle (docs/performance.md); the peer runs as many steps.
        let (cd, newmark) = if m == "slab-q2-8x2" || m == "slab-q1-32x8" {
            (50_000, 5_000)
        } else {
            (2000, 200)
        };
        ladder.push(("cd", m.into(), 0.0, cd, 5));
        ladder.push(("newmark", m.into(), 0.0, newmark, 5));
    }
    // Generated: Q1 nx = 4 ny; DOFs ≈ 2(nx+1)(ny+1).
    for (ny, q2) in [
        (88, false),
        (177, false),
        (354, false),
        (44, true),
        (88, true),
        (125, true),
        (177, true),
    ] {
        let nx = 4 * ny;
        let q = if q2 { 2 } else { 1 };
        let dofs = 2.0 * ((q * nx + 1) * (q * ny + 1)) as f64;
        let name = format!("gen-q{}-{nx}x{ny}", q);
        ladder.push(("cd", name.clone(), dofs, if quick { 20 } else { 100 }, 5));
        if dofs <= 300_000.0 {
            ladder.push(("newmark", name, dofs, if quick { 3 } else { 10 }, 5));
        }
    }
    if gmsh_file("q2-352x88").exists() {
        for name in GMSH_RUNGS {
            let dofs = 248_688.0;
            ladder.push(("cd", name.into(), dofs, if quick { 20 } else { 100 }, 5));
            ladder.push(("newmark", name.into(), dofs, if quick { 3 } else { 10 }, 5));
        }
    } else {
        eprintln!(
            "no Gmsh slab at {}: its rungs are left out (cargo xtask bench step writes it)",
            gmsh_file("q2-352x88").display()
        );
    }
    let exe = std::env::current_exe().unwrap();
    let root = workspace_root();
    let dir = root.join("target/bench");
    let mut rows = Vec::new();
    for (scheme, name, dofs, steps, repeats) in ladder {
        if dofs > max_dofs {
            continue;
        }
        let steps = if quick { steps.min(200) } else { steps };
        // The scipy peer (bench/peer.py) on the paper's 85-node mesh and the
        // generated rungs of ≥ 100k DOFs: it reads the problem our process
        // dumps, checks its state after a few steps against ours
        // (1e-8) and times its own steps, after ours (not concurrently).
        let peer_dir = (peer && PEER_MESHES.contains(&name.as_str()))
            .then(|| dir.join("peer").join(format!("{scheme}-{name}")));
        let mut cmd = Command::new(&exe);
        cmd.args([
            "--case",
            scheme,
            &name,
            &steps.to_string(),
            &repeats.to_string(),
        ]);
        if name.ends_with("-fileorder") {
            cmd.env("STICKSLIP_DOF_ORDER", "mesh");
        }
        if let Some(d) = &peer_dir {
            // The problem and our state for the peer, in a process of its
            // own (run_case: the timed process then writes nothing).
            let dumped = Command::new(&exe)
                .args([
                    "--case",
                    scheme,
                    &name,
                    &steps.to_string(),
                    &repeats.to_string(),
                ])
                .arg("--dump")
                .arg(d)
                .envs(cmd.get_envs().filter_map(|(k, v)| Some((k, v?))))
                .output()
                .expect("runs itself");
            if !dumped.status.success() {
                eprintln!(
                    "{scheme} {name}: the peer's dump failed: {}",
                    String::from_utf8_lossy(&dumped.stderr)
                );
            }
        }
        let out = cmd.output().expect("runs itself");
        let text = String::from_utf8_lossy(&out.stdout);
        let Some(line) = text.lines().find(|l| l.starts_with("RESULT ")) else {
            eprintln!(
                "{scheme} {name}: failed: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            continue;
        };
        let mut row = line.trim_start_matches("RESULT ").to_string();
        if let Some(d) = &peer_dir {
            row.push_str(&run_peer(&root, d, &row, scheme, steps, repeats));
            // The paper mesh's step is so short that the host's other work
            // slows whole repeats of it for seconds at a time: there ours
            // and the peer's are also timed in alternating pairs, and the
            // ratio given per pair.
            if let (Some(ours), Some(theirs)) = (field(&row, "step"), field(&row, "peer_step")) {
                if field(&row, "dofs").unwrap_or(f64::INFINITY) < 1000.0 {
                    let mut ratios = vec![theirs / ours];
                    for _ in 1..PAIRS {
                        let ours = cmd.output().ok().and_then(|o| {
                            let text = String::from_utf8_lossy(&o.stdout).into_owned();
                            let line = text.lines().find(|l| l.starts_with("RESULT "))?;
                            field(line, "step")
                        });
                        let theirs = peer_fields(&root, d, steps, repeats)
                            .and_then(|f| field(&f, "peer_step"));
                        if let (Some(ours), Some(theirs)) = (ours, theirs) {
                            ratios.push(theirs / ours);
                        }
                    }
                    let text: Vec<String> = ratios.iter().map(|r| format!("{r:.1}")).collect();
                    println!(
                        "{scheme} {name}: peer over ours in {} pairs: {}",
                        ratios.len(),
                        text.join(", ")
                    );
                    row.push_str(&format!(
                        " peer_over_ours_pairs={} peer_over_ours_paired={:.2}",
                        ratios.len(),
                        median(ratios)
                    ));
                }
            }
        }
        println!("{row}");
        rows.push(row);
    }
    // The highest triad of the whole run, what the memory delivered when
    // the host let it: a rung's own nine blocks may all fall in a busy
    // spell (docs/performance.md), so each explicit rung's bandwidth is
    // also given as a share of this.
    let run_max = rows
        .iter()
        .filter_map(|r| field(r, "stream_bw"))
        .fold(0.0, f64::max);
    if run_max > 0.0 {
        println!(
            "highest STREAM triad of the run: {:.1} GB/s; explicit rungs against it:",
            run_max / 1e9
        );
        for row in &mut rows {
            if let Some(bw) = field(row, "step_bw") {
                let pct = 100.0 * bw / run_max;
                row.push_str(&format!(
                    " stream_bw_run={run_max:.4e} pct_stream_run={pct:.1}"
                ));
                let name = row
                    .split_whitespace()
                    .nth(1)
                    .unwrap_or("")
                    .trim_start_matches("mesh=");
                println!("  {name}: {:.1} GB/s, {pct:.1}%", bw / 1e9);
            }
        }
    }
    print_targets(&rows);
    std::fs::create_dir_all(&dir).unwrap();
    let mut csv = String::new();
    let mut header: Vec<String> = Vec::new();
    for row in &rows {
        for kv in row.split_whitespace() {
            let k = kv.split('=').next().unwrap().to_string();
            if !header.contains(&k) {
                header.push(k);
            }
        }
    }
    csv.push_str(&header.join(","));
    csv.push('\n');
    for row in &rows {
        let line: Vec<&str> = header
            .iter()
            .map(|h| {
                row.split_whitespace()
                    .find_map(|kv| kv.strip_prefix(&format!("{h}=")))
                    .unwrap_or("")
            })
            .collect();
        csv.push_str(&line.join(","));
        csv.push('\n');
    }
    let path = dir.join("step.csv");
    std::fs::write(&path, csv).unwrap();
    println!("wrote {}", path.display());
}
