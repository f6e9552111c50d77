"""
Henyey–Greenstein phase function
================================

Defines the Henyey–Greenstein phase function, normalised over the sphere (Dobashi et al. 2012, §3, Table 1: g):

-   :func:`hg`: the phase function on numpy arrays; :data:`INV_4PI`: the isotropic value 1/(4π).
-   :func:`hg_dr`: the phase function on Dr.Jit arrays.
-   :func:`hg_p1_dr`: its first two Legendre terms, (1 + 3 g cos θ) / 4π, on Dr.Jit arrays.
-   :func:`hg_sample_cos`, :func:`hg_sample_cos_dr`: cos θ sampled from HG(g) (numpy, Dr.Jit).

p(cos θ, g) = (1 - g²) / (4π (1 + g² - 2 g cos θ)^{3/2}), θ the angle between the propagation directions
before and after scattering (g > 0: forward scattering). Works on numpy arrays and Dr.Jit arrays; the
sampler inverts the CDF (g = 0: uniform on the sphere).

The one implementation of HG in the project: the cloud transport (:mod:`natscene.scatter`, which re-exports
these names from ``natscene.scatter.phase``), the Mie stage's HG comparison table
(:func:`natscene.mie.phase.hg_table`) and the volume previews use it.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Henyey, L. G., & Greenstein, J. L. (1941). Diffuse radiation in the galaxy. Astrophysical Journal, 93, 70–83.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["hg", "hg_dr", "hg_p1_dr", "hg_sample_cos", "hg_sample_cos_dr", "INV_4PI"]

INV_4PI = 1.0 / (4.0 * math.pi)


def hg(cos_theta, g):
    """Henyey–Greenstein phase function (numpy: broadcasts over cos_theta and g)."""
    cos_theta = np.asarray(cos_theta, np.float64)
    g = np.asarray(g, np.float64)
    return (1.0 - g * g) * INV_4PI / (1.0 + g * g - 2.0 * g * cos_theta) ** 1.5


def hg_dr(cos_theta, g):
    """Henyey–Greenstein phase function on Dr.Jit arrays (g a Python float or a Dr.Jit Float)."""
    import drjit as dr
    denom = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) * INV_4PI * dr.rsqrt(denom * denom * denom)


def hg_p1_dr(cos_theta, g):
    """The P1 part of Henyey–Greenstein: its Legendre expansion Σ (2l + 1) g^l P_l(cos θ) / 4π cut after l = 1,
    (1 + 3 g cos θ) / 4π (negative where cos θ < -1 / 3g); Dr.Jit arrays."""
    return (1.0 + 3.0 * g * cos_theta) * INV_4PI


def hg_sample_cos(u, g):
    """cos θ distributed as HG(g) from uniforms u in [0, 1) (numpy: broadcasts over u and g), as
    :func:`hg_sample_cos_dr`."""
    u = np.asarray(u, np.float64)
    g = np.asarray(g, np.float64)
    g_safe = np.where(np.abs(g) < 1e-3, 1e-3, g)
    sq = (1.0 - g_safe * g_safe) / (1.0 - g_safe + 2.0 * g_safe * u)
    cos_hg = (1.0 + g_safe * g_safe - sq * sq) / (2.0 * g_safe)
    return np.clip(np.where(np.abs(g) < 1e-3, 1.0 - 2.0 * u, cos_hg), -1.0, 1.0)


def hg_sample_cos_dr(u, g):
    """cos θ distributed as HG(g) from a uniform u in [0, 1) (Dr.Jit; g scalar or per-lane Float)."""
    import drjit as dr
    g_safe = dr.select(dr.abs(g) < 1e-3, 1e-3, g)
    sq = (1.0 - g_safe * g_safe) / (1.0 - g_safe + 2.0 * g_safe * u)
    cos_hg = (1.0 + g_safe * g_safe - sq * sq) / (2.0 * g_safe)
    cos_iso = 1.0 - 2.0 * u
    return dr.clip(dr.select(dr.abs(g) < 1e-3, cos_iso, cos_hg), -1.0, 1.0)
