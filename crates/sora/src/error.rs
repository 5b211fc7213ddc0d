//! The library's error type: every failure names what was wrong, the bad
//! value, its unit and what would have been accepted, so that the command
//! line and atmosphere files can report it in one line.

use std::fmt;

/// Everything that can go wrong in the library.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A numeric parameter outside its allowed range (or not finite).
    OutOfRange {
        /// The parameter, as a user would name it (`step_nm`, `species[1].scale_height_m`).
        name: String,
        /// The value given.
        value: f64,
        /// Unit of `value` (`"nm"`, `"m"`, `"1"` for dimensionless).
        unit: &'static str,
        /// The accepted range in words (`"360..=830"`, `"> 0"`).
        allowed: String,
    },
    /// A spectrum that cannot be turned into colour or light: NaN, negative,
    /// wrong length, or a table that does not cover the wavelengths asked for.
    InvalidSpectrum(String),
    /// A combination of choices that cannot work together (path tracing
    /// with single scattering, an image from the path tracer); the message
    /// names both.
    Unsupported(String),
    /// Text input (CSV table, TOML file) that does not parse.
    Parse {
        /// What was being read (`"solar spectrum CSV"`).
        what: String,
        /// 1-based line number, 0 when unknown.
        line: usize,
        /// What is wrong, in one line.
        message: String,
    },
    /// A Mie-theory input outside the solver's domain.
    Mie(sora_mie::sphere::MieError),
    /// Writing an output file failed (the output module is the only place
    /// with file I/O).
    Io {
        /// The file.
        path: String,
        /// The operating system's reason.
        message: String,
    },
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Shorthand for [`Error::OutOfRange`].
    pub(crate) fn out_of_range(
        name: impl Into<String>,
        value: f64,
        unit: &'static str,
        allowed: impl Into<String>,
    ) -> Error {
        Error::OutOfRange {
            name: name.into(),
            value,
            unit,
            allowed: allowed.into(),
        }
    }

    /// The one-line error of an unknown name of a choice: `what: 'name'
    /// is unknown: use 'a', 'b' or 'c'`.
    pub(crate) fn unknown_name(what: &str, name: &str, choices: &[&str]) -> Error {
        let quoted: Vec<String> = choices.iter().map(|c| format!("'{c}'")).collect();
        let listed = match quoted.split_last() {
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        };
        Error::parse(what, 0, format!("'{name}' is unknown: use {listed}"))
    }

    /// Shorthand for [`Error::Parse`].
    pub fn parse(what: impl Into<String>, line: usize, message: impl Into<String>) -> Error {
        Error::Parse {
            what: what.into(),
            line,
            message: message.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::OutOfRange {
                name,
                value,
                unit,
                allowed,
            } => {
                let unit = if unit.is_empty() || *unit == "1" {
                    String::new()
                } else {
                    format!(" {unit}")
                };
                let value = format_number(*value);
                write!(
                    f,
                    "{name} = {value}{unit} is out of range: allowed {allowed}{unit}"
                )
            }
            Error::InvalidSpectrum(message) => write!(f, "invalid spectrum: {message}"),
            Error::Unsupported(message) => f.write_str(message),
            Error::Parse {
                what,
                line,
                message,
            } if *line > 0 => {
                write!(f, "{what}, line {line}: {message}")
            }
            Error::Parse { what, message, .. } => write!(f, "{what}: {message}"),
            Error::Mie(e) => write!(f, "{e}"),
            Error::Io { path, message } => write!(f, "{path}: {message}"),
        }
    }
}

impl std::error::Error for Error {}

/// A number as a person would write it in a message: plain when moderate
/// (`-5`, `0.25`), scientific when very large or small (`-2.55e25`, `3e-9`).
pub(crate) fn format_number(value: f64) -> String {
    let magnitude = value.abs();
    if value.is_finite() && magnitude != 0.0 && !(1e-4..1e6).contains(&magnitude) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

impl From<sora_mie::sphere::MieError> for Error {
    fn from(e: sora_mie::sphere::MieError) -> Error {
        Error::Mie(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_message_names_value_unit_and_range() {
        let e = Error::out_of_range("step_nm", -5.0, "nm", "> 0");
        assert_eq!(
            e.to_string(),
            "step_nm = -5 nm is out of range: allowed > 0 nm"
        );
        let e = Error::out_of_range("number_density_m3", -2.55e25, "m^-3", ">= 0");
        assert_eq!(
            e.to_string(),
            "number_density_m3 = -2.55e25 m^-3 is out of range: allowed >= 0 m^-3"
        );
        let e = Error::out_of_range("x", 3e-9, "1", "> 1e-6");
        assert_eq!(e.to_string(), "x = 3e-9 is out of range: allowed > 1e-6");
        let e = Error::out_of_range("asymmetry_g", 1.5, "1", "-1 < g < 1");
        assert_eq!(
            e.to_string(),
            "asymmetry_g = 1.5 is out of range: allowed -1 < g < 1"
        );
        // A count has no unit: no space where the unit would be.
        let e = Error::out_of_range("twilight shift pieces", 0.0, "", "1..=64");
        assert_eq!(
            e.to_string(),
            "twilight shift pieces = 0 is out of range: allowed 1..=64"
        );
    }
}
