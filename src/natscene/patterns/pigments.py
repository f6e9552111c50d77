"""
Pigment absorption spectra
==========================

Defines the pigment absorption spectra for flower colour expression (Dong 2007, §3.4) and leaf colour (Ch. 4):

-   :func:`pigment`: a :class:`Pigment` from a config entry.
-   :func:`prospect_specific_absorption`: the PROSPECT-D specific absorption of a pigment
    (:data:`PROSPECT_PIGMENTS`).
-   :func:`band_absorption`: the parametric absorption-band model (:data:`BAND_PIGMENTS`).
-   :data:`GRID`, :data:`WAVELENGTHS`: the wavelength grid of the spectra.

Measured spectra: the specific absorption coefficients of chlorophyll a+b, carotenoids and anthocyanins
of PROSPECT-D (Féret et al. 2017), shipped by the ``prosail`` package (cm^2/ug, 400-2500 nm, 1 nm).

Other flower pigments (betalains, aurones, ...) have no PROSPECT-D spectrum; they use a documented
parametric absorption-band model: a sum of Gaussian bands in wavelength,

    k(lambda) = sum_i h_i * exp(-(lambda - lambda_i)^2 / (2 sigma_i^2)),

with band centres from the pigment literature: betanin (red-violet betacyanin) 538 nm, vulgaxanthin
(yellow betaxanthin) 476 nm, aureusidin (yellow aurone) 399/~420 nm, a generic "green absorber" at
540 nm. A pigment named ``blank`` absorbs nothing ("blank pigment" of §3.3.2 for one-pigment flowers).

Wavelength grid: :data:`GRID`, a :class:`natscene.spectral.grid.WavelengthGrid` of 400-770 nm in 5 nm steps.
Dong integrates over 380-770 nm; PROSPECT-D starts at 400 nm, and the CIE 1931 colour-matching functions carry
< 0.2 % of Y below 400 nm.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Féret, J.-B., Gitelson, A. A., Noble, S. D., & Jacquemoud, S. (2017). PROSPECT-D: Towards modeling leaf
    optical properties through a complete lifecycle. Remote Sensing of Environment, 193, 204–215.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from natscene.errors import InputError
from natscene.spectral.grid import WavelengthGrid

__all__ = ["GRID", "WAVELENGTHS", "BAND_PIGMENTS", "PROSPECT_PIGMENTS", "prospect_specific_absorption",
           "band_absorption", "Pigment", "pigment"]

#: the wavelength grid of the pigment spectra, flower colour expression and leaf colour
GRID = WavelengthGrid(400.0, 770.0, 5.0)
WAVELENGTHS = GRID.wavelengths

#: parametric bands: name -> list of (centre nm, sigma nm, relative height)
BAND_PIGMENTS = {
    "betanin": [(538.0, 32.0, 1.0), (470.0, 25.0, 0.15)],
    "betaxanthin": [(476.0, 30.0, 1.0)],
    "aurone": [(405.0, 28.0, 1.0), (440.0, 22.0, 0.4)],
    "green_absorber": [(540.0, 35.0, 1.0)],
}
PROSPECT_PIGMENTS = {"chlorophyll": "kab", "carotenoid": "kcar", "anthocyanin": "kant"}


@lru_cache(maxsize=1)
def _prospect():
    from prosail.spectral_library import get_spectra

    return get_spectra().prospectd


def prospect_specific_absorption(name: str, wavelengths=WAVELENGTHS) -> np.ndarray:
    """PROSPECT-D specific absorption coefficient (cm^2/ug) of chlorophyll/carotenoid/anthocyanin."""
    if name not in PROSPECT_PIGMENTS:
        raise InputError(f"pigment '{name}' has no PROSPECT-D spectrum; choose one of {sorted(PROSPECT_PIGMENTS)}")
    k = np.asarray(getattr(_prospect(), PROSPECT_PIGMENTS[name]), float)
    wl = np.arange(400.0, 400.0 + k.size)
    return np.interp(wavelengths, wl, k)


def band_absorption(bands, wavelengths=WAVELENGTHS) -> np.ndarray:
    """The parametric model: sum of Gaussian bands [(centre, sigma, height), ...]."""
    wl = np.asarray(wavelengths, float)[:, None]
    b = np.asarray(bands, float).reshape(-1, 3)
    return (b[None, :, 2] * np.exp(-0.5 * ((wl - b[None, :, 0]) / b[None, :, 1]) ** 2)).sum(axis=1)


@dataclass
class Pigment:
    """A pigment: its absorption shape k(lambda) (peak 1) and the optical depth at the standard
    concentration C_0 (the absorbance at the peak, natural log units)."""

    name: str
    k: np.ndarray
    depth: float = 2.0


def pigment(spec) -> Pigment:
    """A pigment from a config entry: a name (``chlorophyll``, ``carotenoid``, ``anthocyanin``, one of
    BAND_PIGMENTS, or ``blank``) or a mapping ``{name, depth, bands: [[centre, sigma, height], ...]}``."""
    if isinstance(spec, str):
        spec = {"name": spec}
    name = spec.get("name", "custom")
    depth = float(spec.get("depth", 2.0))
    if spec.get("bands"):
        k = band_absorption(spec["bands"])
    elif name == "blank":
        k = np.zeros_like(WAVELENGTHS)
    elif name in PROSPECT_PIGMENTS:
        k = prospect_specific_absorption(name)
    elif name in BAND_PIGMENTS:
        k = band_absorption(BAND_PIGMENTS[name])
    else:
        raise InputError(f"unknown pigment '{name}': use one of {sorted(PROSPECT_PIGMENTS)}, "
                         f"{sorted(BAND_PIGMENTS)}, 'blank', or give 'bands'")
    peak = k.max()
    return Pigment(name, k / peak if peak > 0 else k, depth)
