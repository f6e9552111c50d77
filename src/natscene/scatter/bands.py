"""
Order bands
===========

Defines the grouping of scattering orders into bands, with the closed-form albedo dependence of each band
(Dobashi et al. 2012, §7; Bouthors et al. 2008):

-   :data:`SUN_BANDS`, :data:`SKY_BANDS`: the default bands of the sun's and the sky's light.
-   :func:`check_bands`: validate contiguous bands with an open last band.
-   :func:`band_table`: the band index of every order.
-   :func:`order_distribution`: each band's distribution of orders (sub-bins: share, mean order) from the order
    histogram.
-   :func:`band_weights`: the albedo weights c_b(beta) of the bands.
-   :data:`SKY_GROUPS`, :func:`channel_weights`: the sky's channels (the dome's R, G, B, the ground) and the
    order distribution each of them takes.

Dobashi 2012 §7 proposes to "cluster high orders of scattering into several sets (e.g. 2, 3-4, 5-6, and so
on) as proposed by Bouthors et al. [2008]". The all-orders transport stores, per pixel, the light of each
band of orders B_b = [a_b, e_b] (the last band open, e = ∞) without the albedo, T_b(q) = Σ_{k∈B_b} E^(k)(q),
and composes the multiple scattering of any albedo beta as

    Σ_{k>=2} beta^k E^(k)(q) = Σ_b c_b(beta) T_b(q),    c_b(beta) = Σ_{k∈B_b} w_b(k) beta^k,

where w_b is the distribution of orders inside the band, taken from the order histogram of what the camera sees
(the light of each exact order toward the camera from the voxels in its frame, tallied while tracing). A band's
distribution is kept as ``ORDER_BINS`` sub-bins of orders, log-spaced over the band's orders with light, each with
its share of the band's light and its mean order, and c_b(beta) = Σ_j p_bj beta^(k̄_bj). A geometric distribution
w_b(k) ∝ r^k fitted to the histogram cannot follow the heavy tail of a thick cloud's orders (the reflected light's
orders fall as a power of k; the measured difference is in docs/stages/precompute.md, "Thick clouds"). Light
whose orders differ by source has a histogram of its own: the sky's ground channel (the light from below enters a
cloud's base after a few orders where the dome's light needs hundreds) keeps its own distribution
(:data:`SKY_GROUPS`). The composition stays a linear combination of per-pixel images with weights that are
closed-form functions of beta, as Dobashi's Eq. 8; what the sub-bins cannot hold is the variation of the order
distribution from pixel to pixel inside one band.

References
----------
-   Bouthors, A., Neyret, F., Max, N., Bruneton, E., & Crassin, C. (2008). Interactive multiple anisotropic
    scattering in clouds. Proceedings of the 2008 Symposium on Interactive 3D Graphics and Games, 173–182.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

__all__ = ["SUN_BANDS", "SKY_BANDS", "check_bands", "band_table", "ORDER_BINS", "order_distribution", "band_weights",
           "SKY_GROUPS", "SKY_HISTOGRAMS", "channel_weights"]

SUN_BANDS = ((2, 2), (3, 3), (4, 4), (5, 8), (9, 16), (17, 32), (33, 64), (65, 256), (257, 1024), (1025, 4096),
             (4097, None))
SKY_BANDS = ((1, 1), (2, 8), (9, None))
ORDER_BINS = 32
"""Sub-bins of orders per band. A sub-bin composes beta^k at its mean order, below the mean of beta^k over its
orders (Jensen): the sky's light transmitted through a slab of optical depth 100 (g 0.85) composes at beta 0.99 to
0.92 of adding-doubling with 16 sub-bins of its open band, 0.964 with 32 (four runs; 64 within 1 % of 32 in one)."""
SKY_GROUPS = (0, 0, 0, 1)
"""The order histogram of each of the sky's four channels (:class:`natscene.scatter.photons.SkySource`): the dome's
R, G, B share the first, the ground the second."""
SKY_HISTOGRAMS = max(SKY_GROUPS) + 1
"""The sky's order histograms (and order distributions per node): the dome's and the ground's."""


def band_table(bands, max_order: int) -> np.ndarray:
    """(max_order + 1,) uint32: the band index of every order (orders below the first band: 0, unused)."""
    t = np.zeros(max_order + 1, np.uint32)
    for i, (a, e) in enumerate(bands):
        e = max_order if e is None else min(int(e), max_order)
        t[int(a):e + 1] = i
    return t


def check_bands(bands, first: int) -> tuple:
    """Contiguous bands starting at order ``first``, the last one open; returns them as a tuple of pairs."""
    out = []
    nxt = first
    for i, b in enumerate(bands):
        a, e = int(b[0]), (None if b[1] is None else int(b[1]))
        if a != nxt or (e is not None and e < a) or (e is None and i != len(bands) - 1):
            raise ValueError(f"order bands must be contiguous from order {first}, the last open: {bands}")
        out.append((a, e))
        nxt = None if e is None else e + 1
    if out and out[-1][1] is not None:
        raise ValueError(f"the last order band must be open ([a, null]): {bands}")
    return tuple(out)


def _sub_bins(a: int, e: int) -> np.ndarray:
    """Edges (n + 1,) of at most ``ORDER_BINS`` sub-bins of the orders [a, e], log-spaced, each at least one
    order wide: sub-bin j holds the orders edges[j] <= k < edges[j + 1]."""
    if e - a + 1 <= ORDER_BINS:
        return np.arange(a, e + 2)
    x = np.round(np.geomspace(a, e + 1, ORDER_BINS + 1)).astype(np.int64)
    x[0], x[-1] = a, e + 1
    return np.unique(x)


def order_distribution(bands, histogram) -> np.ndarray:
    """(B, ORDER_BINS, 2): per band, its sub-bins' share of the band's light and mean order, from the order
    histogram (light per exact order, index = order); the open band ends at the histogram's last order with light.
    A band without light puts all of it at its first order; unused sub-bins have share 0. A histogram (G, orders),
    one per channel group, gives (G, B, ORDER_BINS, 2)."""
    h = np.asarray(histogram, np.float64)
    if h.ndim == 2:
        return np.stack([order_distribution(bands, x) for x in h])
    out = np.zeros((len(bands), ORDER_BINS, 2))
    lit = np.flatnonzero(h > 0)
    last = int(lit[-1]) if lit.size else -1
    for i, (a, e) in enumerate(bands):
        hi = last if e is None else min(int(e), last)
        out[i, :, 1] = a
        if hi < a or h[a:hi + 1].sum() <= 0:
            out[i, 0, 0] = 1.0
            continue
        k = np.arange(a, hi + 1, dtype=np.float64)
        v = h[a:hi + 1]
        edges = _sub_bins(a, hi)
        cut = np.searchsorted(k, edges[1:-1])
        w = np.add.reduceat(v, np.r_[0, cut])
        kw = np.add.reduceat(v * k, np.r_[0, cut])
        n = len(w)
        out[i, :n, 0] = w / w.sum()
        out[i, :n, 1] = np.where(w > 0, kw / np.maximum(w, 1e-300), k[np.r_[0, cut]])
    return out


def band_weights(bands, orders, beta) -> np.ndarray:
    """c_b(beta) (P, B) for albedos ``beta`` (P,): Σ_j p_bj beta^(k̄_bj) over each band's sub-bins.

    ``orders``: (B, J, 2) from :func:`order_distribution`, one for every albedo, or (P, B, J, 2), one per albedo
    (a GA population, each individual at its own table node)."""
    beta = np.clip(np.atleast_1d(np.asarray(beta, np.float64)), 0.0, 1.0)
    d = np.asarray(orders, np.float64)
    if d.ndim not in (3, 4) or d.shape[-1] != 2 or d.shape[-3] != len(bands):
        raise ValueError(f"band_weights: order distributions of shape {d.shape} for {len(bands)} bands")
    if d.ndim == 4 and d.shape[0] != beta.size:
        raise ValueError(f"band_weights: {d.shape[0]} order distributions for {beta.size} albedos")
    d = np.broadcast_to(d, (beta.size,) + d.shape[-3:])
    with np.errstate(divide="ignore"):
        lb = np.log(beta)[:, None, None]
    return np.einsum("pbj,pbj->pb", d[..., 0], np.exp(np.where(d[..., 0] > 0, lb * d[..., 1], 0.0)))


def channel_weights(bands, orders, beta, groups=SKY_GROUPS) -> np.ndarray:
    """c_b(beta) (P, C, B) of each of C channels, channel c taking the order distributions ``orders[..., groups[c],
    :, :, :]``: ``orders`` (G, B, J, 2), or (P, G, B, J, 2) one per albedo (:func:`band_weights`)."""
    d = np.asarray(orders, np.float64)
    if d.ndim not in (4, 5) or d.shape[-4] <= max(groups):
        raise ValueError(f"channel_weights: order distributions of shape {d.shape} for the groups {groups}")
    per = [band_weights(bands, d[..., gi, :, :, :], beta) for gi in range(d.shape[-4])]
    return np.stack([per[gi] for gi in groups], 1)
