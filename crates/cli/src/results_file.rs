//! The results file's protection (`stickslip run`): what `run` must not
//! write over, and the lock a run holds on its file so that a second run
//! (`--force`, `--restart`) or `probe` knows it is being written, whatever
//! HDF5's own locking; and what the commands that read a results file
//! (`probe`, `views`, `stress`, `run --restart`) check of its path first.

use std::path::{Path, PathBuf};

use stickslip_case::{Case, InputError};

use crate::sys::{lock_held, ofd_lock};

/// A file a case reads, which no results may be written over, and what
/// it is to the case (for the message).
pub type Input<'a> = (&'a Path, &'static str);

/// The files `case` reads: the case file, its mesh.file and the meshes of
/// its mesh.ladder (which `advise` reads).
pub fn case_inputs(case: &Case) -> Vec<Input<'_>> {
    let mut inputs = vec![
        (case.path.as_path(), "the case file"),
        (
            case.mesh.file.as_path(),
            "an input of the case (its mesh.file)",
        ),
    ];
    inputs.extend(case.mesh.ladder.iter().map(|m| {
        (
            m.as_path(),
            "an input of the case (a mesh of its mesh.ladder)",
        )
    }));
    inputs
}

/// A file `stickslip views` or `stickslip stress` writes beside a results
/// file under its name, which a new run or a restart of that file removes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Companion {
    /// OUT.views.h5 (`stickslip views`).
    Views,
    /// OUT.stress.h5 (`stickslip stress`).
    Stress,
}

impl Companion {
    /// Its path beside the results file `out`.
    pub fn path(self, out: &Path) -> PathBuf {
        match self {
            Companion::Views => crate::views::views_path(out),
            Companion::Stress => crate::stress_cmd::stress_path(out),
        }
    }

    /// What it is, for a message.
    fn what(self) -> &'static str {
        match self {
            Companion::Views => "views file",
            Companion::Stress => "stress file",
        }
    }
}

/// What the file at `kind`'s path beside `out` is, where it exists and
/// holds what replacing it would lose: a directory or special file, a file
/// in use (a run writing its results under that name, a reader), another
/// run's results file (e.g. a run written to `r.views.h5`), a file that is
/// no HDF5 file, or an HDF5 file of another program. Views and stresses,
/// whoever's (a renamed results file's, a copy's, an earlier version's),
/// and a damaged or empty file nothing holds open are made again from a
/// results file: replacing them loses nothing, so they are `None`.
pub fn foreign_companion(out: &Path, kind: Companion) -> Option<String> {
    foreign(
        out,
        kind,
        (in_use, "in use (a run writing it, or a reader)"),
    )
}

/// [`foreign_companion`] for a command that only reads the file (`views`
/// listing the stresses in OUT.xdmf): a reader's lock (ParaView showing
/// them) does not stop another reader, so only a run writing under that
/// name makes it "in use".
pub fn foreign_to_read(out: &Path, kind: Companion) -> Option<String> {
    foreign(out, kind, (being_written, "in use (a run writing it)"))
}

/// [`foreign_companion`] with `busy` telling whether the file is in use,
/// and saying how.
fn foreign(
    out: &Path,
    kind: Companion,
    (busy, in_use): (fn(&Path) -> bool, &str),
) -> Option<String> {
    let path = kind.path(out);
    let meta = std::fs::metadata(&path).ok()?;
    if !meta.is_file() {
        return Some(if meta.is_dir() {
            "a directory".into()
        } else {
            "not a regular file".into()
        });
    }
    // Before anything else: a run's results file is empty, or does not
    // open, while the run writes it.
    if busy(&path) {
        return Some(in_use.into());
    }
    if meta.len() == 0 {
        return None;
    }
    if !is_hdf5(&path) {
        return Some("not an HDF5 file".into());
    }
    let Ok(f) = hdf5::File::open(&path) else {
        return None;
    };
    let text = |name: &str| crate::output::text_attr(&f, name).ok();
    if text("program").as_deref() == Some("stickslip") {
        return Some("the results file of another run".into());
    }
    // What `views` and `stress` write: `source` (stress files of earlier
    // versions lack it: their datasets say what they are).
    let companion = text("source").is_some()
        || (kind == Companion::Stress && f.link_exists("stress") && f.link_exists("von_mises"));
    (!companion).then(|| "an HDF5 file of another program".into())
}

/// The message for [`foreign_companion`]'s file beside `out`, which
/// `doing` (a run, `stickslip views`) would remove or replace.
pub(crate) fn foreign_message(out: &Path, kind: Companion, what: &str, doing: &str) -> String {
    format!(
        "{} is {what}, not the {} of {}, although named as one: {doing} would remove or replace it; \
         move or rename it and run this again",
        kind.path(out).display(),
        kind.what(),
        out.display()
    )
}

/// Refuses an output path `run` must not write (exit code 2), before
/// anything is read: an existing OUT.h5, OUT.xdmf, OUT.contact.xdmf,
/// OUT.views.h5 or OUT.stress.h5 without `force`, a file named as
/// OUT.h5's views or stresses that holds what replacing it would lose
/// ([`foreign_companion`]; even with `force`), an
/// empty name, a directory, an input of the case, a missing directory, or
/// a file another process has open (HDF5 locks files it writes: a second
/// run with `--force` would truncate the first run's file and then fail on
/// the lock, losing both).
///
/// # Errors
/// The [`InputError`] naming the file and what to do.
pub fn check_output(out: &Path, inputs: &[Input], force: bool) -> Result<(), InputError> {
    check_output_place(out, inputs)?;
    let name = out.display();
    // The viewers' files and the stresses beside OUT.h5 (`stickslip views`,
    // `stickslip stress`) show its run: a new run would leave them showing
    // another, and so removes them.
    let beside = [
        (crate::xdmf::xdmf_path(out), None),
        (crate::xdmf::contact_xdmf_path(out), None),
        (Companion::Views.path(out), Some(Companion::Views)),
        (Companion::Stress.path(out), Some(Companion::Stress)),
    ];
    let all = std::iter::once((out, None)).chain(beside.iter().map(|(p, k)| (p.as_path(), *k)));
    for (path, kind) in all {
        if !path.exists() {
            continue;
        }
        if let Some(what) = kind.and_then(|k| foreign_companion(out, k).map(|w| (k, w))) {
            let (kind, what) = what;
            return Err(InputError(format!(
                "{}, or write elsewhere with -o",
                foreign_message(out, kind, &what, &format!("a run on {name}"))
            )));
        }
        if !force {
            let restart = if is_hdf5(out) {
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

/// The part of [`check_output`] that does not depend on what exists at
/// `out` (`stickslip check` calls it, as the run's `--force` is not
/// known there): an `.xdmf` or `.part` name, an empty name, a ':' in the name, a
/// directory, an input of the case, a symbolic link, a device, a missing
/// directory, a directory this process may not write.
///
/// # Errors
/// The [`InputError`] naming the file and what to do.
pub fn check_output_place(out: &Path, inputs: &[Input]) -> Result<(), InputError> {
    let name = out.display();
    if out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xdmf"))
    {
        return Err(InputError(format!(
            "-o {name}: -o names the HDF5 results file, and `stickslip views` writes the .xdmf beside it \
             under the same name; give -o {}",
            out.with_extension("h5").display()
        )));
    }
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
    // `views` and `stress` write FILE.part beside a results file and
    // rename it into place, removing it where they fail: a results file of
    // such a name would be lost to them.
    if out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("part"))
    {
        return Err(InputError(format!(
            "-o {name}: .part names are the files `stickslip views` and `stickslip stress` write \
             beside a results file and then rename or remove; give another name, e.g. -o {}",
            out.with_extension("h5").display()
        )));
    }
    refer_by_name(out).map_err(|why| {
        InputError(format!(
            "{name}: {why}; give a name without ':', e.g. -o {}",
            out.with_file_name(colon_free_name(out)).display()
        ))
    })?;
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    for (input, what) in inputs {
        if same(out, input) {
            return Err(InputError(format!(
                "{name} is {what} itself; write the results elsewhere with -o OUT.h5"
            )));
        }
    }
    // A symbolic link: the run would replace the link, not its target (and
    // a dangling one read as a file another run had just created).
    if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(InputError(format!(
            "{name} is a symbolic link; give the file it stands for, or another name, with -o"
        )));
    }
    // A device, FIFO or socket: --force would replace it with a file (a
    // run as root replaced /dev/null), and a FIFO would hang the run.
    if std::fs::metadata(out).is_ok_and(|m| !m.is_file()) {
        return Err(InputError(format!(
            "{name} exists and is not a regular file (a device, FIFO or socket); \
             write the results to a file with -o OUT.h5"
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
    // The run creates the file (and removes an old one) in its directory.
    let dir = dir_of(out);
    if !crate::sys::can_write_in(dir) {
        return Err(InputError(format!(
            "{name}: cannot write in the directory {} (read-only, or not yours); make it writable, \
             or choose another file with -o",
            dir.display()
        )));
    }
    Ok(())
}

/// Why the results file `out` cannot be named in the XDMF files beside
/// it, if it cannot: they refer to it by file name as `NAME:/dataset`,
/// which ParaView's and VTK's readers and meshio split at the first ':',
/// reading an empty mesh or nothing.
pub(crate) fn refer_by_name(out: &Path) -> Result<(), String> {
    let colon = out
        .file_name()
        .is_some_and(|n| n.as_encoded_bytes().contains(&b':'));
    if colon {
        return Err(
            "a ':' in the results file's name breaks the XDMF files `stickslip views` writes \
             beside it (they refer to it as NAME:/dataset, which ParaView, VTK and meshio split at \
             the first ':')"
                .into(),
        );
    }
    Ok(())
}

/// `out`'s file name with each ':' made '_': a name [`refer_by_name`]
/// takes, for a message.
pub(crate) fn colon_free_name(out: &Path) -> String {
    out.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .replace(':', "_")
}

/// Refuses early what `run --restart` cannot continue: a missing file, a
/// directory, a file that is not HDF5 (the case file given as the results
/// file, say), before the model is built.
///
/// # Errors
/// The [`InputError`] naming the file and what to give instead.
pub fn check_restart(path: &Path) -> Result<(), InputError> {
    let name = path.display();
    let give = "give the OUT.h5 of the run to continue: `stickslip run CASE.toml --restart \
                OUT.h5` (`stickslip run CASE.toml -o OUT.h5` starts a new one)";
    if let Some(kind) = PathKind::of(path) {
        let what = match kind {
            PathKind::Missing => ": no such file",
            PathKind::Directory => " is a directory",
            PathKind::Special => " is not a regular file (a device, FIFO or socket)",
        };
        return Err(InputError(format!("--restart {name}{what}; {give}")));
    }
    if !is_hdf5(path) {
        return Err(InputError(format!(
            "--restart {name} is not a results file of `stickslip run` (not an HDF5 file); {give}"
        )));
    }
    Ok(())
}

/// Whether `path` starts with HDF5's signature (where our files put their
/// superblock): only such a file can be continued with --restart.
fn is_hdf5(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| head == *b"\x89HDF\r\n\x1a\n")
}

/// Whether another process has `path` open: HDF5's flock (taken on every
/// file it opens unless HDF5_USE_FILE_LOCKING=FALSE) or a run's own lock
/// ([`RunLock`]).
pub fn in_use(path: &Path) -> bool {
    let flocked = std::fs::File::open(path)
        .is_ok_and(|f| matches!(f.try_lock(), Err(std::fs::TryLockError::WouldBlock)));
    // A run's exclusive lock, or a reader's shared one (`stickslip stress`),
    // which only an exclusive request meets.
    let locked = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .is_ok_and(|f| ofd_lock(&f, false).is_err_and(|e| lock_held(&e)));
    flocked || locked || being_written(path)
}

/// Whether a run is writing `path` ([`RunLock`]), whatever HDF5's own
/// locking: a read lock of ours, released when `f` closes, conflicts with
/// the run's write lock (and needs only read access to the file).
pub fn being_written(path: &Path) -> bool {
    std::fs::File::open(path).is_ok_and(|f| ofd_lock(&f, true).is_err_and(|e| lock_held(&e)))
}

/// A run's lock on its results file, held while it writes: an open file
/// description lock (F_OFD_SETLK), which HDF5's flock does not meet, which
/// holds when HDF5's locking is off (HDF5_USE_FILE_LOCKING=FALSE, as under
/// `cargo test`), and which no other descriptor's closing drops (as it
/// would a classic fcntl lock). Exclusive, so that of two runs started on
/// one file at once only one gets it; taken before the run writes a byte.
#[derive(Debug)]
pub struct RunLock {
    _file: std::fs::File,
    /// The closing of the old results file `claim` removed, on its own
    /// thread (see [`free_aside`]); joined when the lock is dropped.
    freeing: Option<std::thread::JoinHandle<()>>,
}

impl Drop for RunLock {
    fn drop(&mut self) {
        if let Some(t) = self.freeing.take() {
            let _ = t.join();
        }
    }
}

/// Closes `old`, a removed file's last descriptor, on another thread:
/// the file system frees a removed file's blocks (and drops its cached
/// pages, still dirty for a file a run has just written) at the last
/// close, not at the removal, and that took as long as a small run's
/// steps. Should the process end first, its exit closes the file all
/// the same: nothing is left behind.
fn free_aside(old: std::fs::File) -> Option<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name("free old results".into())
        .spawn(move || drop(old))
        .ok()
}

impl RunLock {
    /// Takes the lock on the existing file `path` (`--restart`).
    ///
    /// # Errors
    /// The file cannot be opened for writing, or another process holds the
    /// lock: an [`InputError`] saying which.
    pub fn take(path: &Path) -> Result<RunLock, InputError> {
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::NotFound {
                    return InputError(format!(
                        "--restart {}: no such file; give the OUT.h5 of the run to continue \
                         (`stickslip run CASE -o OUT.h5` starts a new one)",
                        path.display()
                    ));
                }
                InputError(format!(
                    "cannot open {} for writing: {e}; a restart appends to the file, so it must be writable \
                     (check its permissions)",
                    path.display()
                ))
            })?;
        RunLock::on(f, path)
    }

    /// A shared lock on `path`, for a reader that must keep runs out while
    /// it reads (`stickslip stress`): a run's exclusive lock conflicts
    /// with it, and it needs only read access.
    ///
    /// # Errors
    /// The file cannot be opened, or a run holds its lock.
    pub fn shared(path: &Path) -> Result<RunLock, InputError> {
        let f = std::fs::File::open(path)
            .map_err(|e| InputError(format!("cannot open {}: {e}", path.display())))?;
        match ofd_lock(&f, true) {
            Err(e) if lock_held(&e) => Err(busy(path)),
            _ => Ok(RunLock {
                _file: f,
                freeing: None,
            }),
        }
    }

    /// Takes the lock on `f`, the file `path` names.
    fn on(f: std::fs::File, path: &Path) -> Result<RunLock, InputError> {
        match ofd_lock(&f, false) {
            Err(e) if lock_held(&e) => Err(busy(path)),
            // A file system without such locks (ENOLCK, EINVAL on some
            // network mounts): the run goes on unprotected, as HDF5's own
            // locking would let it.
            _ => Ok(RunLock {
                _file: f,
                freeing: None,
            }),
        }
    }
}

/// What every command that reads a results file checks of its path
/// before anything opens it: the file exists and is a regular file (an
/// open of a FIFO, as the lock tests `being_written` and `in_use` make,
/// waits for a writer), and it is not an XDMF written beside the results
/// file.
///
/// # Errors
/// The [`InputError`] naming the file and what to give instead.
pub(crate) fn check_results_path(path: &Path) -> Result<(), InputError> {
    let name = path.display();
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xdmf"))
    {
        // OUT.xdmf and OUT.contact.xdmf are both written for OUT.h5.
        let stem = path.file_stem().unwrap_or_default().to_string_lossy();
        let stem = stem.strip_suffix(".contact").unwrap_or(&stem);
        return Err(InputError(format!(
            "{name}: give the results file the XDMF is written for, {}",
            path.with_file_name(format!("{stem}.h5")).display()
        )));
    }
    let give = "give the OUT.h5 a `stickslip run` wrote";
    match PathKind::of(path) {
        Some(PathKind::Directory) => Err(InputError(format!(
            "{name} is a directory; give a results file in it, the OUT.h5 a `stickslip run` wrote"
        ))),
        Some(PathKind::Special) => Err(InputError(format!(
            "{name} is not a regular file (a device, FIFO or socket); {give}"
        ))),
        Some(PathKind::Missing) => Err(InputError(format!("{name}: no such results file; {give}"))),
        None => Ok(()),
    }
}

/// What a path given as a results file is, where it is no regular file.
enum PathKind {
    Missing,
    Directory,
    /// A device, FIFO or socket.
    Special,
}

impl PathKind {
    /// `None` for a regular file (or a link to one).
    fn of(path: &Path) -> Option<PathKind> {
        match std::fs::metadata(path) {
            Err(_) => Some(PathKind::Missing),
            Ok(m) if m.is_dir() => Some(PathKind::Directory),
            Ok(m) if !m.is_file() => Some(PathKind::Special),
            Ok(_) => None,
        }
    }
}

/// Opens the results file `path` for a command that reads it after its
/// run and writes beside it (`stickslip stress`, `stickslip views`): it
/// must exist (not be the XDMF beside it), no run may be writing it (nor,
/// with `readers_too`, a reader hold it open), and it must be HDF5 written
/// by `stickslip run`. Returns it with a shared lock that keeps runs off it
/// meanwhile.
///
/// # Errors
/// The [`InputError`] naming the file and what to give instead.
pub(crate) fn open_finished(
    path: &Path,
    readers_too: bool,
) -> Result<(RunLock, hdf5::File), InputError> {
    check_results_path(path)?;
    let name = path.display();
    if readers_too && in_use(path) {
        return Err(InputError(format!(
            "{name}: a run or a reader has it open; wait for the run to end (or close the reader) and run this again"
        )));
    }
    if being_written(path) {
        return Err(InputError(format!(
            "{name}: a run is writing it; wait for the run to end (or stop it with Ctrl-C) and run this again"
        )));
    }
    let lock = RunLock::shared(path)?;
    let f = hdf5::File::open(path).map_err(|e| {
        InputError(format!(
            "{name}: cannot open it as HDF5: {e}; give a results file written by `stickslip run`"
        ))
    })?;
    if crate::output::text_attr(&f, "program").ok().as_deref() != Some("stickslip") {
        return Err(InputError(format!(
            "{name} was not written by `stickslip run` (no program = \"stickslip\" attribute)"
        )));
    }
    Ok((lock, f))
}

/// The message for a results file another process has open.
fn busy(path: &Path) -> InputError {
    InputError(format!(
        "{} is open in another process (a run still writing it, or a reader such as h5py or ParaView); \
         wait for it or close it, or write elsewhere with -o",
        path.display()
    ))
}

/// Claims `out` for a new run: removes an old results file and its XDMF
/// (rather than letting HDF5 truncate a file a reader may hold; refused
/// while another process has it open), creates the file anew and takes the
/// run's lock on it before HDF5 writes a byte, so that of two runs started
/// on one file at once one gets it and the other is told. Exit code 2 with
/// what to do, not HDF5's message.
///
/// # Errors
/// The [`InputError`] naming the file and what to do.
pub(crate) fn claim(out: &Path) -> Result<RunLock, InputError> {
    // An XDMF half written when `stickslip views` was killed, and the
    // stresses and views of the old run (`stickslip stress`, `stickslip
    // views`), which the new one does not have (best effort).
    for stale in [
        "xdmf.part",
        "stress.h5.part",
        "contact.xdmf",
        "contact.xdmf.part",
    ] {
        let _ = std::fs::remove_file(out.with_extension(stale));
    }
    // Only files these commands wrote for `out` ([`check_output`] refused
    // any other by their names).
    for kind in [Companion::Stress, Companion::Views] {
        if foreign_companion(out, kind).is_none() {
            let _ = std::fs::remove_file(kind.path(out));
        }
    }
    let mut old = None;
    for path in [out.to_path_buf(), out.with_extension("xdmf")] {
        if path.exists() {
            if in_use(&path) {
                return Err(busy(&path));
            }
            if path == out {
                old = std::fs::File::open(&path).ok();
            }
            std::fs::remove_file(&path).map_err(|e| {
                InputError(format!(
                    "cannot replace {}: {e}; remove it yourself, or write elsewhere with -o",
                    path.display()
                ))
            })?;
        }
    }
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(out)
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::AlreadyExists {
                InputError(format!(
                    "{} was created by another process just now (a second run on the same file?); \
                     wait for it, or write elsewhere with -o",
                    out.display()
                ))
            } else {
                InputError(format!(
                    "cannot create {}: {e}; choose a writable place with -o",
                    out.display()
                ))
            }
        })?;
    let mut lock = RunLock::on(f, out)?;
    lock.freeing = old.and_then(free_aside);
    // Another run's claim may have removed our new file between its
    // creation and the lock: then the name is that run's.
    use std::os::unix::fs::MetadataExt;
    let ours = lock._file.metadata().map(|m| (m.dev(), m.ino())).ok();
    let named = std::fs::metadata(out).map(|m| (m.dev(), m.ino())).ok();
    if ours.is_none() || ours != named {
        return Err(InputError(format!(
            "{} was taken by another run started at the same time; wait for it, or write elsewhere with -o",
            out.display()
        )));
    }
    Ok(lock)
}

/// Bytes free to an unprivileged writer on the file system of `path`'s
/// directory, where it can be asked.
pub fn free_bytes(path: &Path) -> Option<u64> {
    crate::sys::free_bytes_at(dir_of(path))
}

/// The directory `path` is in (`.` for a bare file name).
pub(crate) fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}
