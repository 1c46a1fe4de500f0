//! Printing to stdout without panicking: a closed pipe ends the program quietly, as
//! `ls | head` does ([`Error::BrokenPipe`]), and any other write error (`> /dev/full`) is an
//! I/O error on `<stdout>` with a non-zero exit.
//!
//! Code that still prints with `print!`/`println!` (which panic on a write error) is covered by
//! [`install_print_panic_guard`], which turns exactly those panics into the same outcomes.
//!
//! A command's summaries (tables, totals, "wrote …" lines) go to stdout, unless one of its
//! outputs is stdout (`-o -`, `--json /dev/stdout`): then they go to stderr, so that the
//! output's bytes are all that stdout carries ([`print_out`], [`say!`](crate::say)). A
//! summary that cannot be written there ends the command as on stdout: a closed pipe
//! quietly, any other write error with [`EXIT_ERROR`] and no message (there is nowhere to
//! print it).
//!
//! Everything else on stderr is a diagnostic (progress, `warning:` and `note:` lines,
//! [`note!`](crate::note)): one that cannot be written is lost and the command goes on, its
//! outcome its own, as coreutils do; a command whose output is a file does not fail for a
//! full or closed stderr. The final `error: …` line of a failed command is written with
//! [`eprint_error`], which keeps the command's own exit status when stderr fails. Outside
//! tests, `eprint!`/`eprintln!` are refused by clippy (`print_stderr`, in `lib.rs`): stderr
//! is written only through these.

use crate::error::{EXIT_BROKEN_PIPE, EXIT_ERROR, Error, Result};
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once an output of this process is stdout ([`stdout_carries_output`]).
static STDOUT_CARRIES_OUTPUT: AtomicBool = AtomicBool::new(false);

/// Records that one of the command's outputs is stdout: every summary printed from now on goes
/// to stderr. Called when such an output is reserved, before any work.
pub fn stdout_carries_output() {
    STDOUT_CARRIES_OUTPUT.store(true, Ordering::Relaxed);
}

fn summaries_to_stderr() -> bool {
    STDOUT_CARRIES_OUTPUT.load(Ordering::Relaxed)
}

/// Prints a summary (`format!` arguments) where [`print_out`] would: stdout, or stderr once an
/// output is stdout. A failed write ends the process as a failed `print!` does
/// ([`install_print_panic_guard`]).
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::console::say_args(format_args!($($arg)*))
    };
}

/// [`say!`](crate::say) with a newline, as `println!`.
#[macro_export]
macro_rules! sayln {
    () => {
        $crate::console::say_args(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::console::say_args(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes a diagnostic line (`format!` arguments; a newline is added) to stderr; a failed
/// write is ignored (see the module docs). For summaries, [`say!`](crate::say).
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::console::note_args(format_args!($($arg)*))
    };
}

/// The function behind [`note!`](crate::note).
pub fn note_args(args: std::fmt::Arguments<'_>) {
    let _ = writeln!(io::stderr().lock(), "{args}");
}

/// The function behind [`say!`](crate::say).
// A summary on stderr fails as one on stdout does: `install_print_panic_guard`.
#[allow(clippy::print_stderr)]
pub fn say_args(args: std::fmt::Arguments<'_>) {
    if summaries_to_stderr() {
        eprint!("{args}");
    } else {
        print!("{args}");
    }
}

/// The name stdout has in error messages.
pub const STDOUT_NAME: &str = "<stdout>";

/// An output path as named in error messages: [`STDOUT_NAME`] for `-` (stdout, which no file
/// of that name stands for), the path itself otherwise (`/dev/stdout` names a file).
#[must_use]
pub fn output_name(path: &std::path::Path) -> &std::path::Path {
    if path == std::path::Path::new("-") {
        std::path::Path::new(STDOUT_NAME)
    } else {
        path
    }
}

/// The error for a failed write to stdout.
pub fn stdout_error(e: io::Error) -> Error {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Error::BrokenPipe
    } else {
        Error::io(STDOUT_NAME, e)
    }
}

/// Writes the summary `text` to stdout (to stderr once an output is stdout, see the module
/// docs) and flushes it.
pub fn print_out(text: &str) -> Result<()> {
    let (mut stream, failed): (Box<dyn Write>, fn(io::Error) -> Error) = if summaries_to_stderr() {
        (Box::new(io::stderr().lock()), |e| match e.kind() {
            io::ErrorKind::BrokenPipe => Error::BrokenPipe,
            _ => Error::io("<stderr>", e),
        })
    } else {
        (Box::new(io::stdout().lock()), stdout_error)
    };
    stream
        .write_all(text.as_bytes())
        .and_then(|()| stream.flush())
        .map_err(failed)
}

/// Ends a command line that did not parse: help and version text go to stdout through
/// [`print_out`] (so `--help > /dev/full` is an error, exit 1, not a silent 0); usage errors
/// to stderr, exit 2, as clap does.
#[must_use]
pub fn clap_exit(e: &clap::Error) -> std::process::ExitCode {
    if e.use_stderr() {
        let _ = e.print();
        return std::process::ExitCode::from(crate::error::EXIT_USAGE);
    }
    match print_out(&e.render().to_string()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(Error::BrokenPipe) => std::process::ExitCode::from(EXIT_BROKEN_PIPE),
        Err(err) => {
            eprint_error(&err);
            std::process::ExitCode::from(EXIT_ERROR)
        }
    }
}

/// The prefix of the standard library's panic message when `print!` fails.
const PRINT_PANIC_PREFIX: &str = "failed printing to stdout: ";

/// The prefix of the standard library's panic message when `eprint!` fails.
const EPRINT_PANIC_PREFIX: &str = "failed printing to stderr: ";

/// Writes a failed command's `error: {e}` line to stderr; a failed write is ignored, so
/// that the command's exit status (the caller's) is what the process ends with even when
/// stderr is full or closed.
pub fn eprint_error(e: &dyn std::fmt::Display) {
    crate::note!("error: {e}");
}

/// Makes a `print!` or `eprint!` (a summary, [`say!`](crate::say)) that fails end the process
/// like [`print_out`] would: silently with [`EXIT_BROKEN_PIPE`] on a closed pipe, otherwise
/// with [`EXIT_ERROR`] (after `error: <stdout>: …` on stderr for stdout; nothing for stderr,
/// which is what failed).
/// Temporary output files are removed first, so nothing is half-written. Every other panic
/// goes to the previous hook. Call once, from `main`.
pub fn install_print_panic_guard() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied());
        let failed = msg.and_then(|m| {
            m.strip_prefix(PRINT_PANIC_PREFIX)
                .map(|cause| (cause, true))
                .or_else(|| m.strip_prefix(EPRINT_PANIC_PREFIX).map(|c| (c, false)))
        });
        let Some((cause, stdout)) = failed else {
            return previous(info);
        };
        crate::outputs::temp::remove_live_temp_files();
        if cause.starts_with("Broken pipe") {
            std::process::exit(i32::from(EXIT_BROKEN_PIPE));
        }
        if stdout {
            let _ = writeln!(io::stderr().lock(), "error: {STDOUT_NAME}: {cause}");
        }
        std::process::exit(i32::from(EXIT_ERROR));
    }));
}
