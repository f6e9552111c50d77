"""
Leaf colour from pigment concentrations
=======================================

Defines the leaf colour of Dong (2007, §4.3.3) from pigment concentrations:

-   :func:`leaf_rgb`: the linear sRGB of a leaf with normalised pigment concentrations.
-   :func:`prospect_reflectance`: the PROSPECT-D reflectance of a leaf.
-   :func:`reflectance_to_rgb`: Eqs. 4.1-4.2, reflectance spectra to linear sRGB.

Dong subtracts pigment absorbance from the light in the spectral domain (Eq. 4.9,
R = L - T_0 - A_0 - sum_p c_p A_p). We use the PROSPECT-D leaf optics model instead (through the
``prosail`` package): a plate model of the leaf whose absorption is the sum of the specific absorption
coefficients of chlorophyll a+b, carotenoids and anthocyanins times their contents (Beer's law inside
the plates) — the same linear-absorption idea with multiple scattering in the mesophyll and measured
spectra. The reflectance R(lambda) is then turned into colour with Eqs. 4.1-4.2 (CIE 1931 CMFs under
an illuminant, on the pigment grid, from :mod:`natscene.spectral.grid`), normalised so a perfect white
reflector has Y = 1, and converted to linear sRGB by natscene.color.

Normalised concentrations c map to contents: Cab = c_ch * cab_max (ug/cm^2), Car = c_ca * car_max,
Anth = c_an * ant_max.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Féret, J.-B., Gitelson, A. A., Noble, S. D., & Jacquemoud, S. (2017). PROSPECT-D: Towards modeling leaf
    optical properties through a complete lifecycle. Remote Sensing of Environment, 193, 204–215.
"""
from __future__ import annotations

import numpy as np

from natscene.color import xyz_to_linear_srgb
from natscene.patterns.pigments import GRID, WAVELENGTHS
from natscene.spectral.grid import cmfs, illuminant_table

__all__ = ["prospect_reflectance", "reflectance_to_rgb", "leaf_rgb"]


def prospect_reflectance(cab: float, car: float, ant: float, n: float = 1.5, cbrown: float = 0.0,
                         cw: float = 0.012, cm: float = 0.009) -> np.ndarray:
    """PROSPECT-D reflectance on WAVELENGTHS."""
    import prosail

    wv, refl, _ = prosail.run_prospect(n, cab, car, cbrown, cw, cm, ant=ant, prospect_version="D")
    return np.interp(WAVELENGTHS, np.asarray(wv, float), np.asarray(refl, float))


def reflectance_to_rgb(refl: np.ndarray, illuminant: str = "D65") -> np.ndarray:
    """Eqs. 4.1-4.2: reflectance spectra (..., N) -> linear sRGB (..., 3)."""
    cmf, L = cmfs(GRID), illuminant_table(illuminant, GRID)
    xyz = (np.asarray(refl, float) * L) @ cmf / float(L @ cmf[:, 1])
    return np.maximum(xyz_to_linear_srgb(xyz), 0.0).astype(np.float32)


def leaf_rgb(c_ch: float, c_ca: float, c_an: float, cab_max: float = 50.0, car_max: float = 12.0,
             ant_max: float = 10.0, brown: float = 0.0, illuminant: str = "D65") -> np.ndarray:
    """Linear sRGB of a leaf with normalised pigment concentrations."""
    r = prospect_reflectance(c_ch * cab_max, c_ca * car_max, c_an * ant_max, cbrown=brown)
    return reflectance_to_rgb(r, illuminant)
