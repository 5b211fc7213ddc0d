//! The engine tables on disk: a directory holding `sky.exr`,
//! `aerial.exr`, `transmittance.exr`, `irradiance.exr` (32-bit float
//! OpenEXR, channels
//! X, Y, Z) and `manifest.json` (the format, the units, the axes, their
//! mappings and the lookup formulas). Written together or not at all
//! ([`OutputFiles`]); the directory is created if it does not exist, and an
//! existing one is refused unless it is empty or holds sora's tables (a
//! manifest of [`TABLE_FORMAT`]), so that `-o` never overwrites something
//! else.

use std::path::Path;

use super::{EngineTables, axes};
use crate::error::{Error, Result};
use crate::output::{ChannelKind, ExrOptions, LinearImage, OutputFiles};

/// The manifest's file name.
pub const MANIFEST_FILE: &str = "manifest.json";

/// The manifest's `format`.
pub const TABLE_FORMAT: &str = "sora-engine-tables";

/// The table format's version (changes with the axes or the layout; 3: the
/// sky table's `zenith_fine_cells_per_half`; 4: its
/// `zenith_wide_cells_per_half`; 5: the irradiance table's own altitude
/// axis, `tables.irradiance.altitude_nodes`).
pub const FORMAT_VERSION: u32 = 5;

/// An error unless `directory` may receive tables: it does not exist (its
/// parent does), or it is an empty directory, or it holds a manifest of
/// [`TABLE_FORMAT`].
pub fn check_output_directory(directory: &Path) -> Result<()> {
    let shown = directory.display();
    let refuse = |why: String| Error::Unsupported(format!("-o {shown}{why}"));
    match std::fs::symlink_metadata(directory) {
        Err(_) => match directory.parent() {
            Some(parent) if !parent.as_os_str().is_empty() && !parent.is_dir() => Err(refuse(
                format!(": the directory {} does not exist", parent.display()),
            )),
            _ => Ok(()),
        },
        Ok(_) if !directory.is_dir() => Err(refuse(
            " exists and is not a directory: give a new directory for the tables".to_string(),
        )),
        Ok(_) => {
            let empty = std::fs::read_dir(directory)
                .map_err(|error| refuse(format!(": cannot read it: {error}")))?
                .next()
                .is_none();
            if empty || holds_tables(directory) {
                Ok(())
            } else {
                Err(refuse(format!(
                    " exists and is not sora's tables (no {MANIFEST_FILE} of format {TABLE_FORMAT}): give a new or empty directory"
                )))
            }
        }
    }
}

/// Whether `directory` holds a manifest of [`TABLE_FORMAT`].
fn holds_tables(directory: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(directory.join(MANIFEST_FILE)) else {
        return false;
    };
    serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| {
            v.get("format")
                .and_then(|f| f.as_str())
                .map(|f| f == TABLE_FORMAT)
        })
        .unwrap_or(false)
}

impl EngineTables {
    /// Writes the tables into `directory` (see the module docs): all five
    /// files (four without an aerial-perspective table) or none; a directory this call created is removed again if
    /// the writing fails.
    pub fn write(&self, directory: &Path) -> Result<()> {
        check_output_directory(directory)?;
        let created = !directory.exists();
        if created {
            std::fs::create_dir(directory).map_err(|error| Error::Io {
                path: directory.display().to_string(),
                message: format!("cannot create the directory: {error}"),
            })?;
        }
        let result = self.stage_and_commit(directory);
        if result.is_err() && created {
            let _ = std::fs::remove_dir_all(directory);
        }
        result
    }

    fn stage_and_commit(&self, directory: &Path) -> Result<()> {
        let settings = &self.settings;
        let mut files = OutputFiles::new();
        let options = ExrOptions {
            text_attributes: vec![("format".into(), TABLE_FORMAT.into())],
            ..ExrOptions::default()
        };
        let image = |width: usize, height: usize, texels: &[[f32; 3]]| {
            LinearImage::new(width, height, ChannelKind::Xyz, texels.to_vec())
        };
        let sky_height = 2 * settings.zenith_nodes_per_half * settings.sky_layers();
        files.exr_with_layers(
            directory.join("sky.exr"),
            &image(settings.azimuth_nodes, sky_height, &self.sky)?,
            &[],
            options.clone(),
        )?;
        let (_, aerial_azimuth, _) = settings.aerial_nodes;
        if !self.aerial.is_empty() {
            files.exr_with_layers(
                directory.join("aerial.exr"),
                &image(
                    aerial_azimuth,
                    self.aerial.len() / aerial_azimuth,
                    &self.aerial,
                )?,
                &[],
                options.clone(),
            )?;
        }
        let (t_altitudes, t_mu) = settings.transmittance_nodes;
        files.exr_with_layers(
            directory.join("transmittance.exr"),
            &image(t_mu, t_altitudes, &self.transmittance)?,
            &[],
            options.clone(),
        )?;
        files.exr_with_layers(
            directory.join("irradiance.exr"),
            &image(
                settings.sun_nodes,
                settings.irradiance_altitude_nodes(),
                &self.irradiance,
            )?,
            &[],
            options,
        )?;
        if let Some(bytes) = self.march_bin() {
            let path = directory.join("march.bin");
            let shown = path.display().to_string();
            files.stage(&path, |file| {
                use std::io::Write;
                file.write_all(&bytes).map_err(|error| Error::Io {
                    path: shown.clone(),
                    message: format!("cannot write: {error}"),
                })
            })?;
        }
        let manifest = serde_json::to_string_pretty(&self.manifest()).map_err(|error| {
            Error::Unsupported(format!("the manifest does not serialise: {error}"))
        })?;
        files.text(directory.join(MANIFEST_FILE), &(manifest + "\n"))?;
        files.commit()
    }

    /// `march.bin`'s bytes (the manifest's `tables.march` gives each
    /// array's offset, length and type): the march's arrays one after
    /// another as little-endian 32-bit floats, `log_source` as 16-bit
    /// floats; None without the march's tables.
    pub fn march_bin(&self) -> Option<Vec<u8>> {
        let march = self.march.as_ref()?;
        let arrays = march.arrays();
        let size = arrays
            .iter()
            .map(|a| a.values.len() * if a.half { 2 } else { 4 })
            .sum();
        let mut bytes = Vec::with_capacity(size);
        for array in arrays {
            for v in array.values.iter() {
                if array.half {
                    bytes.extend_from_slice(&exr::prelude::f16::from_f32(*v).to_le_bytes());
                } else {
                    bytes.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        Some(bytes)
    }

    /// The manifest: format, units, axes, layout and lookup formulas.
    pub fn manifest(&self) -> serde_json::Value {
        let s = &self.settings;
        let matrix = crate::colour::RgbColourSpace::Srgb.linear_rgb_from_xyz_matrix();
        let mut manifest = serde_json::json!({
            "format": TABLE_FORMAT,
            "version": FORMAT_VERSION,
            "generator": format!("sora {}", env!("CARGO_PKG_VERSION")),
            "colour": {
                "channels": "CIE 1931 XYZ (2-degree observer) of the spectral quantity, 1.0 = the XYZ of a flat spectrum of 1 unit per nm (luminance in cd/m^2 = 683 Y)",
                "linear_srgb_from_xyz": matrix,
                "wavelengths_nm": self.provenance.wavelengths_nm,
            },
            "scattering": self.provenance.scattering,
            "planet": {
                "ground_radius_m": self.ground_radius_m,
                "top_radius_m": self.top_radius_m,
            },
            "sun": {
                "irradiance_xyz_w_m2_nm": self.solar_xyz,
                "angular_radius_rad": self.sun_angular_radius_rad,
                "limb_darkening": super::lookup::LIMB_DARKENING,
                "elevation_range_deg": [axes::SUN_ELEVATION_MIN_DEG, axes::SUN_ELEVATION_MAX_DEG],
                "axis_width_deg": axes::SUN_WIDTH_DEG,
            },
            "tables": {
                "sky": {
                    "file": "sky.exr",
                    "unit": "W m^-2 sr^-1 nm^-1 (XYZ)",
                    "width": s.azimuth_nodes,
                    "height": 2 * s.zenith_nodes_per_half * s.sky_layers(),
                    "sun_nodes": s.sun_nodes,
                    "altitude_nodes": s.altitude_nodes,
                    "zenith_nodes_per_half": s.zenith_nodes_per_half,
                    "zenith_fine_cells_per_half": s.zenith_fine_cells_per_half,
                    "zenith_wide_cells_per_half": s.zenith_wide_cells_per_half,
                    "azimuth_nodes": s.azimuth_nodes,
                    "layout": "texel (k, row) of layer L = s * altitude_nodes + a is at x = k, y = L * 2 * zenith_nodes_per_half + row (y = 0 is the file's top scan line); a 2D array texture of sun_nodes * altitude_nodes layers of azimuth_nodes x 2 zenith_nodes_per_half",
                },
                "aerial": {
                    "file": "aerial.exr",
                    "unit": "1 (the ratio R of the segment's in-scattered light to S w, per channel; see lookup.aerial_perspective)",
                    "width": s.aerial_nodes.1,
                    "height": 2 * s.aerial_nodes.0 * s.aerial_nodes.2 * s.sky_layers(),
                    "zenith_nodes_per_half": s.aerial_nodes.0,
                    "azimuth_nodes": s.aerial_nodes.1,
                    "distance_nodes": s.aerial_nodes.2,
                    "layout": "texel (k, row) of distance node j of layer L = s * altitude_nodes + a is at x = k, y = (L * distance_nodes + j) * 2 zenith_nodes_per_half + row; a 2D array texture of sun_nodes * altitude_nodes * distance_nodes layers of azimuth_nodes x 2 zenith_nodes_per_half (array layer L * distance_nodes + j)",
                },
                "transmittance": {
                    "file": "transmittance.exr",
                    "unit": "1 (XYZ of the transmitted solar spectrum / XYZ of the solar spectrum)",
                    "width": s.transmittance_nodes.1,
                    "height": s.transmittance_nodes.0,
                    "layout": "x = mu node m, y = altitude node a",
                },
                "irradiance": {
                    "file": "irradiance.exr",
                    "unit": "W m^-2 nm^-1 (XYZ), diffuse on a horizontal plane",
                    "width": s.sun_nodes,
                    "height": s.irradiance_altitude_nodes(),
                    "altitude_nodes": s.irradiance_altitude_nodes(),
                    "layout": "x = sun node s, y = altitude node a of the table's own altitude axis (the altitude mapping with N = altitude_nodes, the table's height; the sky table's altitude nodes are among its nodes)",
                },
            },
            "axes": {
                "sun": "s = (asinh(e / W) - asinh(-12 / W)) / (asinh(90 / W) - asinh(-12 / W)) * (S - 1), e the sun elevation in degrees clamped to -12..90, W = sun.axis_width_deg",
                "altitude": "a = ln(1 + clamp(h, 0, H) / h0) / ln(1 + D) * (N - 1), h the altitude above the ground in m, H = top_radius_m - ground_radius_m, h0 = H / D, D = altitude_scale_divisor, N the axis's node count",
                "altitude_scale_divisor": axes::ALTITUDE_SCALE_DIVISOR,
                "zenith": "r = ground_radius_m + h, z_h = pi - asin(ground_radius_m / r), m = 1e-6; F = zenith_fine_cells_per_half, W = zenith_wide_cells_per_half (each 0 where absent; the aerial table's are 0), c = Z - 1 - F - W, n(v) = j / 2 if j <= 2 c, c + (j - 2 c) / 3 if j <= 2 c + 3 W, else j - c - 2 W, with j = v (2 (Z - 1) - F + W); above the horizon (z < z_h): y = n(1 - sqrt(1 - clamp(z / (z_h - m), 0, 1))), cells 0..Z-2; below: y = 2Z - 1 - n(1 - sqrt(1 - clamp((pi - z) / (pi - z_h - m), 0, 1))), cells Z..2Z-2 (with F = 0, n(v) = v (Z - 1))",
                "azimuth": "k = sqrt(phi / pi) * (K - 1), phi the view's azimuth from the sun's, 0..pi",
        "distance": "the ray's length l from the eye (radius r) along view cosine mu to the ground (mu < mu_h) or the top: l = -r mu - sqrt(r^2 mu^2 - r^2 + ground_radius_m^2) or -r mu + sqrt(r^2 mu^2 - r^2 + top_radius_m^2); d0 = H / nearest_divisor, l' = max(l, 2 d0); j = clamp(ln(max(d, d0) / d0) / ln(l' / d0), 0, 1) * (D - 1)",
                "distance_nearest_divisor": axes::AERIAL_NEAREST_DIVISOR,
                "transmittance_mu": "mu_h = -sqrt(1 - (ground_radius_m / r)^2); m = sqrt(clamp((mu - mu_h) / (1 - mu_h), 0, 1)) * (M - 1); zero when mu < mu_h",
            },
            "lookup": {
                "zenith_cap_cells": super::lookup::ZENITH_CAP_CELLS,
                "cells": "i = clamp(floor(x), lowest, highest), f = clamp(x - i, 0, 1); lowest/highest 0..nodes-2 unless the zenith axis says otherwise",
                "sky": "bilinear in (k, y) within a layer, but in zenith cell i < zenith_cap_cells (i + 2 < Z) the uniform Catmull-Rom cubic in ln max(L, 1e-30) along y through rows i-1..i+2 (each linear in k; row -1 is row 1 at azimuth pi - phi): exp(a + t ((b - m) + t ((2m - 5a + 4b - n) + t (-m + 3a - 3b + n))) / 2), m, a, b, n the logarithms of rows i-1..i+2, t = f_y; between altitude layers a and a+1: above the eye's horizon (z < z_h) ln max(L, 1e-30) linear in the altitude h, f_h = (h - h_a) / (h_(a+1) - h_a), h_a = h0 ((1 + D)^(a / (N - 1)) - 1) (axes.altitude); below it L linear in the altitude coordinate; between sun layers s and s+1 exp(mix(ln max(A, 1e-30), ln max(B, 1e-30), f_s)) per channel, where layer j (elevation e_j = W sinh(t0 + (t1 - t0) j / (S - 1))) is read at the view turned by w (e_j - e) about the horizontal axis across the sun's azimuth (v = (sin z cos phi, sin z sin phi, cos z) -> x' = v.x cos d - v.z sin d, z' = acos(v.x sin d + v.z cos d), phi' = atan2(|v.y|, x'), z' kept on the same side of z_h: min(z', z_h - 2e-6) above, max(z', z_h) below; unturned when d = 0), w = max(smoothstep(cos 40deg, cos 10deg, cos theta), smoothstep(55, 68, e)) (1 - smoothstep(z_h - 20deg, z_h - 5deg, z)), cos theta = cos z sin e + sin z cos phi cos e, e clamped to -12..90",
                "transmittance": "zero when mu < mu_h(eye); otherwise linear in a between rows a and a+1, each row read linearly at m computed with that row's own radius r_a = ground_radius_m + h(a) (h(a) = h0 (exp(a / (N - 1) ln(1 + D)) - 1))",
                "irradiance": "diffuse: linear in a, the altitude coordinate with N = tables.irradiance.altitude_nodes (the table's height, not the sky table's), geometric in s (as the sky); global = diffuse + sun.irradiance_xyz * T(h, sin e) * max(sin e, 0)",
                "sun_disc": "within gamma < alpha of the sun's centre: sun.irradiance_xyz * T(h, sin e) * (1 - u (1 - sqrt(1 - (gamma/alpha)^2))) / (pi alpha^2 (1 - u/3)), u = sun.limb_darkening",
                "aerial_perspective": "eye x (radius r), point p = x + d v; T(x,p) = T(r, mu) / T(r_p, mu_p), or T(r_p, -mu_p) / T(r, -mu) when v meets the ground (each channel, at most 1); T_end = T(x, x + l v) (l the ray's length, axes.distance); w = clamp((1 - T) / (1 - T_end), 0, 1), 1 where 1 - T_end <= 1e-9; in-scattered = S(x, v) R(x, v, d) w per channel, S the sky lookup at the eye and R the aerial table read as the sky table (the same cells, turned views and sun blend, its own zenith and azimuth node counts), linear in the distance coordinate j between the slices j and j+1 of each layer",
            },
        });
        if let Some(march) = &self.march {
            manifest["tables"]["march"] = march.manifest();
            manifest["lookup"]["aerial_perspective_march"] = MARCH_LOOKUP.into();
            manifest["lookup"]["sky_raised_eye"] = RAISED_SKY_LOOKUP.into();
        }
        if self.aerial.is_empty() {
            manifest["tables"]
                .as_object_mut()
                .map(|tables| tables.remove("aerial"));
            manifest["lookup"]["aerial_perspective"] = "no aerial table: in-scattered = max(S(x, v) - T(x, p) S(p, v), 0), S the sky lookup at each end's altitude, zenith angle, azimuth from the sun and sun elevation in its own local frame, T(x, p) as above".into();
        }
        manifest
    }
}

/// The sky's lookup for an eye above the ground with the march's tables
/// (`lookup.rs`, `EngineTables::raised_sky_xyz`), as the manifest states it.
const RAISED_SKY_LOOKUP: &str = "with tables.march and the eye above the ground (h > 0; on the ground, or without march tables, lookup.sky): e the sun's elevation, sun = (cos e, 0, sin e), v = (sin z cos phi, sin z sin phi, cos z), z_h(h) = pi - asin(R / (R + h)), a and f_h the eye's altitude cell and share as lookup.sky, h_a the altitude of node a; scale(V, W, G, f) = V exp(f (ln max(W, 1e-30) - ln max(G, 1e-30))) per channel; Table(h, z) lookup.sky at (h, z, phi, e). Whole(h, v): the aerial_perspective_march with d = the split and every node (both stretches) counted as the segment's, so that there is no 'beyond' (the light and transmittance of the whole ray); the split is the ray's length l (axes.distance) but, for a view going down (v.z < 0), l + (min(p, l) - l) smoothstep(0, 0.05 thickness, r - sqrt(r^2 - p^2)), p = -r v.z the distance to the perigee. Composed(h, v, h_n) (h_n <= h): t = -r v.z - sqrt(r^2 v.z^2 - (r^2 - r_n^2)) where the ray meets the sphere of radius r_n = R + h_n (0 when h = h_n), point p = (v.x t, v.y t, r + v.z t), up = p / |p|; far = Table(h_n) at the view's zenith angle and azimuth from the sun in p's frame and the sun's elevation asin(sun.up) there; far itself if t = 0, else the aerial_perspective_march's in-scattered + transmittance * far for the segment of length t. Above the eye's horizon (z < z_h(h)): Whole(h, v); if a = 0 and f_h < 1 times scale by (1 - f_h) of Table(0, z_0) over Whole(0, v(z_0)), z_0 = z z_h(0) / z_h(h). Below it: B = Composed(h, v, h_a); if f_h > 0, scale(B, Table(h_(a+1), z_b), Composed(h_(a+1), v(z_b), h_a), f_h), z_b = pi - (pi - z) (pi - z_h(h_(a+1))) / (pi - z_h(h)). The reference shaders (sora_sky.glsl, sora_sky.wgsl) read this as soraRaisedSkyView / sora_raised_sky_view (soraRaisedSkyXyz / sora_raised_sky_xyz from a zenith angle and azimuth), lookup.sky alone as soraSkyView / sora_sky_view: a host draws an eye above the ground with a program that calls the first and an eye on the ground with one that calls the second, which compiles no march.";

/// The march's lookup formula (`lookup.rs`, `MarchTables::aerial_perspective_xyz`), as the manifest states it.
const MARCH_LOOKUP: &str = "tables.march (march.bin), per wavelength i, species j: eye at radius r on the z axis, view v, sun s (unit, cos theta = v.s); the ray inside the atmosphere from enter to exit, the segment's length l = min(d, exit) - enter, beyond it b = exit - enter - l. Nodes: march_steps[0] along the segment at s_k = u^2 l, weight 2 u l / N (u = (k + 0.5) / N), then march_steps[1] from the point at l + u^2 b, weight 2 u b / N'. At each node x (altitude h, local view cosine, sun cosine mu_s, azimuth from the sun): rho_j from density (linear), columns c_j from the eye by trapezoids (the segment's closed at s = l), C_j toward the sun from sun_columns (bilinear over the transmittance axes; none, unlit, when mu_s < mu_h(x)), ln R quadrilinear from log_source at its channels (levels, sun zenith nodes and azimuths located linearly in altitude and angle among source_levels_m, source_sun_zenith_rad and source_azimuth_rad), linear in the wavelength's index between the channels' wavelengths (source_wavelength_indices); R = 0 at or below dark_log_source. tau = sum extinction c, tau* = sum scaled_extinction c, tau_sun, tau*_sun likewise with C; T = e^-tau etc. Single (segment nodes, lit): S += w E sum_j scattering_j phase_j(theta) rho_j T T_sun. Field: F (segment) or F_b (beyond) += w sum_j scaled_scattering_j rho_j R T*. Peak integrals (has_forward_peaks): with the peak beam B (ln_beam bilinear in altitude and elevation e = asin(mu_s); share a = min((e3 - e) / (e3 - e2), 1) for e in [e1, e3) of beam_range_deg, else 0) and Sb = T*_sun - T_sun, Sc = Sb + a (B - Sb) (T*_sun = T_sun = 0 unlit): rows I_j += w rho_j (T* Sc + T_sun (T* - T)), scaled I*_j += w rho_j T* (Sc + T_sun), and where lit and T*_sun > 0: Q += q, QX += q X with q = w T T_sun (sum_j (extinction_j - scaled_extinction_j) rho_j) (T_sun + Sc) / T*_sun, X = (tau + tau_sun) - (tau* + tau*_sun). Gather the segment's (I, I*, Q, QX, c) at s = l and the whole ray's at the end. Then with the segment's T, T*: share = 1 - T / T*, depth = ln(T* / T); rows_j = I_j,seg + share (I*_j,ray - I*_j,seg), Q = Q_ray, QX = QX_ray; behind: Q_b = Q_ray - Q_seg, QX_b = QX_ray - QX_seg - depth Q_b; P(rows) = E sum_j scattering_j smooth_phase_j(theta) rows_j + (1 - wide) E Q K(theta, X) e^X within kernel_radius_rad (X = clamp(QX / Q, 0, last kernel_x), K bilinear in kernel_x and t = sqrt(theta / kernel_radius_rad) (kernel_angles - 1), wide = clamp((theta - kernel_blend_start_rad) / (kernel_radius_rad - kernel_blend_start_rad), 0, 1)). L_air = S + F + share (F_b + G) + P(rows) - P(behind), G = T*_ray (ground_diffuse + ground_direct) where the ray ends on the ground (geometric in the sun zenith node at the ground point); in-scattered XYZ = sum_i L_air xyz_i; transmittance XYZ = sum_i E_i T_i xyz_i / sum_i E_i xyz_i per channel.";
