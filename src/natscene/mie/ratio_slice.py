"""
Slice of the Mie/isotropic ratio
================================

Defines the picture of the Mie/isotropic ratio R_i of Reimschuessel (2011, Fig. 8): a slice of the solved point
cloud through its middle, along the light (the ratio itself: :func:`natscene.mie.solver.solve`, Eq. 1).

-   :func:`ratio_slice`: R_i on the lattice slice through the middle containing the light direction.
-   :func:`ratio_image`: the slice as a grey image.

References
----------
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

import numpy as np

__all__ = ["ratio_slice", "ratio_image"]


def ratio_slice(solution) -> np.ndarray:
    """Fig. 8: R_i on the lattice slice through the middle containing the light direction (rows: along
    the light, sun at the top; columns: across), NaN where there is no point. Returns (nc, na)."""
    p = solution.points
    nc, nb, na = p.shape
    b_mid = int(np.median(p.index[:, 1]))
    img = np.full((nc, na), np.nan, np.float32)
    sel = p.index[:, 1] == b_mid
    img[p.index[sel, 0], p.index[sel, 2]] = solution.ratio[sel]
    return img


def ratio_image(solution, scale: int = 4) -> np.ndarray:
    """Fig. 8 as a grey image (dark = isotropic, light = Mie), blue where there is no point."""
    r = ratio_slice(solution)
    rgb = np.where(np.isnan(r)[..., None], np.array([0.05, 0.08, 0.2], np.float32), np.nan_to_num(r)[..., None])
    return np.repeat(np.repeat(rgb, scale, 0), scale, 1).astype(np.float32)
