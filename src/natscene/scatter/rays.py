"""
Camera rays
===========

Defines the camera rays on the Dr.Jit side for the pinhole camera of :mod:`natscene.geometry`
(DESIGN §3, Geometry):

-   :func:`camera_rays`: origins, directions and pixel indices of W*H*spp samples.
-   :func:`pixel_means`: the box-filtered average of each pixel's samples, for several arrays at once. The arrays
    are evaluated together before their block sums: a block sum evaluates its input on its own, so taking a
    symbolic loop's C outputs one at a time would run the loop C times.

Sample s of pixel (i, j) lives at flat index ``(i * W + j) * spp + s`` so that ``dr.block_sum(x, spp)``
returns one value per pixel in row-major order. Sub-pixel positions are either a stratified grid
(``stratified=True``, ``spp`` must be a square) or uniform random from a PCG32 stream: the pixel value is
the box-filtered average over the pixel, the same as Mitsuba's ``hdrfilm`` with a ``box`` filter.
"""
from __future__ import annotations

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

__all__ = ["camera_rays", "pixel_means"]


def camera_rays(camera, spp: int, rng=None, stratified: bool = False, pixels=None):
    """(origin Point3f, unit direction Vector3f, pixel index UInt32) for W*H*spp samples.

    ``pixels``: flat pixel indices (numpy) to trace instead of all W*H: sample s of the i-th listed pixel
    lives at flat index i * spp + s; the returned pixel index is the image's.
    """
    W, H = camera.width, camera.height
    npix = W * H if pixels is None else int(len(pixels))
    n = npix * spp
    idx = dr.arange(mi.UInt32, n)
    slot = idx // spp
    s = idx - slot * spp
    pix = slot if pixels is None else dr.gather(mi.UInt32, mi.UInt32(np.asarray(pixels, np.uint32)), slot)
    row = pix // W
    col = pix - row * W
    if stratified:
        m = int(round(np.sqrt(spp)))
        if m * m != spp:
            raise ValueError(f"stratified sampling needs a square spp, got {spp}")
        sy = s // m
        sx = s - sy * m
        jx = (mi.Float(sx) + 0.5) / m
        jy = (mi.Float(sy) + 0.5) / m
    elif rng is not None:
        jx = rng.next_float32()
        jy = rng.next_float32()
    else:
        jx = mi.Float(0.5)
        jy = mi.Float(0.5)
    right, up, fwd = (np.asarray(v, np.float64) for v in camera.basis())
    tan_half = float(np.tan(np.radians(camera.fov) / 2))
    aspect = W / H
    x = (2 * (mi.Float(col) + jx) / W - 1) * (tan_half * aspect)
    y = (1 - 2 * (mi.Float(row) + jy) / H) * tan_half
    d = x * mi.ScalarVector3f(*right) + y * mi.ScalarVector3f(*up) + mi.ScalarVector3f(*fwd)
    d = dr.normalize(mi.Vector3f(d))
    o = mi.Point3f(*[float(c) for c in camera.position])
    o = dr.zeros(mi.Point3f, n) + o
    return o, d, pix


def pixel_means(xs, spp: int, width: int, height: int) -> np.ndarray:
    """(len(xs), H, W) float32: the average of the spp samples of each pixel, for each array of ``xs``."""
    if not xs:
        return np.zeros((0, height, width), np.float32)
    dr.eval(*xs)        # one launch of the loop that made them (a block sum evaluates its input alone)
    vs = [dr.block_sum(x, spp) / spp if spp > 1 else x for x in xs]
    dr.eval(*vs)
    return np.stack([np.asarray(v, np.float32).reshape(height, width) for v in vs])
