"""Filtered texture lookup for the set: a mip-map pyramid and anisotropic probes along the pixel footprint.

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
  SPAN = 1.5 is the width OpenImageIO's anisotropic filter covers (measured against its TextureSystem:
  mean difference about 1 % of the texture's range, against 5 % for SPAN = 1; isotropic footprints agree
  with it to float precision: the same box pyramid and trilinear level choice).

Wrap-around (``wrap=True``, the tiled ground) or clamp-to-edge (petals, leaves). (u, v) in [0, 1]² with v up
(row 0 is v = 1). OpenImageIO's ``TextureSystem`` does the same filtering per point; its Python binding
takes one point per call, so the renderer uses this vectorised lookup and the tests compare the two.
"""
from __future__ import annotations

import numpy as np

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
        self.levels = levels
        self.heights = np.array([l.shape[0] for l in levels], np.int64)
        self.widths = np.array([l.shape[1] for l in levels], np.int64)
        self.offsets = np.concatenate([[0], np.cumsum(self.heights * self.widths)[:-1]]).astype(np.int64)
        self.flat = np.concatenate([l.reshape(-1, self.channels) for l in levels])
        self.max_level = len(levels) - 1

    @property
    def shape(self) -> tuple:
        return self.levels[0].shape

    def mean(self) -> np.ndarray:
        """The texture's mean (the 1×1 top of the pyramid), (C,)."""
        return self.levels[-1].reshape(-1, self.channels).mean(0)

    # -- lookups
    def _bilinear(self, uv: np.ndarray, level: np.ndarray) -> np.ndarray:
        w = self.widths[level]
        h = self.heights[level]
        off = self.offsets[level]
        u = uv[:, 0] - np.floor(uv[:, 0]) if self.wrap else uv[:, 0]  # wrap first: float32 keeps texel precision
        v = uv[:, 1] - np.floor(uv[:, 1]) if self.wrap else uv[:, 1]
        x = u.astype(np.float32) * w.astype(np.float32) - np.float32(0.5)
        y = (np.float32(1.0) - v.astype(np.float32)) * h.astype(np.float32) - np.float32(0.5)
        xf, yf = np.floor(x), np.floor(y)
        fx = (x - xf)[:, None]
        fy = (y - yf)[:, None]
        x0, y0 = xf.astype(np.int64), yf.astype(np.int64)
        if self.wrap:
            x0 %= w
            y0 %= h
            x1, y1 = (x0 + 1) % w, (y0 + 1) % h
        else:
            x1, y1 = np.clip(x0 + 1, 0, w - 1), np.clip(y0 + 1, 0, h - 1)
            x0, y0 = np.clip(x0, 0, w - 1), np.clip(y0, 0, h - 1)
        r0, r1 = off + y0 * w, off + y1 * w
        f = self.flat
        top = np.take(f, r0 + x0, axis=0)
        top += (np.take(f, r0 + x1, axis=0) - top) * fx
        bot = np.take(f, r1 + x0, axis=0)
        bot += (np.take(f, r1 + x1, axis=0) - bot) * fx
        top += (bot - top) * fy
        return top

    def bilinear(self, uv: np.ndarray, level: int = 0) -> np.ndarray:
        """Unfiltered (point) lookup of one level: bilinear interpolation of its texels, (M, 2) -> (M, C)."""
        uv = np.asarray(uv, np.float64).reshape(-1, 2)
        return self._bilinear(uv, np.full(uv.shape[0], min(max(int(level), 0), self.max_level), np.int64))

    def trilinear(self, uv: np.ndarray, lod: np.ndarray) -> np.ndarray:
        """Bilinear lookups of the two levels around ``lod`` (M,), blended linearly."""
        uv = np.asarray(uv, np.float64).reshape(-1, 2)
        lod = np.clip(np.asarray(lod, np.float64), 0.0, float(self.max_level))
        l0 = np.floor(lod).astype(np.int64)
        l1 = np.minimum(l0 + 1, self.max_level)
        t = (lod - l0).astype(np.float32)[:, None]
        out = self._bilinear(uv, l0)
        blend = t[:, 0] > 0
        if blend.any():
            hi = self._bilinear(uv[blend], l1[blend])
            out[blend] += (hi - out[blend]) * t[blend]
        return out

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
        out = np.empty((M, self.channels), np.float32)
        for k in np.unique(n):
            sel = np.flatnonzero(n == k)
            if k == 1:
                out[sel] = self.trilinear(uv[sel], lod[sel])
                continue
            t = (np.arange(k) + 0.5) / k - 0.5  # probe positions along the major axis, in footprint lengths
            step = (e[sel] * s1[sel, None] * SPAN) / [W, H]  # the probe line's full length in uv
            pts = uv[sel, None, :] + t[None, :, None] * step[:, None, :]
            v = self.trilinear(pts.reshape(-1, 2), np.repeat(lod[sel], k))
            out[sel] = v.reshape(sel.size, k, -1).mean(1)
        return out
