//! Printing to stdout without panicking: a closed pipe ends the program quietly, as
//! `ls | head` does ([`Error::BrokenPipe`]), and any other write error (`> /dev/full`) is an
//! I/O error on `<stdout>` with a non-zero exit.
//!
//! Code that still prints with `print!`/`println!` (which panic on a write error) is covered by
//! [`install_print_panic_guard`], which turns exactly those panics into the same outcomes.

use crate::error::{EXIT_BROKEN_PIPE, EXIT_ERROR, Error, Result};
use std::io::{self, Write};

/// The name stdout has in error messages.
pub const STDOUT_NAME: &str = "<stdout>";

/// The error for a failed write to stdout.
pub fn stdout_error(e: io::Error) -> Error {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Error::BrokenPipe
    } else {
        Error::io(STDOUT_NAME, e)
    }
}

/// Writes `text` to stdout and flushes it.
pub fn print_out(text: &str) -> Result<()> {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// The prefix of the standard library's panic message when `print!` fails.
const PRINT_PANIC_PREFIX: &str = "failed printing to stdout: ";

/// Makes a `print!` that fails end the process like [`print_out`] would: silently with
/// [`EXIT_BROKEN_PIPE`] on a closed pipe, with `error: <stdout>: …` and [`EXIT_ERROR`]
/// otherwise. Every other panic goes to the previous hook. Call once, from `main`.
pub fn install_print_panic_guard() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied());
        match msg.and_then(|m| m.strip_prefix(PRINT_PANIC_PREFIX)) {
            Some(cause) if cause.starts_with("Broken pipe") => {
                crate::outputs::temp::remove_live_temp_files();
                std::process::exit(i32::from(EXIT_BROKEN_PIPE));
            }
            Some(cause) => {
                crate::outputs::temp::remove_live_temp_files();
                eprintln!("error: {STDOUT_NAME}: {cause}");
                std::process::exit(i32::from(EXIT_ERROR));
            }
            None => previous(info),
        }
    }));
}
