"""
Shape descriptors of a pigment map
==================================

Defines shape descriptors of a pigment map on a petal, used to check the four Fig. 3.3 patterns of Dong (2007)
(centre spot, marginal band, ring, radial stripes):

-   :func:`radial_profile`: the radial profile from the vein root to the petal margin.
-   :func:`angular_contrast`: the angular (vein / inter-vein) contrast.
-   :func:`polar_coordinates`: the angle from the root and the relative distance rho (root 0, margin 1) of every
    petal pixel.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np

__all__ = ["polar_coordinates", "radial_profile", "angular_contrast"]


def polar_coordinates(mask: np.ndarray, root) -> tuple[np.ndarray, np.ndarray]:
    """Per petal pixel (in ``np.flatnonzero(mask > 0.5)`` order): the angle from the root (0 = from the root
    toward the top of the image) and rho = distance to the root / distance from the root to the margin in that
    direction (0 at the root, 1 at the margin; the margin distance is the maximum over 1.875-degree bins)."""
    inside = np.asarray(mask) > 0.5
    rr, cc = np.nonzero(inside)
    r0, c0 = root
    ang = np.arctan2(cc - c0, r0 - rr)
    d = np.hypot(rr - r0, cc - c0)
    nb = 96
    abin = np.clip(((ang + np.pi / 2) / np.pi * nb).astype(int), 0, nb - 1)
    far = np.zeros(nb)
    np.maximum.at(far, abin, d)
    return ang, np.clip(d / np.maximum(far[abin], 1.0), 0.0, 1.0)


def radial_profile(conc: np.ndarray, mask: np.ndarray, root, bins: int = 10) -> np.ndarray:
    """Mean of the map, stretched to [0, 1] over the petal, in ``bins`` equal bins of rho (root to margin)."""
    inside = np.asarray(mask) > 0.5
    c = np.asarray(conc, float)[inside]
    c = (c - c.min()) / max(float(np.ptp(c)), 1e-30)
    _, rho = polar_coordinates(mask, root)
    k = np.minimum((rho * bins).astype(int), bins - 1)
    return np.bincount(k, c, bins) / np.maximum(np.bincount(k, None, bins), 1)


def angular_contrast(conc: np.ndarray, mask: np.ndarray, root, half_angle_deg: float = 40.0,
                     rho_range=(0.3, 0.9), n_angle: int = 32) -> float:
    """Radial-stripe strength: in rings of rho within ``rho_range`` (0.1 wide), the 90th minus the 10th
    percentile of the angular-bin means of the stretched map over |angle| < ``half_angle_deg``; averaged."""
    inside = np.asarray(mask) > 0.5
    c = np.asarray(conc, float)[inside]
    c = (c - c.min()) / max(float(np.ptp(c)), 1e-30)
    ang, rho = polar_coordinates(mask, root)
    h = np.radians(half_angle_deg)
    a_bin = np.clip(((ang + h) / (2 * h) * n_angle).astype(int), 0, n_angle - 1)
    out = []
    for lo in np.arange(rho_range[0], rho_range[1] - 1e-9, 0.1):
        s = (np.abs(ang) < h) & (rho >= lo) & (rho < lo + 0.1)
        cnt = np.bincount(a_bin[s], None, n_angle)
        m = (np.bincount(a_bin[s], c[s], n_angle) / np.maximum(cnt, 1))[cnt > 0]
        if m.size >= 4:
            out.append(np.percentile(m, 90) - np.percentile(m, 10))
    return float(np.mean(out)) if out else 0.0
