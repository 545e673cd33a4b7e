//! Standard output that ends the program cleanly when it cannot be written.
//!
//! `println!` panics when stdout is a closed pipe (`clothlab sim … | head -1`) or a full
//! disk (`> /dev/full`). Every line a command prints goes through [`outln!`] instead,
//! which returns the write's error as [`OutputError`]; `main` ends quietly with status
//! 141 (what a shell reports for a program killed by SIGPIPE, as `head`'s other writers
//! are) on a closed pipe, and with one line on any other write error.

use std::io::Write;

/// A line could not be written to standard output.
#[derive(Debug)]
pub struct OutputError(pub std::io::Error);

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot write to standard output: {}", self.0)
    }
}

impl std::error::Error for OutputError {}

impl From<std::io::Error> for OutputError {
    fn from(e: std::io::Error) -> Self {
        Self(e)
    }
}

impl OutputError {
    /// Whether the reader has gone (a closed pipe): the program ends without a word.
    pub fn is_closed_pipe(&self) -> bool {
        self.0.kind() == std::io::ErrorKind::BrokenPipe
    }
}

/// Writes `args` and a newline to standard output, flushed (a line is the unit the reader
/// waits for, as `println!` gives it).
pub fn line(args: std::fmt::Arguments<'_>) -> Result<(), OutputError> {
    let mut out = std::io::stdout().lock();
    out.write_fmt(args)?;
    out.write_all(b"\n")?;
    out.flush()?;
    Ok(())
}

/// `println!` that returns [`OutputError`] instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::out::line(format_args!($($arg)*))
    };
}
pub(crate) use outln;

/// The exit status of a program whose standard output was closed: 128 + SIGPIPE.
pub const CLOSED_PIPE_STATUS: u8 = 141;
