"""
Parameter sets of the cloud model
=================================

Defines the parameter sets of the cloud model (Dobashi et al. 2012, Table 1): one set, or a GA population of
P sets, as the compositions and the renderer read them:

-   :data:`PARAM_KEYS`: the keys of a set.
-   :func:`population`: a parameter dict broadcast to a population of P sets.
-   :func:`rgb_per_individual`: one per-channel parameter as (P, 3).

A set holds c_in (sunlight colour, 3), L_in (sun intensity), g (HG asymmetry), the extinction in 1/m (mu_t =
extinction * rho), beta (albedo), L_amb (the ``dobashi`` transport's ambient intensity) and kappa_a (the
atmosphere's extinction per channel, 3); the all-orders transport adds ``sky_scale`` and ``ground_albedo`` (3).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError

__all__ = ["PARAM_KEYS", "population", "rgb_per_individual"]

PARAM_KEYS = ("c_in", "L_in", "g", "extinction", "beta", "L_amb", "kappa_a")


def rgb_per_individual(params: dict, key: str, P: int, default) -> np.ndarray:
    """``params[key]`` (a scalar, 3 values or (P, 3)) as (P, 3) float32, ``default`` where absent."""
    v = np.asarray(params.get(key, default), np.float64)
    if v.ndim == 0 or v.size == 1:
        v = np.full(3, float(v.reshape(-1)[0]))
    if v.ndim == 1 and v.size == 3:
        v = np.broadcast_to(v, (P, 3))
    if v.shape != (P, 3):
        raise InputError(f"compose: '{key}' must be a scalar, 3 values or (P, 3), got shape {v.shape}")
    return np.ascontiguousarray(v, np.float32)


def population(params: dict) -> tuple[int, dict]:
    """Broadcast the parameter dict to a population: (P, {key: array}) with c_in (P,3), kappa_a (P,3)."""
    missing = [k for k in ("L_in", "g", "extinction", "beta") if k not in params]
    if missing:
        raise InputError(f"compose: parameters {missing} missing (need {', '.join(PARAM_KEYS)})")
    scal = {k: np.atleast_1d(np.asarray(params.get(k, 0.0), np.float64)) for k in ("L_in", "g", "extinction", "beta", "L_amb")}
    c_in = np.asarray(params.get("c_in", (1.0, 1.0, 1.0)), np.float64)
    kap = np.asarray(params.get("kappa_a", 0.0), np.float64)
    sizes = [v.size for v in scal.values()] + [c_in.shape[0] if c_in.ndim == 2 else 1,
                                               kap.shape[0] if kap.ndim == 2 else 1]
    P = max(sizes)
    if any(s not in (1, P) for s in sizes):
        raise InputError(f"compose: parameter arrays have incompatible population sizes {sizes}")
    out = {k: np.broadcast_to(v, (P,)).copy() for k, v in scal.items()}
    out["c_in"] = np.broadcast_to(c_in.reshape(-1, 3) if c_in.size % 3 == 0 else c_in[..., None], (P, 3)).copy()
    out["kappa_a"] = np.broadcast_to(kap.reshape(-1, 3) if kap.ndim >= 1 and kap.shape[-1] == 3
                                     else kap.reshape(-1, 1), (P, 3)).copy()
    for k in ("sky_scale", "ground_albedo"):     # all-orders only: kept when given, (P, 3)
        if k in params:
            out[k] = rgb_per_individual(params, k, P, None)
    for k in ("g",):
        if np.any(np.abs(out[k]) >= 1):
            raise InputError(f"compose: g must lie in (-1, 1), got {out[k].tolist()}")
    return P, out
