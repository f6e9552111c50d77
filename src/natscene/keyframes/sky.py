"""
Sky of a shot's frames
======================

Defines the sky behind the clouds of a shot's frames: an analytic daylight sky that follows the sun.

-   :func:`sky_image`: the sky behind a frame seen by a camera.

Dobashi et al. 2012 take L_sky from the photo (§4.1); a shot whose sun moves away from the photo's has no
photo of its sky, so frames use the Preetham et al. (1999) daylight model of :mod:`natscene.sky.daylight`,
scaled once per shot (``zenith_luminance`` at ``reference_elevation``), so that the sky darkens and reddens
by itself as the sun sets. ``model: constant`` gives a flat colour instead. The model and the shot's sky
settings live in :func:`natscene.sky.daylight.shot_sky_radiance`; this module only points it at a frame's pixels.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Preetham, A. J., Shirley, P., & Smits, B. (1999). A practical analytic model for daylight. SIGGRAPH '99,
    91–100.
"""
from __future__ import annotations

import numpy as np

from natscene.sky.daylight import shot_sky_radiance

__all__ = ["sky_image"]


def sky_image(camera, sun_dir, settings: dict) -> np.ndarray:
    """The sky (H, W, 3) behind a frame seen by ``camera`` (settings: a validated ``shots.<name>.sky``)."""
    return shot_sky_radiance(settings, camera.ray_directions(), sun_dir)
