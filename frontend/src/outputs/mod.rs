//! Output files: where a command may write, checked before it starts working, and how the
//! bytes get there without clobbering what is not ours ([`file`](mod@file)).
//!
//! [`reserve_outputs`] is what every command calls first: each output location is checked
//! (and a regular file's temporary file created, see [`OutputFile::reserve`]), and an output
//! that is one of the inputs, or two outputs that are the same file, are refused as usage
//! errors. "Same file" is file identity ([`identity`]: device and inode, symlinks followed;
//! for a file not created yet, its canonical folder and name), not the spelling of the path.
//! A character device (`/dev/null`) may be several outputs ([`OutputFile::repeat_id`]).

pub mod file;
pub mod identity;
pub mod replace;
pub mod target;
pub mod temp;
pub mod xattr;

pub use file::{OutputFile, write_together};
pub use identity::{FileId, file_id, first_repeat};

use crate::error::{Error, Result};
use crate::text;
use std::path::Path;

/// A path a command reads or writes, with the option (or role) that named it, for messages
/// (`-o`, `--stats-json`, `scene`, `mesh.bunny.file`).
#[derive(Clone, Copy, Debug)]
pub struct Named<'a> {
    /// The option or role.
    pub name: &'a str,
    /// The path.
    pub path: &'a Path,
}

impl<'a> Named<'a> {
    /// `path`, named by `name`.
    pub fn new(name: &'a str, path: &'a Path) -> Self {
        Self { name, path }
    }
}

/// Reserves every output (see [`OutputFile::reserve`]) and refuses outputs that are inputs or
/// each other (but for a character device, [`OutputFile::repeat_id`]); `force` allows
/// replacing read-only, other users' and hard-linked files. The outputs come back in the
/// order given.
pub fn reserve_outputs(
    outputs: &[Named<'_>],
    inputs: &[Named<'_>],
    force: bool,
) -> Result<Vec<OutputFile>> {
    let mut reserved: Vec<OutputFile> = Vec::with_capacity(outputs.len());
    for out in outputs {
        // An input first: a hard-linked input is "the input", not "has 2 hard links".
        if let Ok(id) = file_id(out.path) {
            refuse_input(out, &id, inputs)?;
        }
        reserved.push(OutputFile::reserve(out.path, force)?);
    }
    // Temporary files reserved so far are removed when `reserved` drops on refusal.
    if let Some((j, k)) = first_repeat(reserved.iter().map(OutputFile::repeat_id)) {
        let (e, out) = (outputs[j], outputs[k]);
        return Err(Error::Usage(format!(
            "{} `{}` and {} `{}` are the same file",
            e.name,
            text::path(e.path),
            out.name,
            text::path(out.path)
        )));
    }
    refuse_inputs(&reserved, outputs, inputs)?;
    Ok(reserved)
}

/// Refuses when an output (reserved from `names`, same order) is one of `inputs`: checked
/// again by callers that learn of more inputs later (a scene's mesh files).
pub fn refuse_inputs(
    reserved: &[OutputFile],
    names: &[Named<'_>],
    inputs: &[Named<'_>],
) -> Result<()> {
    for (out, name) in reserved.iter().zip(names) {
        if let Some(id) = out.id() {
            refuse_input(name, id, inputs)?;
        }
    }
    Ok(())
}

/// Refuses the output `name`, of file identity `id`, when it is one of `inputs`.
fn refuse_input(name: &Named<'_>, id: &FileId, inputs: &[Named<'_>]) -> Result<()> {
    for input in inputs {
        // An input that cannot be identified cannot be opened either: reading it reports that.
        if file_id(input.path).is_ok_and(|i| &i == id) {
            return Err(Error::Usage(format!(
                "{} `{}` is the {} `{}`: refusing to overwrite an input",
                name.name,
                text::path(name.path),
                input.name,
                text::path(input.path)
            )));
        }
    }
    Ok(())
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn reserve(paths: &[&Path]) -> Result<Vec<OutputFile>> {
        let named: Vec<Named<'_>> = paths.iter().map(|p| Named::new("-o", p)).collect();
        reserve_outputs(&named, &[], false)
    }

    /// `/dev/null` (a character device written in place) may be several outputs; a FIFO, a
    /// descriptor named twice and a regular file named twice are still "the same file".
    #[test]
    fn only_a_character_device_may_be_several_outputs() {
        let null = Path::new("/dev/null");
        assert_eq!(reserve(&[null, null]).unwrap().len(), 2);
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.expect("mkfifo (coreutils) runs").success());
        let file = dir.path().join("out.json");
        let spelt = dir.path().join("./out.json");
        for pair in [
            [fifo.as_path(), fifo.as_path()],
            [Path::new("/dev/stderr"), Path::new("/dev/fd/2")],
            [file.as_path(), spelt.as_path()],
        ] {
            let e = reserve(&pair).unwrap_err().to_string();
            assert!(e.contains("are the same file"), "{pair:?}: {e}");
        }
    }
}
