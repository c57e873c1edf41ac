//! The commands' text on stdout and stderr, written without panicking:
//! `print!` and `eprint!` panic when the write fails (a full disk behind
//! `> FILE`, a closed descriptor), exit 101 with a backtrace. A closed
//! pipe ends the commands other than `run` before they see the error
//! (SIGPIPE, main.rs), as it ends other Unix tools.

use std::fmt;
use std::io::{self, Write};

/// A write to stdout or stderr that failed: main.rs exits 1 on it, with a
/// message unless the stream was a closed pipe (or the message cannot be
/// written either).
#[derive(Debug)]
pub struct WriteError {
    /// `"stdout"` or `"stderr"`.
    pub stream: &'static str,
    /// What the system said.
    pub error: io::Error,
}

impl WriteError {
    /// A pipe whose reader is gone (`| head`): nothing to say.
    pub fn broken_pipe(&self) -> bool {
        self.error.kind() == io::ErrorKind::BrokenPipe
    }
}

impl fmt::Display for WriteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "cannot write to {}: {}; make room on the disk it goes to, or send it elsewhere",
            self.stream, self.error
        )
    }
}

impl std::error::Error for WriteError {}

/// Writes `text` to stdout and flushes it.
///
/// # Errors
/// The write failed.
pub fn out(text: &str) -> Result<(), WriteError> {
    write_all(io::stdout().lock(), "stdout", text)
}

/// Writes `text` to stderr.
///
/// # Errors
/// The write failed.
pub fn err(text: &str) -> Result<(), WriteError> {
    write_all(io::stderr().lock(), "stderr", text)
}

fn write_all(mut w: impl Write, stream: &'static str, text: &str) -> Result<(), WriteError> {
    w.write_all(text.as_bytes())
        .and_then(|()| w.flush())
        .map_err(|error| WriteError { stream, error })
}
