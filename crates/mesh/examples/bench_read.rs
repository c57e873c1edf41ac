//! Read-speed and memory benchmark of the .msh reader, driven by `cargo
//! xtask bench mesh`, usable alone:
//!
//! ```text
//! cargo run -p stickslip-mesh --example bench_read -- FILE.msh [RUNS]
//! ```
//!
//! Times `Mesh::from_file` (file read from the page cache + parse + checks)
//! RUNS times (default 5) and prints the median and MB/s, then the medians
//! of `std::fs::read` alone and of `Mesh::from_bytes` alone. Memory: the peak
//! resident set (`VmHWM` of /proc/self/status) during one read, above the
//! resident set before it, compared with the `Mesh`'s own size estimated from
//! its Vec lengths. That peak includes whatever `from_file` holds while
//! parsing (its read window of 1 MiB, the builder's side tables); it is
//! reported as is, not netted out.
//! CPU time per read (user + system) is printed too, as the figure least
//! disturbed by other processes on a shared machine.
//! The last line is `RESULT key=value …` for xtask to parse.

use std::process::ExitCode;
use std::time::Instant;

use stickslip_mesh::{Edge, Group, Mesh};

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: bench_read FILE.msh [RUNS]");
        return ExitCode::from(2);
    };
    let runs: usize = match args.next().map(|s| s.parse()) {
        None => 5,
        Some(Ok(n)) if n > 0 => n,
        Some(_) => {
            eprintln!("RUNS must be a positive integer");
            return ExitCode::from(2);
        }
    };
    let file_bytes = match std::fs::metadata(&path) {
        Ok(m) => m.len(),
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };

    // Memory: one read with the peak counter reset just before it.
    let hwm_reset = reset_peak_rss();
    let rss_before = proc_status_kib("VmRSS");
    let mesh = match Mesh::from_file(&path) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let hwm = proc_status_kib("VmHWM");
    let mesh_bytes = mesh_size_bytes(&mesh);
    println!(
        "{path}: MSH {} {}, {} nodes, {} {} cells, {} groups, {} cells re-oriented",
        mesh.source.version,
        if mesh.source.binary {
            "binary"
        } else {
            "ASCII"
        },
        mesh.nodes.len(),
        mesh.n_cells(),
        mesh.kind.name(),
        mesh.groups.len(),
        mesh.source.reoriented
    );
    drop(mesh);

    // Speed: median of `runs` reads (the first read above warmed the page cache).
    let mut times = Vec::with_capacity(runs);
    let cpu0 = proc_cpu_seconds();
    for _ in 0..runs {
        let t = Instant::now();
        let m = Mesh::from_file(&path);
        let dt = t.elapsed().as_secs_f64();
        if let Err(e) = m {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
        drop(m);
        times.push(dt);
    }
    // CPU time (user + system) per read: less sensitive than wall time to
    // other processes on a shared machine (10 ms ticks, averaged over RUNS).
    let cpu_s = match (cpu0, proc_cpu_seconds()) {
        (Some(a), Some(b)) => (b - a) / runs as f64,
        _ => f64::NAN,
    };
    let median = median_of(&mut times);
    let mbps = file_bytes as f64 / 1e6 / median;

    // Where the time goes: the file read alone, and parse + checks alone
    // (`from_bytes` on bytes already in memory).
    let mut read_times = Vec::with_capacity(runs);
    let mut parse_times = Vec::with_capacity(runs);
    for _ in 0..runs {
        let t = Instant::now();
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("{path}: {e}");
                return ExitCode::FAILURE;
            }
        };
        read_times.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        let m = Mesh::from_bytes(&bytes);
        parse_times.push(t.elapsed().as_secs_f64());
        drop(m);
    }
    let read_median = median_of(&mut read_times);
    let parse_median = median_of(&mut parse_times);

    println!("file size        {:>10.1} MB", file_bytes as f64 / 1e6);
    println!(
        "read (median/{runs})  {:>10.3} s   ({:.3} .. {:.3} s)",
        median,
        times[0],
        times[times.len() - 1]
    );
    println!("throughput       {mbps:>10.1} MB/s");
    println!(
        "CPU per read     {cpu_s:>10.3} s   (user + system, mean of {runs}; {:.1} MB per CPU-second)",
        file_bytes as f64 / 1e6 / cpu_s
    );
    println!(
        "  of which        {read_median:>10.3} s std::fs::read, {parse_median:.3} s Mesh::from_bytes ({:.1} MB/s) (medians)",
        file_bytes as f64 / 1e6 / parse_median
    );
    println!(
        "Mesh size        {:>10.1} MB (from Vec lengths)",
        mesh_bytes as f64 / 1e6
    );
    let (peak, ratio) = match (hwm, rss_before) {
        (Some(h), Some(b)) if hwm_reset => {
            let peak = h.saturating_sub(b) * 1024;
            let ratio = peak as f64 / mesh_bytes as f64;
            println!(
                "peak RSS growth  {:>10.1} MB during one read = {ratio:.2} x the Mesh (all from_file holds while parsing; the {:.1} MB file is streamed)",
                peak as f64 / 1e6,
                file_bytes as f64 / 1e6
            );
            (peak.to_string(), format!("{ratio:.3}"))
        }
        (Some(h), _) => {
            println!(
                "peak RSS         {:>10.1} MB (whole process; could not reset VmHWM, so not a per-read figure)",
                (h * 1024) as f64 / 1e6
            );
            ("nan".into(), "nan".into())
        }
        _ => {
            println!("peak RSS         unavailable (no /proc/self/status)");
            ("nan".into(), "nan".into())
        }
    };
    println!("RESULT file_bytes={file_bytes} median_s={median:.6} mb_per_s={mbps:.3} read_s={read_median:.6} parse_s={parse_median:.6} mesh_bytes={mesh_bytes} peak_bytes={peak} peak_ratio={ratio} cpu_s={cpu_s:.6}");
    ExitCode::SUCCESS
}

/// Sorts `v` and returns its median (upper median for an even length).
fn median_of(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The Mesh's heap and inline size from its Vec lengths (not capacities).
fn mesh_size_bytes(m: &Mesh) -> usize {
    use std::mem::size_of;
    let mut n = size_of::<Mesh>()
        + m.nodes.len() * size_of::<[f64; 2]>()
        + m.node_tags.len() * size_of::<u64>()
        + m.cells.len() * size_of::<usize>()
        + m.cell_tags.len() * size_of::<u64>()
        + m.source.version.len();
    for g in &m.groups {
        n += size_of::<Group>()
            + g.name.len()
            + g.edges.len() * size_of::<Edge>()
            + (g.cells.len() + g.points.len() + g.nodes.len()) * size_of::<usize>();
    }
    n
}

/// Resets the process's peak RSS counter (Linux ≥ 4.0: "5" > clear_refs).
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// User + system CPU seconds of this process so far (/proc/self/stat
/// fields 14 and 15, in clock ticks assumed to be the usual 100 per second).
fn proc_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name, which is in parentheses.
    let rest = s.get(s.rfind(')')? + 2..)?;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// A `kB` field of /proc/self/status, in KiB.
fn proc_status_kib(key: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    s.lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(':'))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}
