"""
Image composition
=================

Defines the composition of cloud images from the precomputed tables (Dobashi et al. 2012, §4.3, Eqs. 3 and 4),
vectorised over a whole GA population:

-   :func:`compose_cloud`: L_c of Eq. 4 for a population, by the tables' transport.
-   :func:`apply_atmosphere`: L_cg of Eq. 3.
-   :func:`compose`: both, with each set's kappa_a.

For each parameter set (c_in, L_in, g, e, beta, L_amb, kappa_a; e the extinction coefficient in 1/m, mu_t = e rho)
and pixel q the cloud's radiance is Eq. 4, L_c = L_s + L_m + L_b, with single scattering
L_s = c_in L_in beta p(θ_q, g) S_sun(q, e) (Eq. 5), the sky seen through the cloud L_b = T(q, e) L_sky(q) (Eq. 9)
and the multiple scattering L_m of the tables' transport (:mod:`natscene.scatter.transport`: its ``compose``
writes the whole of Eq. 4 in one fused pass); then the atmosphere (Eq. 3),

    L_cg = L_c e^{-kappa_a t_c} + (1 - e^{-kappa_a t_c}) L_sky.

The tables are interpolated linearly in e and g (bilinearly for the multiple scattering); values outside a grid
are clamped to its ends (:mod:`natscene.scatter.nodes`). The GA's fast path (``pixels=``) composes only the N pixels it needs
from a pixel-compressed copy of the tables (:class:`PixelTables`), built once per pixel set and cached on the
tables object.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError
from natscene.scatter.params import population

__all__ = ["compose_cloud", "apply_atmosphere", "compose"]



def _check_sky(tables, sky) -> np.ndarray:
    H, W = tables.t_c.shape
    s = np.asarray(sky, np.float32)
    if s.ndim == 2:
        s = np.repeat(s[..., None], 3, axis=-1)
    if s.shape != (H, W, 3):
        raise InputError(f"compose: sky image has shape {s.shape}, the precompute tables are {W}x{H}: "
                         f"use the sky resampled to the fit resolution (results/sky/<photo>/{W}x{H}/sky.exr)")
    return s


class PixelTables:
    """The tables restricted to N pixels in a pixel-compressed layout for fast composition.

    ``single`` (Ns, 3, N) = (S_sun, S_amb, T); ``multiple`` (Ng, Ns, K, N) so that the (g, e) bracket of
    one individual is two contiguous (2, K, N) slices; ``cos_theta``, ``t_c`` (N,); ``index`` (N,) the flat
    pixel indices into the H x W image.
    """

    def __init__(self, tables, index: np.ndarray):
        H, W = tables.t_c.shape
        self.index = index
        self.shape = (H, W)
        take = lambda a: np.asarray(a).reshape(a.shape[:-2] + (H * W,))[..., index]  # noqa: E731
        self.single = np.ascontiguousarray(np.stack([take(tables.s_sun), take(tables.s_amb),
                                                     take(tables.transmittance)], axis=1), np.float32)
        m = take(tables.multiple)                                     # (K, Ng, Ns, N)
        self.multiple = np.ascontiguousarray(np.moveaxis(m, 0, 2), np.float32)
        self.cos_theta = np.ascontiguousarray(take(tables.cos_theta), np.float32)
        self.t_c = np.ascontiguousarray(take(tables.t_c), np.float32)
        self.sun_ms = self.sky_ms = None
        if getattr(tables, "sun_ms", None) is not None:
            self.sun_ms = np.ascontiguousarray(np.moveaxis(take(tables.sun_ms), 0, 2), np.float32)      # (Ng, Ns, B, N)
            self.sky_ms = np.ascontiguousarray(np.moveaxis(take(tables.sky_ms), (0, 1), (2, 3)), np.float32)  # (Ng, Ns, 4, B', N)
        self.nbytes = sum(a.nbytes for a in (self.single, self.multiple, self.sun_ms, self.sky_ms) if a is not None)


def pixel_index(tables, pixels) -> np.ndarray:
    """Flat pixel indices (N,) from a boolean (H, W) mask or an index array (flat, or (rows, cols))."""
    H, W = tables.t_c.shape
    p = np.asarray(pixels)
    if p.dtype == bool:
        if p.shape != (H, W):
            raise InputError(f"compose: pixel mask has shape {p.shape}, the tables are {W}x{H}")
        return np.flatnonzero(p)
    if p.ndim == 2 and p.shape[0] == 2 and p.shape[1] != W:    # (rows, cols)
        p = p[0] * W + p[1]
    p = p.reshape(-1).astype(np.int64)
    if p.size and (p.min() < 0 or p.max() >= H * W):
        raise InputError(f"compose: pixel indices must lie in [0, {H * W}), got [{p.min()}, {p.max()}]")
    return p


def pixel_tables(tables, pixels) -> PixelTables:
    """The :class:`PixelTables` of ``pixels`` (cached on the tables object: a GA builds it once)."""
    idx = pixel_index(tables, pixels)
    cache = tables.__dict__.setdefault("_pixel_cache", {})
    key = (idx.size, hash(idx.tobytes()))
    pt = cache.get(key)
    if pt is None:
        if len(cache) >= 4:
            cache.pop(next(iter(cache)))
        pt = cache[key] = PixelTables(tables, idx)
    return pt


def compose_cloud(tables, params: dict, sky, pixels=None, backend: str = "auto") -> np.ndarray:
    """L_c of Eq. 4 (no atmosphere) for a population of parameter sets, by the tables' transport
    (:meth:`natscene.scatter.transport.base.Transport.compose`).

    ``pixels=None``: the whole image, (P, H, W, 3). ``pixels``: a boolean (H, W) mask or flat pixel indices
    (N,): only those pixels, (P, N, 3) in index order (the GA's fast path: the tables are re-laid out once
    per pixel set as (Ng, Ns, K, N) and cached on ``tables``). ``sky``: (H, W, 3), or (N, 3) with ``pixels``.

    Per individual the (e, g) bracket is a gather of at most 2 x 2 table slices and the orders (or bands) a
    weighted sum: the work is O(P · 4K · N), independent of the grid sizes Ns, Ng. ``backend``: "auto" (a
    fused numba kernel when numba imports) or "numpy".
    """
    from natscene.scatter.transport import of
    from natscene.scatter.transport.base import Arrays
    model = of(tables)
    P, p = population(params)
    H, W = tables.t_c.shape
    if pixels is None:
        sky = _check_sky(tables, sky).reshape(-1, 3)
        N = H * W
        if getattr(tables, "sun_ms", None) is not None:   # the pixel-compressed layout of every pixel (cached)
            pt = pixel_tables(tables, np.arange(N))
            arrays = Arrays(pt.single[:, 0], pt.single[:, 1], pt.single[:, 2], pt.multiple, pt.sun_ms, pt.sky_ms,
                            pt.cos_theta)
        else:
            K, Ng, Ns = tables.multiple.shape[:3]
            M = tables.multiple.reshape(K, Ng, Ns, N)
            arrays = Arrays(tables.s_sun.reshape(Ns, N), tables.s_amb.reshape(Ns, N),
                            tables.transmittance.reshape(Ns, N), np.moveaxis(M, 0, 2), None, None,
                            tables.cos_theta.reshape(N))
        return model.compose(tables, p, P, arrays, sky, backend).reshape(P, H, W, 3)
    pt = pixel_tables(tables, pixels)
    N = pt.index.size
    s = np.asarray(sky, np.float32)
    if s.shape == (H, W, 3):
        sky = s.reshape(-1, 3)[pt.index]
    elif s.shape == (N, 3):
        sky = s
    else:
        raise InputError(f"compose: sky has shape {s.shape}; expected the full ({H}, {W}, 3) image or the "
                         f"selected pixels ({N}, 3) (results/sky/<photo>/{W}x{H}/sky.exr)")
    arrays = Arrays(pt.single[:, 0], pt.single[:, 1], pt.single[:, 2], pt.multiple, pt.sun_ms, pt.sky_ms,
                    pt.cos_theta)
    return model.compose(tables, p, P, arrays, np.ascontiguousarray(sky, np.float32), backend)


def apply_atmosphere(L_c, t_c, kappa_a, sky) -> np.ndarray:
    """L_cg of Eq. 3: L_c e^{-kappa_a t_c} + (1 - e^{-kappa_a t_c}) L_sky.

    ``L_c`` (..., H, W, 3); ``t_c`` (H, W); ``kappa_a`` scalar, (3,), (P,) or (P, 3) (or any shape
    broadcastable to L_c's leading axes + channel); ``sky`` (H, W, 3).
    """
    L_c = np.asarray(L_c, np.float32)
    k = np.asarray(kappa_a, np.float32)
    if k.ndim == 1 and k.size != 3:
        k = k[:, None]
    if k.ndim >= 1:
        if k.shape[-1] not in (1, 3):
            raise InputError(f"apply_atmosphere: kappa_a must end in 3 channels (or 1), got shape {k.shape}")
        k = k.reshape(k.shape[:-1] + (1,) * np.ndim(t_c) + k.shape[-1:])
    e = np.exp(-k * np.asarray(t_c, np.float32)[..., None])
    sky = np.asarray(sky, np.float32)
    return sky + (L_c - sky) * e


def compose(tables, params: dict, sky, pixels=None) -> np.ndarray:
    """L_cg: :func:`compose_cloud` then :func:`apply_atmosphere` with each set's kappa_a; (P, H, W, 3), or
    (P, N, 3) for the selected ``pixels``."""
    _, p = population(params)
    if pixels is None:
        sky = _check_sky(tables, sky)
        L_c = compose_cloud(tables, params, sky)
        return apply_atmosphere(L_c, tables.t_c, p["kappa_a"], sky)
    pt = pixel_tables(tables, pixels)
    s = np.asarray(sky, np.float32)
    sky_n = s.reshape(-1, 3)[pt.index] if s.ndim == 3 else s
    L_c = compose_cloud(tables, params, sky_n, pixels=pt.index)
    return apply_atmosphere(L_c, pt.t_c, p["kappa_a"], sky_n)
