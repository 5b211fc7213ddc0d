//! Twilight accuracy survey: the fast method and/or the path tracer for
//! earth-clear at suns 0 to -12 degrees, in the zenith and at view
//! elevations 5, 20, 45 degrees, 0/90/180 degrees from the sun's azimuth.
//! CSV on stdout: method,sun_deg,view_elevation_deg,view_azimuth_deg,
//! then value and standard error at 460, 540, 620 nm.
//!
//! cargo run --release -p sora --example twilight_accuracy -- fast
//! cargo run --release -p sora --example twilight_accuracy -- pt 400000 [suns]
use sora::{Atmosphere, Method, Sky, ViewDirection};

fn main() -> sora::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let mode = args.get(1).map(String::as_str).unwrap_or("fast");
    let samples: u64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(400_000);
    let suns: Vec<f64> = args
        .get(3)
        .map(|s| s.split(',').map(|v| v.parse().unwrap()).collect())
        .unwrap_or(vec![0.0, -2.0, -4.0, -6.0, -8.0, -10.0, -12.0]);
    let preset = args.get(4).map(String::as_str).unwrap_or("earth-clear");
    let atmosphere = Atmosphere::preset(preset)?;
    let mut views = vec![(90.0, 0.0)];
    for el in [5.0, 20.0, 45.0] {
        for az in [0.0, 90.0, 180.0] {
            views.push((el, az));
        }
    }
    let directions: Vec<ViewDirection> = views
        .iter()
        .map(|(e, a)| ViewDirection::new(*e, *a))
        .collect::<sora::Result<_>>()?;
    for sun in suns {
        let method = match mode {
            "pt" => Method::PathTracing { samples, seed: 11 },
            _ => Method::Fast,
        };
        let sky = Sky::builder(&atmosphere)
            .sun_deg(sun, 0.0)
            .method(method)
            .polarisation(sora::Polarisation::Scalar)
            .build()?;
        let results = sky.radiances(&directions)?;
        for ((el, az), r) in views.iter().zip(&results) {
            let v = r.radiance_w_m2_sr_nm.values();
            let e = r
                .standard_error_w_m2_sr_nm
                .as_ref()
                .map(|e| e.values().to_vec())
                .unwrap_or(vec![0.0; v.len()]);
            print!("{mode},{sun},{el},{az}");
            for i in [4, 8, 12] {
                print!(",{:.5e},{:.3e}", v[i], e[i]);
            }
            println!();
        }
    }
    Ok(())
}
