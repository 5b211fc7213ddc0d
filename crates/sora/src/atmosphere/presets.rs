//! Built-in atmospheres. Each is a file under `atmospheres/` in the
//! repository, embedded here verbatim (`include_str!`), so the files users
//! copy and edit and the presets the library loads are the same text; the
//! choices behind each are documented in its comments.
//!
//! | preset | what |
//! |---|---|
//! | `paper-earth` | the paper's Table 1 (units corrected), Mie aerosol set to tau 0.15 at 550 nm |
//! | `paper-mars` | the paper's Table 2 (Mars sunset), as in the shared reference file |
//! | `earth-clear` | physical air, 300 DU ozone, OPAC continental aerosol tau 0.1 |
//! | `earth-hazy` | the same air and ozone, OPAC haze tau 0.4 |
//! | `mars-dust` | CO2 and Wolff et al. (2009) dust, tau 0.5 at 880 nm |
//! | `clear-sky-reference` | the parametric atmosphere of the reference radiative-transfer cases |
//! | `us-standard-1976-rayleigh` | U.S. Standard Atmosphere 1976 air, Rayleigh only |

use super::Atmosphere;
use crate::error::{Error, Result};

/// A built-in atmosphere: its name, a one-line description, its TOML text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Preset {
    /// The name `--preset` takes.
    pub name: &'static str,
    /// One line for `sora atmosphere list`.
    pub description: &'static str,
    /// The atmosphere file's text.
    pub toml: &'static str,
}

/// Every built-in atmosphere, in the order `sora atmosphere presets` lists them.
pub const PRESETS: [Preset; 8] = [
    Preset {
        name: "paper-earth",
        description: "the paper's Table 1: air 2.55e25 m^-3, Mie aerosol 0.1-2.5 um (tau 0.15 at 550 nm), paper HG phase",
        toml: include_str!("../../../../atmospheres/paper-earth.toml"),
    },
    Preset {
        name: "paper-mars",
        description: "the paper's Table 2 (Mars sunset): CO2 2.55e23 m^-3, Mie dust 0.45-0.56 um, paper HG phase",
        toml: include_str!("../../../../atmospheres/paper-mars.toml"),
    },
    Preset {
        name: "earth-clear",
        description: "Earth, clear: physical air, 300 DU ozone, OPAC continental aerosol tau 0.1 at 550 nm, ASTM E490 sun",
        toml: include_str!("../../../../atmospheres/earth-clear.toml"),
    },
    Preset {
        name: "earth-clear-summer",
        description: "earth-clear with 2.92 cm of water vapour (mid-latitude summer), the O2 and CO2 bands (SPECTRL2 band model, 5-term k-distribution), O2-O2 (Thalman & Volkamer 2013, HITRAN 2016) and 0.22 DU of NO2 (AFGL mid-latitude summer)",
        toml: include_str!("../../../../atmospheres/earth-clear-summer.toml"),
    },
    Preset {
        name: "earth-hazy",
        description: "Earth, hazy: physical air, 300 DU ozone, OPAC polluted continental haze tau 0.4 at 550 nm",
        toml: include_str!("../../../../atmospheres/earth-hazy.toml"),
    },
    Preset {
        name: "mars-dust",
        description: "Mars: CO2 at 610 Pa and Wolff et al. 2009 dust (r_eff 1.5 um), tau 0.5 at 880 nm",
        toml: include_str!("../../../../atmospheres/mars-dust.toml"),
    },
    Preset {
        name: "clear-sky-reference",
        description: "the reference radiative-transfer atmosphere: parametric Rayleigh and aerosol (tau 0.1, g 0.7)",
        toml: include_str!("../../../../atmospheres/clear-sky-reference.toml"),
    },
    Preset {
        name: "us-standard-1976-rayleigh",
        description: "U.S. Standard Atmosphere 1976 air (tabulated profile, depolarisation), Rayleigh only",
        toml: include_str!("../../../../atmospheres/us-standard-1976-rayleigh.toml"),
    },
];

/// The preset called `name`, if there is one.
pub fn find_preset(name: &str) -> Option<&'static Preset> {
    PRESETS.iter().find(|preset| preset.name == name)
}

/// The Damerau (optimal string alignment) edit distance between `a` and
/// `b`: insertions, deletions, substitutions and swaps of neighbours.
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

/// Loads the preset called `name`; an unknown name is an error that lists
/// the known ones.
pub(crate) fn load_preset(name: &str) -> Result<Atmosphere> {
    let Some(preset) = find_preset(name) else {
        let known: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        // A misspelling (at most 2 edits, e.g. earth-claer) gets a suggestion.
        let suggestion = known
            .iter()
            .map(|k| (edit_distance(&name.to_lowercase(), k), *k))
            .filter(|(distance, _)| *distance <= 2)
            .min()
            .map(|(_, k)| format!(" (did you mean {k}?)"))
            .unwrap_or_default();
        return Err(Error::parse(
            "atmosphere preset",
            0,
            format!(
                "'{name}' is not a preset{suggestion}; known presets: {}",
                known.join(", ")
            ),
        ));
    };
    Atmosphere::from_toml_str(preset.toml).map_err(|e| match e {
        Error::Parse { line, message, .. } => {
            Error::parse(format!("preset {}", preset.name), line, message)
        }
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_loads() {
        for preset in &PRESETS {
            let atmosphere =
                load_preset(preset.name).unwrap_or_else(|e| panic!("{}: {e}", preset.name));
            assert!(!atmosphere.species.is_empty(), "{}", preset.name);
            assert!(!preset.description.contains('\n'));
        }
    }

    #[test]
    fn a_misspelt_preset_gets_a_suggestion() {
        let e = load_preset("earth-claer").unwrap_err().to_string();
        assert!(e.contains("did you mean earth-clear?"), "{e}");
        let e = load_preset("paper-mras").unwrap_err().to_string();
        assert!(e.contains("did you mean paper-mars?"), "{e}");
        let e = load_preset("venus").unwrap_err().to_string();
        assert!(!e.contains("did you mean"), "{e}");
        assert_eq!(edit_distance("earth-claer", "earth-clear"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn unknown_preset_lists_the_known_ones() {
        let e = load_preset("venus").unwrap_err().to_string();
        assert!(
            e.contains("'venus' is not a preset") && e.contains("earth-clear"),
            "{e}"
        );
    }
}
