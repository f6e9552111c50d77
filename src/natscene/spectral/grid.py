"""
Wavelength grid and CIE integration
===================================

Defines the wavelength grid, the CIE tables on it, and spectrum -> CIE XYZ -> linear sRGB (Dong 2007, §2.4, the
colour-transformation stage):

-   :class:`WavelengthGrid`, :data:`DEFAULT_GRID`: regular wavelength sampling in nm.
-   :func:`cmfs`, :func:`illuminant_table`: the CIE 1931 2° colour-matching functions and an illuminant's SPD on
    a grid.
-   :func:`kappa`, :func:`integration_matrix`: the constant and the matrix of the X_k integration.
-   :func:`spectrum_to_rgb`, :func:`spectrum_to_rgb_matrix`, :func:`reflectance_to_rgb`: spectra to linear sRGB.

The one home of the wavelength grid and of the colour-matching functions and
illuminant tables (colour-science's) for every stage that works with spectra (compositing, pigments, leaves).

Spectra are sampled on a regular grid (by default the schema's ``composite.<name>.wavelengths``, 380-780 nm
every 5 nm, 81 samples; the pigment stages use 400-770 nm, where PROSPECT-D has data). Tristimulus values are
``X_k = kappa * sum_i S(lambda_i) xbar_k(lambda_i) dlambda`` with the CIE 1931 2° colour-matching functions
(Dong §2.4). ``kappa`` is fixed once for the whole project: it makes the CIE D65 SPD (as tabulated, 100 at
560 nm) integrate to Y = 1, so a *radiance* spectrum equal to D65 is the linear-sRGB white (1, 1, 1) that the
RGB part of the renderer uses, and a reflectance R lit by D65 gives its usual XYZ (Y = luminance factor).
XYZ -> linear sRGB goes through :mod:`natscene.color` (colour-science).

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Mansencal, T., Mauderer, M., Parsons, M., et al. Colour: Colour Science for Python (software).
    https://www.colour-science.org
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import colour
import numpy as np

from natscene.color import xyz_to_linear_srgb
from natscene.errors import InputError

__all__ = ["WavelengthGrid", "DEFAULT_GRID", "cmfs", "illuminant_table", "kappa", "integration_matrix",
           "spectrum_to_rgb", "spectrum_to_rgb_matrix", "reflectance_to_rgb"]

CMFS_NAME = "CIE 1931 2 Degree Standard Observer"


@dataclass(frozen=True)
class WavelengthGrid:
    """Regular wavelength sampling in nm, both ends included (no default: a composite's grid is its config's
    ``wavelengths``, :data:`DEFAULT_GRID` the schema's default of it)."""

    start: float
    stop: float
    step: float

    def __post_init__(self):
        if not (self.step > 0 and self.stop > self.start):
            raise ValueError(f"bad wavelength grid {self.start}-{self.stop} step {self.step}")
        n = (self.stop - self.start) / self.step
        if abs(n - round(n)) > 1e-9:
            raise ValueError("wavelength grid: (stop - start) must be a multiple of step")

    @property
    def wavelengths(self) -> np.ndarray:
        return self.start + self.step * np.arange(self.size)

    @property
    def size(self) -> int:
        return int(round((self.stop - self.start) / self.step)) + 1

    def channel_names(self, prefix: str = "S") -> list[str]:
        """EXR channel names of the spectral part of the hybrid image (Dong §2.3.2): S380 ... S780."""
        return [f"{prefix}{w:g}" for w in self.wavelengths]

    @property
    def shape(self) -> "colour.SpectralShape":
        return colour.SpectralShape(self.start, self.stop, self.step)


def _schema_grid() -> WavelengthGrid:
    """The schema's default of ``composite.<name>.wavelengths`` (its one home)."""
    from natscene.config import schema_section
    props = schema_section("composite.schema.yaml", ("additionalProperties", "wavelengths"))["properties"]
    return WavelengthGrid(*(float(props[k]["default"]) for k in ("start", "stop", "step")))


#: The library's default grid: the composite's default ``wavelengths`` (config ``composite.<name>.wavelengths``).
DEFAULT_GRID = _schema_grid()


@lru_cache(maxsize=8)
def _cmfs(grid: WavelengthGrid) -> np.ndarray:
    cmfs = colour.MSDS_CMFS[CMFS_NAME].copy().align(grid.shape)
    return np.asarray(cmfs.values, np.float64)  # (N, 3)


def cmfs(grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """CIE 1931 2° xbar, ybar, zbar sampled on the grid, shape (N, 3)."""
    return _cmfs(grid).copy()


@lru_cache(maxsize=16)
def _illuminant(name: str, grid: WavelengthGrid) -> np.ndarray:
    if name not in colour.SDS_ILLUMINANTS:
        raise InputError(f"unknown illuminant '{name}'; use a colour-science name such as D65, D50, A")
    sd = colour.SDS_ILLUMINANTS[name].copy().align(grid.shape)
    return np.asarray(sd.values, np.float64)


def illuminant_table(name: str = "D65", grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """A CIE illuminant's SPD as colour-science tabulates it (D65: 100 at 560 nm) on the grid, shape (N,).
    The array is shared (cached): do not modify it."""
    return _illuminant(name, grid)


@lru_cache(maxsize=8)
def kappa(grid: WavelengthGrid = DEFAULT_GRID) -> float:
    """The constant of Dong's X_k = kappa ∫ I xbar_k dlambda: D65 (tabulated) integrates to Y = 1."""
    return float(1.0 / (illuminant_table("D65", grid) @ _cmfs(grid)[:, 1] * grid.step))


def integration_matrix(grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """(N, 3) matrix W with XYZ = S @ W, i.e. W = kappa * cmfs * dlambda."""
    return _cmfs(grid) * (kappa(grid) * grid.step)


def spectrum_to_xyz(spectra: np.ndarray, grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """CIE XYZ of radiance spectra (..., N) (Dong §2.4)."""
    s = np.asarray(spectra)
    if s.shape[-1] != grid.size:
        raise ValueError(f"spectra have {s.shape[-1]} samples, grid has {grid.size}")
    return s @ integration_matrix(grid).astype(s.dtype if s.dtype == np.float32 else np.float64)


def spectrum_to_rgb(spectra: np.ndarray, grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """Linear sRGB of radiance spectra (..., N): X_k integration, then M_XYZ->sRGB (colour-science)."""
    return xyz_to_linear_srgb(spectrum_to_xyz(spectra, grid))


@lru_cache(maxsize=8)
def _xyz_to_rgb_matrix() -> np.ndarray:
    return np.asarray(xyz_to_linear_srgb(np.eye(3)), np.float64).T  # rgb = M @ xyz


def spectrum_to_rgb_matrix(grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """(N, 3) matrix taking spectra straight to linear sRGB (rgb = S @ A), for hot paths.

    Equal to ``integration_matrix(grid) @ M_XYZ->sRGB^T``; M taken from :mod:`natscene.color`.
    """
    return integration_matrix(grid) @ _xyz_to_rgb_matrix().T


def reflectance_to_rgb(reflectance: np.ndarray, illuminant: np.ndarray | None = None,
                       grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """Linear sRGB of reflectance spectra (..., N) under an illuminant SPD (default D65)."""
    illum = illuminant_table("D65", grid) if illuminant is None else np.asarray(illuminant, np.float64)
    return spectrum_to_rgb(np.asarray(reflectance, np.float64) * illum, grid)
