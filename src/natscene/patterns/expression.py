"""
Flower colour expression
========================

Defines the flower colour expression of Dong (2007, §3.4, Eqs. 3.6-3.10):

-   :func:`precompute`: the Eq. 3.8 terms of a set of pigments, as a :class:`ColourTable`.
-   :func:`express_xyz`, :func:`express_rgb`: Eq. 3.9, the colour of pigment concentrations in XYZ and linear
    sRGB.
-   :func:`lightness`: Eq. 3.10.
-   :func:`tissue_transmittance`: the transmittance of a pigment-free tissue layer.
-   :func:`chromaticity`: CIE (x, y) of XYZ.

Light L(lambda) (CIE illuminant, default D65, from colour-science), petal tissue transmittance T(lambda)
and pigment absorption A(lambda) give the reflected spectrum R = L - T - A (§3.4.1). Precomputed:

    X_0^(k)  = int (L - T) xbar_k dlambda                 (Eq. 3.8a)
    X_Ai^(k) = int A_i xbar_k dlambda                      (Eq. 3.8b)

with A_i the light absorbed at the standard concentration C_0 by Beer's law,
A_i(lambda) = (L - T)(lambda) (1 - exp(-depth_i k_i(lambda))). At run time, for normalised
concentrations c_i (Beer's law linearised, A_c = c A):

    X^(k) = X_0^(k) - sum_i c_i X_Ai^(k)                    (Eq. 3.9)
    V_c   = V_0 - sum_i c_i V_Ai       (V with v = ybar)    (Eq. 3.10)

xbar_k are the CIE 1931 2-degree colour-matching functions and L(lambda) the illuminant's table, both on the
pigment grid from :mod:`natscene.spectral.grid`. Tristimulus values are normalised so that the illuminant
itself has Y = 1, and converted to linear sRGB by natscene.color.

Tissue transmittance T: the PROSPECT-D transmittance of a pigment-free petal layer (N = 1.2,
water 0.005 cm, dry matter 0.002 g/cm^2), i.e. measured leaf-tissue optics standing in for the
"typical plant tissue" data of [TSP00, SG02].

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Féret, J.-B., Gitelson, A. A., Noble, S. D., & Jacquemoud, S. (2017). PROSPECT-D: Towards modeling leaf
    optical properties through a complete lifecycle. Remote Sensing of Environment, 193, 204–215.
-   Sims, D. A., & Gamon, J. A. (2002). Relationships between leaf pigment content and spectral reflectance
    across a wide range of species, leaf structures and developmental stages. Remote Sensing of Environment,
    81, 337–354.
-   Thenkabail, P. S., Smith, R. B., & De Pauw, E. (2000). Hyperspectral vegetation indices and their
    relationships with agricultural crop characteristics. Remote Sensing of Environment, 71, 158–182.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from natscene.color import xyz_to_linear_srgb
from natscene.errors import InputError
from natscene.patterns.pigments import GRID, WAVELENGTHS, Pigment
from natscene.spectral.grid import cmfs, illuminant_table

__all__ = ["tissue_transmittance", "ColourTable", "precompute", "express_xyz", "lightness", "express_rgb",
           "chromaticity"]


@lru_cache(maxsize=4)
def tissue_transmittance(n: float = 1.2, cw: float = 0.005, cm: float = 0.002) -> np.ndarray:
    """PROSPECT-D transmittance of a pigment-free tissue layer on WAVELENGTHS."""
    import prosail

    wv, _, trans = prosail.run_prospect(n, 0.0, 0.0, 0.0, cw, cm, ant=0.0, prospect_version="D")
    return np.interp(WAVELENGTHS, np.asarray(wv, float), np.asarray(trans, float))


@dataclass
class ColourTable:
    """Precomputed Eq. 3.8 terms: X0 (3,), XA (n, 3) in XYZ with Y(illuminant) = 1."""

    X0: np.ndarray
    XA: np.ndarray
    names: list

    @property
    def V0(self) -> float:
        return float(self.X0[1])

    @property
    def VA(self) -> np.ndarray:
        return self.XA[:, 1]


def precompute(pigments: list[Pigment], illuminant: str = "D65", transmittance: np.ndarray | None = None,
               base_reflectance: float = 1.0) -> ColourTable:
    """Eq. 3.8 for each pigment. ``transmittance`` T(lambda)/L(lambda) as a fraction (default PROSPECT-D
    tissue); ``base_reflectance`` scales L - T (1 = all non-transmitted light is reflected)."""
    cmf, L = cmfs(GRID), illuminant_table(illuminant, GRID)
    T = tissue_transmittance() if transmittance is None else np.broadcast_to(np.asarray(transmittance, float),
                                                                            WAVELENGTHS.shape)
    norm = float(L @ cmf[:, 1])
    base = base_reflectance * L * (1.0 - T)  # L - T
    X0 = base @ cmf / norm
    XA = np.array([(base * (1.0 - np.exp(-p.depth * p.k))) @ cmf / norm for p in pigments]).reshape(-1, 3)
    return ColourTable(X0, XA, [p.name for p in pigments])


def express_xyz(table: ColourTable, conc: np.ndarray) -> np.ndarray:
    """Eq. 3.9: XYZ for concentrations ``conc`` (..., n) (normalised c_i = C_i / C_0)."""
    c = np.asarray(conc, float)
    if c.shape[-1] != table.XA.shape[0]:
        raise InputError(f"{c.shape[-1]} concentration maps for {table.XA.shape[0]} pigments")
    return np.maximum(table.X0 - c @ table.XA, 0.0)


def lightness(table: ColourTable, conc: np.ndarray) -> np.ndarray:
    """Eq. 3.10: V_c = V_0 - sum_i c_i V_Ai."""
    return table.V0 - np.asarray(conc, float) @ table.VA


def express_rgb(table: ColourTable, conc: np.ndarray) -> np.ndarray:
    """Linear sRGB (..., 3) of Eq. 3.9, clipped to >= 0 (out-of-gamut negatives)."""
    return np.maximum(xyz_to_linear_srgb(express_xyz(table, conc)), 0.0).astype(np.float32)


def chromaticity(xyz: np.ndarray) -> np.ndarray:
    """CIE (x, y) of XYZ (..., 3)."""
    xyz = np.asarray(xyz, float)
    s = xyz.sum(axis=-1, keepdims=True)
    return xyz[..., :2] / np.where(s > 0, s, 1.0)
