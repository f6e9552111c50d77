"""
RGB to spectrum upsampling
==========================

Defines the RGB -> spectrum upsampling of the hybrid renderer (Dong 2007, §2.3.1: "RGB light sources ...
converted into spectrum"; §2.4: the RGB part gathered by a ray that hits a spectral material is converted to a
spectrum):

-   :func:`rgb_to_reflectance`: reflectance spectra of linear-sRGB reflectances.
-   :func:`rgb_to_radiance`: radiance spectra of linear-sRGB radiances (D65 × the upsampled reflectance).

Two published methods (:data:`METHODS`):

- ``"mallett2019"`` (default): Mallett & Yuksel, "Spectral Primary Decomposition for Rendering with sRGB
  Reflectance", EGSR 2019. A reflectance is ``r B_r(λ) + g B_g(λ) + b B_b(λ)`` with three fixed basis
  spectra (colour-science's ``MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019``, tabulated 380-780 nm / 5 nm). It is
  linear, stays in [0, 1] for RGB in [0, 1], and round-trips exactly under D65, which is what a hybrid
  renderer needs: an RGB light (r, g, b) becomes the radiance ``D65(λ) · (r B_r + g B_g + b B_b)`` whose
  colour is (r, g, b) again.
- ``"smits1999"``: Smits, "An RGB-to-Spectrum Conversion for Reflectances", JGT 1999 (colour-science's
  basis spectra, vectorised here): piecewise combination of white, cyan, magenta, yellow, red, green, blue.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Mallett, I., & Yuksel, C. (2019). Spectral primary decomposition for rendering with sRGB reflectance.
    Eurographics Symposium on Rendering (EGSR) 2019.
-   Smits, B. (1999). An RGB-to-spectrum conversion for reflectances. Journal of Graphics Tools, 4(4), 11–22.
"""
from __future__ import annotations

from functools import lru_cache

import colour
import numpy as np

from natscene.spectral.grid import DEFAULT_GRID, WavelengthGrid, illuminant_table

__all__ = ["METHODS", "rgb_to_reflectance", "rgb_to_radiance"]

METHODS = ("mallett2019", "smits1999")


@lru_cache(maxsize=8)
def mallett_basis(grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """(3, N) Mallett-Yuksel 2019 basis spectra B_r, B_g, B_b on the grid."""
    b = colour.recovery.MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019.copy()
    if b.shape != grid.shape:
        b = b.align(grid.shape)
    return np.ascontiguousarray(np.asarray(b.values, np.float64).T)


@lru_cache(maxsize=8)
def smits_basis(grid: WavelengthGrid = DEFAULT_GRID) -> dict:
    """Smits 1999 basis spectra on the grid (white, cyan, magenta, yellow, red, green, blue)."""
    from colour.recovery import SDS_SMITS1999
    out = {}
    for name, sd in SDS_SMITS1999.items():
        s = sd.copy()
        s.interpolator = colour.LinearInterpolator
        s.extrapolator_kwargs = {"method": "Constant", "left": None, "right": None}
        out[name] = np.asarray(s[grid.wavelengths], np.float64)
    return out


def _smits(rgb: np.ndarray, grid: WavelengthGrid) -> np.ndarray:
    """Vectorised Smits 1999 (his Fig. 3 decision tree)."""
    B = smits_basis(grid)
    r, g, b = rgb[..., 0:1], rgb[..., 1:2], rgb[..., 2:3]
    out = np.zeros(rgb.shape[:-1] + (grid.size,), np.float64)
    # r smallest
    m = (r <= g) & (r <= b)
    s = r * B["white"] + np.where(g <= b, (g - r) * B["cyan"] + (b - g) * B["blue"],
                                 (b - r) * B["cyan"] + (g - b) * B["green"])
    out = np.where(m, s, out)
    # g smallest
    m2 = (~m) & (g <= r) & (g <= b)
    s = g * B["white"] + np.where(r <= b, (r - g) * B["magenta"] + (b - r) * B["blue"],
                                 (b - g) * B["magenta"] + (r - b) * B["red"])
    out = np.where(m2, s, out)
    # b smallest
    m3 = (~m) & (~m2)
    s = b * B["white"] + np.where(r <= g, (r - b) * B["yellow"] + (g - r) * B["green"],
                                 (g - b) * B["yellow"] + (r - g) * B["red"])
    return np.where(m3, s, out)


def rgb_to_reflectance(rgb, grid: WavelengthGrid = DEFAULT_GRID, method: str = "mallett2019") -> np.ndarray:
    """Reflectance spectra (..., N) for linear-sRGB reflectances (..., 3)."""
    a = np.asarray(rgb, np.float64)
    if a.shape[-1] != 3:
        raise ValueError(f"rgb must end in 3 channels, got shape {a.shape}")
    if method == "mallett2019":
        return a @ mallett_basis(grid)
    if method == "smits1999":
        return _smits(a, grid)
    raise ValueError(f"unknown upsampling method {method!r}; use one of {METHODS}")


def rgb_to_radiance(rgb, grid: WavelengthGrid = DEFAULT_GRID, method: str = "mallett2019") -> np.ndarray:
    """Radiance spectra (..., N) for linear-sRGB radiances (..., 3): D65 × the upsampled reflectance.

    RGB (1, 1, 1) maps to D65 (the white of the RGB part). Values above 1 are handled by linearity for
    Mallett 2019; Smits 1999 is applied to rgb / max(rgb) and rescaled.
    """
    a = np.asarray(rgb, np.float64)
    if method == "smits1999":
        scale = np.maximum(a.max(axis=-1, keepdims=True), 1e-30)
        return _smits(a / scale, grid) * scale * illuminant_table("D65", grid)
    return rgb_to_reflectance(a, grid, method) * illuminant_table("D65", grid)
