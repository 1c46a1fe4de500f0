//! The frontend's error type: every message names the file, and where it can the line, column
//! and field, and maps to a process exit code. Every string from outside (paths, tokens,
//! strings read from JSON) is escaped when shown ([`crate::text`]): no escape sequence or line
//! break of an input reaches the terminal.

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

    /// Adds where `serde_json` reported `e`: its line (counted from the line already set,
    /// the first line of the JSON text in the file, if any) and column. Nothing is added
    /// where `e` has no position (line 0: an error of the data's shape found after the whole
    /// value was read, such as no variant of an untagged enum matching).
    #[must_use]
    pub fn json_position(self, e: &serde_json::Error) -> Self {
        if e.line() == 0 {
            return self;
        }
        let line = self.line.map_or(e.line(), |first| first + e.line() - 1);
        // serde_json counts the characters consumed on the line: 0 when it stopped before the
        // line's first (the end of the text after a line break), which is column 1 here.
        self.line(line).column(e.column().max(1))
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
        write!(f, "{}", crate::text::path(&self.file))?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        if let Some(field) = &self.field {
            // A field may be the input's own text (a scene's key, a JSON path): escaped.
            write!(f, ": field `{}`", crate::text::escaped(field))?;
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
    /// Encoding an output (JSON, PNG) failed.
    Encode {
        /// What was being encoded ("the JSON report").
        what: &'static str,
        /// The encoder's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A command needs an optional backend this binary was built without.
    Unavailable {
        /// The cargo feature that brings it.
        feature: &'static str,
        /// How to build with it.
        hint: &'static str,
    },
    /// Meshes of a multi-mesh run that could not be processed (the others were).
    MeshesFailed {
        /// Each failed mesh's path and error.
        failed: Vec<(String, String)>,
        /// Meshes in the run.
        total: usize,
    },
    /// Building an acceleration structure failed.
    Bvh(halfray_core::bvh::BvhError),
    /// The worker threads could not be started.
    Threads(rayon::ThreadPoolBuildError),
    /// Embree refused or failed (device, scene, layout).
    #[cfg(feature = "embree")]
    Embree(crate::embree::EmbreeError),
    /// An error about one input file, with the file named.
    InFile {
        /// The file.
        path: PathBuf,
        /// What went wrong with it.
        source: Box<Error>,
    },
    /// A check of halfray's own results failed: a bug to report, not bad input.
    Internal {
        /// What failed to hold.
        what: String,
        /// The error that showed it, if any.
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
    /// Stdout is a closed pipe (the reader is gone): nothing to report, stop quietly.
    BrokenPipe,
}

impl Error {
    /// An encoding failure of `what`.
    pub fn encode(
        what: &'static str,
        source: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> Self {
        Self::Encode {
            what,
            source: source.into(),
        }
    }

    /// An internal check that failed, with the error that showed it.
    pub fn internal(
        what: impl Into<String>,
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    ) -> Self {
        Self::Internal {
            what: what.into(),
            source,
        }
    }

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
            Self::Io { path, source } => write!(
                f,
                "{}: {}",
                crate::text::path(path),
                crate::text::escaped(&source.to_string())
            ),
            Self::Usage(m) => f.write_str(&bounded(m)),
            // Reports halfray composes itself, shown whole.
            Self::Mismatch(m) => f.write_str(m),
            Self::Encode { what, source } => write!(f, "encoding {what}: {source}"),
            Self::Unavailable { feature, hint } => {
                write!(
                    f,
                    "halfray was built without the `{feature}` feature: {hint}"
                )
            }
            Self::MeshesFailed { failed, total } => {
                write!(
                    f,
                    "{} of {total} meshes could not be checked:",
                    failed.len()
                )?;
                for (path, error) in failed {
                    // An error that already starts with its file is printed as it is.
                    let (path, error) = (crate::text::escaped(path), crate::text::escaped(error));
                    if error.starts_with(&format!("{path}:")) {
                        write!(f, "\n  {error}")?;
                    } else {
                        write!(f, "\n  {path}: {error}")?;
                    }
                }
                Ok(())
            }
            Self::Bvh(e) => write!(f, "building the BVH: {e}"),
            Self::Threads(e) => write!(f, "starting the worker threads: {e}"),
            #[cfg(feature = "embree")]
            Self::Embree(e) => write!(f, "embree: {e}"),
            Self::InFile { path, source } => write!(f, "{}: {source}", crate::text::path(path)),
            Self::Internal { what, source } => {
                write!(f, "internal error: {what}")?;
                if let Some(e) = source {
                    write!(f, " ({e})")?;
                }
                f.write_str("; please report this")
            }
            Self::BrokenPipe => f.write_str("stdout is a closed pipe"),
        }
    }
}

#[cfg(feature = "embree")]
impl From<crate::embree::EmbreeError> for Error {
    fn from(e: crate::embree::EmbreeError) -> Self {
        Self::Embree(e)
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Encode { source, .. } => Some(source.as_ref()),
            Self::Bvh(e) => Some(e),
            Self::Threads(e) => Some(e),
            #[cfg(feature = "embree")]
            Self::Embree(e) => Some(e),
            Self::InFile { source, .. } => Some(source.as_ref()),
            Self::Internal { source, .. } => source.as_deref().map(|e| e as _),
            _ => None,
        }
    }
}

/// `e`'s message without the ` at line L column C` that `serde_json` appends: the message of an
/// error whose [`Location::json_position`] already says where (else the place was said twice).
/// serde's `expected struct Name` (`… with N elements`), which names a type of ours, reads
/// `expected a JSON object`; the input's own text that serde quotes (an unknown variant) is
/// escaped ([`crate::text::escaped`]).
#[must_use]
pub fn json_message(e: &serde_json::Error) -> String {
    let text = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let message = match text.strip_suffix(&suffix) {
        Some(message) if e.line() != 0 => message,
        _ => &text,
    };
    // serde quotes the input's own text raw in some messages (an unknown variant or field).
    let message = &crate::text::escaped(message);
    match message.split_once("expected struct ") {
        Some((head, tail)) => {
            // The type's name, then serde's ` with N element(s)` for a sequence.
            let rest = tail.split_once(' ').map_or("", |(_, rest)| rest);
            let rest = match rest.strip_prefix("with ") {
                Some(count) => count.split_once(' ').map_or("", |(_, r)| r),
                None => rest,
            };
            let rest = rest
                .strip_prefix("elements")
                .or_else(|| rest.strip_prefix("element"))
                .unwrap_or(rest);
            format!("{head}expected a JSON object{rest}")
        }
        None => message.to_string(),
    }
}

/// Result alias of the frontend.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    /// A JSON syntax error is located where the parser stopped, in the file's lines; an error
    /// of the data's shape that names no position gets the file alone (never `:0:0`).
    #[test]
    fn json_errors_are_located_where_serde_knows_the_position() {
        let syntax = serde_json::from_str::<Vec<u32>>("[1,\n 2,\n x]").unwrap_err();
        let at = |l: Location| l.to_string();
        assert_eq!(
            at(Location::file("r.json").json_position(&syntax)),
            "r.json:3:2"
        );
        assert_eq!(
            at(Location::file("r.jsonl").line(7).json_position(&syntax)),
            "r.jsonl:9:2"
        );
        #[derive(serde::Deserialize, Debug)]
        #[serde(untagged)]
        #[allow(dead_code)]
        enum Either {
            A { a: u32 },
            B { b: u32 },
        }
        let shape = serde_json::from_str::<Either>("{\"c\": 1}").unwrap_err();
        assert_eq!(shape.line(), 0, "{shape}");
        assert_eq!(at(Location::file("r.json").json_position(&shape)), "r.json");
        assert_eq!(
            at(Location::file("r.jsonl").line(7).json_position(&shape)),
            "r.jsonl:7"
        );
        // Stopped at a line's start (serde's column 0): column 1, columns being 1-based.
        let at_start = serde_json::from_str::<Vec<u32>>("[1,\n").unwrap_err();
        assert_eq!((at_start.line(), at_start.column()), (2, 0), "{at_start}");
        assert_eq!(
            at(Location::file("r.json").json_position(&at_start)),
            "r.json:2:1"
        );
        // The message says the place once: in the location, not again in serde's words.
        assert_eq!(json_message(&syntax), "expected value");
        assert!(
            syntax.to_string().ends_with("at line 3 column 2"),
            "{syntax}"
        );
        assert_eq!(json_message(&shape), shape.to_string());
    }

    /// serde's words for a value that is not an object name the Rust type it was read into;
    /// the message names the JSON's shape instead, and keeps the rest of serde's words.
    #[test]
    fn json_messages_name_no_type_of_ours() {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct ReportView {
            a: u32,
            b: u32,
        }
        for (json, want) in [
            (
                "\"x\"",
                "invalid type: string \"x\", expected a JSON object",
            ),
            ("[]", "invalid length 0, expected a JSON object"),
            ("[1]", "invalid length 1, expected a JSON object"),
            ("{\"a\": [1]}", "invalid type: sequence, expected u32"),
        ] {
            let e = serde_json::from_str::<ReportView>(json).unwrap_err();
            assert_eq!(json_message(&e), want, "{json}: serde said {e}");
        }
    }

    /// An unknown variant is quoted by serde as the input has it: the message escapes it, so
    /// no JSON string puts a line break or a terminal escape into a message.
    #[test]
    fn json_messages_escape_the_text_they_quote() {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        enum Kind {
            A,
        }
        let e = serde_json::from_str::<Kind>("\"x\\u001b[2J\\nerror: forged\"").unwrap_err();
        let m = json_message(&e);
        assert!(
            m.starts_with("unknown variant `x\\u{1b}[2J\\nerror: forged`"),
            "{m:?}"
        );
        assert!(!m.contains('\u{1b}') && !m.contains('\n'), "{m:?}");
    }

    #[test]
    fn typed_errors_name_what_failed_and_keep_their_source() {
        use std::error::Error as _;
        let json = serde_json::from_str::<u32>("x").unwrap_err();
        let e = Error::encode("the JSON report", json);
        assert!(
            e.to_string().starts_with("encoding the JSON report: "),
            "{e}"
        );
        assert!(e.source().is_some());
        let e = Error::InFile {
            path: "m.obj".into(),
            source: Box::new(Error::Bvh(halfray_core::bvh::BvhError::TooManyPrimitives {
                count: 7,
            })),
        };
        assert!(
            e.to_string()
                .starts_with("m.obj: building the BVH: too many primitives"),
            "{e}"
        );
        assert!(e.source().and_then(|s| s.source()).is_some());
        let e = Error::MeshesFailed {
            failed: vec![
                ("a.obj".into(), "bad".into()),
                ("b.obj".into(), "worse".into()),
            ],
            total: 5,
        };
        assert_eq!(
            e.to_string(),
            "2 of 5 meshes could not be checked:\n  a.obj: bad\n  b.obj: worse"
        );
        // An error naming its file already is not prefixed with it a second time.
        let e = Error::MeshesFailed {
            failed: vec![
                (
                    "a.obj".into(),
                    "a.obj:3: field `y`: `nan` is not finite".into(),
                ),
                ("b.obj".into(), "b.obj.bak: unrelated".into()),
            ],
            total: 2,
        };
        assert_eq!(
            e.to_string(),
            "2 of 2 meshes could not be checked:\n  a.obj:3: field `y`: `nan` is not finite\n  \
             b.obj: b.obj.bak: unrelated"
        );
        let e = Error::internal("counts disagree", None);
        assert_eq!(
            e.to_string(),
            "internal error: counts disagree; please report this"
        );
        assert_eq!(e.exit_code(), EXIT_ERROR);
        let e = Error::Unavailable {
            feature: "embree",
            hint: "build with it",
        };
        assert_eq!(
            e.to_string(),
            "halfray was built without the `embree` feature: build with it"
        );
    }

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
