//! The results file's protection (`stickslip run`): what `run` must not
//! write over, and the lock a run holds on its file so that a second run
//! (`--force`, `--restart`) or `probe` knows it is being written, whatever
//! HDF5's own locking.

use std::path::Path;

use crate::error::InputError;

/// Refuses an output path `run` must not write (exit code 2), before
/// anything is read: an existing OUT.h5 or OUT.xdmf without `force`, an
/// empty name, a directory, the case file itself, a missing directory, or
/// a file another process has open (HDF5 locks files it writes: a second
/// run with `--force` would truncate the first run's file and then fail on
/// the lock, losing both).
///
/// # Errors
/// The [`InputError`] naming the file and what to do.
pub fn check_output(out: &Path, case_file: &Path, force: bool) -> Result<(), InputError> {
    let name = out.display();
    if out.as_os_str().is_empty() || out.file_name().is_none() {
        return Err(InputError(format!(
            "the results file name {:?} is empty or a directory; give a file such as -o out.h5",
            out.as_os_str()
        )));
    }
    if out.is_dir() {
        return Err(InputError(format!(
            "{name} is a directory; give a file in it, e.g. -o {}",
            out.join("out.h5").display()
        )));
    }
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same(out, case_file) {
        return Err(InputError(format!(
            "{name} is the case file itself; write the results elsewhere with -o OUT.h5"
        )));
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            let what = if dir.exists() {
                "is not a directory"
            } else {
                "does not exist"
            };
            return Err(InputError(format!(
                "{name}: {} {what}; create the directory, or choose another file with -o",
                dir.display()
            )));
        }
    }
    let xdmf = out.with_extension("xdmf");
    for path in [out, xdmf.as_path()] {
        if !path.exists() {
            continue;
        }
        if !force {
            let restart = if out.exists() {
                format!(", or --restart {name} to continue it")
            } else {
                String::new()
            };
            return Err(InputError(format!(
                "{} already exists; use --force to overwrite it, -o to write elsewhere{restart}",
                path.display(),
            )));
        }
        if in_use(path) {
            return Err(InputError(format!(
                "{} is open in another process (a run still writing it, or a reader such as h5py or ParaView); \
                 wait for it or close it, or write elsewhere with -o",
                path.display()
            )));
        }
    }
    Ok(())
}

/// Whether another process has `path` open: HDF5's flock (taken on every
/// file it opens unless HDF5_USE_FILE_LOCKING=FALSE) or a run's own lock
/// ([`RunLock`]).
pub fn in_use(path: &Path) -> bool {
    let flocked = std::fs::File::open(path)
        .is_ok_and(|f| matches!(f.try_lock(), Err(std::fs::TryLockError::WouldBlock)));
    flocked || being_written(path)
}

/// Whether a run is writing `path` ([`RunLock`]), whatever HDF5's own
/// locking: a write lock of ours, released when `f` closes, conflicts
/// with the run's read lock.
pub fn being_written(path: &Path) -> bool {
    let held = |e: std::io::Error| {
        e.kind() == std::io::ErrorKind::WouldBlock || e.raw_os_error() == Some(libc::EACCES)
    };
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .is_ok_and(|f| ofd_lock(&f, false).is_err_and(held))
}

/// A run's lock on its results file, held while it writes: an open file
/// description lock (F_OFD_SETLK), which HDF5's flock does not meet, which
/// holds when HDF5's locking is off (HDF5_USE_FILE_LOCKING=FALSE, as under
/// `cargo test`), and which no other descriptor's closing drops (as it
/// would a classic fcntl lock).
#[derive(Debug)]
pub struct RunLock {
    _file: std::fs::File,
}

impl RunLock {
    /// Takes the lock on `path` (a read lock: [`in_use`] asks for a write
    /// lock).
    ///
    /// # Errors
    /// The file cannot be opened, or another process holds a write lock.
    pub fn take(path: &Path) -> std::io::Result<RunLock> {
        let f = std::fs::File::open(path)?;
        ofd_lock(&f, true)?;
        Ok(RunLock { _file: f })
    }
}

/// An F_OFD_SETLK lock on the whole of `f`: shared (`read`) or exclusive.
#[allow(unsafe_code)]
fn ofd_lock(f: &std::fs::File, read: bool) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    // SAFETY: flock is plain data, and all zeros a valid value: the whole
    // file from offset 0, and l_pid 0 as OFD locks require.
    let mut fl: libc::flock = unsafe { std::mem::zeroed() };
    fl.l_type = (if read { libc::F_RDLCK } else { libc::F_WRLCK }) as libc::c_short;
    fl.l_whence = libc::SEEK_SET as libc::c_short;
    // SAFETY: a valid descriptor and a pointer to a live flock.
    let r = unsafe { libc::fcntl(f.as_raw_fd(), libc::F_OFD_SETLK, &fl) };
    if r == -1 {
        Err(std::io::Error::last_os_error())
    } else {
        Ok(())
    }
}

/// Removes an old results file (and its XDMF) before the new one is
/// created, rather than letting HDF5 truncate it in place (a process that
/// opened it since [`check_output`] keeps its own copy), and makes sure the
/// place is writable: exit code 2 with what to do, not HDF5's message.
pub(crate) fn make_room(out: &Path) -> Result<(), InputError> {
    for path in [out.to_path_buf(), out.with_extension("xdmf")] {
        if path.exists() {
            std::fs::remove_file(&path).map_err(|e| {
                InputError(format!(
                    "cannot replace {}: {e}; remove it yourself, or write elsewhere with -o",
                    path.display()
                ))
            })?;
        }
    }
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(out)
        .map_err(|e| {
            InputError(format!(
                "cannot create {}: {e}; choose a writable place with -o",
                out.display()
            ))
        })?;
    std::fs::remove_file(out)
        .map_err(|e| InputError(format!("cannot remove the empty {}: {e}", out.display())))
}
