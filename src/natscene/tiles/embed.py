"""Meaning embedment (Dong 2007 §5.6): an object cut from another image with GrabCut (Rother et al.
2004) is pasted into chosen tiles by Poisson image editing (Pérez et al. 2003, ``cv2.seamlessClone``).

The object is scaled to fit inside the tile's graph-cut circle and cloned at the tile centre; pixels
outside the circle are restored afterwards so tile borders (and tiling continuity) are unchanged.
"""
from __future__ import annotations

import cv2
import numpy as np

from natscene.color import linear_to_srgb, srgb_to_linear
from natscene.tiles.graphcut import constraint_masks


def grabcut_object(source_linear: np.ndarray, rect, iterations: int = 5):
    """(object sRGB uint8 crop, mask uint8 crop) of the foreground inside ``rect`` = [x, y, w, h]."""
    src8 = np.round(linear_to_srgb(np.asarray(source_linear)[..., :3]) * 255).astype(np.uint8)
    src8 = np.ascontiguousarray(src8[..., ::-1])  # OpenCV is BGR
    x, y, w, h = (int(v) for v in rect)
    H, W = src8.shape[:2]
    if w < 4 or h < 4 or x < 0 or y < 0 or x + w > W or y + h > H:
        raise ValueError(f"GrabCut rect {rect} not inside the {W}x{H} source image")
    mask = np.zeros((H, W), np.uint8)
    bgd, fgd = np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64)
    cv2.grabCut(src8, mask, (x, y, w, h), bgd, fgd, iterations, cv2.GC_INIT_WITH_RECT)
    fg = ((mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)).astype(np.uint8) * 255
    ys, xs = np.nonzero(fg)
    if len(ys) == 0:
        raise ValueError(f"GrabCut found no foreground in rect {rect}")
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    return src8[y0:y1, x0:x1], fg[y0:y1, x0:x1]


def embed(tile_linear: np.ndarray, obj8: np.ndarray, mask8: np.ndarray, size: float = 0.6,
          margin: float = 1.0) -> np.ndarray:
    """Clone the object (BGR uint8 + mask) into the centre of a linear RGB tile (s, s, 3); the object's
    longest side becomes ``size`` * s."""
    tile = np.asarray(tile_linear, np.float32)
    s = tile.shape[0]
    k = size * s / max(obj8.shape[:2])
    nw, nh = max(2, int(obj8.shape[1] * k)), max(2, int(obj8.shape[0] * k))
    obj = cv2.resize(obj8, (nw, nh), interpolation=cv2.INTER_AREA)
    msk = cv2.resize(mask8, (nw, nh), interpolation=cv2.INTER_NEAREST)
    msk[[0, -1], :] = 0
    msk[:, [0, -1]] = 0
    dst8 = np.ascontiguousarray(np.round(linear_to_srgb(tile[..., :3]) * 255).astype(np.uint8)[..., ::-1])
    out8 = cv2.seamlessClone(obj, dst8, msk, (s // 2, s // 2), cv2.NORMAL_CLONE)
    out = srgb_to_linear(out8[..., ::-1].astype(np.float32) / 255.0)
    keep, _ = constraint_masks(s, margin)
    out[keep] = tile[..., :3][keep]
    return out.astype(np.float32)
