//! The frontend's error type: every message names the file, and where it can the line, column
//! and field, and maps to a process exit code.

use std::fmt;

/// A message as shown: control characters escaped, at most [`MAX_MESSAGE_CHARS`] characters.
fn bounded(m: &str) -> String {
    crate::text::bounded_lines(m, MAX_MESSAGE_CHARS, true)
}

use crate::text::MAX_MESSAGE_CHARS;
use std::path::{Path, PathBuf};

/// Exit code for errors in input data or I/O.
pub const EXIT_ERROR: u8 = 1;
/// Exit code for command-line usage errors (clap uses the same).
pub const EXIT_USAGE: u8 = 2;
/// Exit code when a cross-check finds more genuine mismatches than allowed.
pub const EXIT_MISMATCH: u8 = 3;
/// Exit code when stdout is a closed pipe: 128 + SIGPIPE (13), what a shell reports for
/// `ls | head` when `ls` is killed by the signal, so `set -o pipefail` scripts see the same.
pub const EXIT_BROKEN_PIPE: u8 = 141;

/// Where in an input file an error is.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
    /// The field (for example `objects[2].radius`), when known.
    pub field: Option<String>,
}

impl Location {
    /// A location naming only the file.
    pub fn file(file: impl AsRef<Path>) -> Self {
        Self {
            file: file.as_ref().to_path_buf(),
            ..Self::default()
        }
    }

    /// Adds a 1-based line.
    #[must_use]
    pub fn line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }

    /// Adds a 1-based column.
    #[must_use]
    pub fn column(mut self, column: usize) -> Self {
        self.column = Some(column);
        self
    }

    /// Adds a field name.
    #[must_use]
    pub fn field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        if let Some(field) = &self.field {
            write!(f, ": field `{field}`")?;
        }
        Ok(())
    }
}

/// A frontend error.
#[derive(Debug)]
pub enum Error {
    /// Bad input data (scene file, OBJ, mesh the core rejects), with its location.
    Input {
        /// Where.
        at: Location,
        /// What is wrong.
        message: String,
    },
    /// An I/O failure on a path.
    Io {
        /// The path being read or written.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A command-line argument that parsed but makes no sense.
    Usage(String),
    /// A cross-check found more genuine mismatches than allowed.
    Mismatch(String),
    /// Anything else (for example an unavailable optional backend).
    Other(String),
    /// Stdout is a closed pipe (the reader is gone): nothing to report, stop quietly.
    BrokenPipe,
}

impl Error {
    /// An input error at `at`.
    pub fn input(at: Location, message: impl Into<String>) -> Self {
        Self::Input {
            at,
            message: message.into(),
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Usage(_) => EXIT_USAGE,
            Self::Mismatch(_) => EXIT_MISMATCH,
            Self::BrokenPipe => EXIT_BROKEN_PIPE,
            _ => EXIT_ERROR,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Input { at, message } => write!(f, "{at}: {}", bounded(message)),
            Self::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Self::Usage(m) => f.write_str(&bounded(m)),
            // Reports halfray composes itself, shown whole.
            Self::Mismatch(m) | Self::Other(m) => f.write_str(m),
            Self::BrokenPipe => f.write_str("stdout is a closed pipe"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Result alias of the frontend.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn location_formats_file_line_column_field() {
        let at = Location::file("s.toml")
            .line(4)
            .column(11)
            .field("camera.fov");
        let e = Error::input(at, "must be finite");
        assert_eq!(
            e.to_string(),
            "s.toml:4:11: field `camera.fov`: must be finite"
        );
        assert_eq!(e.exit_code(), EXIT_ERROR);
        assert_eq!(Error::Mismatch("x".into()).exit_code(), EXIT_MISMATCH);
    }
}
