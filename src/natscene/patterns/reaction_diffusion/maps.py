"""
Pigment distribution maps
=========================

Defines the pigment distribution maps of Dong (2007, §3.3.2): concentrations C on the petal to normalised maps
c in [0, 1].

-   :func:`normalise`: the map of a concentration field.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError

__all__ = ["normalise"]


def normalise(conc: np.ndarray, mask: np.ndarray, c0: float | None = None, mode: str = "max") -> np.ndarray:
    """Pigment distribution map (§3.3.2), 0 off-petal, clipped to [0, 1].

    ``mode="max"``: c = C / C_0 (the paper's normalisation), C_0 = the highest concentration on the petal unless
    given. ``mode="range"``: c = (C - C_min) / (C_0 - C_min), i.e. the lowest concentration on the petal is taken
    as the pigment-free level. A steady state of Eq. 3.5 sits on the positive homogeneous state a*, b* and the
    patterns are deviations of 10-60 % from it, so C / C_max keeps the whole pattern in the top of the colour
    range; "range" maps it onto the full range of the pigment database (Fig. 3.3's dark-on-white maps)."""
    inside = np.asarray(mask) > 0.5
    if mode not in ("max", "range"):
        raise InputError(f"pigment map normalisation '{mode}': use 'max' (C / C_0) or 'range'")
    c0 = float(conc[inside].max()) if c0 is None else float(c0)
    lo = float(conc[inside].min()) if mode == "range" else 0.0
    span = c0 - lo
    out = np.where(inside, (conc - lo) / span if span > 0 else 0.0, 0.0)
    return np.clip(out, 0.0, 1.0).astype(np.float32)
