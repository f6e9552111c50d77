"""Image composition from the precomputed tables (Dobashi 2012 Eqs. 3, 4, 5, 8, 9), vectorised over a
whole GA population.

For each parameter set (c_in, L_in, g, sigma_t, beta, L_amb, kappa_a) and pixel q:

    L_s  = c_in L_in beta p(θ_q, g) S_sun(q, sigma_t) + c_in L_amb S_amb(q, sigma_t)      (Eq. 5)
    L_m  = c_in L_in Σ_{k=2..n_m} beta^k E_m^(k)(q, g, sigma_t)                           (Eq. 8)
    L_b  = T(q, sigma_t) L_sky(q)                                                         (Eq. 9)
    L_c  = L_s + L_m + L_b                                                                (Eq. 4)
    L_cg = L_c e^{-kappa_a t_c} + (1 - e^{-kappa_a t_c}) L_sky                             (Eq. 3)

with linear interpolation of the tables in sigma_t and g (bilinear for E_m^(k)); values outside a grid are
clamped to its ends. The phase p(θ_q, g) is evaluated exactly (HG). Every interpolation is a sparse row of
weights, so the whole population is a handful of (P x N) @ (N x H·W) products.
"""
from __future__ import annotations

import numpy as np

from natscene.io import InputError
from natscene.scatter.phase import INV_4PI

PARAM_KEYS = ("c_in", "L_in", "g", "sigma_t", "beta", "L_amb", "kappa_a")


def lerp_weights(grid, x) -> np.ndarray:
    """(P, N) linear-interpolation weights of the values x (P,) on an increasing grid (N,), clamped."""
    grid = np.asarray(grid, np.float64)
    x = np.atleast_1d(np.asarray(x, np.float64))
    n = grid.size
    w = np.zeros((x.size, n), np.float32)
    if n == 1:
        w[:, 0] = 1
        return w
    xc = np.clip(x, grid[0], grid[-1])
    i = np.clip(np.searchsorted(grid, xc, side="right") - 1, 0, n - 2)
    f = (xc - grid[i]) / (grid[i + 1] - grid[i])
    rows = np.arange(x.size)
    w[rows, i] = 1 - f
    w[rows, i + 1] += f
    return w


def population(params: dict) -> tuple[int, dict]:
    """Broadcast the parameter dict to a population: (P, {key: array}) with c_in (P,3), kappa_a (P,3)."""
    missing = [k for k in ("L_in", "g", "sigma_t", "beta") if k not in params]
    if missing:
        raise InputError(f"compose: parameters {missing} missing (need {', '.join(PARAM_KEYS)})")
    scal = {k: np.atleast_1d(np.asarray(params.get(k, 0.0), np.float64)) for k in ("L_in", "g", "sigma_t", "beta", "L_amb")}
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
    for k in ("g",):
        if np.any(np.abs(out[k]) >= 1):
            raise InputError(f"compose: g must lie in (-1, 1), got {out[k].tolist()}")
    return P, out


def _check_sky(tables, sky) -> np.ndarray:
    H, W = tables.t_c.shape
    s = np.asarray(sky, np.float32)
    if s.ndim == 2:
        s = np.repeat(s[..., None], 3, axis=-1)
    if s.shape != (H, W, 3):
        raise InputError(f"compose: sky image has shape {s.shape}, the precompute tables are {W}x{H}: "
                         f"use the sky resampled to the fit resolution (results/sky/<photo>/{W}x{H}/sky.exr)")
    return s


def compose_cloud(tables, params: dict, sky) -> np.ndarray:
    """L_c (P, H, W, 3) of Eq. 4 (no atmosphere) for a population of parameter sets."""
    sky = _check_sky(tables, sky)
    P, p = population(params)
    H, W = tables.t_c.shape
    Ns, Ng = tables.sigma_t.size, tables.g.size
    ws = lerp_weights(tables.sigma_t, p["sigma_t"])              # (P, Ns)
    wg = lerp_weights(tables.g, p["g"])                          # (P, Ng)
    s_sun = ws @ tables.s_sun.reshape(Ns, -1)                    # (P, HW)
    s_amb = ws @ tables.s_amb.reshape(Ns, -1)
    T = ws @ tables.transmittance.reshape(Ns, -1)
    g = p["g"].astype(np.float32)[:, None]
    cos_t = tables.cos_theta.reshape(1, -1)
    denom = 1.0 + g * g - 2.0 * g * cos_t
    phase = (1.0 - g * g) * np.float32(INV_4PI) / (denom * np.sqrt(denom))
    L_in = p["L_in"].astype(np.float32)[:, None]
    A = (L_in * p["beta"].astype(np.float32)[:, None]) * phase * s_sun
    A += p["L_amb"].astype(np.float32)[:, None] * s_amb
    K = len(tables.orders)
    if K:
        bk = p["beta"][:, None] ** np.asarray(tables.orders, np.float64)[None, :]          # (P, K)
        wm = (bk[:, :, None, None] * wg[:, None, :, None] * ws[:, None, None, :]).astype(np.float32)
        # one dense (P x K·Ng·Ns) @ (K·Ng·Ns x H·W) product: no gathers/copies of the big table
        A += L_in * (wm.reshape(P, -1) @ tables.multiple.reshape(K * Ng * Ns, -1))
    out = A[:, :, None] * p["c_in"].astype(np.float32)[:, None, :]
    out += T[:, :, None] * sky.reshape(1, -1, 3)
    return out.reshape(P, H, W, 3)


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
        k = k[..., None, None, :]
    e = np.exp(-k * np.asarray(t_c, np.float32)[..., None])
    sky = np.asarray(sky, np.float32)
    return sky + (L_c - sky) * e


def compose(tables, params: dict, sky) -> np.ndarray:
    """L_cg (P, H, W, 3): :func:`compose_cloud` then :func:`apply_atmosphere` with each set's kappa_a."""
    sky = _check_sky(tables, sky)
    L_c = compose_cloud(tables, params, sky)
    _, p = population(params)
    return apply_atmosphere(L_c, tables.t_c, p["kappa_a"], sky)
