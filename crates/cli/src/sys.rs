//! The command's system calls, behind safe functions: the one place in the
//! crate allowed `unsafe` (the crate root denies it). Signals for `run`
//! and the other commands, the results file's lock, the free space on a
//! disk and whether a directory may be written; what each is for is said
//! where it is called.
#![allow(unsafe_code)]

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// Restores the default action of SIGPIPE (end the process), which the
/// Rust runtime sets to ignore. Call it before any thread starts.
pub fn default_sigpipe() {
    // SAFETY: sets the action of one signal to the default; no handler of
    // ours is involved, and no other thread is changing signal actions.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Keeps freed memory in the process for its next allocations: glibc's
/// malloc serves blocks from 128 KiB (its default threshold, raised as
/// blocks are freed) by fresh mappings and returns them, and the heap's
/// top above 128 KiB, to the system when freed, so every factor, scratch
/// buffer and vector of a setup faults its pages in again, zeroed by the
/// kernel. Blocks up to 32 MiB (glibc's largest threshold) now come from
/// the heap, which is kept up to 1 GiB (docs/performance.md, "The
/// allocator's thresholds"). Call it before anything allocates much.
pub fn keep_freed_memory() {
    #[cfg(target_env = "gnu")]
    // SAFETY: mallopt only sets two of malloc's parameters; no other
    // thread allocates yet.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
    }
}

/// A signal within this many nanoseconds of the first is the same
/// signal sent twice (GNU `timeout` signals the process and then its
/// group), not a user's second Ctrl-C: a quarter second, which a loaded
/// machine's two sends stay within, and a second Ctrl-C after a stop that
/// hangs comes later (one sooner is taken as the first, which stops the
/// run all the same).
const SAME_SIGNAL_NS: u64 = 250_000_000;

/// CLOCK_MONOTONIC in nanoseconds (clock_gettime is async-signal-safe).
fn monotonic_ns() -> u64 {
    // SAFETY: timespec is plain data, all zeros a valid value, and
    // clock_gettime only writes it.
    let mut ts: libc::timespec = unsafe { std::mem::zeroed() };
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    (ts.tv_sec as u64).saturating_mul(1_000_000_000) + ts.tv_nsec as u64
}

/// Adds an action on `sig` (beside any others registered with
/// signal-hook): when it arrives while `armed` is set, and more than
/// [`SAME_SIGNAL_NS`] after the first signal (whose time it keeps in
/// `first`, shared by the signals of one set), writes `msg` to stderr
/// and ends the process at once with exit code `code` (no unwinding, no
/// destructors, no buffers flushed).
///
/// # Errors
/// The action cannot be installed.
pub(crate) fn exit_on_signal_if(
    sig: i32,
    (armed, first): (Arc<AtomicBool>, Arc<AtomicU64>),
    msg: &'static [u8],
    code: i32,
) -> std::io::Result<()> {
    // SAFETY: the action only reads the clock, uses atomics and calls
    // write(2) and _exit(2), which are async-signal-safe; it allocates
    // nothing and takes no lock.
    unsafe {
        signal_hook::low_level::register(sig, move || {
            let now = monotonic_ns();
            if !armed.load(Ordering::SeqCst) {
                let _ = first.compare_exchange(0, now, Ordering::SeqCst, Ordering::SeqCst);
            } else if now.saturating_sub(first.load(Ordering::SeqCst)) >= SAME_SIGNAL_NS {
                libc::write(2, msg.as_ptr().cast(), msg.len());
                libc::_exit(code);
            }
        })?;
    }
    Ok(())
}

/// Takes an open file description lock (F_OFD_SETLK, not waiting) on the
/// whole of `f`: shared if `read`, else exclusive. It lasts until every
/// descriptor of this open file is closed.
///
/// # Errors
/// The OS error: another process holds a conflicting lock ([`lock_held`]),
/// or the file system has no such locks.
pub(crate) fn ofd_lock(f: &std::fs::File, read: bool) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    // SAFETY: flock is plain data, and all zeros a valid value: the whole
    // file from offset 0, and l_pid 0 as OFD locks require.
    let mut fl: libc::flock = unsafe { std::mem::zeroed() };
    fl.l_type = (if read { libc::F_RDLCK } else { libc::F_WRLCK }) as libc::c_short;
    fl.l_whence = libc::SEEK_SET as libc::c_short;
    // SAFETY: a valid descriptor (borrowed from a live File) and a pointer
    // to a live flock, which fcntl only reads.
    let r = unsafe { libc::fcntl(f.as_raw_fd(), libc::F_OFD_SETLK, &fl) };
    if r == -1 {
        Err(std::io::Error::last_os_error())
    } else {
        Ok(())
    }
}

/// Whether [`ofd_lock`] failed because another process holds a
/// conflicting lock (fcntl(2) gives EAGAIN or EACCES for it).
pub(crate) fn lock_held(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::WouldBlock || e.raw_os_error() == Some(libc::EACCES)
}

/// Bytes free to an unprivileged writer on the file system holding `dir`
/// (statvfs(3)), or None where it cannot be asked or the file system has
/// no size (proc, sysfs: 0 blocks of 0, which read as a full disk).
pub(crate) fn free_bytes_at(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    // SAFETY: statvfs is plain data, all zeros a valid value.
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: a NUL-terminated path and a pointer to a live statvfs, which
    // the call fills.
    let r = unsafe { libc::statvfs(c.as_ptr(), &mut st) };
    #[allow(clippy::useless_conversion)] // u64 here; other platforms differ
    (r == 0 && st.f_blocks > 0)
        .then(|| u64::from(st.f_bavail).saturating_mul(u64::from(st.f_frsize)))
}

/// Whether this process may create files in the directory `dir`
/// (access(2) with W_OK: its permissions, and a read-only file system).
/// Where it cannot be asked, true: the write itself then says.
pub(crate) fn can_write_in(dir: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt;
    let Ok(c) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else {
        return true;
    };
    // SAFETY: a NUL-terminated path, which access only reads.
    unsafe { libc::access(c.as_ptr(), libc::W_OK) == 0 }
}

/// Whether `e`, the OS error of creating or renaming a file, is one its
/// place must change for (bad input, exit 2): a directory this process
/// may not write, a read-only file system, a directory or another file in
/// the way, a directory missing. Any other (a full disk, a quota, a
/// file-size limit, an I/O error) is the work failing (exit 1).
pub(crate) fn place_error(e: &std::io::Error) -> bool {
    matches!(
        e.raw_os_error(),
        Some(
            libc::EACCES
                | libc::EPERM
                | libc::EROFS
                | libc::EISDIR
                | libc::ENOTDIR
                | libc::ENOENT
                | libc::ENOTEMPTY
                | libc::EEXIST
                | libc::ELOOP
                | libc::ENAMETOOLONG
                | libc::ETXTBSY
        )
    )
}
