//! The one spelling of a sky's choices, shared by every front end (the
//! command line's values, Python's keywords, the explorer's requests):
//! [`std::fmt::Display`] writes the name and [`std::str::FromStr`] reads
//! it back, with the library's defaults for what the name leaves open.

use std::fmt;
use std::str::FromStr;

use super::{Method, Scattering};
use crate::error::{Error, Result};

impl Method {
    /// The methods' names, in the order of the enum.
    pub const NAMES: [&'static str; 3] = ["fast", "reference", "path-tracing"];
    /// Paths per view of `"path-tracing"` read by [`FromStr`] (every front
    /// end's default for a radiance).
    pub const DEFAULT_SAMPLES: u64 = 10_000;
    /// The path tracer's seed read by [`FromStr`].
    pub const DEFAULT_SEED: u64 = 1;

    /// The method's name: `"fast"`, `"reference"` or `"path-tracing"`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Fast => Self::NAMES[0],
            Method::Reference { .. } => Self::NAMES[1],
            Method::PathTracing { .. } => Self::NAMES[2],
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = Error;

    /// `"fast"`; `"reference"` with [`Method::REFERENCE_DEFAULT`]'s steps;
    /// `"path-tracing"` with [`Method::DEFAULT_SAMPLES`] paths and
    /// [`Method::DEFAULT_SEED`]. Anything else is a one-line error naming
    /// the value and the choices.
    fn from_str(name: &str) -> Result<Method> {
        match name {
            "fast" => Ok(Method::Fast),
            "reference" => Ok(Method::REFERENCE_DEFAULT),
            "path-tracing" => Ok(Method::PathTracing {
                samples: Method::DEFAULT_SAMPLES,
                seed: Method::DEFAULT_SEED,
            }),
            other => Err(Error::unknown_name("method", other, &Method::NAMES)),
        }
    }
}

impl Scattering {
    /// The names, in the order of the enum.
    pub const NAMES: [&'static str; 2] = ["single", "multiple"];

    /// `"single"` or `"multiple"`.
    pub fn name(&self) -> &'static str {
        match self {
            Scattering::Single => Self::NAMES[0],
            Scattering::Multiple(_) => Self::NAMES[1],
        }
    }
}

impl fmt::Display for Scattering {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scattering {
    type Err = Error;

    /// `"single"`, or `"multiple"` at the default resolution
    /// ([`Scattering::multiple`]); anything else is a one-line error.
    fn from_str(name: &str) -> Result<Scattering> {
        match name {
            "single" => Ok(Scattering::Single),
            "multiple" => Ok(Scattering::multiple()),
            other => Err(Error::unknown_name("scattering", other, &Scattering::NAMES)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Polarisation;
    use crate::camera::Camera;

    /// Every name reads back to a value that writes the same name.
    fn round_trip<T: FromStr<Err = Error> + fmt::Display>(names: &[&str]) {
        for name in names {
            let value: T = name.parse().unwrap();
            assert_eq!(value.to_string(), *name);
        }
    }

    #[test]
    fn names_read_back() {
        round_trip::<Method>(&Method::NAMES);
        round_trip::<Scattering>(&Scattering::NAMES);
        round_trip::<Camera>(&Camera::NAMES);
        round_trip::<Polarisation>(&["scalar", "vector"]);
        assert_eq!(
            "reference".parse::<Method>().unwrap(),
            Method::REFERENCE_DEFAULT
        );
        assert_eq!(
            "path-tracing".parse::<Method>().unwrap(),
            Method::PathTracing {
                samples: 10_000,
                seed: 1
            }
        );
        assert_eq!(
            "multiple".parse::<Scattering>().unwrap(),
            Scattering::multiple()
        );
        // The old spelling of the panorama still reads.
        assert_eq!(
            "equirect".parse::<Camera>().unwrap(),
            Camera::Equirectangular
        );
    }

    #[test]
    fn unknown_names_are_one_line_errors_listing_the_choices() {
        let message = "slow".parse::<Method>().unwrap_err().to_string();
        assert_eq!(
            message,
            "method: 'slow' is unknown: use 'fast', 'reference' or 'path-tracing'"
        );
        let message = "double".parse::<Scattering>().unwrap_err().to_string();
        assert_eq!(
            message,
            "scattering: 'double' is unknown: use 'single' or 'multiple'"
        );
        let message = "cube".parse::<Camera>().unwrap_err().to_string();
        assert!(
            message.contains("'cube'") && message.contains("'equirectangular'"),
            "{message}"
        );
    }

    #[test]
    fn image_sides_as_users_give_them() {
        use crate::sky::image_side;
        assert_eq!(image_side("image width", 512).unwrap(), 512);
        assert_eq!(image_side("image width", 16384).unwrap(), 16384);
        for bad in [-5, 0, 16385] {
            let message = image_side("image width", bad).unwrap_err().to_string();
            assert_eq!(
                message,
                format!("image width = {bad} pixels is out of range: allowed 1..=16384 pixels")
            );
        }
        // Past u32 (the type of a side), an error too, not a wrapped value.
        for bad in [i64::from(u32::MAX) + 513, i64::MIN] {
            let message = image_side("image width", bad).unwrap_err().to_string();
            assert!(message.ends_with("pixels is out of range: allowed 1..=16384 pixels"));
        }
    }
}
