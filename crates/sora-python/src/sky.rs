//! `sora.Sky` (native part): the library's [`sora::Sky`] built from
//! keyword arguments, with the radiance of arrays of views and images as
//! numpy arrays.
//!
//! Units: angles in degrees (elevation above the horizon, azimuth clockwise
//! from north), altitude in m, wavelengths in nm, radiance in
//! W m^-2 sr^-1 nm^-1, XYZ radiometric (Y = the integral of the radiance
//! times CIE y-bar, W m^-2 sr^-1; 683 Y is the luminance in cd m^-2).

use numpy::ndarray::{Array2, Array3, Array4};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use sora::colour::{Observer, RgbColourSpace, SpectrumToXyz};
use sora::spectrum::SampledSpectrum;
use sora::{Camera, ImageSettings, Method, Polarisation, Scattering, ViewDirection};

use crate::atmosphere::Atmosphere;
use crate::errors::{to_py_err, value_error};
use crate::grid::grid_from_python;
use crate::threads::run_detached;

/// A sky: atmosphere, sun, eye, wavelengths, physics and method.
#[pyclass(frozen, module = "sora._sora")]
pub struct Sky {
    inner: sora::Sky,
    /// The sun's distance, AU, when `sun_distance_au` or a time set it.
    sun_distance_au: Option<f64>,
}

/// The library's scattering and method for the keyword arguments.
fn scattering_and_method(
    scattering: &str,
    method: &str,
    samples: Option<u64>,
    seed: Option<u64>,
    reference_steps: Option<(usize, usize)>,
) -> PyResult<(Scattering, Method)> {
    // The library's names (`FromStr`), its defaults for what they leave open.
    let scattering: Scattering = scattering.parse().map_err(to_py_err)?;
    let kind: Method = method.parse().map_err(to_py_err)?;
    if !matches!(kind, Method::PathTracing { .. }) && (samples.is_some() || seed.is_some()) {
        return Err(value_error(format!(
            "samples and seed apply to method='path-tracing' only, not method='{method}'"
        )));
    }
    if !matches!(kind, Method::Reference { .. }) && reference_steps.is_some() {
        return Err(value_error(
            "reference_steps applies to method='reference' only",
        ));
    }
    let method = match kind {
        Method::Reference { .. } => match reference_steps {
            Some((view_steps, sun_steps)) => Method::Reference {
                view_steps,
                sun_steps,
            },
            None => kind,
        },
        Method::PathTracing {
            samples: default_samples,
            seed: default_seed,
        } => Method::PathTracing {
            samples: samples.unwrap_or(default_samples),
            seed: seed.unwrap_or(default_seed),
        },
        Method::Fast => kind,
    };
    Ok((scattering, method))
}

/// The sun at `time` (RFC 3339, e.g. 2026-06-21T05:30:00+09:00) from
/// `location` (latitude deg N, longitude deg E, elevation m), refracted
/// (when `refraction`) through the site's air: the standard atmosphere's
/// at its elevation, or the measured `air` (pressure hPa, temperature C)
/// where given.
fn sun_from_time(
    time: &str,
    location: &[f64],
    refraction: bool,
    air: (Option<f64>, Option<f64>),
) -> PyResult<sora::SunPosition> {
    let time = sora::sun_position::parse_time_utc(time).map_err(to_py_err)?;
    let (latitude, longitude, elevation) = match location {
        [latitude, longitude] => (*latitude, *longitude, 0.0),
        [latitude, longitude, elevation] => (*latitude, *longitude, *elevation),
        _ => {
            return Err(value_error(format!(
                "location has {} values: give (latitude_deg, longitude_deg) or (latitude_deg, longitude_deg, elevation_m)",
                location.len()
            )));
        }
    };
    let place = sora::sun_position::Location::new(latitude, longitude, elevation)
        .map_err(|e| value_error(format!("location: {e}")))?;
    let refraction = if refraction {
        sora::sun_position::Refraction::at_site(elevation, air.0, air.1)
    } else {
        sora::sun_position::Refraction::Off
    };
    sora::SunPosition::at(time, place, refraction).map_err(to_py_err)
}

/// Checks a number given for an angle or a length before the library sees
/// it, so that the message names the keyword.
fn finite(name: &str, value: f64, unit: &str) -> PyResult<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(value_error(format!(
            "{name} = {value} {unit} is not a finite number"
        )))
    }
}

/// The camera named `camera` (perspective: looking at `look_deg` with
/// `fov_deg` across the width; their defaults are the library's,
/// `PerspectiveCamera::DEFAULT_*`, as `sora render`'s).
fn camera_from_name(camera: &str, look_deg: (f64, f64), fov_deg: f64) -> PyResult<Camera> {
    Ok(match camera.parse::<Camera>().map_err(to_py_err)? {
        Camera::Perspective(_) => Camera::Perspective(
            sora::camera::PerspectiveCamera::new(look_deg.0, look_deg.1, fov_deg)
                .map_err(to_py_err)?,
        ),
        other => other,
    })
}

#[pymethods]
impl Sky {
    /// See `sora.Sky` (the Python class documents every keyword).
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (
        atmosphere, *, sun_elevation_deg=None, sun_azimuth_deg=None, time=None, location=None,
        refraction=true, pressure_hpa=None, temperature_c=None, sun_distance_au=None,
        observer_altitude_m=0.0, wavelengths_nm=None, scattering="multiple",
        method="fast", samples=None, seed=None, reference_steps=None, polarisation=None,
        streams=None, layers=None, twilight_shift_pieces=None
    ))]
    fn new(
        py: Python<'_>,
        atmosphere: &Atmosphere,
        sun_elevation_deg: Option<f64>,
        sun_azimuth_deg: Option<f64>,
        time: Option<&str>,
        location: Option<Vec<f64>>,
        refraction: bool,
        pressure_hpa: Option<f64>,
        temperature_c: Option<f64>,
        sun_distance_au: Option<f64>,
        observer_altitude_m: f64,
        wavelengths_nm: Option<&Bound<'_, PyAny>>,
        scattering: &str,
        method: &str,
        samples: Option<u64>,
        seed: Option<u64>,
        reference_steps: Option<(usize, usize)>,
        polarisation: Option<&str>,
        streams: Option<usize>,
        layers: Option<usize>,
        twilight_shift_pieces: Option<usize>,
    ) -> PyResult<Sky> {
        // The library's names; None: its default for the method
        // (`sora::Polarisation::for_method`: vector, scalar for reference).
        let chosen = polarisation
            .map(|name| {
                name.parse::<Polarisation>().map_err(|_| {
                    value_error(format!(
                        "polarisation = '{name}' is unknown: use 'scalar' or 'vector' (or None: the default, vector; scalar for method='reference')"
                    ))
                })
            })
            .transpose()?;
        if time.is_none() && (pressure_hpa.is_some() || temperature_c.is_some()) {
            return Err(value_error(
                "pressure_hpa and temperature_c apply with time only (the air that refracts the sun's light)",
            ));
        }
        let mut date_sun = None;
        let (elevation_deg, azimuth_deg) = match (sun_elevation_deg, time) {
            (Some(elevation), None) => (
                finite("sun_elevation_deg", elevation, "deg")?,
                finite("sun_azimuth_deg", sun_azimuth_deg.unwrap_or(180.0), "deg")?,
            ),
            (None, Some(time)) => {
                if sun_azimuth_deg.is_some() {
                    return Err(value_error(
                        "sun_azimuth_deg and time exclude each other: the time and location give the sun's azimuth",
                    ));
                }
                let location = location.as_deref().ok_or_else(|| {
                    value_error("time needs location=(latitude_deg, longitude_deg[, elevation_m])")
                })?;
                let sun = sun_from_time(time, location, refraction, (pressure_hpa, temperature_c))?;
                date_sun = Some(sun);
                (sun.elevation_deg, sun.azimuth_deg)
            }
            (Some(_), Some(_)) => {
                return Err(value_error(
                    "give the sun either as sun_elevation_deg (and sun_azimuth_deg) or as time and location, not both",
                ));
            }
            (None, None) => {
                return Err(value_error(
                    "give the sun: sun_elevation_deg=... (degrees above the horizon), or time=... and location=...",
                ));
            }
        };
        if time.is_none() && location.is_some() {
            return Err(value_error("location applies with time only"));
        }
        finite("observer_altitude_m", observer_altitude_m, "m")?;
        let grid = grid_from_python(wavelengths_nm)?;
        let (scattering, method) =
            scattering_and_method(scattering, method, samples, seed, reference_steps)?;
        let scattering = scattering
            .with_resolution(method, streams, layers)
            .and_then(|s| s.with_twilight_shift_pieces(method, twilight_shift_pieces))
            .map_err(to_py_err)?;
        // The sun's distance as `sora spectrum` takes it: given, or the
        // date's for a sun at 1 AU (sora::atmosphere::Sun::date_distance_au).
        let mut atmosphere = atmosphere.inner.clone();
        // The location's elevation is the ground's, as for `sora --location`.
        if let (Some(_), Some(&elevation_m)) =
            (date_sun, location.as_deref().and_then(|l| l.get(2)))
        {
            atmosphere.planet = atmosphere
                .planet
                .clone()
                .with_ground_altitude_m(elevation_m)
                .map_err(|e| value_error(format!("location's elevation: {e}")))?;
        }
        let sun_distance_au = sun_distance_au
            .or_else(|| date_sun.and_then(|sun| atmosphere.sun.date_distance_au(&sun)));
        if let Some(distance_au) = sun_distance_au {
            atmosphere.sun = atmosphere
                .sun
                .at_distance_au(distance_au)
                .map_err(|e| value_error(format!("sun_distance_au: {e}")))?;
        }
        let atmosphere = &atmosphere;
        let polarisation = chosen.unwrap_or(Polarisation::for_method(method));
        let inner = run_detached(py, || {
            sora::Sky::builder(atmosphere)
                .sun_deg(elevation_deg, azimuth_deg)
                .observer_altitude_m(observer_altitude_m)
                .wavelengths(grid)
                .scattering(scattering)
                .method(method)
                .polarisation(polarisation)
                .build()
        })?
        .map_err(to_py_err)?;
        // Parametric phase functions carry no polarisation: say so, once per
        // species, when vector light was asked for by name (as `sora
        // spectrum --stokes` does on stderr; the default says nothing, as
        // the command line's does not).
        let species = if chosen == Some(Polarisation::Vector) {
            inner.non_polarising_species()
        } else {
            Vec::new()
        };
        for (name, kind) in species {
            let message = format!(
                "species {name} has a {kind} phase function, which carries no polarisation: the Stokes vectors treat it as non-polarising (F12 = F34 = 0, F33 = F44 = F11)"
            );
            let message = std::ffi::CString::new(message)
                .map_err(|_| value_error("a species name holds a NUL character"))?;
            PyErr::warn(
                py,
                &py.get_type::<pyo3::exceptions::PyUserWarning>(),
                &message,
                1,
            )?;
        }
        Ok(Sky {
            inner,
            sun_distance_au,
        })
    }

    /// The sun's distance, AU, when `sun_distance_au` or a time set it
    /// (None: the atmosphere file's sun).
    #[getter]
    fn sun_distance_au(&self) -> Option<f64> {
        self.sun_distance_au
    }

    /// The wavelengths of every spectrum, nm.
    #[getter]
    fn wavelengths_nm<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner
            .wavelengths()
            .wavelengths_nm()
            .collect::<Vec<_>>()
            .into_pyarray(py)
    }

    /// The sun's elevation and azimuth, degrees.
    #[getter]
    fn sun_position_deg(&self) -> (f64, f64) {
        self.inner.sun_position_deg()
    }

    /// The method's name ('fast', 'reference' or 'path-tracing').
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method().name()
    }

    /// 'single' or 'multiple'.
    #[getter]
    fn scattering(&self) -> &'static str {
        self.inner.scattering().name()
    }

    /// The direct normal irradiance at the eye, W m^-2 nm^-1.
    fn direct_normal_irradiance<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let values = run_detached(py, || self.inner.direct_normal_irradiance().into_values())?;
        Ok(values.into_pyarray(py))
    }

    /// The colour of spectra on this sky's grid (2-D array [spectrum,
    /// wavelength], W m^-2 sr^-1 nm^-1 or W m^-2 nm^-1): CIE 1931 XYZ
    /// (Y in W m^-2 sr^-1, or W m^-2 for irradiance; 683 Y is cd m^-2, or
    /// lux) or, with `linear_srgb`, the
    /// linear sRGB of that XYZ, as images' pixels are made.
    fn colours<'py>(
        &self,
        py: Python<'py>,
        spectra: PyReadonlyArray2<'py, f64>,
        linear_srgb: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let grid = self.inner.wavelengths();
        let spectra = spectra.as_array();
        if spectra.ncols() != grid.len() {
            return Err(value_error(format!(
                "spectra have {} values each, but the sky's grid {grid} has {} wavelengths",
                spectra.ncols(),
                grid.len()
            )));
        }
        let rows: Vec<Vec<f64>> = spectra.rows().into_iter().map(|r| r.to_vec()).collect();
        let values = run_detached(py, || {
            let to_xyz = SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree);
            let mut values = Vec::with_capacity(rows.len() * 3);
            for row in rows {
                let xyz = to_xyz.to_xyz(&SampledSpectrum::from_values(row))?;
                if linear_srgb {
                    let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz);
                    values.extend([rgb.r, rgb.g, rgb.b]);
                } else {
                    values.extend([xyz.x, xyz.y, xyz.z]);
                }
            }
            Ok::<_, sora::Error>(values)
        })?
        .map_err(to_py_err)?;
        let count = values.len() / 3;
        Ok(Array2::from_shape_vec((count, 3), values)
            .expect("three values per spectrum")
            .into_pyarray(py))
    }

    /// The radiance of views (1-D arrays of equal length, degrees):
    /// (radiance [view, wavelength], standard error or None),
    /// W m^-2 sr^-1 nm^-1.
    #[allow(clippy::type_complexity)]
    fn radiances<'py>(
        &self,
        py: Python<'py>,
        elevation_deg: PyReadonlyArray1<'py, f64>,
        azimuth_deg: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Option<Bound<'py, PyArray2<f64>>>)> {
        let views = views_from_arrays(&elevation_deg, &azimuth_deg)?;
        let results = run_detached(py, || self.inner.radiances(&views))?.map_err(to_py_err)?;
        let wavelengths = self.inner.wavelengths().len();
        let mut values = Vec::with_capacity(views.len() * wavelengths);
        let mut errors = Vec::new();
        for result in &results {
            values.extend_from_slice(result.radiance_w_m2_sr_nm.values());
            if let Some(e) = &result.standard_error_w_m2_sr_nm {
                errors.extend_from_slice(e.values());
            }
        }
        let shape = (views.len(), wavelengths);
        let values = Array2::from_shape_vec(shape, values).expect("one row per view");
        let errors = (matches!(self.inner.method(), Method::PathTracing { .. }))
            .then(|| Array2::from_shape_vec(shape, errors).expect("one row per view"));
        Ok((values.into_pyarray(py), errors.map(|e| e.into_pyarray(py))))
    }

    /// The wavelength grid as `start:stop:step`, nm (as `--wavelengths`).
    #[getter]
    fn wavelength_grid(&self) -> String {
        self.inner.wavelengths().to_string()
    }

    /// Aerial perspective of points at `distance_m` along views (1-D arrays
    /// of equal length; degrees, m): (radiance scattered into each segment
    /// W m^-2 sr^-1 nm^-1, its transmittance, the sun's transmittance to
    /// the point, the sky's horizontal diffuse irradiance W m^-2 nm^-1),
    /// each [view, wavelength].
    #[allow(clippy::type_complexity)]
    fn aerial_perspective<'py>(
        &self,
        py: Python<'py>,
        elevation_deg: PyReadonlyArray1<'py, f64>,
        azimuth_deg: PyReadonlyArray1<'py, f64>,
        distance_m: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Vec<Bound<'py, PyArray2<f64>>>> {
        let views = views_from_arrays(&elevation_deg, &azimuth_deg)?;
        let distances = distance_m.as_array();
        if distances.len() != views.len() {
            return Err(value_error(format!(
                "distance_m has {} values and the views {}: they must broadcast together",
                distances.len(),
                views.len()
            )));
        }
        let segments: Vec<(ViewDirection, f64)> = views
            .iter()
            .copied()
            .zip(distances.iter().copied())
            .collect();
        let results =
            run_detached(py, || self.inner.aerial_perspectives(&segments))?.map_err(to_py_err)?;
        let wavelengths = self.inner.wavelengths().len();
        let shape = (views.len(), wavelengths);
        let mut parts: Vec<Vec<_>> = (0..4)
            .map(|_| Vec::with_capacity(views.len() * wavelengths))
            .collect();
        for ap in &results {
            parts[0].extend_from_slice(ap.radiance.radiance_w_m2_sr_nm.values());
            parts[1].extend_from_slice(ap.transmittance.values());
            parts[2].extend_from_slice(ap.sun_transmittance_at_point.values());
            parts[3].extend_from_slice(ap.sky_irradiance_at_point.values());
        }
        Ok(parts
            .into_iter()
            .map(|values| {
                Array2::from_shape_vec(shape, values)
                    .expect("one row per view")
                    .into_pyarray(py)
            })
            .collect())
    }

    /// 'scalar' or 'vector'.
    #[getter]
    fn polarisation(&self) -> String {
        self.inner.polarisation().to_string()
    }

    /// The Stokes vectors of views (1-D arrays of equal length, degrees),
    /// referred to each view's meridian plane: an array [4, view,
    /// wavelength] of I, Q, U, V, and their standard errors (path tracing)
    /// or None, W m^-2 sr^-1 nm^-1. Needs polarisation='vector'.
    #[allow(clippy::type_complexity)]
    fn stokes<'py>(
        &self,
        py: Python<'py>,
        elevation_deg: PyReadonlyArray1<'py, f64>,
        azimuth_deg: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<(Bound<'py, PyArray3<f64>>, Option<Bound<'py, PyArray3<f64>>>)> {
        if self.inner.polarisation() != Polarisation::Vector {
            return Err(value_error(
                "stokes needs a sky built with polarisation='vector'",
            ));
        }
        let views = views_from_arrays(&elevation_deg, &azimuth_deg)?;
        let results = run_detached(py, || self.inner.radiances(&views))?.map_err(to_py_err)?;
        let wavelengths = self.inner.wavelengths().len();
        let shape = (4, views.len(), wavelengths);
        let mut values = Array3::<f64>::zeros(shape);
        let mut errors = Array3::<f64>::zeros(shape);
        let mut has_errors = false;
        for (k, result) in results.iter().enumerate() {
            let stokes = result
                .stokes
                .as_ref()
                .expect("a vector sky gives Stokes vectors");
            let parts = [
                &result.radiance_w_m2_sr_nm,
                &stokes.q_w_m2_sr_nm,
                &stokes.u_w_m2_sr_nm,
                &stokes.v_w_m2_sr_nm,
            ];
            for (c, part) in parts.iter().enumerate() {
                for (i, v) in part.values().iter().enumerate() {
                    values[[c, k, i]] = *v;
                }
            }
            if let (Some(i_error), Some([q, u, v])) = (
                &result.standard_error_w_m2_sr_nm,
                &stokes.standard_errors_w_m2_sr_nm,
            ) {
                has_errors = true;
                for (c, part) in [i_error, q, u, v].iter().enumerate() {
                    for (i, e) in part.values().iter().enumerate() {
                        errors[[c, k, i]] = *e;
                    }
                }
            }
        }
        Ok((
            values.into_pyarray(py),
            has_errors.then(|| errors.into_pyarray(py)),
        ))
    }

    /// An image, `width` x `height` pixels (default 512 x 512; 1024 x 512
    /// for 'equirectangular'; with only a width, the height is the width,
    /// half of it for 'equirectangular'): `output` 'xyz' (height, width, 3; CIE 1931 XYZ),
    /// 'linear-srgb' (height, width, 3), 'spectral' (height, width,
    /// wavelengths; W m^-2 sr^-1 nm^-1) or, for a vector sky, 'stokes-xyz'
    /// (height, width, 4, 3: the XYZ of I, Q, U, V); black outside a
    /// fisheye's circle.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (
        camera="fisheye", width=None, height=None, output="xyz", draw_sun_disc=true,
        look_elevation_deg=10.0, look_azimuth_deg=180.0, fov_deg=90.0
    ))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        camera: &str,
        width: Option<i64>,
        height: Option<i64>,
        output: &str,
        draw_sun_disc: bool,
        look_elevation_deg: f64,
        look_azimuth_deg: f64,
        fov_deg: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let camera = camera_from_name(camera, (look_elevation_deg, look_azimuth_deg), fov_deg)?;
        // The library's range check and message, as `sora render --width`'s.
        // The library's default sizes, as `sora render`'s.
        let side = |name, side: Option<i64>| {
            side.map(|s| sora::sky::image_side(name, s))
                .transpose()
                .map_err(to_py_err)
        };
        let width = side("image width", width)?.unwrap_or(camera.default_width_px());
        let height = side("image height", height)?.unwrap_or(camera.default_height_px(width));
        let mut image = ImageSettings::new(camera, width, height);
        image.draw_sun_disc = draw_sun_disc;
        let shape = |per_pixel| (height as usize, width as usize, per_pixel);
        match output {
            "spectral" => {
                let values = run_detached(py, || self.inner.render_spectral(&image, &|_| {}))?
                    .map_err(to_py_err)?;
                let wavelengths = self.inner.wavelengths().len();
                // Zero-copy: the library's buffer becomes the array's.
                Ok(Array3::from_shape_vec(shape(wavelengths), values)
                    .expect("one spectrum per pixel")
                    .into_pyarray(py)
                    .into_any())
            }
            "stokes-xyz" => {
                let values = run_detached(py, || {
                    let to_xyz =
                        SpectrumToXyz::new(self.inner.wavelengths(), Observer::Cie1931TwoDegree);
                    let stokes = self.inner.render_stokes_xyz(&image, &to_xyz, &|_| {})?;
                    Ok::<_, sora::Error>(
                        stokes
                            .iter()
                            .flatten()
                            .flat_map(|c| [c.x, c.y, c.z])
                            .collect::<Vec<f64>>(),
                    )
                })?
                .map_err(to_py_err)?;
                Ok(
                    Array4::from_shape_vec((height as usize, width as usize, 4, 3), values)
                        .expect("four XYZ per pixel")
                        .into_pyarray(py)
                        .into_any(),
                )
            }
            "xyz" | "linear-srgb" => {
                let linear_srgb = output == "linear-srgb";
                let values = run_detached(py, || {
                    let to_xyz =
                        SpectrumToXyz::new(self.inner.wavelengths(), Observer::Cie1931TwoDegree);
                    let xyz = self.inner.render_xyz(&image, &to_xyz, &|_| {})?;
                    Ok::<_, sora::Error>(
                        xyz.iter()
                            .flat_map(|c| {
                                if linear_srgb {
                                    let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(*c);
                                    [rgb.r, rgb.g, rgb.b]
                                } else {
                                    [c.x, c.y, c.z]
                                }
                            })
                            .collect::<Vec<f64>>(),
                    )
                })?
                .map_err(to_py_err)?;
                Ok(Array3::from_shape_vec(shape(3), values)
                    .expect("three values per pixel")
                    .into_pyarray(py)
                    .into_any())
            }
            other => Err(value_error(format!(
                "output = '{other}' is unknown: use 'xyz', 'linear-srgb', 'spectral' or 'stokes-xyz'"
            ))),
        }
    }

    fn __repr__(&self) -> String {
        let (elevation, azimuth) = self.inner.sun_position_deg();
        format!(
            "Sky(sun_elevation_deg={elevation}, sun_azimuth_deg={azimuth}, wavelengths_nm='{}', scattering='{}', method='{}', polarisation='{}')",
            self.inner.wavelengths(),
            self.scattering(),
            self.method(),
            self.polarisation()
        )
    }
}

/// The views of two 1-D arrays of equal length (elevation, azimuth; deg),
/// each checked, the bad one named by its index.
fn views_from_arrays(
    elevation_deg: &PyReadonlyArray1<'_, f64>,
    azimuth_deg: &PyReadonlyArray1<'_, f64>,
) -> PyResult<Vec<ViewDirection>> {
    let (elevations, azimuths) = (elevation_deg.as_array(), azimuth_deg.as_array());
    if elevations.len() != azimuths.len() {
        return Err(value_error(format!(
            "view_elevation_deg has {} values and view_azimuth_deg {}: they must broadcast to one list of directions",
            elevations.len(),
            azimuths.len()
        )));
    }
    elevations
        .iter()
        .zip(azimuths.iter())
        .enumerate()
        .map(|(k, (e, a))| {
            ViewDirection::new(*e, *a)
                .map_err(|error| value_error(format!("direction {k}: {error}")))
        })
        .collect()
}
