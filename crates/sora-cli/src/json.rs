//! `--format json`: every command's JSON is a `#[derive(Serialize)]` value
//! written by serde_json, its schema documented in docs/json.md.
//!
//! Numbers are f64 in the shortest text that reads back to the same value
//! (serde_json's `float_roundtrip`); a value that is not finite, which
//! JSON cannot hold, is `null`.

use serde::Serialize;

/// `value` as indented JSON and a final line break.
pub fn to_string<T: Serialize + ?Sized>(value: &T) -> anyhow::Result<String> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    Ok(text)
}

/// The sun a command used, as members of its object (flattened):
/// `sun_elevation_deg`, `sun_azimuth_deg` and, when known,
/// `sun_distance_au` and `earth_sun_distance_au`.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Sun {
    /// Elevation above the horizon, degrees.
    pub sun_elevation_deg: f64,
    /// Azimuth clockwise from north, degrees.
    pub sun_azimuth_deg: f64,
    /// The sun's distance when --sun-distance-au or --time set it, AU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sun_distance_au: Option<f64>,
    /// The Earth-Sun distance at --time, AU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub earth_sun_distance_au: Option<f64>,
}

impl Sun {
    /// The sun at (`elevation_deg`, `azimuth_deg`) with `used`'s distances.
    pub fn new(elevation_deg: f64, azimuth_deg: f64, used: &crate::arguments::SunUsed) -> Self {
        Sun {
            sun_elevation_deg: elevation_deg,
            sun_azimuth_deg: azimuth_deg,
            sun_distance_au: used.distance_au,
            earth_sun_distance_au: used.earth_sun_distance_au,
        }
    }
}

/// Members whose names are known only at run time (an irradiance's
/// quantities, a retrieval's parameters), in this order.
pub struct Members<V>(pub Vec<(String, V)>);

impl<V: Serialize> Serialize for Members<V> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(name, value)| (name, value)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Example<'a> {
        name: &'a str,
        values_nm: Vec<f64>,
        missing: Option<f64>,
        #[serde(flatten)]
        members: Members<f64>,
    }

    #[test]
    fn strings_escape_and_numbers_read_back_exactly() {
        let values = vec![
            0.4072515344,
            2.546899e25,
            1.16e-5,
            -3.5e-30,
            780.0,
            f64::NAN,
        ];
        let text = to_string(&Example {
            name: "a \"b\"\\\n\u{1}",
            values_nm: values.clone(),
            missing: None,
            members: Members(vec![("z_w_m2".into(), 1.5), ("a_lx".into(), 2.0)]),
        })
        .unwrap();
        assert!(text.ends_with("}\n"));
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back["name"], "a \"b\"\\\n\u{1}");
        assert_eq!(back["missing"], serde_json::Value::Null);
        let read: Vec<Option<f64>> = back["values_nm"]
            .as_array()
            .unwrap()
            .iter()
            .map(serde_json::Value::as_f64)
            .collect();
        let expected: Vec<Option<f64>> =
            values.iter().map(|v| v.is_finite().then_some(*v)).collect();
        assert_eq!(read, expected);
        // Run-time members keep their order.
        assert_eq!(back["z_w_m2"], 1.5);
        assert!(text.find("z_w_m2").unwrap() < text.find("a_lx").unwrap());
    }
}
