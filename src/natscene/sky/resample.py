"""
Sky products at the fit resolutions
===================================

Defines the resampling of the sky products to the fit resolutions (Dobashi et al. 2012, §4.2 compares the
synthetic image with the photo pixel for pixel in L_sky and by histogram over the cloud pixels, at the
precompute's resolution):

-   :func:`crop_box`: the centre crop to a target aspect ratio.
-   :func:`area_resample`: centre-crop then area-average an image.
-   :func:`resample_labels`: the majority label per output pixel.

Resampling: the photo is first centre-cropped to the target aspect ratio (so that pixels stay square; no
crop when the aspects agree), then area-averaged (OpenCV ``INTER_AREA``: each output pixel is the
area-weighted mean of the input pixels it covers; exact box averaging for integer factors). Linear images
are averaged in linear RGB. Labels are resampled by area-averaging their one-hot encoding and taking the
majority class (ties: cloud over sky over neither); the soft alpha is area-averaged.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import cv2
import numpy as np

from natscene.sky.segmentation import CLOUD, NEITHER, SKY

__all__ = ["crop_box", "area_resample", "resample_labels"]


def crop_box(width: int, height: int, tw: int, th: int) -> tuple[int, int, int, int]:
    """Centre crop (x0, y0, w, h) of a width x height image to the aspect ratio tw:th."""
    if width * th > height * tw:  # too wide
        w = int(round(height * tw / th))
        return (width - w) // 2, 0, w, height
    h = int(round(width * th / tw))
    return 0, (height - h) // 2, width, h


def area_resample(img: np.ndarray, tw: int, th: int) -> np.ndarray:
    """Centre-crop to tw:th then area-average to (th, tw[, C]), float32."""
    a = np.asarray(img, np.float32)
    h, w = a.shape[:2]
    x0, y0, cw, ch = crop_box(w, h, tw, th)
    a = np.ascontiguousarray(a[y0:y0 + ch, x0:x0 + cw])
    interp = cv2.INTER_AREA if (tw <= cw and th <= ch) else cv2.INTER_LINEAR
    if a.ndim == 3 and a.shape[-1] > 4:
        return np.stack([cv2.resize(a[..., i], (tw, th), interpolation=interp) for i in range(a.shape[-1])], -1)
    out = cv2.resize(a, (tw, th), interpolation=interp)
    return out[..., None] if (a.ndim == 3 and out.ndim == 2) else out


def resample_labels(labels: np.ndarray, tw: int, th: int) -> np.ndarray:
    """Majority label per output pixel from area-averaged one-hot classes (float32 (th, tw))."""
    lab = np.asarray(labels)
    order = [CLOUD, SKY, NEITHER]  # argmax takes the first maximum: ties go to cloud, then sky
    onehot = np.stack([(lab == k).astype(np.float32) for k in order], -1)
    frac = area_resample(onehot, tw, th)
    return np.asarray(order, np.float32)[np.argmax(frac, axis=-1)]
