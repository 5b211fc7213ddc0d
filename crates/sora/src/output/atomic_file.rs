//! Atomic file replacement: a file is written in full to a temporary file in
//! the target's directory, flushed to disk, and only then renamed onto the
//! target. A reader (or a crashed run) therefore sees either the old file or
//! the complete new one, never a partial file, and a failed write leaves
//! neither a partial target nor a temporary file behind.

use std::ffi::OsStr;
use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// How many temporary names to try before giving up: names only collide with
/// leftovers of crashed runs or with concurrent writes of the same target, so
/// running out means something else is wrong with the directory.
const MAX_TEMPORARY_NAME_ATTEMPTS: u32 = 1000;

/// The longest prefix of the target's file name reused in the temporary
/// name, in characters, so that a target name near the file system's limit
/// (255 bytes on most) still leaves room for the suffix.
const MAX_TEMPORARY_NAME_PREFIX_CHARS: usize = 64;

/// Writes the file at `path` atomically: `write_contents` fills a new
/// temporary file `.<name>.tmp-<pid>-<n>` in the same directory (the same
/// file system, so that the final rename is atomic), which is then synced
/// to disk and renamed onto `path`, replacing any existing file.
///
/// If anything fails (creating, writing, syncing or renaming, an error
/// returned by `write_contents`, or a panic in it), the temporary file is
/// removed, an existing file at `path` is left untouched, and the error
/// names `path`. The new file gets default permissions (those of the old
/// file, if any, are not copied); a symbolic link at `path` is replaced by
/// the file rather than followed.
pub(crate) fn write_file_atomically(
    path: impl AsRef<Path>,
    write_contents: impl FnOnce(&mut File) -> Result<()>,
) -> Result<()> {
    let path = path.as_ref();
    let io_error = |what: &str, error: io::Error| Error::Io {
        path: path.display().to_string(),
        message: format!("{what}: {error}"),
    };
    let Some(file_name) = path.file_name() else {
        return Err(Error::Io {
            path: path.display().to_string(),
            message: "not a file path (it has no file name)".to_string(),
        });
    };
    let directory = directory_of(path);

    let (file, temporary) = create_temporary_file(directory, file_name)
        .map_err(|error| io_error("cannot create a temporary file next to it", error))?;
    // The file is moved into the closure so that it is closed before the
    // guard removes it on failure (Windows cannot remove an open file).
    let fill_and_sync = move || {
        let mut file = file;
        write_contents(&mut file)?;
        file.sync_all()
            .map_err(|error| io_error("cannot flush the file to disk", error))
    };
    fill_and_sync()?;
    std::fs::rename(&temporary.path, path)
        .map_err(|error| io_error("cannot move the finished file into place", error))?;
    temporary.disarm();
    sync_directory(directory);
    Ok(())
}

/// The directory that holds `path`: its parent, or the current directory
/// for a bare file name (whose parent is the empty path, which cannot be
/// opened).
fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// A temporary file that is removed when this guard is dropped, unless
/// [`TemporaryFileGuard::disarm`] was called after the file was renamed into
/// place. Removing on drop covers every early return and unwinding panics.
struct TemporaryFileGuard {
    path: PathBuf,
}

impl TemporaryFileGuard {
    /// Keeps the file: it has been renamed and no longer exists under `path`.
    fn disarm(self) {
        std::mem::forget(self);
    }
}

impl Drop for TemporaryFileGuard {
    fn drop(&mut self) {
        // The write has already failed and that error is what the caller
        // needs to see; a failure to clean up cannot be reported from here.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Creates a new, empty temporary file in `directory` for a target named
/// `file_name`, trying successive names until one does not exist yet
/// (`create_new` makes the choice race-free without any shared counter).
fn create_temporary_file(
    directory: &Path,
    file_name: &OsStr,
) -> io::Result<(File, TemporaryFileGuard)> {
    let prefix: String = file_name
        .to_string_lossy()
        .chars()
        .take(MAX_TEMPORARY_NAME_PREFIX_CHARS)
        .collect();
    let process_id = std::process::id();
    let mut last_error = None;
    for attempt in 0..MAX_TEMPORARY_NAME_ATTEMPTS {
        let path = directory.join(format!(".{prefix}.tmp-{process_id}-{attempt}"));
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(file) => return Ok((file, TemporaryFileGuard { path })),
            Err(error) if error.kind() == io::ErrorKind::AlreadyExists => last_error = Some(error),
            Err(error) => return Err(error),
        }
    }
    Err(last_error.unwrap_or_else(|| io::Error::other("no temporary name available")))
}

/// Makes the rename itself durable by syncing the directory entry (on Unix;
/// elsewhere there is no portable way). The file is already complete and in
/// place, so a failure here is not an error of the write.
fn sync_directory(directory: &Path) {
    #[cfg(unix)]
    if let Ok(handle) = File::open(directory) {
        let _ = handle.sync_all();
    }
    #[cfg(not(unix))]
    let _ = directory;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// Names of all entries in `directory`, sorted.
    fn directory_entries(directory: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(directory)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_the_whole_file_and_leaves_no_temporary() {
        let directory = tempfile::tempdir().unwrap();
        let target = directory.path().join("sky.bin");
        write_file_atomically(&target, |file| {
            file.write_all(b"complete contents").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"complete contents");
        assert_eq!(directory_entries(directory.path()), ["sky.bin"]);
    }

    #[test]
    fn a_failing_writer_leaves_the_old_file_and_no_temporary() {
        let directory = tempfile::tempdir().unwrap();
        let target = directory.path().join("sky.bin");
        std::fs::write(&target, b"old").unwrap();
        let result = write_file_atomically(&target, |file| {
            file.write_all(b"half of the new conte").unwrap();
            Err(Error::Io {
                path: "encoder".to_string(),
                message: "injected failure".to_string(),
            })
        });
        assert_eq!(
            result.unwrap_err().to_string(),
            "encoder: injected failure",
            "the writer's own error is passed through"
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(directory_entries(directory.path()), ["sky.bin"]);
    }

    #[test]
    fn a_panicking_writer_leaves_no_temporary() {
        let directory = tempfile::tempdir().unwrap();
        let target = directory.path().join("sky.bin");
        let result = std::panic::catch_unwind(|| {
            write_file_atomically(&target, |file| {
                file.write_all(b"partial").unwrap();
                panic!("injected panic in the middle of a write");
            })
        });
        assert!(result.is_err());
        assert!(directory_entries(directory.path()).is_empty());
    }

    #[test]
    fn temporary_names_skip_leftovers_of_other_runs() {
        let directory = tempfile::tempdir().unwrap();
        let leftover = format!(".sky.bin.tmp-{}-0", std::process::id());
        std::fs::write(directory.path().join(&leftover), b"stale").unwrap();
        let target = directory.path().join("sky.bin");
        write_file_atomically(&target, |file| {
            file.write_all(b"new").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(
            std::fs::read(directory.path().join(&leftover)).unwrap(),
            b"stale",
            "someone else's temporary file must not be touched"
        );
        assert_eq!(
            directory_entries(directory.path()),
            [leftover.as_str(), "sky.bin"]
        );
    }

    #[test]
    fn a_very_long_target_name_still_gets_a_valid_temporary_name() {
        let directory = tempfile::tempdir().unwrap();
        let target = directory.path().join(format!("{}.png", "a".repeat(240)));
        write_file_atomically(&target, |file| {
            file.write_all(b"x").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"x");
    }

    #[test]
    fn a_bare_file_name_lives_in_the_current_directory() {
        assert_eq!(directory_of(Path::new("sky.png")), Path::new("."));
        assert_eq!(directory_of(Path::new("out/sky.png")), Path::new("out"));
        assert_eq!(directory_of(Path::new("/sky.png")), Path::new("/"));
    }

    #[test]
    fn a_path_without_file_name_is_rejected_before_writing() {
        let mut called = false;
        let error = write_file_atomically(Path::new("/"), |_| {
            called = true;
            Ok(())
        })
        .unwrap_err();
        assert!(!called);
        assert!(matches!(error, Error::Io { ref path, .. } if path == "/"));
    }
}
