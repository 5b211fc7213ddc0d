//! Text files in: every file sora reads (atmosphere files and the files
//! they name, spectra, directions, measurements) is read through
//! [`read_text`], which stops at [`MAX_INPUT_BYTES`] before reading
//! everything, so that an endless input (`/dev/zero`, a FIFO that never
//! ends) or a huge file is a one-line "file too large" error, not minutes
//! of reading and gigabytes of memory.

use std::io::Read;
use std::path::Path;

use crate::{Error, Result};

/// The largest text file sora reads: 256 MiB (an AERONET file of a decade
/// of scans is a few MB; a `sora mie --batch` file of 5 million spheres is
/// about 100 MB).
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// The text of the file at `path`: at most [`MAX_INPUT_BYTES`] of UTF-8
/// (a byte-order mark is kept for the parsers to skip), or an
/// [`Error::Io`] naming the path: it cannot be opened or read, it is a
/// directory, it is larger than the limit ("file too large", found after
/// reading at most one byte past the limit), or it is not UTF-8.
pub fn read_text(path: impl AsRef<Path>) -> Result<String> {
    let path = path.as_ref();
    let io_error = |message: String| Error::Io {
        path: path.display().to_string(),
        message,
    };
    let file = std::fs::File::open(path).map_err(|e| io_error(format!("cannot read: {e}")))?;
    if let Ok(metadata) = file.metadata() {
        if metadata.is_dir() {
            return Err(io_error("cannot read: it is a directory".to_string()));
        }
        if metadata.is_file() && metadata.len() > MAX_INPUT_BYTES {
            return Err(io_error(too_large(metadata.len())));
        }
    }
    read_text_from(file, &path.display().to_string())
}

/// The text of `reader` (named `name` in errors: e.g. "stdin"), bounded as
/// [`read_text`] is.
pub fn read_text_from(reader: impl Read, name: &str) -> Result<String> {
    let io_error = |message: String| Error::Io {
        path: name.to_string(),
        message,
    };
    let mut bytes = Vec::new();
    reader
        .take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| io_error(format!("cannot read: {e}")))?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(io_error(too_large(bytes.len() as u64)));
    }
    String::from_utf8(bytes).map_err(|e| {
        io_error(format!(
            "not UTF-8 text (byte {} is not valid UTF-8)",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// The message for an input of (at least) `bytes` bytes.
fn too_large(bytes: u64) -> String {
    format!(
        "file too large: {} bytes or more, more than the limit of {} MiB of text",
        bytes,
        MAX_INPUT_BYTES >> 20
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_input_stops_at_the_limit_with_file_too_large() {
        // An endless reader (as /dev/zero is) is read to one byte past the
        // limit, then refused.
        let endless = std::io::repeat(0);
        let message = read_text_from(endless, "stdin").unwrap_err().to_string();
        assert!(message.starts_with("stdin: file too large"), "{message}");
        assert!(!message.contains('\n'));
    }

    #[test]
    fn text_at_the_limit_is_read_and_bad_bytes_are_named() {
        let text = read_text_from("a,b\n1,2\n".as_bytes(), "x").unwrap();
        assert_eq!(text, "a,b\n1,2\n");
        let message = read_text_from(&[b'a', 0xff][..], "x")
            .unwrap_err()
            .to_string();
        assert!(message.contains("not UTF-8 text (byte 1"), "{message}");
        let directory = tempfile::tempdir().unwrap();
        let message = read_text(directory.path()).unwrap_err().to_string();
        assert!(message.contains("directory"), "{message}");
    }
}
