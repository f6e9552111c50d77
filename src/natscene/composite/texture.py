"""
Filtered texture lookup
=======================

Defines the filtered texture lookup for the set: a mip-map pyramid and anisotropic probes along the pixel
footprint:

-   :class:`MipTexture`: a texture with its mip pyramid and the filtered lookup (:data:`SPAN`).

A texture seen at a grazing angle (the ground toward the horizon) covers many texels per pixel along one
direction only; a point sample there aliases (moiré on a regular texture, sparkle on grass). The lookup
filters over the footprint of the sample in texture space, given by the derivatives of (u, v) across one
sample spacing (:mod:`natscene.composite.footprint`):

- pyramid: level 0 is the texture, level k+1 the 2×2 box average of level k (odd sizes: exact area
  resampling to half the size, rounded up);
- footprint: the Jacobian J = [[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]] in texels; its singular values are the
  ellipse's major and minor radii σ₁ ≥ σ₂, the first left singular vector its major axis e;
- Feline-style probes (McCormack, Perry, Farkas & Jouppi 1999, "Feline: fast elliptical lines for anisotropic
  texture mapping"; the scheme of hardware anisotropic filtering): n = 2^⌈log₂(σ₁/σ₂)⌉ ≤ ``max_aniso``
  trilinear probes, evenly spaced along e over a length ``SPAN``·σ₁, each at the mip level
  λ = log₂ max(σ₁/n, σ₂), averaged with equal weights; λ < 0 (magnification) is a bilinear lookup of level 0.
  SPAN = 1.5 is the width OpenImageIO's anisotropic filter covers (isotropic footprints agree with its
  TextureSystem: the same box pyramid and trilinear level choice; the comparison: docs/stages/composite.md).

Wrap-around (``wrap=True``, the tiled ground) or clamp-to-edge (petals, leaves). (u, v) in [0, 1]² with v up
(row 0 is v = 1). OpenImageIO's ``TextureSystem`` does the same filtering per point; its Python binding
takes one point per call, so the renderer uses this vectorised lookup and the tests compare the two. The
footprint analysis is numpy; the probes (positions, wrap, texel gathers, blends, their mean) run as one Dr.Jit
kernel per lookup, with a loop over each sample's own probe count, in the arithmetic order of the formulas
above: on the LLVM backend the same float32 results as numpy evaluating them (the CUDA backend fuses
multiply-adds: results within a few float32 ulps of those).

References
----------
-   McCormack, J., Perry, R., Farkas, K. I., & Jouppi, N. P. (1999). Feline: fast elliptical lines for
    anisotropic texture mapping. SIGGRAPH '99, 243–250.
"""
from __future__ import annotations

import numpy as np

__all__ = ["SPAN", "MipTexture"]

#: length of the line of probes, in units of the footprint's major radius σ₁ (see the module docstring)
SPAN = 1.5


def _area_halve(a: np.ndarray, axis: int) -> np.ndarray:
    """Area resampling of ``a`` along ``axis`` to ceil(n / 2) samples (each the exact mean of the input over its
    interval, from the running integral; the texture's mean is kept)."""
    n = a.shape[axis]
    m = max(1, (n + 1) // 2)
    a = np.moveaxis(a, axis, 0)
    I = np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(a, 0)])
    x = np.linspace(0.0, n, m + 1)
    i = np.minimum(np.floor(x).astype(np.int64), n - 1)
    f = (x - i).reshape((-1,) + (1,) * (a.ndim - 1))
    at = I[i] + f * a[i]  # the integral at the interval ends
    return np.moveaxis((at[1:] - at[:-1]) * (m / n), 0, axis)


class MipTexture:
    """A float32 texture (h, w, C) with its mip pyramid, addressed as one flat table of all levels."""

    def __init__(self, image: np.ndarray, wrap: bool = False):
        img = np.asarray(image, np.float32)
        if img.ndim == 2:
            img = img[..., None]
        self.wrap = bool(wrap)
        self.channels = img.shape[-1]
        levels = [img]
        while max(levels[-1].shape[:2]) > 1:
            a = levels[-1]
            h, w = a.shape[:2]
            if h % 2 == 0 and w % 2 == 0:
                b = 0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2])
            else:
                b = _area_halve(_area_halve(a.astype(np.float64), 0), 1)
            levels.append(b.astype(np.float32))
        self._set_levels(levels)

    @classmethod
    def atlas(cls, images: list[np.ndarray]) -> "MipTexture":
        """Several clamped (h, w, C) images as the "levels" of one table, without a pyramid: a per-sample
        ``level`` of :meth:`bilinear` picks the image (one lookup for samples on different textures)."""
        t = cls.__new__(cls)
        t.wrap = False
        t.channels = images[0].shape[-1]
        t._set_levels([np.asarray(i, np.float32) for i in images])
        return t

    def _set_levels(self, levels: list[np.ndarray]):
        self.levels = levels
        self.heights = np.array([l.shape[0] for l in levels], np.int64)
        self.widths = np.array([l.shape[1] for l in levels], np.int64)
        self.offsets = np.concatenate([[0], np.cumsum(self.heights * self.widths)[:-1]]).astype(np.int64)
        self.max_level = len(levels) - 1
        self._jit = None  # the Dr.Jit table, built on first lookup (_table)

    @property
    def shape(self) -> tuple:
        return self.levels[0].shape

    def mean(self) -> np.ndarray:
        """The texture's mean (the 1×1 top of the pyramid), (C,)."""
        return self.levels[-1].reshape(-1, self.channels).mean(0)

    # -- lookups
    def _table(self):
        """The flat table of all levels and the levels' sizes and offsets as Dr.Jit arrays (built on first use,
        in the active Mitsuba variant's backend; an RGB variant is chosen when none is active)."""
        if self._jit is None:
            import mitsuba as mi
            if mi.variant() is None:
                from natscene.variant import select_variant
                select_variant(spectral=False)
            flat = np.concatenate([l.reshape(-1) for l in self.levels])  # all levels, one table
            self._jit = (mi, mi.Float(flat), mi.UInt32(self.widths.astype(np.uint32)),
                         mi.UInt32(self.heights.astype(np.uint32)), mi.UInt32(self.offsets.astype(np.uint32)))
        return self._jit

    def _lookup(self, uv: np.ndarray, l0: np.ndarray, l1: np.ndarray, t: np.ndarray, step: np.ndarray | None = None,
                k: np.ndarray | None = None) -> np.ndarray:
        """:meth:`lookup_dr` of numpy inputs, (M, C) float32."""
        import drjit as dr
        mi = self._table()[0]
        u0, v0 = mi.Float64(np.ascontiguousarray(uv[:, 0])), mi.Float64(np.ascontiguousarray(uv[:, 1]))
        tt = mi.Float(np.ascontiguousarray(t, np.float32))
        lev = [mi.UInt32(np.ascontiguousarray(l, np.uint32)) for l in (l0, l1)]
        if step is None:
            res = self.lookup_dr(u0, v0, lev[0], lev[1], tt)
        else:
            res = self.lookup_dr(u0, v0, lev[0], lev[1], tt, mi.Float64(np.ascontiguousarray(step[:, 0])),
                                 mi.Float64(np.ascontiguousarray(step[:, 1])),
                                 mi.Int32(np.ascontiguousarray(k, np.int32)))
        dr.eval(*res)
        return np.stack([np.asarray(r, np.float32) for r in res], -1)

    def lookup_dr(self, u0, v0, l0, l1, tt, su=None, sv=None, kk=None) -> list:
        """The mean over probes j < k of (1 − t)·bilinear(level l0) + t·bilinear(level l1) at
        uv + ((j + ½)/k − ½)·step (``su``, ``sv``, ``kk`` None: the one probe at uv), one Dr.Jit Float per
        channel (unevaluated; u0, v0, su, sv Float64, l0, l1 UInt32, tt Float, kk Int32).

        One fused Dr.Jit kernel with a per-sample loop over its probes (four texel gathers per level and
        channel). The probe positions and the wrap are float64, the filtering float32, each in the order of
        the textbook formulas (row lerps along x, then along y, then between the levels; the probes summed in
        order and divided by k)."""
        import drjit as dr
        mi, flat, W, H, O = self._table()
        C, wrap = self.channels, self.wrap
        sizes = [tuple(dr.gather(mi.UInt32, a, l) for a in (W, H, O)) for l in (l0, l1)]
        if su is None:
            su = sv = mi.Float64(0.0)
            kk = mi.Int32(1)

        def bilinear(u, v, size):
            w, h, off = size
            wi, hi = mi.Int32(w), mi.Int32(h)
            # clamped to [-1, size] before the integer conversion (far probes; NaN -> -1), the result that of
            # the unclamped coordinate (beyond the edge both neighbours are the edge texel)
            x = u * mi.Float(w) - 0.5
            y = (1.0 - v) * mi.Float(h) - 0.5
            x = dr.select(x >= -1.0, dr.minimum(x, mi.Float(w)), -1.0)
            y = dr.select(y >= -1.0, dr.minimum(y, mi.Float(h)), -1.0)
            xf, yf = dr.floor(x), dr.floor(y)
            fx, fy = x - xf, y - yf
            x0, y0 = mi.Int32(xf), mi.Int32(yf)
            if wrap:  # u, v in [0, 1): x0 in [-1, w - 1]
                x0 = dr.select(x0 < 0, x0 + wi, x0)
                y0 = dr.select(y0 < 0, y0 + hi, y0)
                x1 = dr.select(x0 + 1 >= wi, 0, x0 + 1)
                y1 = dr.select(y0 + 1 >= hi, 0, y0 + 1)
            else:
                x1, y1 = dr.clip(x0 + 1, 0, wi - 1), dr.clip(y0 + 1, 0, hi - 1)
                x0, y0 = dr.clip(x0, 0, wi - 1), dr.clip(y0, 0, hi - 1)
            r0, r1 = off + mi.UInt32(y0) * w, off + mi.UInt32(y1) * w
            i00, i01 = (r0 + mi.UInt32(x0)) * C, (r0 + mi.UInt32(x1)) * C
            i10, i11 = (r1 + mi.UInt32(x0)) * C, (r1 + mi.UInt32(x1)) * C
            out = []
            for c in range(C):
                top = dr.gather(mi.Float, flat, i00 + c)
                top = top + (dr.gather(mi.Float, flat, i01 + c) - top) * fx
                bot = dr.gather(mi.Float, flat, i10 + c)
                bot = bot + (dr.gather(mi.Float, flat, i11 + c) - bot) * fx
                out.append(top + (bot - top) * fy)
            return out

        def body(j, acc):
            tj = (mi.Float64(j) + 0.5) / mi.Float64(kk) - 0.5
            pu, pv = u0 + tj * su, v0 + tj * sv
            if wrap:  # wrap first, in float64: float32 keeps texel precision on [0, 1)
                pu, pv = pu - dr.floor(pu), pv - dr.floor(pv)
            u, v = mi.Float(pu), mi.Float(pv)
            lo, hi = bilinear(u, v, sizes[0]), bilinear(u, v, sizes[1])
            return j + 1, [s_ + (a_ + (b_ - a_) * tt) for s_, a_, b_ in zip(acc, lo, hi)]

        zero = dr.zeros(mi.Float, dr.width(u0))
        _, acc = dr.while_loop((mi.Int32(0), [zero] * C), lambda j, acc: j < kk, body)
        return [a_ / mi.Float(kk) for a_ in acc]

    def bilinear(self, uv: np.ndarray, level=0) -> np.ndarray:
        """Unfiltered (point) lookup of one level (an int, or one per sample): bilinear interpolation of its
        texels, (M, 2) -> (M, C)."""
        uv = np.asarray(uv, np.float64).reshape(-1, 2)
        if uv.shape[0] == 0:
            return np.zeros((0, self.channels), np.float32)
        lev = np.clip(np.broadcast_to(np.asarray(level, np.int64), uv.shape[:1]), 0, self.max_level)
        return self._lookup(uv, lev, lev, np.zeros(uv.shape[0], np.float32))

    def trilinear(self, uv: np.ndarray, lod: np.ndarray) -> np.ndarray:
        """Bilinear lookups of the two levels around ``lod`` (M,), blended linearly."""
        uv = np.asarray(uv, np.float64).reshape(-1, 2)
        if uv.shape[0] == 0:
            return np.zeros((0, self.channels), np.float32)
        lod = np.clip(np.asarray(lod, np.float64), 0.0, float(self.max_level))
        l0 = np.floor(lod).astype(np.int64)
        l1 = np.minimum(l0 + 1, self.max_level)
        return self._lookup(uv, l0, l1, (lod - l0).astype(np.float32))

    def filtered(self, uv: np.ndarray, duv_dx: np.ndarray, duv_dy: np.ndarray, max_aniso: int = 16) -> np.ndarray:
        """Anisotropic filtered lookup over the footprint spanned by ``duv_dx``, ``duv_dy`` (M, 2) (uv units per
        sample step), (M, C). See the module docstring."""
        uv = np.asarray(uv, np.float64).reshape(-1, 2)
        M = uv.shape[0]
        if M == 0:
            return np.zeros((0, self.channels), np.float32)
        W, H = float(self.widths[0]), float(self.heights[0])
        ax, ay = np.asarray(duv_dx, np.float64) * [W, H], np.asarray(duv_dy, np.float64) * [W, H]
        a = ax[:, 0] ** 2 + ay[:, 0] ** 2  # J J^T = [[a, b], [b, c]]
        b = ax[:, 0] * ax[:, 1] + ay[:, 0] * ay[:, 1]
        c = ax[:, 1] ** 2 + ay[:, 1] ** 2
        mid, rad = 0.5 * (a + c), np.sqrt(0.25 * (a - c) ** 2 + b ** 2)
        s1 = np.sqrt(np.maximum(mid + rad, 0.0))
        s2 = np.sqrt(np.maximum(mid - rad, 0.0))
        e1 = np.stack([b, mid + rad - a], -1)  # eigenvector of the largest eigenvalue (two forms: keep the larger)
        e2 = np.stack([mid + rad - c, b], -1)
        e = np.where((np.einsum("ij,ij->i", e1, e1) >= np.einsum("ij,ij->i", e2, e2))[:, None], e1, e2)
        ne = np.linalg.norm(e, axis=-1, keepdims=True)
        e = np.where(ne > 1e-30, e / np.maximum(ne, 1e-30), np.array([1.0, 0.0]))
        ratio = s1 / np.maximum(s2, 1e-12)
        n = np.minimum(2 ** np.ceil(np.log2(np.maximum(ratio, 1.0))), float(max_aniso)).astype(np.int64)
        n = np.maximum(n, 1)
        lod = np.log2(np.maximum(np.maximum(s1 / n, s2), 1e-12))
        lod = np.clip(lod, 0.0, float(self.max_level))
        l0 = np.floor(lod).astype(np.int64)
        step = (e * s1[:, None] * SPAN) / [W, H]  # the probe line's full length in uv
        return self._lookup(uv, l0, np.minimum(l0 + 1, self.max_level), (lod - l0).astype(np.float32), step, n)
