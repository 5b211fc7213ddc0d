//! Every command's `--format json` parses, and its fields are the ones
//! docs/json.md lists for it: none printed that the page does not list,
//! none listed that no run prints.

mod common;

use std::collections::BTreeSet;

use common::{json, numbers, sora};
use serde_json::Value;

const DOC: &str = include_str!("../../../docs/json.md");

/// The fields docs/json.md lists in the section whose heading is
/// `heading`: the first cell of each table row, `[]` dropped
/// (`species[].name` is `species.name`).
fn documented(heading: &str) -> BTreeSet<String> {
    let start = DOC
        .find(&format!("\n## {heading}\n"))
        .unwrap_or_else(|| panic!("no section {heading} in docs/json.md"));
    let section = &DOC[start + 1..];
    let end = section[3..].find("\n## ").map_or(section.len(), |e| e + 3);
    section[..end]
        .lines()
        .filter_map(|line| line.strip_prefix("| `"))
        .map(|rest| rest[..rest.find('`').unwrap()].replace("[]", ""))
        .collect()
}

/// Whether `value` is an estimate, `{"value": v, "sigma": s}`: a leaf.
fn is_estimate(value: &Value) -> bool {
    value
        .as_object()
        .is_some_and(|o| o.len() == 2 && o.contains_key("value") && o.contains_key("sigma"))
}

/// Every field's path in `value` (`a.b` for b in a, through lists of
/// objects), with `strip` removed from the front of each.
fn fields(value: &Value, prefix: &str, strip: &str, into: &mut BTreeSet<String>) {
    match value {
        Value::Object(members) => {
            for (name, member) in members {
                let path = format!("{prefix}{name}");
                into.insert(path.strip_prefix(strip).unwrap_or(&path).to_string());
                if !is_estimate(member) {
                    fields(member, &format!("{path}."), strip, into);
                }
            }
        }
        Value::Array(items) => {
            for item in items.iter().filter(|i| i.is_object()) {
                fields(item, prefix, strip, into);
            }
        }
        _ => {}
    }
}

/// The fields of the runs of `runs`, against docs/json.md's `heading`.
fn check(heading: &str, runs: &[Value], strip: &str) {
    let listed = documented(heading);
    let mut printed = BTreeSet::new();
    for run in runs {
        let mut fields_of_run = BTreeSet::new();
        fields(run, "", strip, &mut fields_of_run);
        let unlisted: Vec<_> = fields_of_run.difference(&listed).collect();
        assert!(
            unlisted.is_empty(),
            "{heading}: {unlisted:?} not in docs/json.md: {run}"
        );
        printed.extend(fields_of_run);
    }
    let never: Vec<_> = listed.difference(&printed).collect();
    assert!(
        never.is_empty(),
        "{heading}: listed, never printed: {never:?}"
    );
}

#[test]
fn atmosphere_show() {
    let runs: Vec<Value> = ["earth-clear", "mars-dust"]
        .iter()
        .map(|preset| {
            json(&sora(&[
                "atmosphere",
                "show",
                "--preset",
                preset,
                "--wavelengths",
                "400:700:150",
                "--format",
                "json",
            ]))
        })
        .collect();
    check("`sora atmosphere show`", &runs, "");
    let earth = &runs[0];
    assert_eq!(numbers(&earth["wavelengths_nm"]), [400.0, 550.0, 700.0]);
    let species = earth["species"].as_array().unwrap().len();
    assert_eq!(earth["optics"].as_array().unwrap().len(), 3 * species);
}

#[test]
fn spectrum() {
    const SKY: [&str; 6] = [
        "spectrum",
        "--preset",
        "earth-clear",
        "--wavelengths",
        "400:700:150",
        "--format",
    ];
    let run = |extra: &[&str]| json(&sora(&[&SKY[..], &["json"], extra].concat()));
    let one_view = [
        "--sun-elevation",
        "30",
        "--view-elevation",
        "40",
        "--view-azimuth",
        "10",
    ];
    let runs = [
        run(&[&one_view[..], &["--stokes"]].concat()),
        run(&[&one_view[..], &["--distance-m", "5000"]].concat()),
        run(&[
            "--almucantar",
            "90",
            "--method",
            "path-tracing",
            "--samples",
            "200",
            "--stokes",
            "--time",
            "2026-06-21T03:00:00Z",
            "--location",
            "35.68,139.77",
        ]),
        // No wavelength with a colour: null XYZ.
        json(&sora(&[
            "spectrum",
            "--preset",
            "earth-clear",
            "--sun-elevation",
            "30",
            "--wavelengths",
            "900:1000:100",
            "--format",
            "json",
            "--view-elevation",
            "40",
            "--view-azimuth",
            "10",
        ])),
    ];
    check("`sora spectrum`", &runs, "directions.");
    // The one-direction run and the CSV agree to the CSV's ten digits.
    let csv = common::stdout(&sora(&[&SKY[..], &["csv"], &one_view].concat()));
    let rows = common::spectrum_rows(&csv);
    let radiance = numbers(&runs[0]["radiance_w_m2_sr_nm"]);
    assert_eq!(radiance.len(), rows.len());
    for (value, (_, from_csv)) in radiance.iter().zip(&rows) {
        assert!(
            (value / from_csv - 1.0).abs() < 6e-10,
            "{value} vs {from_csv}"
        );
    }
    assert_eq!(runs[0]["polarisation"], "vector");
    assert_eq!(runs[2]["directions"].as_array().unwrap().len(), 4);
    assert!(runs[3]["xyz_w_m2_sr"].is_null() && runs[3]["linear_srgb_w_m2_sr"].is_null());
}

/// Single scattering in one direction: a quick filtered run.
const SINGLE_VIEW: [&str; 6] = [
    "--scattering",
    "single",
    "--view-elevation",
    "40",
    "--view-azimuth",
    "10",
];

#[test]
fn spectrum_through_filters() {
    let run = |extra: &[&str]| {
        json(&sora(
            &[
                &[
                    "spectrum",
                    "--preset",
                    "earth-clear",
                    "--filter",
                    "cimel-870",
                    "--filter",
                    "cimel-440",
                    "--format",
                    "json",
                ][..],
                extra,
            ]
            .concat(),
        ))
    };
    let runs = [
        run(&[&["--sun-elevation", "30"][..], &SINGLE_VIEW].concat()),
        run(&[
            "--sun-elevation",
            "30",
            "--almucantar",
            "90",
            "--method",
            "path-tracing",
            "--samples",
            "50",
            "--sun-distance-au",
            "1.01",
        ]),
        run(&[
            &SINGLE_VIEW[..],
            &[
                "--time",
                "2026-06-21T03:00:00Z",
                "--location",
                "35.68,139.77",
            ],
        ]
        .concat()),
    ];
    check("`sora spectrum --filter`", &runs, "directions.");
    assert_eq!(numbers(&runs[0]["radiance_w_m2_sr_nm"]).len(), 2);
}

#[test]
fn irradiance() {
    let run = |extra: &[&str]| {
        json(&sora(
            &[
                &["irradiance", "--preset", "earth-clear", "--format", "json"][..],
                extra,
            ]
            .concat(),
        ))
    };
    let runs = [
        run(&[
            "--wavelengths",
            "450:650:100",
            "--time",
            "2026-06-21T03:00:00Z",
            "--location",
            "35.68,139.77",
            "--tilt-deg",
            "35",
            "--method",
            "path-tracing",
            "--samples",
            "100",
        ]),
        run(&["--sun-elevation", "30", "--filter", "cimel-870"]),
    ];
    check("`sora irradiance`", &runs, "");
    let broadband = runs[0]["global_horizontal_irradiance_w_m2"]
        .as_f64()
        .unwrap();
    assert!(broadband > 0.0);
    assert_eq!(numbers(&runs[0]["broadband_range_nm"]), [450.0, 650.0]);
}

#[test]
fn retrieve() {
    let run = |extra: &[&str]| {
        json(&sora(
            &[
                &[
                    "retrieve",
                    "--starting-points",
                    "1",
                    "--max-iterations",
                    "1",
                    "--format",
                    "json",
                ][..],
                extra,
            ]
            .concat(),
        ))
    };
    let runs = [run(&[
        "--radiances",
        "../../docs/retrieval_case4_radiances.csv",
        "--optical-depths",
        "../../docs/retrieval_case4_optical_depths.csv",
    ])];
    check("`sora retrieve`", &runs, "");
    assert_eq!(runs[0].as_array().unwrap().len(), 1);
}
