"""
Meaning embedment
=================

Defines the meaning embedment of Dong 2007, §5.6: an object cut from another image with GrabCut (Rother et al.
2004) is pasted into chosen tiles by Poisson image editing (Pérez et al. 2003; solved here with a sparse solve,
not OpenCV's ``seamlessClone``: docs/stages/tiles.md):

-   :func:`grabcut_object`: the foreground object (and its mask) inside a rectangle of an image.
-   :func:`embed`: clone an object into the centre of chosen tiles.
-   :func:`poisson_clone`: Poisson image editing (seamless cloning) inside a mask.

The object is scaled to fit inside the tile's graph-cut circle and cloned at the tile centre; pixels
outside the circle are restored afterwards so tile borders (and tiling continuity) are unchanged.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Pérez, P., Gangnet, M., & Blake, A. (2003). Poisson image editing. ACM Transactions on Graphics, 22(3),
    313–318.
-   Rother, C., Kolmogorov, V., & Blake, A. (2004). "GrabCut": interactive foreground extraction using iterated
    graph cuts. ACM Transactions on Graphics, 23(3), 309–314.
"""
from __future__ import annotations

import cv2
import numpy as np

from natscene.color import linear_to_srgb, srgb_to_linear
from natscene.tiles.graphcut import constraint_masks

__all__ = ["grabcut_object", "embed", "poisson_clone"]


def grabcut_object(source_linear: np.ndarray, rect, iterations: int = 5, pad: int = 4):
    """(object BGR uint8 crop, mask uint8 crop) of the foreground inside ``rect`` = [x, y, w, h], the crop
    ``pad`` pixels larger than the object's bounding box (room for the Poisson boundary)."""
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
    y0, y1 = max(0, ys.min() - pad), min(H, ys.max() + 1 + pad)
    x0, x1 = max(0, xs.min() - pad), min(W, xs.max() + 1 + pad)
    return src8[y0:y1, x0:x1], fg[y0:y1, x0:x1]


def poisson_clone(dst: np.ndarray, src: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Poisson image editing (Pérez et al. 2003, seamless cloning): inside ``mask`` solve
    lap f = lap src with f = dst on the mask boundary; ``src``, ``dst`` (H, W, C) float, same shape."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    H, W, C = dst.shape
    inside = mask.astype(bool).copy()
    inside[[0, -1], :] = False
    inside[:, [0, -1]] = False
    idx = -np.ones((H, W), np.int64)
    ys, xs = np.nonzero(inside)
    n = len(ys)
    if n == 0:
        return dst.copy()
    idx[ys, xs] = np.arange(n)
    rows, cols, vals = [np.arange(n)], [np.arange(n)], [np.full(n, 4.0)]
    b = 4.0 * src[ys, xs] - sum(src[ys + dy, xs + dx] for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)))
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        ny, nx = ys + dy, xs + dx
        j = idx[ny, nx]
        inn = j >= 0
        rows.append(np.nonzero(inn)[0])
        cols.append(j[inn])
        vals.append(-np.ones(inn.sum()))
        b[~inn] += dst[ny[~inn], nx[~inn]]
    A = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    sol = spla.spsolve(A.tocsc(), b)
    out = dst.copy()
    out[ys, xs] = sol.reshape(n, C)
    return out


def embed(tile_linear: np.ndarray, obj8: np.ndarray, mask8: np.ndarray, size: float = 0.6,
          margin: float = 1.0) -> np.ndarray:
    """Clone an object (BGR uint8 crop + mask, from :func:`grabcut_object`) into the centre of a
    linear RGB tile (s, s, 3) by Poisson editing; the object's longest side becomes ``size`` * s.
    The boundary lies a few pixels outside the object (cf. drag-and-drop pasting, Jia et al. 2006) so
    its own edge gradients are kept."""
    tile = np.asarray(tile_linear, np.float64)[..., :3]
    s = tile.shape[0]
    k = size * s / max(obj8.shape[:2])
    nw, nh = max(2, int(obj8.shape[1] * k)), max(2, int(obj8.shape[0] * k))
    obj = cv2.resize(obj8, (nw, nh), interpolation=cv2.INTER_AREA)[..., ::-1]
    msk = cv2.resize(mask8, (nw, nh), interpolation=cv2.INTER_NEAREST)
    msk = cv2.dilate(msk, np.ones((5, 5), np.uint8))
    y0, x0 = (s - nh) // 2, (s - nw) // 2
    src = tile.copy()
    src[y0:y0 + nh, x0:x0 + nw] = srgb_to_linear(obj.astype(np.float32) / 255.0)
    full = np.zeros((s, s), bool)
    full[y0:y0 + nh, x0:x0 + nw] = msk > 0
    keep, _ = constraint_masks(s, margin)
    full &= ~keep
    out = poisson_clone(tile, src, full)
    out[keep] = tile[keep]
    return out.astype(np.float32)
