//! Atomic file replacement: a file is written in full to a temporary file in
//! the target's directory, flushed to disk, and only then renamed onto the
//! target. A reader (or a crashed run) therefore sees either the old file or
//! the complete new one, never a partial file, and a failed write leaves
//! neither a partial target nor a temporary file behind. The outputs of one
//! run are renamed together ([`OutputFiles`]): all of them or none.

use std::ffi::OsStr;
use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

use super::path::{comparable_path, directory_of, output_target};
use crate::{Error, Result};

/// How many temporary names to try before giving up: names only collide with
/// leftovers of crashed runs or with concurrent writes of the same target, so
/// running out means something else is wrong with the directory.
const MAX_TEMPORARY_NAME_ATTEMPTS: u32 = 1000;

/// The longest prefix of the target's file name reused in the temporary
/// name, in characters, so that a target name near the file system's limit
/// (255 bytes on most) still leaves room for the suffix.
const MAX_TEMPORARY_NAME_PREFIX_CHARS: usize = 64;

/// Output files of one run, written together or not at all: each is
/// written in full to a temporary file `.<name>.tmp-<pid>-<n>` beside its
/// target (the same file system, so that the rename is atomic) and synced
/// ("staged": [`OutputFiles::png`], [`OutputFiles::exr_with_layers`],
/// [`OutputFiles::text`]); [`OutputFiles::commit`] then renames them onto
/// their targets in turn.
///
/// Every target is checked by [`output_target`] when it is staged and
/// again just before its rename: only a regular file (a link is followed
/// to its file) or a new file is written, never a device, a FIFO or a
/// directory; two outputs on one file are refused. If anything fails
/// (staging, a check, a rename), every temporary file is removed, the
/// files this run had already created are removed, and the error names
/// the path; files that existed and were already replaced keep their new
/// contents (there is no older copy to put back). Dropping an
/// `OutputFiles` without committing removes its temporaries. The new files
/// get default permissions (those of the old files are not copied).
#[derive(Debug, Default)]
pub struct OutputFiles {
    staged: Vec<StagedFile>,
}

/// A complete temporary file waiting to be renamed onto `target`.
#[derive(Debug)]
struct StagedFile {
    /// The file to replace or create (links already followed).
    target: PathBuf,
    /// `target` as compared with later outputs ([`comparable_path`], once).
    key: PathBuf,
    /// The path the caller gave, for messages.
    shown: String,
    temporary: TemporaryFileGuard,
}

impl OutputFiles {
    /// No files yet.
    pub fn new() -> OutputFiles {
        OutputFiles::default()
    }

    /// Stages the file at `path`: `write_contents` fills a new temporary
    /// file next to its target, which is then synced. On failure (an
    /// error or a panic in `write_contents`) the temporary is removed and
    /// the error names `path`.
    pub(crate) fn stage(
        &mut self,
        path: &Path,
        write_contents: impl FnOnce(&mut File) -> Result<()>,
    ) -> Result<()> {
        let target = output_target(path, "output")?;
        let io_error = |what: &str, error: io::Error| Error::Io {
            path: path.display().to_string(),
            message: format!("{what}: {error}"),
        };
        let Some(file_name) = target.file_name() else {
            return Err(Error::Io {
                path: path.display().to_string(),
                message: "not a file path (it has no file name)".to_string(),
            });
        };
        let key = comparable_path(&target);
        if let Some(earlier) = self.staged.iter().find(|staged| staged.key == key) {
            return Err(Error::Unsupported(format!(
                "{} is the same file as the output {}: give each output its own file",
                path.display(),
                earlier.shown
            )));
        }
        let (file, temporary) = create_temporary_file(directory_of(&target), file_name)
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
        self.staged.push(StagedFile {
            target,
            key,
            shown: path.display().to_string(),
            temporary,
        });
        Ok(())
    }

    /// Renames every staged file onto its target, in the order staged; on
    /// any failure removes the remaining temporaries and the files this
    /// commit created, and returns the error.
    pub fn commit(self) -> Result<()> {
        let mut created: Vec<PathBuf> = Vec::new();
        let undo = |created: &[PathBuf]| {
            for path in created {
                let _ = std::fs::remove_file(path);
            }
        };
        let mut staged = self.staged.into_iter();
        for file in staged.by_ref() {
            // Checked again at the last moment: a device or a FIFO put there
            // since the file was staged is not replaced either.
            let existed = match output_target(&file.target, "output") {
                Ok(_) => file.target.exists(),
                Err(error) => {
                    undo(&created);
                    return Err(error);
                }
            };
            if let Err(error) = std::fs::rename(&file.temporary.path, &file.target) {
                undo(&created);
                return Err(Error::Io {
                    path: file.shown.clone(),
                    message: format!("cannot move the finished file into place: {error}"),
                });
            }
            file.temporary.disarm();
            if !existed {
                created.push(file.target.clone());
            }
            sync_directory(directory_of(&file.target));
        }
        Ok(())
    }
}

/// Writes the file at `path` atomically, alone (see [`OutputFiles`]).
#[cfg(test)]
fn write_file_atomically(
    path: impl AsRef<Path>,
    write_contents: impl FnOnce(&mut File) -> Result<()>,
) -> Result<()> {
    let mut files = OutputFiles::new();
    files.stage(path.as_ref(), write_contents)?;
    files.commit()
}

/// A temporary file that is removed when this guard is dropped, unless
/// [`TemporaryFileGuard::disarm`] was called after the file was renamed into
/// place. Removing on drop covers every early return and unwinding panics.
#[derive(Debug)]
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
        assert_eq!(
            error.to_string(),
            "output / is a directory: give a file name in it"
        );
    }

    #[cfg(unix)]
    #[test]
    fn outputs_are_written_together_or_not_at_all() {
        let directory = tempfile::tempdir().unwrap();
        let first = directory.path().join("residuals.csv");
        let second = directory.path().join("fit.png");
        let mut files = OutputFiles::new();
        files
            .stage(&first, |file| {
                file.write_all(b"a").unwrap();
                Ok(())
            })
            .unwrap();
        files
            .stage(&second, |file| {
                file.write_all(b"b").unwrap();
                Ok(())
            })
            .unwrap();
        // A FIFO takes the second target's place after staging: the commit
        // refuses it, and the first file, which it had created, goes too.
        let status = std::process::Command::new("mkfifo")
            .arg(&second)
            .status()
            .unwrap();
        assert!(status.success());
        let message = files.commit().unwrap_err().to_string();
        assert!(message.contains("not a regular file"), "{message}");
        assert_eq!(directory_entries(directory.path()), ["fit.png"]);
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::symlink_metadata(&second)
                .unwrap()
                .file_type()
                .is_fifo()
        );
    }

    #[test]
    fn one_file_staged_twice_is_refused() {
        let directory = tempfile::tempdir().unwrap();
        let target = directory.path().join("sky.png");
        let mut files = OutputFiles::new();
        files.stage(&target, |_| Ok(())).unwrap();
        let again = directory.path().join(".").join("sky.png");
        let message = files.stage(&again, |_| Ok(())).unwrap_err().to_string();
        assert!(
            message.contains("is the same file as the output"),
            "{message}"
        );
        drop(files);
        assert!(directory_entries(directory.path()).is_empty());
    }
}
