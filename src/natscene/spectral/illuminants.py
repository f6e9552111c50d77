"""
Illuminant SPDs
===============

Defines the illuminant SPDs of the spectral renderer (Dong 2007, §2.3.1: spectral light sources; §2.5: a
parallel D65 light):

- :func:`d65`: CIE standard illuminant D65 (colour-science's table) on the grid, scaled so that its
  radiance is linear-sRGB white (1, 1, 1) (see :mod:`natscene.spectral.grid`);
- :func:`daylight`: CIE daylight (D series) at a correlated colour temperature;
- :func:`sun_spd`: a sunlight SPD matched to a fitted sunlight colour ``c_in`` (Dobashi's c_in, linear
  sRGB): the CIE daylight SPD at the CCT of c_in's chromaticity, times the smooth spectral-primary
  residual that brings its colour exactly onto c_in (so the spectral sun and the RGB sun agree).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
"""
from __future__ import annotations

import colour
import numpy as np

from natscene.color import linear_srgb_to_xyz
from natscene.spectral.grid import DEFAULT_GRID, WavelengthGrid, illuminant_table, kappa, spectrum_to_rgb

__all__ = ["d65", "daylight", "sun_spd"]


def d65(grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """D65 radiance on the grid whose colour is linear sRGB (1, 1, 1) (Y = 1)."""
    return illuminant_table("D65", grid).copy()


def daylight(cct: float, grid: WavelengthGrid = DEFAULT_GRID) -> np.ndarray:
    """CIE D-series daylight SPD at ``cct`` kelvin (4000-25000), scaled to Y = 1."""
    cct = float(np.clip(cct, 4000.0, 25000.0))
    xy = colour.temperature.CCT_to_xy_CIE_D(cct)
    sd = colour.sd_CIE_illuminant_D_series(xy).align(grid.shape)
    s = np.asarray(sd.values, np.float64)
    from natscene.spectral.grid import integration_matrix
    return s / (s @ integration_matrix(grid)[:, 1])


def sun_spd(c_in, grid: WavelengthGrid = DEFAULT_GRID, method: str = "mallett2019") -> np.ndarray:
    """Sunlight SPD whose linear-sRGB colour is ``c_in`` (a daylight spectrum shaped to match it).

    The CCT comes from c_in's chromaticity (McCamy 1992 via colour-science), clamped to the daylight
    range 4000-25000 K; the remaining colour difference is applied as a reflectance-like factor
    upsampled from the RGB ratio (:mod:`natscene.spectral.upsampling`), which is exact for in-gamut
    ratios with the default spectral-primary method.
    """
    from natscene.spectral.upsampling import rgb_to_reflectance

    c = np.asarray(c_in, np.float64).reshape(3)
    if not np.all(np.isfinite(c)) or np.any(c < 0) or c.sum() <= 0:
        raise ValueError(f"sun colour c_in must be 3 finite non-negative values, got {c.tolist()}")
    xyz = linear_srgb_to_xyz(c).astype(np.float64)
    xy = xyz[:2] / max(xyz.sum(), 1e-12)
    try:
        cct = float(colour.xy_to_CCT(xy, method="McCamy 1992"))
    except Exception:  # noqa: BLE001 - far from the locus: fall back to D65's CCT
        cct = 6504.0
    if not np.isfinite(cct):
        cct = 6504.0
    base = daylight(cct, grid)
    ratio = c / np.maximum(spectrum_to_rgb(base, grid), 1e-9)
    spd = base
    for _ in range(6):  # fixed point: the upsampled factor is exact under D65 only, close elsewhere
        scale = max(float(ratio.max()), 1e-12)
        spd = base * rgb_to_reflectance(np.clip(ratio / scale, 0.0, 1.0), grid=grid, method=method) * scale
        got = spectrum_to_rgb(spd, grid)
        ratio = ratio * c / np.maximum(got, 1e-9)
    return spd
