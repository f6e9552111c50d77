"""
Image completion by feature-aware synthesis
===========================================

Defines the image completion of a textured region by feature-aware synthesis (Dong 2007, §6.7, Fig. 6.16):

-   :func:`complete`: fill a hole of an image by texture optimisation from the rest of the image.
-   :func:`inpaint_baseline`: the exemplar-free inpainting the chapter compares with.

The scale feature is recovered from the photo around the hole (a scale map of the whole image: from the slant and
tilt of the textured plane, Eq. 6.2, or from a feature mask, Eq. 6.1, where the hole's own pixels do not count),
and the hole is synthesised by texture optimisation with the control energy of Eq. 6.3 (feature-guided start,
the modified E- and M-steps of :mod:`natscene.features.optimisation`), the example being the rest of the image:
only neighbourhoods that lie wholly in the known part are candidates, and the known pixels stay as they are.
:func:`inpaint_baseline` is the exemplar-free inpainting the chapter compares with (OpenCV's Telea method).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Telea, A. (2004). An image inpainting technique based on the fast marching method. Journal of Graphics
    Tools, 9(1), 23–34.
"""
from __future__ import annotations

import cv2
import numpy as np

from natscene.errors import InputError
from natscene.features.optimisation import OptimisationSettings, Result, synthesise

__all__ = ["complete", "inpaint_baseline"]


def complete(image: np.ndarray, hole: np.ndarray, scale_features: np.ndarray | None,
             settings: OptimisationSettings | None = None, log=None) -> Result:
    """Fill ``hole`` (H, W) bool of ``image`` (H, W, C) in [0, 1]; ``scale_features`` (H, W) or (H, W, k): the
    feature maps over the whole image (None: plain texture optimisation, lambda's term empty)."""
    img = np.asarray(image, np.float32)
    hole = np.asarray(hole, bool)
    if hole.shape != img.shape[:2]:
        raise InputError(f"completion: the hole mask is {hole.shape[1]}x{hole.shape[0]}, the image "
                         f"{img.shape[1]}x{img.shape[0]}")
    if not hole.any():
        raise InputError("completion: the hole mask is empty")
    if hole.all():
        raise InputError("completion: the hole covers the whole image; nothing is left to copy from")
    f = None if scale_features is None else np.asarray(scale_features, np.float32)
    return synthesise(img, img.shape[:2], f, f, settings, known=~hole, initial=np.where(hole[..., None], 0, img),
                      log=log)


def inpaint_baseline(image: np.ndarray, hole: np.ndarray, radius: int = 5) -> np.ndarray:
    """OpenCV's exemplar-free inpainting (Telea 2004) of the same hole, float in [0, 1]."""
    img8 = np.clip(np.asarray(image) * 255 + 0.5, 0, 255).astype(np.uint8)
    out = cv2.inpaint(img8, hole.astype(np.uint8), radius, cv2.INPAINT_TELEA)
    return out.astype(np.float32) / 255.0
