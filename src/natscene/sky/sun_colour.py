"""
Sunlight colour
===============

Defines the colour of the light incident on the clouds, c_in(λ) (Dobashi et al. 2012, §4.1):

-   :func:`sun_colour`: c_in from the brighter half of the cloud pixels, a :class:`SunColour`.

§4.1: "the colors of the cloud pixels are converted into grayscale. Each of the cloud pixels is then
classified into either a brighter or a darker pixel [...] by Otsu [1979]. The average color of the brighter
cloud pixels is used for the color of the light incident on the clouds. [...] the method does not work well
when the sun is completely hidden by optically thick clouds. In this case, the estimated color would be a
gray. This situation happens when the user specifies a photograph of an overcast sky."

Grey level: Rec. 709 luminance Y of linear RGB. Pixels with a channel at or above ``clip_level`` (sensor
or JPEG clipping: their colour is not the light's) are left out of the mean when enough others remain.
Normalisation: c_in is the mean linear RGB of the brighter class divided by its luminance, so that
Y(c_in) = 1 (white light gives [1, 1, 1]); the intensity is left to L_in, fitted by the GA.
"Near grey": CIE C*ab of c_in (at L* = 100) below ``grey_chroma``. "Overcast": cloud pixels make up at least
``overcast_cloud_fraction`` of the sky + cloud pixels. Both together give a warning, not a failure.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Otsu, N. (1979). A threshold selection method from gray-level histograms. IEEE Transactions on Systems, Man,
    and Cybernetics, 9(1), 62–66.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from natscene.color import linear_srgb_to_lab, luminance
from natscene.errors import InputError
from natscene.sky.segmentation import CLOUD, SKY, otsu_threshold

__all__ = ["SunColour", "sun_colour"]


@dataclass
class SunColour:
    c_in: np.ndarray  # (3,), luminance-normalised
    mean_rgb: np.ndarray  # (3,), mean linear RGB of the brighter cloud pixels (before normalisation)
    grey_threshold: float  # Otsu threshold on luminance
    counts: dict
    chroma: float  # CIE C*ab of c_in
    overcast: bool
    warnings: list = field(default_factory=list)


def sun_colour(photo: np.ndarray, labels: np.ndarray, clip_level: float = 0.99, grey_chroma: float = 3.0,
               overcast_cloud_fraction: float = 0.8, min_unclipped_fraction: float = 0.01) -> SunColour:
    """c_in from the brighter half (Otsu on luminance) of the cloud pixels; see the module docstring."""
    cloud = np.asarray(labels) == CLOUD
    n_cloud = int(cloud.sum())
    if n_cloud == 0:
        raise InputError("no cloud pixels: nothing to estimate the sunlight colour c_in from; use a photo "
                         "with clouds, lower/raise photos.<name>.threshold, or paint cloud (white) in a mask")
    rgb = photo[cloud].astype(np.float64)
    y = luminance(rgb.astype(np.float32)).astype(np.float64)
    warnings = []
    if np.ptp(y) > 0:
        t = otsu_threshold(y)
        bright = y > t
    else:
        t, bright = float(y[0]), np.ones_like(y, bool)
    unclipped = bright & np.all(rgb < clip_level, axis=-1)
    use = unclipped
    if unclipped.sum() < max(1, min_unclipped_fraction * bright.sum()):
        use = bright
        warnings.append(f"almost all bright cloud pixels are clipped (a channel >= {clip_level}); c_in is "
                        f"the mean of clipped pixels and biased toward white")
    mean = rgb[use].mean(axis=0)
    Y = float(mean @ np.array([0.2126, 0.7152, 0.0722]))
    if Y <= 0:
        raise InputError("the brighter cloud pixels are black: cannot estimate the sunlight colour c_in")
    c_in = mean / Y
    lab = linear_srgb_to_lab((c_in / max(c_in.max(), 1e-12)).astype(np.float32))
    chroma = float(np.hypot(lab[1], lab[2]))
    n_sky = int((np.asarray(labels) == SKY).sum())
    overcast = n_cloud / max(n_cloud + n_sky, 1) >= overcast_cloud_fraction
    if overcast and chroma < grey_chroma:
        warnings.append(f"c_in is near grey (C*ab = {chroma:.2f}) and the photo looks overcast "
                        f"({100 * n_cloud / (n_cloud + n_sky):.0f}% cloud): the sun may be hidden by thick "
                        f"clouds, so c_in may not be the sunlight's colour (Dobashi 2012 §4.1, failure case)")
    counts = {"cloud": n_cloud, "bright_cloud": int(bright.sum()), "bright_cloud_used": int(use.sum()),
              "bright_cloud_clipped": int((bright & ~np.all(rgb < clip_level, axis=-1)).sum())}
    return SunColour(c_in.astype(np.float64), mean, float(t), counts, chroma, bool(overcast), warnings)
