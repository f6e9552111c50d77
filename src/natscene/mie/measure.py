"""
Measures of the Mie effects on images
=====================================

Defines the measures of the Mie effects on rendered images (Reimschuessel 2011, Ch. 4), used by the rule
``mie_render``'s summaries and the tests of the effects:

-   :func:`angular_profile`: the azimuthal profile around a direction (the antisolar point).
-   :func:`ring_contrast`: the contrast of the glory's first bright ring in a radial profile.
-   :func:`rim_peak`: the silver-lining rim's peak brightness.

References
----------
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

import numpy as np

from natscene.geometry import Camera

__all__ = ["angular_profile", "ring_contrast", "rim_peak"]


def angular_profile(img: np.ndarray, camera: Camera, direction, max_deg: float = 4.0, step_deg: float = 0.1):
    """Azimuthal mean of the RGB mean of ``img`` in rings of width ``step_deg`` around ``direction`` (a
    unit vector, e.g. the antisolar direction -sun): -> (ring centres (deg), profile); NaN for empty rings."""
    d = camera.ray_directions()
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    ang = np.degrees(np.arccos(np.clip(d @ u, -1, 1)))
    edges = np.arange(0.0, max_deg + 1e-9, step_deg)
    k = np.digitize(ang, edges) - 1
    y = np.asarray(img, np.float64).mean(axis=-1)
    ok = (k >= 0) & (k < len(edges) - 1)
    s = np.bincount(k[ok], y[ok], minlength=len(edges) - 1)
    n = np.bincount(k[ok], minlength=len(edges) - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (edges[:-1] + edges[1:]) / 2, s / n


def ring_contrast(centres: np.ndarray, profile: np.ndarray):
    """The first bright ring of a radial profile (around the antisolar point): the first local minimum
    outward from the centre, then the maximum beyond it -> (ring angle (deg), ring max / that minimum).
    A profile with no local minimum (monotone) gives (NaN, 1.0)."""
    p = np.asarray(profile, np.float64)
    ok = np.isfinite(p)
    c, p = np.asarray(centres)[ok], p[ok]
    for i in range(1, len(p) - 1):
        if p[i] < p[i - 1] and p[i] <= p[i + 1]:
            j = i + int(np.argmax(p[i:]))
            if j == i:
                break
            return float(c[j]), float(p[j] / p[i])
    return float("nan"), 1.0


def rim_peak(img: np.ndarray, fraction: float = 0.001) -> float:
    """Brightness of the brightest ``fraction`` of pixels (mean of their RGB means): the silver-lining
    rim's peak."""
    y = np.sort(np.asarray(img, np.float64).mean(axis=-1).ravel())
    return float(y[-max(1, int(round(fraction * y.size))):].mean())
