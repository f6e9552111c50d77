"""Recolouring a flower photograph with a pigment pattern (Dong 2007 §3.5, Fig. 3.8).

"We split the original image in YIQ space, and extract the shape and venation information. Then we
redefine the I channel with user-appointed pigment, and replace the Q channel with the pigment
distribution map. The Y channel, which includes geometry detail, material property and lighting
environment, is also modified based on the pigment distribution map."

Here, with the colour texture C(x) of §3.4 (Eq. 3.9 evaluated on the pigment maps) and its base colour
C_0 (zero concentration), all in display-encoded sRGB as NTSC YIQ expects:

    Y_out = Y_photo * Y_C(x) / Y_C0          (detail of the photo, lightness of Eq. 3.10)
    I_out, Q_out = (I_C, Q_C)(x) * Y_out / Y_C(x)   (hue and saturation of the pigment colour)

outside the petal mask the photo is kept. Colour conversions go through natscene.color.

``flower_mask`` extracts the petal shape: saturated, not-too-dark pixels (HSV saturation >= s_min and
value >= v_min of the encoded photo), cleaned by a morphological opening and hole filling.
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from natscene import color as _color
from natscene.color import linear_to_srgb, srgb_to_linear
from natscene.io import InputError

#: NTSC (FCC 1953) RGB -> YIQ matrix. colour-science 0.4.7 has no RGB_to_YIQ, so natscene.color's
#: srgb_to_yiq/yiq_to_srgb raise AttributeError; until natscene.color carries this matrix, we fall
#: back to it here (reported to the lead).
_YIQ = np.array([[0.299, 0.587, 0.114], [0.595716, -0.274453, -0.321263], [0.211456, -0.522591, 0.311135]])


def srgb_to_yiq(rgb):
    try:
        return _color.srgb_to_yiq(rgb)
    except AttributeError:
        return (np.asarray(rgb, np.float64) @ _YIQ.T).astype(np.float32)


def yiq_to_srgb(yiq):
    try:
        return _color.yiq_to_srgb(yiq)
    except AttributeError:
        return (np.asarray(yiq, np.float64) @ np.linalg.inv(_YIQ).T).astype(np.float32)


def flower_mask(photo_linear: np.ndarray, s_min: float = 0.35, v_min: float = 0.08) -> np.ndarray:
    enc = linear_to_srgb(photo_linear[..., :3])
    mx, mn = enc.max(axis=-1), enc.min(axis=-1)
    sat = np.where(mx > 0, (mx - mn) / np.maximum(mx, 1e-6), 0.0)
    m = (sat >= s_min) & (mx >= v_min)
    m = ndimage.binary_opening(m, iterations=2)
    m = ndimage.binary_fill_holes(m)
    if m.sum() < 16:
        raise InputError("no flower found in the photo (no saturated pixels); lower 's_min' or give a mask")
    return m.astype(np.float32)


def recolour(photo_linear: np.ndarray, colour_linear: np.ndarray, base_linear: np.ndarray,
             mask: np.ndarray, eps: float = 1e-4) -> np.ndarray:
    """The §3.5 YIQ recolouring; all inputs linear sRGB, returns linear sRGB (H, W, 3)."""
    if photo_linear.shape[:2] != colour_linear.shape[:2] or mask.shape != photo_linear.shape[:2]:
        raise InputError(f"photo {photo_linear.shape[:2]}, colour {colour_linear.shape[:2]} and mask "
                         f"{mask.shape} must have the same size")
    yiq_p = srgb_to_yiq(linear_to_srgb(photo_linear[..., :3]))
    yiq_c = srgb_to_yiq(linear_to_srgb(colour_linear[..., :3]))
    y0 = float(srgb_to_yiq(linear_to_srgb(np.asarray(base_linear, np.float32).reshape(1, 3)))[0, 0])
    y_out = yiq_p[..., 0] * yiq_c[..., 0] / max(y0, eps)
    ratio = y_out / np.maximum(yiq_c[..., 0], eps)
    out = np.stack([y_out, yiq_c[..., 1] * ratio, yiq_c[..., 2] * ratio], axis=-1)
    rgb = srgb_to_linear(np.clip(yiq_to_srgb(out), 0.0, 1.0))
    m = (np.asarray(mask) > 0.5)[..., None]
    return np.where(m, rgb, photo_linear[..., :3]).astype(np.float32)
