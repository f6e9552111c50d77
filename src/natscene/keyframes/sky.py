"""The sky behind the clouds of a shot's frames: an analytic daylight sky that follows the sun.

Dobashi et al. 2012 take L_sky from the photo (§4.1); a shot whose sun moves away from the photo's has no
photo of its sky, so frames use the Preetham et al. (1999) daylight model of :mod:`natscene.sky.daylight`,
scaled once per shot (``zenith_luminance`` at ``reference_elevation``), so that the sky darkens and reddens
by itself as the sun sets. ``model: constant`` gives a flat colour instead.
"""
from __future__ import annotations

import numpy as np

from natscene.sky.daylight import preetham_Yxy, preetham_rgb, sky_scale, zenith_Yxy  # noqa: F401


def sky_image(camera, sun_dir, settings: dict) -> np.ndarray:
    """The sky (H, W, 3) behind a frame seen by ``camera`` (settings: a validated ``shots.<name>.sky``)."""
    model = settings.get("model", "preetham")
    if model == "preetham":
        return preetham_rgb(camera.ray_directions(), sun_dir, settings.get("turbidity", 3.0),
                            settings.get("zenith_luminance", 0.3), settings.get("reference_elevation", 35.0),
                            settings.get("min_view_elevation", 1.0))
    if model == "constant":
        c = np.asarray(settings.get("color", [0.3, 0.45, 0.8]), np.float32)
        return np.broadcast_to(c, (camera.height, camera.width, 3)).copy()
    raise ValueError(f"unknown sky model {model!r}")
