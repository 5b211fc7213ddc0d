//! Where an output file goes, checked before any work is done.
//!
//! Every file sora writes (`sora render -o`, its sequence frames, `sora
//! colour --swatch`) goes through [`output_target`] first, so that a path
//! that cannot be written is refused in one line before minutes of
//! rendering, not after:
//!
//! - a directory is refused (name a file in it);
//! - a missing parent directory is refused;
//! - an existing read-only file is refused (sora does not replace a file
//!   the user protected; make it writable or write elsewhere);
//! - a symbolic link is followed: the file it points to (through any chain
//!   of links, relative targets taken from the link's own directory) is
//!   written, atomically in the target's directory, and the link is kept,
//!   as a shell's `>` would. A dangling link writes the file it names.
//!
//! The library's atomic writer then replaces the target in one rename
//! (`sora::output`): a reader sees the old file or the new one, never part.

use std::path::{Path, PathBuf};

use anyhow::bail;

/// Links followed before giving up (Linux's own limit for path lookup).
const MAX_SYMBOLIC_LINK_HOPS: usize = 40;

/// The file to write for the output path `path` given to `option` (e.g.
/// `-o`), or a one-line error naming the option, the path and what to do.
pub fn output_target(path: &Path, option: &str) -> anyhow::Result<PathBuf> {
    let shown = path.display();
    let mut target = path.to_path_buf();
    let mut hops = 0;
    while let Ok(metadata) = std::fs::symlink_metadata(&target) {
        if !metadata.file_type().is_symlink() {
            break;
        }
        hops += 1;
        if hops > MAX_SYMBOLIC_LINK_HOPS {
            bail!(
                "{option} {shown}: more than {MAX_SYMBOLIC_LINK_HOPS} symbolic links in a chain (a loop?)"
            );
        }
        let link = std::fs::read_link(&target)?;
        target = if link.is_absolute() {
            link
        } else {
            directory_of(&target).join(link)
        };
    }
    let via = if target == path {
        String::new()
    } else {
        format!(" (a symbolic link to {})", target.display())
    };
    if target.is_dir() {
        bail!("{option} {shown}{via} is a directory: give a file name in it");
    }
    let directory = directory_of(&target);
    if !directory.is_dir() {
        bail!(
            "{option} {shown}{via}: the directory {} does not exist",
            directory.display()
        );
    }
    if let Ok(metadata) = std::fs::metadata(&target)
        && metadata.permissions().readonly()
    {
        bail!(
            "{option} {shown}{via} exists and is read-only: sora does not replace it; make it writable or give another name"
        );
    }
    Ok(target)
}

/// The directory holding `path` ("." for a bare file name).
fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}
