"""
Scale feature of a texture
==========================

Defines the scale feature of Dong (2007, §6.3): texel scale maps from a feature mask (Eq. 6.1), from slant and
tilt (Eq. 6.2), and their editing (§6.3.3):

-   :func:`scale_from_mask`: Eq. 6.1, the scale map of a feature mask (after Wu & Yu 2004).
-   :func:`scale_from_angles`: Eq. 6.2, the scale map of a plane seen at a slant and tilt.
-   :func:`scale_region`, :func:`copy_region`: the editing of §6.3.3.
-   :func:`grey_from_scale`, :func:`scale_from_grey`, :func:`scale_preview`: scale to the thesis' grey and back.

Scale 1 is the undistorted texel; larger values are magnified texels (a grey of 128 shows 1 in the thesis'
figures, :func:`scale_preview` here).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Wu, Q., & Yu, Y. (2004). Feature matching and deformation for texture synthesis. ACM Transactions on
    Graphics, 23(3), 364–367.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from natscene.errors import InputError

__all__ = ["scale_from_mask", "scale_from_angles", "scale_region", "copy_region", "grey_from_scale",
           "scale_from_grey", "scale_preview"]


def scale_from_mask(mask: np.ndarray, n: int = 32, gaussian: int = 13) -> np.ndarray:
    """Eq. 6.1: the scale map of a binary feature mask (texel edges or centres drawn at a fixed pixel size).

    a(p) is the number of feature pixels in the n x n neighbourhood of p; a_mid = (a_min + a_max) / 2 has scale 1.
    The thesis prints S(p) = a(p) / a_mid but says in the same paragraph that the point with the fewest feature
    pixels, a_min, is the largest-scaled one (fewer texel edges per window: bigger texels); S(p) = a_mid / a(p)
    is the form that agrees with that statement and with a warped texture's true scale (tests/test_features.py),
    so it is the one used. Windows with no feature pixel take the scale of a_min's neighbours (a clipped to at
    least one pixel). The noisy map is then smoothed by a ``gaussian`` x ``gaussian`` Gaussian filter (13 in the
    thesis), sigma = size / 6 so that the kernel spans +-3 sigma.
    """
    m = np.asarray(mask) > 0
    if m.ndim != 2:
        raise InputError(f"feature mask: expected a 2-D mask, got shape {m.shape}")
    if not m.any():
        raise InputError("feature mask: no feature pixel (the mask is empty); draw the texel edges or lower the "
                         "threshold")
    if n < 1 or n > min(m.shape):
        raise InputError(f"feature mask: neighbourhood n = {n} must be between 1 and the mask's smaller side "
                         f"{min(m.shape)}")
    a = ndimage.uniform_filter(m.astype(np.float64), size=n, mode="reflect") * (n * n)
    a = np.maximum(a, 1.0)
    a_mid = 0.5 * (a.min() + a.max())
    s = a_mid / a
    return ndimage.gaussian_filter(s, sigma=gaussian / 6.0, truncate=3.0, mode="reflect").astype(np.float32)


def scale_from_angles(width: int, height: int, slant_deg: float, tilt_deg: float) -> np.ndarray:
    """Eq. 6.2: the scale map of a planar texture seen at slant sigma and tilt tau (degrees), (height, width).

    S_max = 1 / cos(sigma) at the image's bottom-left origin (the thesis mirrors the photo so that the largest
    texels are there), S_min = cos(sigma) toward the top right, linear in the coordinate projected on the tilt
    direction: Y(p) = (x - w/2) sin(tau) + (y - h/2) cos(tau), y up from the bottom row, Y_max from the far corner,
    Y_min = -Y_max, S(p) = S_max - (Y(p) - Y_min) S_dif / Y_dif. (The thesis prints ``Y_max - ...`` for the first
    term; S_max is what makes S run from S_max to S_min.)
    """
    if not 0.0 <= slant_deg < 90.0:
        raise InputError(f"slant {slant_deg} deg: must be in [0, 90)")
    sig, tau = np.radians(slant_deg), np.radians(tilt_deg)
    s_max, s_min = 1.0 / np.cos(sig), np.cos(sig)
    w, h = int(width), int(height)
    y_max = (w - 1 - w / 2) * np.sin(tau) + (h - 1 - h / 2) * np.cos(tau)
    y_min = -y_max
    x = np.arange(w)[None, :]
    y = (h - 1 - np.arange(h))[:, None]  # rows run down, the thesis' y runs up from the bottom-left origin
    y_proj = (x - w / 2) * np.sin(tau) + (y - h / 2) * np.cos(tau)
    if abs(y_max - y_min) < 1e-12:
        return np.full((h, w), 1.0, np.float32)
    return (s_max - (y_proj - y_min) * (s_max - s_min) / (y_max - y_min)).astype(np.float32)


def scale_region(scale: np.ndarray, region: np.ndarray, factor: float) -> np.ndarray:
    """§6.3.3: magnify (factor > 1) or minify (< 1) the scale values inside a region (boolean mask or weights in
    [0, 1] for a soft edge)."""
    if factor <= 0:
        raise InputError(f"scale edit: factor {factor} must be > 0")
    w = np.clip(np.asarray(region, np.float64), 0.0, 1.0)
    return (scale * (1.0 + w * (factor - 1.0))).astype(np.float32)


def copy_region(scale: np.ndarray, source: tuple, target: tuple) -> np.ndarray:
    """§6.3.3: duplicate the values of one rectangle (x, y, w, h) to another of the same size."""
    x0, y0, w, h = (int(v) for v in source)
    x1, y1 = int(target[0]), int(target[1])
    H, W = scale.shape
    for name, (x, y) in (("source", (x0, y0)), ("target", (x1, y1))):
        if x < 0 or y < 0 or x + w > W or y + h > H:
            raise InputError(f"scale edit copy: {name} rectangle ({x}, {y}, {w}, {h}) leaves the {W}x{H} map")
    out = scale.copy()
    out[y1:y1 + h, x1:x1 + w] = scale[y0:y0 + h, x0:x0 + w]
    return out


def grey_from_scale(scale: np.ndarray) -> np.ndarray:
    """Scale S -> the grey the thesis draws scale maps in (0.5, i.e. 128, is S = 1; one octave per 0.5):
    0.5 + 0.5 log2 S. Not clipped: it is the scale feature's value in Eq. 6.3."""
    return (0.5 + 0.5 * np.log2(np.maximum(scale, 1e-6))).astype(np.float32)


def scale_from_grey(grey: np.ndarray) -> np.ndarray:
    """The inverse of :func:`grey_from_scale`."""
    return (2.0 ** ((np.asarray(grey, np.float64) - 0.5) * 2.0)).astype(np.float32)


def scale_preview(scale: np.ndarray) -> np.ndarray:
    """The scale map as a grey image in [0, 1] (:func:`grey_from_scale`, clipped)."""
    return np.clip(grey_from_scale(scale), 0.0, 1.0)
