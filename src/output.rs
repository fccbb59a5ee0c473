//! Fallible terminal output. User-facing lines go through [`outln!`](crate::outln) and
//! [`errln!`](crate::errln) instead of `println!` / `eprintln!`, which panic (exit 101, "failed
//! printing to stdout") when a stream cannot be written: `>/dev/full`, a full disk behind
//! `> file`, a closed terminal.
//!
//! * [`outln!`](crate::outln) writes one line to stdout, flushes it, and returns
//!   `Result<(), String>`. Stdout carries a command's result (`diff`'s numbers, `bench`'s
//!   figures), so losing it is an error: the caller propagates it and the process exits 1.
//! * [`errln!`](crate::errln) writes one line to stderr and ignores failures: diagnostics must
//!   never turn a run into a failure or a panic, and when stderr itself is gone there is nowhere
//!   left to report anything. The exit status still tells the story.
//! * A closed pipe on stdout (`forecast diff … | head`) ends the process quietly with
//!   [`EXIT_BROKEN_PIPE`], the status a shell shows for a tool killed by SIGPIPE. The binary keeps
//!   Rust's ignored SIGPIPE, so a closed *stderr* (`forecast render … 2>&1 | true`) only loses
//!   the messages: the render goes on and writes its files.
//!
//! Exit statuses of the binary: [`EXIT_OK`], [`EXIT_ERROR`], [`EXIT_USAGE`] (clap's own
//! convention for a command line it cannot parse); a panic (101) is always a bug.

use std::fmt;
use std::io::{self, Write};

/// The command did what was asked.
pub const EXIT_OK: u8 = 0;
/// The command ran and failed: unreadable or invalid input (scene, image, checkpoint), an option
/// value refused after parsing (it names the option), an output that could not be written, a
/// failed check (`diff --half0/--half1`, `stability`), or stdout that could not be written.
pub const EXIT_ERROR: u8 = 1;
/// clap could not parse the command line (unknown command or option, missing or malformed
/// value); clap prints the usage.
pub const EXIT_USAGE: u8 = 2;

/// 128 + SIGPIPE: the status of a process whose stdout reader has gone (see the module docs).
pub const EXIT_BROKEN_PIPE: u8 = 141;

/// Writes `args` and a newline to stdout and flushes; an error names the stream. A closed pipe
/// ends the process at once, quietly, with [`EXIT_BROKEN_PIPE`] (nobody is left to read a result).
pub fn stdout_line(args: fmt::Arguments<'_>) -> Result<(), String> {
    match write_line(&mut io::stdout().lock(), args) {
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => std::process::exit(EXIT_BROKEN_PIPE.into()),
        r => r.map_err(|e| format!("cannot write to stdout: {e}")),
    }
}

/// Writes `args` and a newline to stderr; failures are ignored (see the module docs).
pub fn stderr_line(args: fmt::Arguments<'_>) {
    let _ = write_line(&mut io::stderr().lock(), args);
}

/// One line to any writer, flushed, so that a failure surfaces here and not at exit. The line is
/// formatted first and handed over in one `write` where the OS allows, so that a line printed
/// just before the process ends (the MPI watchdog's, before `MPI_Abort`) reaches `mpirun`'s
/// forwarding whole.
pub fn write_line(w: &mut dyn Write, args: fmt::Arguments<'_>) -> io::Result<()> {
    w.write_all(format!("{args}\n").as_bytes())?;
    w.flush()
}

/// `println!` that returns `Result<(), String>` instead of panicking (see [`crate::output`]).
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::output::stdout_line(format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics and ignores write errors (see [`crate::output`]).
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::output::stderr_line(format_args!($($arg)*))
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A writer that accepts `room` bytes, then fails like a full disk.
    struct Full {
        room: usize,
        got: Vec<u8>,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::Error::from_raw_os_error(28)); // ENOSPC
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.got.extend_from_slice(&buf[..n]);
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_full_writer_is_an_error_not_a_panic() {
        let mut w = Full { room: 100, got: Vec::new() };
        write_line(&mut w, format_args!("a {}", 1)).unwrap();
        assert_eq!(w.got, b"a 1\n");
        let mut w = Full { room: 3, got: Vec::new() };
        assert!(write_line(&mut w, format_args!("abcdef")).is_err());
    }
}
