//! Text files (CSV, JSON) written atomically, like every output of sora.

use std::io::Write;
use std::path::Path;

use super::atomic_file::OutputFiles;
use crate::error::{Error, Result};

/// Writes `text` to `path` atomically: the whole file or, on any failure,
/// no change (see the module docs of [`crate::output`]).
pub fn write_text(path: impl AsRef<Path>, text: &str) -> Result<()> {
    let mut files = OutputFiles::new();
    files.text(path, text)?;
    files.commit()
}

impl OutputFiles {
    /// Stages `text` for `path` (see [`OutputFiles`]).
    pub fn text(&mut self, path: impl AsRef<Path>, text: &str) -> Result<()> {
        let path = path.as_ref();
        self.stage(path, |file| {
            file.write_all(text.as_bytes()).map_err(|error| Error::Io {
                path: path.display().to_string(),
                message: format!("cannot write: {error}"),
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_written_whole_and_a_bad_path_leaves_nothing() {
        let directory = tempfile::tempdir().unwrap();
        let path = directory.path().join("a.csv");
        write_text(&path, "x,y\n1,2\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "x,y\n1,2\n");
        let missing = directory.path().join("no/such/dir/b.csv");
        assert!(matches!(
            write_text(&missing, "x"),
            Err(Error::Unsupported(_))
        ));
        assert_eq!(std::fs::read_dir(directory.path()).unwrap().count(), 1);
    }
}
