"""
Order bands
===========

Defines the grouping of scattering orders into bands, with the closed-form albedo dependence of each band
(Dobashi et al. 2012, §7; Bouthors et al. 2008):

-   :data:`SUN_BANDS`, :data:`SKY_BANDS`: the default bands of the sun's and the sky's light.
-   :func:`check_bands`: validate contiguous bands with an open last band.
-   :func:`band_table`: the band index of every order.
-   :func:`fit_ratios`: each band's geometric ratio r_b from the order histogram.
-   :func:`band_weights`: the albedo weights c_b(beta) of the bands.

Dobashi 2012 §7 proposes to "cluster high orders of scattering into several sets (e.g. 2, 3-4, 5-6, and so
on) as proposed by Bouthors et al. [2008]". The all-orders transport stores, per pixel, the light of each
band of orders B_b = [a_b, e_b] (the last band open, e = ∞) without the albedo, T_b(q) = Σ_{k∈B_b} E^(k)(q),
and composes the multiple scattering of any albedo beta as

    Σ_{k>=2} beta^k E^(k)(q) = Σ_b c_b(beta) T_b(q),    c_b(beta) = Σ_{k∈B_b} w_b(k) beta^k,

where w_b is the distribution of orders inside the band. It is taken geometric, w_b(k) ∝ r_b^k, with the
ratio r_b fitted to the order histogram of the whole cloud (the light of each exact order, tallied while
tracing); the high orders of a thick medium do decay geometrically, so the open last band is a geometric
tail, c(beta) = beta^a (1 - r) / (1 - r beta). The composition stays a linear combination of per-pixel
images with weights that are closed-form functions of beta, as Dobashi's Eq. 8.

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

__all__ = ["SUN_BANDS", "SKY_BANDS", "check_bands", "band_table", "fit_ratios", "band_weights"]

SUN_BANDS = ((2, 2), (3, 3), (4, 4), (5, 8), (9, 16), (17, 32), (33, 64), (65, None))
SKY_BANDS = ((1, 1), (2, 8), (9, None))


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


def fit_ratios(bands, histogram) -> np.ndarray:
    """Per-band geometric ratio r_b of the order histogram (light per exact order, index = order).

    Weighted least squares of log H(k) on k over the band's orders with H > 0 (weights H); bands with
    fewer than two populated orders get r = 1 (flat). The open band's ratio is fitted over its populated
    orders and kept below 1 (a geometric tail must converge).
    """
    h = np.asarray(histogram, np.float64)
    r = np.ones(len(bands))
    for i, (a, e) in enumerate(bands):
        hi = len(h) - 1 if e is None else min(e, len(h) - 1)
        k = np.arange(a, hi + 1)
        v = h[a:hi + 1] if a <= hi else np.zeros(0)
        ok = v > 0
        if ok.sum() >= 2:
            kk, lv, ww = k[ok], np.log(v[ok]), v[ok]
            km = np.average(kk, weights=ww)
            slope = np.sum(ww * (kk - km) * (lv - np.average(lv, weights=ww))) / max(np.sum(ww * (kk - km) ** 2), 1e-30)
            r[i] = float(np.exp(slope))
        if e is None:
            r[i] = min(r[i], 0.9995)
    return r


def band_weights(bands, ratios, beta) -> np.ndarray:
    """c_b(beta) (P, B) for albedos ``beta`` (P,): the band's order distribution w_b(k) ∝ r_b^k weighted by beta^k.

    ``ratios``: (B,), one set for every albedo, or (P, B), one set per albedo (a GA population, each
    individual at its own table node)."""
    beta = np.clip(np.atleast_1d(np.asarray(beta, np.float64)), 0.0, 1.0)
    r_all = np.asarray(ratios, np.float64)
    if r_all.ndim == 2 and r_all.shape[0] != beta.size:
        raise ValueError(f"band_weights: {r_all.shape[0]} ratio sets for {beta.size} albedos")
    r_all = np.broadcast_to(r_all, (beta.size, len(bands)))
    out = np.zeros((beta.size, len(bands)))
    for i, (a, e) in enumerate(bands):
        r = r_all[:, i]
        if e is None:
            out[:, i] = beta ** a * (1.0 - r) / (1.0 - r * beta)
        else:
            k = np.arange(a, e + 1, dtype=np.float64)
            w = r[:, None] ** (k - a)[None, :]
            w /= w.sum(1, keepdims=True)
            out[:, i] = np.einsum("pk,pk->p", beta[:, None] ** k[None, :], w)
    return out
