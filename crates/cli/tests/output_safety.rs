//! Where the commands write, and what happens when they cannot: `probe
//! --along -o` never writes over an existing file without `--force` nor
//! over the results file it reads; a failed write to stdout or stderr
//! exits 1 with a message, not a panic (101), and `run --json` says so
//! with its file complete; `views` and `stress` refuse a place beside the
//! results they cannot write with exit code 2, naming the path, and leave
//! no `.part` behind; but a results file they cannot read, or a write that
//! fails once started (HDF5's first write of a file too), exits 1 naming
//! the file involved, and leaves no partial file (an earlier views file as
//! it was); so does `probe --along -o FILE`, FILE as it was.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

mod common;
use common::{bin, data, probe, run, scratch, skip_without, stderr, tmpfs};

/// What to do where /dev/full is missing (a container without /dev).
const NO_DEV_FULL: &str = "give the container its /dev (docker mounts /dev/full by default)";

/// tests/data/slab.toml run into `dir/slab.h5`.
fn slab_run(dir: &Path) -> PathBuf {
    let h5 = dir.join("slab.h5");
    let o = run(&data("slab.toml"), &h5, &["--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    h5
}

/// `cmd` with stdout (or stderr, `on_stderr`) sent to /dev/full, where
/// every write fails with ENOSPC; `None` where the system has no
/// /dev/full.
fn into_full(mut cmd: Command, on_stderr: bool) -> Option<Output> {
    let full = File::options().write(true).open("/dev/full").ok()?;
    if on_stderr {
        cmd.stderr(full).stdout(Stdio::null());
        // stderr is lost: only the exit code can tell.
        let status = cmd.status().unwrap();
        Some(Output {
            status,
            stdout: Vec::new(),
            stderr: Vec::new(),
        })
    } else {
        cmd.stdout(full);
        Some(cmd.output().unwrap())
    }
}

/// Exit 1, said on stderr, without a panic.
fn failed_to_write(o: &Output, what: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{what}: {e}");
    assert!(!e.contains("panicked"), "{what}: {e}");
    assert!(
        e.contains("error: cannot write to stdout: No space left on device"),
        "{what}: {e}"
    );
}

#[test]
fn probe_along_writes_over_no_file_unasked_and_never_the_results() {
    let dir = scratch("probe-o");
    let h5 = slab_run(&dir);
    let results = std::fs::read(&h5).unwrap();
    let along = |out: &Path, extra: &[&str]| {
        let mut args = vec!["--along", "contact", "--times", "0.01", "-o"];
        args.push(out.to_str().unwrap());
        args.extend(extra);
        probe(&h5, &args)
    };
    // The results file itself, by its name or through a link, even with
    // --force: refused before it is read, and left as it was.
    let link = dir.join("link.h5");
    std::os::unix::fs::symlink(&h5, &link).unwrap();
    for (out, extra) in [
        (&h5, &[][..]),
        (&h5, &["--force"][..]),
        (&link, &["--force"][..]),
    ] {
        let o = along(out, extra);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{} {extra:?}: {e}", out.display());
        assert!(
            e.contains("is the results file being read") && e.contains("-o"),
            "{e}"
        );
        assert_eq!(std::fs::read(&h5).unwrap(), results, "{e}");
    }
    // Another existing file: only with --force.
    let csv = dir.join("along.csv");
    std::fs::write(&csv, "precious").unwrap();
    let o = along(&csv, &[]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("already exists; use --force"), "{e}");
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), "precious");
    let o = along(&csv, &["--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with("t_asked,t,record,node,x,y,s,ux\n"),
        "{text}"
    );
    // --force goes with --along only.
    let o = probe(&h5, &["--at", "8,0", "--force"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// `--force` without `-o` has nothing to overwrite: refused (exit 2)
/// before anything is read or printed, rather than ignored.
#[test]
fn probe_along_refuses_force_without_o() {
    let dir = scratch("probe-force");
    let h5 = slab_run(&dir);
    let o = probe(&h5, &["--along", "contact", "--times", "0.01", "--force"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--force applies to -o FILE") && e.contains("leave out --force"),
        "{e}"
    );
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}

#[test]
fn a_full_stdout_exits_1_without_a_panic() {
    let dir = scratch("full");
    let h5 = slab_run(&dir);
    let mesh = common::root().join("cases/meshes/slab-q2-8x2.msh");
    let mut check = bin();
    check.arg("check").arg(data("slab.toml"));
    let mut table = bin();
    table.arg("mesh").arg(&mesh);
    let mut json = bin();
    json.arg("mesh").arg(&mesh).arg("--json");
    let mut at = bin();
    at.arg("probe").arg(&h5).args(["--at", "8,0", "--csv"]);
    let mut along = bin();
    along
        .arg("probe")
        .arg(&h5)
        .args(["--along", "contact", "--times", "0.01"]);
    for (what, cmd) in [
        ("check", check),
        ("mesh", table),
        ("mesh --json", json),
        ("probe --at", at),
        ("probe --along", along),
    ] {
        let Some(o) = into_full(cmd, false) else {
            skip_without("/dev/full", NO_DEV_FULL);
            return;
        };
        failed_to_write(&o, what);
    }
    // stderr full: the summary of `views` is lost, which only the exit
    // code can say; the files are written all the same.
    let mut views = bin();
    views.arg("views").arg(&h5);
    let o = into_full(views, true).unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(dir.join("slab.xdmf").is_file());
}

#[test]
fn run_json_into_a_full_stdout_exits_1_with_its_file_complete() {
    let dir = scratch("json-full");
    let h5 = dir.join("slab.h5");
    let mut cmd = bin();
    cmd.arg("run")
        .arg(data("slab.toml"))
        .arg("-o")
        .arg(&h5)
        .args(["--quiet", "--json"]);
    let Some(o) = into_full(cmd, false) else {
        skip_without("/dev/full", NO_DEV_FULL);
        return;
    };
    failed_to_write(&o, "run --json");
    assert!(stderr(&o).contains("the run is complete all the same"));
    let f = hdf5::File::open(&h5).unwrap();
    assert!(f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
}

#[test]
fn run_json_into_a_closed_pipe_exits_1_quietly() {
    let dir = scratch("json-pipe");
    let h5 = dir.join("slab.h5");
    let mut child = bin()
        .arg("run")
        .arg(data("slab.toml"))
        .arg("-o")
        .arg(&h5)
        .args(["--quiet", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes before the run ends: its summary meets a closed pipe.
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(!e.contains("panicked") && !e.contains("error"), "{e}");
    let f = hdf5::File::open(&h5).unwrap();
    assert!(f.attr("complete").unwrap().read_scalar::<bool>().unwrap());
}

#[test]
fn views_and_stress_refuse_a_directory_in_their_place() {
    let dir = scratch("in-the-way");
    let h5 = slab_run(&dir);
    for (command, file) in [
        ("views", "slab.xdmf"),
        ("views", "slab.views.h5"),
        ("stress", "slab.stress.h5"),
        ("stress", "slab.contact.xdmf"),
    ] {
        let in_the_way = dir.join(file);
        std::fs::create_dir(&in_the_way).unwrap();
        let o = bin().arg(command).arg(&h5).output().unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{command} with {file}: {e}");
        assert!(
            e.contains(&in_the_way.display().to_string())
                && e.contains("remove or rename the directory"),
            "{e}"
        );
        let left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|d| d.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".part"))
            .collect();
        assert!(left.is_empty(), "{command} left {left:?}");
        std::fs::remove_dir(&in_the_way).unwrap();
    }
    // Nothing in the way: both write.
    let o = bin().arg("stress").arg(&h5).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A results file in a directory this process may not write: by its
/// permissions, or for root (whom permissions do not stop) on a tmpfs
/// remounted read-only. Where root may not mount one (a container
/// without CAP_SYS_ADMIN) the test fails under CI and is skipped
/// elsewhere, as the disk-full test of robustness.rs.
#[test]
fn views_in_a_read_only_directory_say_what_to_do() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("read-only");
    let h5 = slab_run(&dir);
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    let writable = File::create(dir.join("probe")).is_ok();
    let mut outputs: Vec<Output> = ["views", "stress"]
        .iter()
        .map(|c| bin().arg(c).arg(&h5).output().unwrap())
        .collect();
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    if writable {
        // Root: a read-only file system stops it.
        let Some(ro) = tmpfs(&dir, "ro", "size=4M") else {
            return;
        };
        let inside = ro.join("slab.h5");
        std::fs::copy(&h5, &inside).unwrap();
        let remounted = Command::new("mount")
            .args(["-o", "remount,ro"])
            .arg(&ro)
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if remounted {
            outputs = ["views", "stress"]
                .iter()
                .map(|c| bin().arg(c).arg(&inside).output().unwrap())
                .collect();
        }
        let unmounted = Command::new("umount").arg(&ro).status();
        assert!(remounted, "cannot remount {} read-only", ro.display());
        assert!(
            unmounted.is_ok_and(|s| s.success()),
            "umount {}",
            ro.display()
        );
    }
    for o in &outputs {
        let e = stderr(o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(
            e.contains("cannot write in the directory") && e.contains("copy"),
            "{e}"
        );
    }
}

/// `advise`'s report into a full stdout: exit 1 with the message, after
/// its pilots ran (their lines go to stderr).
#[test]
fn advise_into_a_full_stdout_exits_1_without_a_panic() {
    let case = common::root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let mut cmd = bin();
    cmd.arg("advise")
        .arg(&case)
        .args(["--tol", "2e-2", "--on", "ux", "--at", "8,1"]);
    let Some(o) = into_full(cmd, false) else {
        skip_without("/dev/full", NO_DEV_FULL);
        return;
    };
    failed_to_write(&o, "advise");
}

/// `stickslip ARGS…` with writes limited to files of `blocks` blocks of
/// 512 bytes (and SIGXFSZ ignored, so that a write past it fails with
/// EFBIG instead of killing the process): a write that fails after the
/// file was made, at its first write with 0 blocks.
fn with_small_files(blocks: u32, args: &[&std::ffi::OsStr]) -> Output {
    Command::new("sh")
        .args([
            "-c",
            &format!("trap '' XFSZ; ulimit -f {blocks} && exec \"$@\""),
            "sh",
            env!("CARGO_BIN_EXE_stickslip"),
        ])
        .args(args)
        .output()
        .unwrap()
}

/// The names in `dir` ending in `.part`.
fn parts_in(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|d| d.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".part"))
        .collect()
}

/// A write beside the results that fails once started (a disk filled
/// meanwhile; here a file-size limit), HDF5's create writing its first
/// bytes (no room at all) too, is the work failing: exit 1 naming the
/// file, not a place to change (exit 2); no `.part` and no partial file
/// is left.
#[test]
fn views_and_stress_failing_mid_write_exit_1() {
    let dir = scratch("mid-write");
    let h5 = slab_run(&dir);
    for blocks in [0, 16] {
        for (command, file) in [("stress", "slab.stress.h5"), ("views", "slab.views.h5")] {
            let o = with_small_files(blocks, &[command.as_ref(), h5.as_os_str()]);
            let e = stderr(&o);
            let what = format!("{command} with {blocks} blocks");
            assert_eq!(o.status.code(), Some(1), "{what}: {e}");
            assert!(
                e.contains(&format!("cannot write {}:", dir.join(file).display()))
                    && e.contains("make room")
                    && !e.contains("writable directory"),
                "{what}: {e}"
            );
            assert!(!e.contains("panicked"), "{what}: {e}");
            assert_eq!(parts_in(&dir), Vec::<String>::new(), "{what}: {e}");
            for written in [
                "slab.stress.h5",
                "slab.views.h5",
                "slab.xdmf",
                "slab.contact.xdmf",
            ] {
                assert!(!dir.join(written).exists(), "{what} left {written}: {e}");
            }
        }
    }
}

/// `views` after a restart brings the views it made before up to the
/// frames (new ones added, moved ones pointed again); where that fails midway, the views file it had is kept as it
/// was (not lost, not left half grown), and the command run again adds
/// them.
#[test]
fn views_failing_midway_keep_the_views_file_they_had() {
    let dir = scratch("views-kept");
    let h5 = dir.join("slab.h5");
    let o = run(
        &data("slab.toml"),
        &h5,
        &["--quiet", "--set", "time.t_end=0.01"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let views = dir.join("slab.views.h5");
    let o = bin().arg("views").arg(&h5).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let before = std::fs::read(&views).unwrap();
    let o = bin()
        .arg("run")
        .arg(data("slab.toml"))
        .arg("--restart")
        .arg(&h5)
        .args(["--quiet", "--set", "time.t_end=0.05"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    for blocks in [0, 120] {
        let o = with_small_files(blocks, &["views".as_ref(), h5.as_os_str()]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{blocks} blocks: {e}");
        assert!(
            e.contains(&format!("cannot write {}:", views.display())),
            "{blocks} blocks: {e}"
        );
        assert!(
            std::fs::read(&views).unwrap() == before,
            "{blocks} blocks: {e}"
        );
        assert_eq!(parts_in(&dir), Vec::<String>::new(), "{e}");
    }
    let o = bin().arg("views").arg(&h5).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let f = hdf5::File::open(&views).unwrap();
    assert_eq!(f.group("displacement").unwrap().len(), 51);
}

/// `probe --along -o FILE` whose write fails midway (a disk filled; here a
/// file-size limit): exit 1 naming FILE, which is left as it was (with
/// `--force`, the earlier CSV whole), and no `.part`.
#[test]
fn probe_along_failing_mid_write_keeps_the_file() {
    let dir = scratch("probe-mid-write");
    let h5 = slab_run(&dir);
    let csv = dir.join("along.csv");
    let earlier = "t_asked,t,record,node,x,y,s,ux\n".repeat(40);
    std::fs::write(&csv, &earlier).unwrap();
    let fresh = dir.join("fresh.csv");
    for (out, force) in [(&csv, true), (&fresh, false)] {
        let mut args: Vec<&std::ffi::OsStr> = vec!["probe".as_ref(), h5.as_os_str()];
        args.extend(
            ["--along", "contact", "--times", "0.01,0.02,0.03", "-o"].map(std::ffi::OsStr::new),
        );
        args.push(out.as_os_str());
        if force {
            args.push("--force".as_ref());
        }
        let o = with_small_files(1, &args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(
            e.contains(&format!("-o {}: cannot write the CSV", out.display()))
                && !e.contains("panicked"),
            "{e}"
        );
        assert_eq!(parts_in(&dir), Vec::<String>::new(), "{e}");
    }
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), earlier);
    assert!(!fresh.exists());
}

/// `stress` on a results file whose /displacement cannot be read (its
/// compressed chunks overwritten): exit 1, the message naming the results
/// file, not the stress file it would have written.
#[test]
fn stress_of_a_damaged_results_file_names_it() {
    let dir = scratch("damaged");
    let h5 = dir.join("slab.h5");
    let o = run(
        &data("slab.toml"),
        &h5,
        &["--quiet", "--set", "output.compression=4"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let chunks: Vec<(u64, u64)> = {
        let f = hdf5::File::open(&h5).unwrap();
        let u = f.dataset("displacement").unwrap();
        (0..u.num_chunks().unwrap())
            .map(|i| u.chunk_info(i).unwrap())
            .map(|c| (c.addr, c.size))
            .collect()
    };
    assert!(!chunks.is_empty());
    {
        use std::io::{Seek, SeekFrom, Write};
        let mut f = File::options().write(true).open(&h5).unwrap();
        for (addr, size) in chunks {
            f.seek(SeekFrom::Start(addr)).unwrap();
            f.write_all(&vec![0xff; size as usize]).unwrap();
        }
    }
    let o = bin().arg("stress").arg(&h5).output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&format!("{}: cannot read /displacement", h5.display()))
            && !e.contains("cannot write"),
        "{e}"
    );
    assert!(!dir.join("slab.stress.h5").exists() && !dir.join("slab.stress.h5.part").exists());
}

/// `advise` with stderr on a full disk: its pilots' lines are lost, which
/// exits 1 (not a panic's 101) once the work is done; --write is written.
#[test]
fn advise_into_a_full_stderr_exits_1_with_its_case_written() {
    let dir = scratch("advise-stderr");
    let written = dir.join("adjusted.toml");
    let case = common::root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let mut cmd = bin();
    cmd.arg("advise")
        .arg(&case)
        .args(["--tol", "2e-2", "--on", "ux", "--at", "8,1", "--write"])
        .arg(&written);
    let Some(o) = into_full(cmd, true) else {
        skip_without("/dev/full", NO_DEV_FULL);
        return;
    };
    assert_eq!(o.status.code(), Some(1));
    assert!(written.is_file());
}
