//! Which paths sora may write: the one check every output goes through
//! ([`output_target`] for one path, [`output_targets`] for all the outputs
//! of a run), before any work and again by the writers themselves.
//!
//! - a regular file is replaced (unless it is read-only: sora does not
//!   replace a file the user protected);
//! - a symbolic link is followed, through any chain of links (relative
//!   targets taken from the link's own directory), and the file it points
//!   to is written, as a shell's `>` would; the link is kept. A dangling
//!   link writes the file it names;
//! - a new file is created in an existing directory;
//! - anything else is refused in one line: a directory, a missing
//!   directory, a read-only directory (one with no write permission at
//!   all, where no file can be created or renamed into place; refused
//!   even for root, as a read-only file is), a device (`/dev/full`, `/dev/null`), a FIFO, a socket, or
//!   a link to one of them.

use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Links followed before giving up (Linux's own limit for path lookup).
pub const MAX_SYMBOLIC_LINK_HOPS: usize = 40;

/// The file to write for the output path `path` given as `option` (e.g.
/// `-o`, or `output` for a library call): `path` itself, or the file its
/// links lead to. Anything but a regular file or a new file in an existing
/// directory is an [`Error::Unsupported`] whose one-line message names
/// `option`, the path and what to do.
pub fn output_target(path: &Path, option: &str) -> Result<PathBuf> {
    let shown = path.display();
    // One line: the option, the path (and the file a link leads to), why.
    let refuse = |via: &str, why: String| Error::Unsupported(format!("{option} {shown}{via}{why}"));
    let mut target = path.to_path_buf();
    let mut hops = 0;
    while let Ok(metadata) = std::fs::symlink_metadata(&target) {
        if !metadata.file_type().is_symlink() {
            break;
        }
        hops += 1;
        if hops > MAX_SYMBOLIC_LINK_HOPS {
            return Err(refuse(
                "",
                format!(": more than {MAX_SYMBOLIC_LINK_HOPS} symbolic links in a chain (a loop?)"),
            ));
        }
        let link = std::fs::read_link(&target)
            .map_err(|error| refuse("", format!(": cannot read the symbolic link: {error}")))?;
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
    match std::fs::symlink_metadata(&target) {
        Ok(metadata) if metadata.is_dir() => {
            return Err(refuse(
                &via,
                " is a directory: give a file name in it".to_string(),
            ));
        }
        Ok(metadata) if !metadata.is_file() => {
            return Err(refuse(
                &via,
                " is not a regular file (a device, a FIFO or a socket): sora writes only regular files; give a file name"
                    .to_string(),
            ));
        }
        Ok(metadata) if metadata.permissions().readonly() => {
            return Err(refuse(
                &via,
                " exists and is read-only: sora does not replace it; make it writable or give another name"
                    .to_string(),
            ));
        }
        _ => {}
    }
    if target.file_name().is_none() {
        return Err(refuse(
            &via,
            " is not a file path (it has no file name)".to_string(),
        ));
    }
    let directory = directory_of(&target);
    if !directory.is_dir() {
        return Err(refuse(
            &via,
            format!(": the directory {} does not exist", directory.display()),
        ));
    }
    if std::fs::metadata(directory).is_ok_and(|metadata| metadata.permissions().readonly()) {
        return Err(refuse(
            &via,
            format!(
                ": the directory {} is read-only: sora cannot write there; give a file in a writable directory",
                directory.display()
            ),
        ));
    }
    Ok(target)
}

/// The files to write for all the outputs of one run, `(path, option)`
/// each checked by [`output_target`], in order; two outputs that name one
/// file (by any spelling or link) are an error naming both options.
pub fn output_targets(outputs: &[(&Path, &str)]) -> Result<Vec<PathBuf>> {
    let mut targets: Vec<PathBuf> = Vec::with_capacity(outputs.len());
    let mut keys: Vec<PathBuf> = Vec::with_capacity(outputs.len());
    for (k, (path, option)) in outputs.iter().enumerate() {
        let target = output_target(path, option)?;
        let key = comparable_path(&target);
        if let Some(earlier) = keys.iter().position(|other| *other == key) {
            let (earlier_path, earlier_option) = outputs[earlier];
            return Err(Error::Unsupported(format!(
                "{option} {} is the same file as {earlier_option} {}: give each output its own file",
                path.display(),
                earlier_path.display()
            )));
        }
        debug_assert_eq!(k, targets.len());
        keys.push(key);
        targets.push(target);
    }
    Ok(targets)
}

/// `path` with its directory made absolute and free of links (when it
/// can be), so that two spellings of one file compare equal.
pub(crate) fn comparable_path(path: &Path) -> PathBuf {
    match (std::fs::canonicalize(directory_of(path)), path.file_name()) {
        (Ok(directory), Some(name)) => directory.join(name),
        _ => path.to_path_buf(),
    }
}

/// The directory holding `path` ("." for a bare file name).
pub(crate) fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn regular_files_links_to_them_and_new_files_may_be_written() {
        let directory = tempfile::tempdir().unwrap();
        let file = directory.path().join("old.png");
        std::fs::write(&file, b"old").unwrap();
        assert_eq!(output_target(&file, "-o").unwrap(), file);
        let link = directory.path().join("link.png");
        std::os::unix::fs::symlink("old.png", &link).unwrap();
        assert_eq!(
            output_target(&link, "-o").unwrap(),
            directory.path().join("old.png")
        );
        let new = directory.path().join("new.png");
        assert_eq!(output_target(&new, "-o").unwrap(), new);
    }

    #[test]
    fn fifos_directories_and_links_to_devices_are_refused_in_one_line() {
        let directory = tempfile::tempdir().unwrap();
        let fifo = directory.path().join("fifo.png");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(status.success());
        let device_link = directory.path().join("null.png");
        std::os::unix::fs::symlink("/dev/null", &device_link).unwrap();
        let fifo_link = directory.path().join("fifo-link.csv");
        std::os::unix::fs::symlink(&fifo, &fifo_link).unwrap();
        for (path, expected) in [
            (&fifo, "not a regular file"),
            (&device_link, "not a regular file"),
            (&fifo_link, "not a regular file"),
            (&directory.path().to_path_buf(), "is a directory"),
            (&directory.path().join("missing/a.png"), "does not exist"),
        ] {
            let message = output_target(path, "--plot").unwrap_err().to_string();
            assert!(message.starts_with("--plot "), "{message}");
            assert!(message.contains(expected), "{path:?}: {message}");
            assert!(!message.contains('\n'), "{message}");
        }
        // A read-only directory, for a new file and for an existing one
        // (which could not be renamed into place either).
        use std::os::unix::fs::PermissionsExt;
        let locked = directory.path().join("locked");
        std::fs::create_dir(&locked).unwrap();
        std::fs::write(locked.join("old.png"), b"old").unwrap();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
        for name in ["new.png", "old.png"] {
            let message = output_target(&locked.join(name), "--plot")
                .unwrap_err()
                .to_string();
            assert!(
                message.starts_with("--plot ")
                    && message
                        .contains(&format!("the directory {} is read-only", locked.display())),
                "{message}"
            );
        }
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
        // The stand-in is untouched.
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::symlink_metadata(&fifo)
                .unwrap()
                .file_type()
                .is_fifo()
        );
    }

    #[test]
    fn two_outputs_on_one_file_are_refused_by_any_spelling() {
        let directory = tempfile::tempdir().unwrap();
        let a = directory.path().join("a.png");
        let same = directory.path().join(".").join("a.png");
        let link = directory.path().join("b.png");
        std::os::unix::fs::symlink("a.png", &link).unwrap();
        let message = output_targets(&[(&a, "-o"), (&same, "--dolp")])
            .unwrap_err()
            .to_string();
        assert!(message.starts_with("--dolp ") && message.contains("is the same file as -o"));
        assert!(output_targets(&[(&a, "--residuals"), (&link, "--plot")]).is_err());
        let other = directory.path().join("c.png");
        assert_eq!(
            output_targets(&[(&a, "-o"), (&other, "--aop")]).unwrap(),
            [a, other]
        );
    }
}
