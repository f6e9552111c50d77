"""
Noise figure of a rendered frame
================================

Defines the noise figure of a rendered frame (docs/stages/shots.md, "Noise figure"):

-   :func:`noise_figure`: N of two renders over the cloud pixels.
-   :func:`cloud_pixels`: the cloud pixels of a frame.
-   :func:`luminance`: the Rec. 709 luminance of an image.

Render the same frame twice with different random seeds, a and b. Over the cloud pixels (luminance Y, Rec. 709
weights)

    N = median(|Y_a - Y_b|) / median((Y_a + Y_b) / 2) / sqrt(2).

The difference of two independent renders has sqrt(2) times the noise of one, so N is a robust (median)
per-pixel relative noise of a single render: 0.05 reads "5 % grain". A deterministic image has N = 0.
"""
from __future__ import annotations

import numpy as np

from natscene.color import LUMA_709

__all__ = ["luminance", "noise_figure", "cloud_pixels"]


def luminance(img: np.ndarray) -> np.ndarray:
    a = np.asarray(img, np.float64)
    return a[..., :3] @ np.asarray(LUMA_709, np.float64) if a.ndim == 3 else a


def noise_figure(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    """N of two renders a, b (H, W, 3) over ``mask`` (H, W) bool (the cloud pixels)."""
    m = np.asarray(mask, bool)
    if not m.any():
        raise ValueError("noise_figure: the mask selects no pixel")
    ya, yb = luminance(a)[m], luminance(b)[m]
    level = float(np.median(0.5 * (ya + yb)))
    if level <= 0:
        raise ValueError("noise_figure: the cloud pixels have no light")
    return float(np.median(np.abs(ya - yb)) / level / np.sqrt(2.0))


def cloud_pixels(opacity: np.ndarray, threshold: float = 0.5) -> np.ndarray:
    """The cloud pixels of a frame: opacity (1 - T along the view ray) at least ``threshold``."""
    return np.asarray(opacity) >= threshold
