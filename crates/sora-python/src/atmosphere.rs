//! `sora.Atmosphere` (native part): an atmosphere from a preset, a TOML
//! file or text, or a Python dict with the file schema (converted to TOML
//! and parsed by the library, so the schema, the checks and the messages
//! are the files'); and its vertical optical depths on a grid.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{to_py_err, value_error};
use crate::grid::grid_from_python;
use crate::threads::run_detached;

/// An atmosphere: planet, sun, species (see the atmosphere file schema).
#[pyclass(frozen, module = "sora._sora")]
pub struct Atmosphere {
    pub inner: sora::Atmosphere,
    /// Where it came from, for `repr` ("preset earth-clear", a path, "dict").
    source: String,
}

/// The names of the built-in atmospheres.
#[pyfunction]
pub fn preset_names() -> Vec<&'static str> {
    sora::atmosphere::PRESETS.iter().map(|p| p.name).collect()
}

/// The atmosphere file of the built-in atmosphere `name`, verbatim (the
/// same text the library loads); an unknown name is the library's error.
#[pyfunction]
pub fn preset_toml(name: &str) -> PyResult<&'static str> {
    // An unknown name: the library's message, with its suggestion.
    sora::Atmosphere::preset(name).map_err(to_py_err)?;
    Ok(sora::atmosphere::presets::find_preset(name).map_or("", |preset| preset.toml))
}

/// Parses `text` with the files it names read from `directory`; a file
/// that cannot be read is an `OSError`, anything else a `ValueError`.
fn parse_with_files(text: &str, directory: &Path, context: &str) -> PyResult<sora::Atmosphere> {
    let unreadable: RefCell<Option<String>> = RefCell::new(None);
    let mut read_file = |name: &str| {
        let path = directory.join(name);
        sora::input::read_text(&path).map_err(|e| {
            let message = e.to_string();
            *unreadable.borrow_mut() = Some(message.clone());
            message
        })
    };
    sora::Atmosphere::from_toml_str_with_files(text, &mut read_file).map_err(|error| {
        let message = format!("{context}: {error}");
        if unreadable.borrow().is_some() {
            PyOSError::new_err(message)
        } else {
            value_error(message)
        }
    })
}

#[pymethods]
impl Atmosphere {
    /// A built-in atmosphere by name (`sora.Atmosphere.presets()` lists them).
    #[staticmethod]
    fn preset(name: &str) -> PyResult<Atmosphere> {
        Ok(Atmosphere {
            inner: sora::Atmosphere::preset(name).map_err(to_py_err)?,
            source: format!("preset {name}"),
        })
    }

    /// An atmosphere file (TOML); files it names are read relative to its
    /// directory.
    #[staticmethod]
    fn from_toml(path: PathBuf) -> PyResult<Atmosphere> {
        let text = sora::input::read_text(&path).map_err(to_py_err)?;
        let directory = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(Atmosphere {
            inner: parse_with_files(&text, &directory, &path.display().to_string())?,
            source: path.display().to_string(),
        })
    }

    /// An atmosphere from TOML text; files it names are read relative to
    /// `base_dir` (default: the working directory).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None))]
    fn from_toml_str(text: &str, base_dir: Option<PathBuf>) -> PyResult<Atmosphere> {
        Ok(Atmosphere {
            inner: parse_with_files(text, &base_dir.unwrap_or_default(), "atmosphere text")?,
            source: "TOML text".into(),
        })
    }

    /// An atmosphere from a dict with the schema of the files (tables are
    /// dicts, arrays are lists); files it names are read relative to
    /// `base_dir` (default: the working directory).
    #[staticmethod]
    #[pyo3(signature = (table, base_dir=None))]
    fn from_dict(table: &Bound<'_, PyAny>, base_dir: Option<PathBuf>) -> PyResult<Atmosphere> {
        let dict = table.cast::<PyDict>().map_err(|_| {
            value_error(format!(
                "an atmosphere dict must be a dict (the schema of the atmosphere files), not {}",
                type_name(table)
            ))
        })?;
        let toml_table = table_from_dict(dict, "")?;
        let text = toml::to_string(&toml_table)
            .map_err(|e| value_error(format!("atmosphere dict: {e}")))?;
        Ok(Atmosphere {
            inner: parse_with_files(&text, &base_dir.unwrap_or_default(), "atmosphere dict")?,
            source: "dict".into(),
        })
    }

    /// The vertical optical depths (ground to top) on `wavelengths_nm`:
    /// (species names, kinds, wavelengths nm, extinction and scattering
    /// optical depth [species, wavelength], single-scattering albedo,
    /// asymmetry parameter, solar irradiance W m^-2 nm^-1).
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (wavelengths_nm=None))]
    fn optical_depth_arrays<'py>(
        &self,
        py: Python<'py>,
        wavelengths_nm: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(
        Vec<String>,
        Vec<&'static str>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let grid = grid_from_python(wavelengths_nm)?;
        let optics = run_detached(py, || self.inner.compute_optics(&grid))?.map_err(to_py_err)?;
        let (species, wavelengths) = (optics.species.len(), grid.len());
        let table = |f: &dyn Fn(&sora::atmosphere::SpeciesOptics) -> Vec<f64>| {
            let values: Vec<f64> = optics.species.iter().flat_map(f).collect();
            Array2::from_shape_vec((species, wavelengths), values)
                .expect("one value per species and wavelength")
                .into_pyarray(py)
        };
        Ok((
            optics.species.iter().map(|s| s.name.clone()).collect(),
            optics.species.iter().map(|s| s.kind).collect(),
            grid.wavelengths_nm().collect::<Vec<_>>().into_pyarray(py),
            table(&|s| s.optical_depth_extinction().into_values()),
            table(&|s| s.optical_depth_scattering().into_values()),
            table(&|s| s.single_scattering_albedo().into_values()),
            table(&|s| s.asymmetry_g().into_values()),
            optics
                .solar_irradiance_w_m2_nm
                .values()
                .to_vec()
                .into_pyarray(py),
        ))
    }

    /// The coefficients at altitudes above the ground (1-D array, m, each
    /// within 0..=the top of the atmosphere) on `wavelengths_nm`:
    /// (extinction and scattering coefficients [species, altitude,
    /// wavelength] in m^-1, the library's relative density of each species
    /// there times its coefficients at relative density 1; the asymmetry
    /// parameter [species, wavelength]).
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (altitudes_m, wavelengths_nm=None))]
    fn coefficient_arrays<'py>(
        &self,
        py: Python<'py>,
        altitudes_m: PyReadonlyArray1<'py, f64>,
        wavelengths_nm: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(
        Bound<'py, PyArray3<f64>>,
        Bound<'py, PyArray3<f64>>,
        Bound<'py, PyArray2<f64>>,
    )> {
        let altitudes = altitudes_m.as_slice()?.to_vec();
        let top_m = self.inner.planet.atmosphere_height_m();
        if let Some(bad) = altitudes
            .iter()
            .find(|h| !(h.is_finite() && (0.0..=top_m).contains(*h)))
        {
            return Err(value_error(format!(
                "altitude_m = {bad} m is out of range: allowed 0..={top_m} m (the ground to the top of the atmosphere)"
            )));
        }
        let grid = grid_from_python(wavelengths_nm)?;
        let optics = run_detached(py, || self.inner.compute_optics(&grid))?.map_err(to_py_err)?;
        let shape = (optics.species.len(), altitudes.len(), grid.len());
        let per_altitude = |coefficients: &dyn Fn(&sora::atmosphere::SpeciesOptics) -> &[f64]| {
            let values: Vec<f64> = optics
                .species
                .iter()
                .flat_map(|species| {
                    let at_one = coefficients(species);
                    altitudes.iter().flat_map(move |h| {
                        let density = species.profile.relative_density(*h);
                        at_one.iter().map(move |beta| beta * density)
                    })
                })
                .collect();
            Array3::from_shape_vec(shape, values)
                .expect("one value per species, altitude and wavelength")
                .into_pyarray(py)
        };
        let asymmetry: Vec<f64> = optics
            .species
            .iter()
            .flat_map(|s| s.asymmetry_g().into_values())
            .collect();
        Ok((
            per_altitude(&|s| s.extinction_per_m.values()),
            per_altitude(&|s| s.scattering_per_m.values()),
            Array2::from_shape_vec((shape.0, shape.2), asymmetry)
                .expect("one value per species and wavelength")
                .into_pyarray(py),
        ))
    }

    /// Where this atmosphere came from.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// The species' names, in the file's order.
    #[getter]
    fn species_names(&self) -> Vec<String> {
        self.inner.species.iter().map(|s| s.name.clone()).collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "Atmosphere({}: {} species)",
            self.source,
            self.inner.species.len()
        )
    }
}

fn type_name(value: &Bound<'_, PyAny>) -> String {
    value
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "an unknown type".into())
}

/// `dict` as a TOML table; `path` names where it is (`species[0].`).
fn table_from_dict(dict: &Bound<'_, PyDict>, path: &str) -> PyResult<toml::Table> {
    let mut table = toml::Table::new();
    for (key, value) in dict.iter() {
        let key: String = key.extract().map_err(|_| {
            value_error(format!(
                "atmosphere dict: the key {} at '{path}' is not a string",
                key.repr().map(|r| r.to_string()).unwrap_or_default()
            ))
        })?;
        let here = format!("{path}{key}");
        table.insert(key, toml_value(&value, &here)?);
    }
    Ok(table)
}

/// One Python value as a TOML value (bool, int, float, str, list, dict).
fn toml_value(value: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    // bool first: a Python bool is also an int.
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        return value
            .extract::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| {
                value_error(format!(
                    "atmosphere dict: '{path}' = {} does not fit a 64-bit integer",
                    value.repr().map(|r| r.to_string()).unwrap_or_default()
                ))
            });
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if let Ok(text) = value.cast::<PyString>() {
        return Ok(toml::Value::String(text.to_cow()?.into_owned()));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        return Ok(toml::Value::Table(table_from_dict(
            dict,
            &format!("{path}."),
        )?));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = value.extract()?;
        return items
            .iter()
            .enumerate()
            .map(|(i, item)| toml_value(item, &format!("{path}[{i}]")))
            .collect::<PyResult<Vec<_>>>()
            .map(toml::Value::Array);
    }
    // numpy scalars and other numbers: by their float value.
    if let Ok(number) = value.extract::<f64>() {
        return Ok(toml::Value::Float(number));
    }
    Err(value_error(format!(
        "atmosphere dict: '{path}' is {} ({}), which an atmosphere file cannot hold: use a number, string, bool, list or dict",
        type_name(value),
        value.repr().map(|r| r.to_string()).unwrap_or_default()
    )))
}
