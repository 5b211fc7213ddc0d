//! Choosing the output format from a file name's extension.

use std::path::Path;

use crate::{Error, Result};

/// The file formats the output stage writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OutputFormat {
    /// PNG: display-encoded RGB, 8 or 16 bits per channel
    /// ([`write_png`](super::write_png)).
    Png,
    /// OpenEXR: linear float RGB or XYZ ([`write_exr`](super::write_exr)).
    Exr,
}

impl OutputFormat {
    /// Every format, in the order error messages list them.
    pub const ALL: [OutputFormat; 2] = [OutputFormat::Png, OutputFormat::Exr];

    /// The format's file extension, lower case, without the dot.
    pub(crate) fn extension(self) -> &'static str {
        match self {
            OutputFormat::Png => "png",
            OutputFormat::Exr => "exr",
        }
    }

    /// The format named by the extension of `path` (`.png`, `.exr`, in any
    /// letter case). Fails with an [`Error::Io`] naming `path` and listing
    /// the supported extensions if the extension is missing or unknown.
    pub fn from_path(path: impl AsRef<Path>) -> Result<OutputFormat> {
        let path = path.as_ref();
        let extension = path.extension().map(|e| e.to_string_lossy());
        let found = extension.as_deref().and_then(|extension| {
            OutputFormat::ALL
                .into_iter()
                .find(|format| extension.eq_ignore_ascii_case(format.extension()))
        });
        found.ok_or_else(|| {
            let supported: Vec<String> = OutputFormat::ALL
                .iter()
                .map(|format| format!(".{}", format.extension()))
                .collect();
            let problem = match &extension {
                Some(extension) => format!("unsupported output file extension \".{extension}\""),
                None => "output file name has no extension".to_string(),
            };
            Error::Io {
                path: path.display().to_string(),
                message: format!(
                    "{problem}: supported extensions are {} (in any letter case)",
                    supported.join(", ")
                ),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_select_formats_in_any_letter_case() {
        for (path, format) in [
            ("sky.png", OutputFormat::Png),
            ("out/Sky.PNG", OutputFormat::Png),
            ("a.b.Png", OutputFormat::Png),
            ("sky.exr", OutputFormat::Exr),
            ("/tmp/SKY.EXR", OutputFormat::Exr),
            ("sky.eXr", OutputFormat::Exr),
        ] {
            assert_eq!(OutputFormat::from_path(path).unwrap(), format, "{path}");
        }
    }

    #[test]
    fn unknown_or_missing_extensions_list_the_supported_ones() {
        let error = OutputFormat::from_path("out/sky.tiff").unwrap_err();
        assert_eq!(
            error.to_string(),
            "out/sky.tiff: unsupported output file extension \".tiff\": \
             supported extensions are .png, .exr (in any letter case)"
        );
        let error = OutputFormat::from_path("sky").unwrap_err();
        assert_eq!(
            error.to_string(),
            "sky: output file name has no extension: \
             supported extensions are .png, .exr (in any letter case)"
        );
        // A dot file's name is not an extension; a trailing dot is empty.
        assert!(OutputFormat::from_path(".png").is_err());
        assert!(OutputFormat::from_path("sky.").is_err());
        assert!(OutputFormat::from_path("sky.png.bak").is_err());
    }
}
