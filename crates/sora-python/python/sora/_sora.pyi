"""Type stubs of the native module (built from crates/sora-python/src).
Use the documented wrappers in :mod:`sora` and :mod:`sora.mie`; these are
the arrays they wrap."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_F64 = npt.NDArray[np.float64]
_Grid = Union[str, Sequence[float], None]

def set_num_threads(threads: int) -> None:
    """Threads for every later computation (0: one per core)."""

def get_num_threads() -> int: ...
def preset_names() -> List[str]: ...
def preset_toml(name: str) -> str: ...
def write_exr(path: str, rgb: _F64) -> None:
    """Linear RGB (height, width, 3), rows top first, as a 32-bit OpenEXR."""

class Atmosphere:
    @staticmethod
    def preset(name: str) -> "Atmosphere": ...
    @staticmethod
    def from_toml(path: Union[str, "PathLike[str]"]) -> "Atmosphere": ...
    @staticmethod
    def from_toml_str(text: str, base_dir: Optional[str] = None) -> "Atmosphere": ...
    @staticmethod
    def from_dict(table: Dict[str, Any], base_dir: Optional[str] = None) -> "Atmosphere": ...
    def optical_depth_arrays(
        self, wavelengths_nm: _Grid = None
    ) -> Tuple[List[str], List[str], _F64, _F64, _F64, _F64, _F64, _F64]:
        """(names, kinds, wavelengths nm, tau_ext, tau_sca, albedo, g
        [species, wavelength], solar irradiance W m^-2 nm^-1)."""
    def coefficient_arrays(
        self, altitudes_m: _F64, wavelengths_nm: _Grid = None
    ) -> Tuple[_F64, _F64, _F64]:
        """(extinction, scattering [species, altitude, wavelength] m^-1,
        g [species, wavelength])."""
    @property
    def source(self) -> str: ...
    @property
    def species_names(self) -> List[str]: ...

class Sky:
    def __init__(
        self,
        atmosphere: Atmosphere,
        *,
        sun_elevation_deg: Optional[float] = None,
        sun_azimuth_deg: Optional[float] = None,
        time: Optional[str] = None,
        location: Optional[Sequence[float]] = None,
        refraction: bool = True,
        pressure_hpa: Optional[float] = None,
        temperature_c: Optional[float] = None,
        sun_distance_au: Optional[float] = None,
        observer_altitude_m: float = 0.0,
        wavelengths_nm: _Grid = None,
        scattering: str = "multiple",
        method: str = "fast",
        samples: Optional[int] = None,
        seed: Optional[int] = None,
        reference_steps: Optional[Tuple[int, int]] = None,
        polarisation: Optional[str] = None,
        streams: Optional[int] = None,
        layers: Optional[int] = None,
        twilight_shift_pieces: Optional[int] = None,
    ) -> None: ...
    @property
    def wavelengths_nm(self) -> _F64: ...
    @property
    def sun_position_deg(self) -> Tuple[float, float]: ...
    @property
    def sun_distance_au(self) -> Optional[float]: ...
    @property
    def method(self) -> str: ...
    @property
    def scattering(self) -> str: ...
    def direct_normal_irradiance(self) -> _F64: ...
    def colours(self, spectra: _F64, linear_srgb: bool) -> _F64:
        """[spectrum, 3]: CIE 1931 XYZ or linear sRGB of each spectrum."""
    def radiances(self, elevation_deg: _F64, azimuth_deg: _F64) -> Tuple[_F64, Optional[_F64]]:
        """(radiance [view, wavelength], standard error or None), W m^-2 sr^-1 nm^-1."""
    def aerial_perspective(
        self, elevation_deg: _F64, azimuth_deg: _F64, distance_m: _F64
    ) -> List[_F64]:
        """[radiance, transmittance, sun transmittance, sky irradiance], each [view, wavelength]."""
    @property
    def polarisation(self) -> str: ...
    @property
    def wavelength_grid(self) -> str: ...
    def stokes(self, elevation_deg: _F64, azimuth_deg: _F64) -> Tuple[_F64, Optional[_F64]]:
        """(I, Q, U, V [4, view, wavelength], standard errors or None), W m^-2 sr^-1 nm^-1."""
    def render(
        self,
        camera: str = "fisheye",
        width: Optional[int] = None,
        height: Optional[int] = None,
        output: str = "xyz",
        draw_sun_disc: bool = True,
        look_elevation_deg: float = 10.0,
        look_azimuth_deg: float = 180.0,
        fov_deg: float = 90.0,
    ) -> _F64: ...

def mie_efficiencies(
    m_re: _F64, m_im: _F64, x: _F64
) -> Tuple[_F64, _F64, _F64, _F64, _F64]:
    """(qext, qsca, qabs, qback, g) of flat arrays of equal length."""

def mie_phase_function(
    m_re: float, m_im: float, x: float, cos_theta: _F64
) -> Tuple[_F64, _F64]:
    """(phase function sr^-1, S12/S11)."""

def mie_ensemble(
    kind: str,
    first: float,
    second: float,
    m_re: _F64,
    m_im: _F64,
    wavelengths_nm: _F64,
    window_um: Optional[Tuple[float, float]] = None,
) -> Tuple[_F64, _F64, _F64, _F64, _F64, _F64, _F64]:
    """(C_ext, C_sca, C_abs m^2, albedo, g, paper g, number fraction)."""
