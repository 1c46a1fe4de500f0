//! Build script of the `halfray` frontend.
//!
//! Only the `embree` feature needs it: `embree4-sys` links `-lembree4`, and the Embree 4.4.0 we use
//! comes from the `embreex` wheel that `scripts/setup-embree.sh` unpacks into `.embree/` (see
//! `docs/embree.md`). With the feature on, this script adds that folder to the link search path
//! and as an rpath of everything this package links (lib tests, the binary, integration tests), so
//! no `LD_LIBRARY_PATH` is needed. With the feature off it emits no link directives at all.
//!
//! `EMBREE_DIR` selects the folder (default: `<workspace root>/.embree`; a relative value is taken
//! relative to the workspace root). The library may sit in `$EMBREE_DIR`, `$EMBREE_DIR/embreex.libs`
//! (the layout the setup script makes) or `$EMBREE_DIR/lib`.

use std::env;
use std::path::{Path, PathBuf};
use std::process::exit;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var_os("CARGO_FEATURE_EMBREE").is_none() {
        return;
    }
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");

    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let workspace_root = manifest_dir.parent().unwrap_or(&manifest_dir).to_path_buf();
    let embree_dir = match env::var_os("EMBREE_DIR") {
        Some(dir) if !dir.is_empty() => {
            let dir = PathBuf::from(dir);
            if dir.is_absolute() {
                dir
            } else {
                workspace_root.join(dir)
            }
        }
        _ => workspace_root.join(".embree"),
    };

    let candidates = [
        embree_dir.join("embreex.libs"),
        embree_dir.clone(),
        embree_dir.join("lib"),
    ];
    let Some(lib_dir) = candidates.iter().find(|d| has_library(d)) else {
        fail(&format!(
            "the `embree` feature is on, but no libembree4.so was found in {} (looked in {}).\n\
             Run `bash scripts/setup-embree.sh` from the repository root, then build with\n\
             `EMBREE_DIR=$PWD/.embree cargo ... --features embree`.",
            embree_dir.display(),
            candidates
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    };
    let lib_dir = lib_dir.canonicalize().unwrap_or_else(|_| lib_dir.clone());
    let Some(lib_dir_str) = lib_dir.to_str().filter(|s| !s.contains(',')) else {
        fail(&format!(
            "Embree folder {} is not valid UTF-8 or contains a comma (cannot be passed as an rpath)",
            lib_dir.display()
        ));
    };

    println!(
        "cargo:rerun-if-changed={}",
        lib_dir.join("libembree4.so").display()
    );
    println!("cargo:rustc-link-search=native={lib_dir_str}");
    // rustc-link-arg applies to every target this package links (it does not propagate to
    // dependent crates: those need their own rpath or LD_LIBRARY_PATH).
    println!("cargo:rustc-link-arg=-Wl,-rpath,{lib_dir_str}");
}

/// `libembree4.so` exists and resolves (a dangling symlink does not count).
fn has_library(dir: &Path) -> bool {
    dir.join("libembree4.so").is_file()
}

/// Fail the build with a readable message instead of a panic backtrace.
fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    println!(
        "cargo:warning={}",
        message.lines().next().unwrap_or(message)
    );
    exit(1);
}
