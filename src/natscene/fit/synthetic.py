"""
Synthetic fit problem
=====================

A synthetic fit problem with a known answer: analytic tables of a homogeneous sphere and a gradient sky.

-   :func:`sphere_tables`: the analytic tables of a homogeneous sphere (extinction scale :data:`EXT`).
-   :func:`gradient_sky`: a blue sky brightening slightly toward the bottom of the image.

The tables follow the shape of Dobashi 2012's Eqs. 5-9 in closed form (the path length through a sphere seen head
on, a sun depth growing from left to right, multiple-scattering images falling geometrically with the order), so
that a target rendered from known parameters can be fitted back. Used by the fit's tests and, without the main
job's tables, by ``benchmarks/fit.py``.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import types

import numpy as np

__all__ = ["EXT", "sphere_tables", "gradient_sky"]

#: extinction scale of the synthetic sphere: optical depth = extinction x EXT x chord
EXT = 8.0


def sphere_tables(w: int = 96, h: int = 72) -> types.SimpleNamespace:
    """Tables of a homogeneous sphere (radius 0.35 of the image height) seen head on, lit from the left, on an
    extinction grid 0..1 (11 nodes) and a g grid 0..0.9 (10 nodes), orders 2-4."""
    yy, xx = np.mgrid[0:h, 0:w]
    r = np.hypot((xx + 0.5 - w / 2) / h, (yy + 0.5 - h / 2) / h) / 0.35
    chord = np.where(r < 1, 2 * np.sqrt(np.clip(1 - r * r, 0, 1)) * 0.35, 0.0)  # path length in units
    sun_depth = 0.5 + 0.5 * (xx / w)  # relative path to the sun: lit from the left
    s = np.round(np.arange(11) * 0.1, 10)
    g = np.round(np.arange(10) * 0.1, 10)
    tau = s[:, None, None] * EXT * chord[None]
    trans = np.exp(-tau)
    with np.errstate(invalid="ignore", divide="ignore"):
        s_amb = np.where(tau > 0, (1 - trans) / (s[:, None, None] * EXT), chord[None])
        k = 1 + sun_depth[None]
        s_sun = np.where(tau > 0, (1 - np.exp(-tau * k)) / k / EXT, 0.0)
    orders = [2, 3, 4]
    mult = np.stack([np.stack([(1 - trans) * (0.35 ** o) * (1 + 0.5 * gg) for gg in g]) for o in orders])
    return types.SimpleNamespace(
        extinction=s, g=g, orders=orders, s_sun=s_sun.astype(np.float32), s_amb=s_amb.astype(np.float32),
        transmittance=trans.astype(np.float32), multiple=mult.astype(np.float32),
        t_c=(0.9 + 0.2 * yy / h).astype(np.float32), cos_theta=np.full((h, w), 0.3, np.float32),
        footprint=(chord > 0).astype(np.float32))


def gradient_sky(w: int = 96, h: int = 72) -> np.ndarray:
    """A blue sky (H, W, 3) brightening slightly toward the bottom of the image."""
    yy = np.mgrid[0:h, 0:w][0] / h
    return np.stack([0.15 + 0.1 * yy, 0.3 + 0.1 * yy, 0.7 + 0.05 * yy], -1).astype(np.float32)
