"""Image composition from the precomputed tables (Dobashi 2012 Eqs. 3, 4, 5, 8, 9), vectorised over a
whole GA population.

For each parameter set (c_in, L_in, g, e, beta, L_amb, kappa_a; e the extinction coefficient in 1/m, mu_t = e rho)
and pixel q:

    L_s  = c_in L_in beta p(θ_q, g) S_sun(q, e) + c_in L_amb S_amb(q, e)      (Eq. 5)
    L_m  = c_in L_in Σ_{k=2..n_m} beta^k E_m^(k)(q, g, e)                           (Eq. 8)
    L_b  = T(q, e) L_sky(q)                                                         (Eq. 9)
    L_c  = L_s + L_m + L_b                                                                (Eq. 4)
    L_cg = L_c e^{-kappa_a t_c} + (1 - e^{-kappa_a t_c}) L_sky                             (Eq. 3)

(``transport: dobashi``), or, for the default all-orders transport (:mod:`natscene.scatter.allorders`),

    L_c  = c_in L_in [beta p(θ_q, g) S_sun + Σ_b c_b(beta) T_b^sun]
           + Σ_b c'_b(beta) [a ⊙ T_b^{sky,RGB} + G T_b^{ground}] + T L_sky,
    G    = albedo / π (L_in c_in sin(el_sun) + a ⊙ E_dome)

with every order of the sun's light in bands T_b^sun and every order of the skylight in bands T_b^sky
(the dome's R, G, B channels and a unit-radiance ground), c_b(beta) the bands' closed-form albedo weights
(:func:`natscene.scatter.bands.band_weights`), ``sky_scale`` a = the dome's calibration to the photo
(:func:`natscene.scatter.skylight.calibration`), E_dome the dome's horizontal irradiance and G the radiance of
a Lambertian ground of ``ground_albedo``. L_amb has no role there: the skylight replaces it.

Linear interpolation of the tables in e and g (bilinear for the multiple scattering); values outside a
grid are clamped to its ends. The phase p(θ_q, g) is evaluated exactly (HG). Per individual, the interpolation is a
gather of the 2 x 2 bracketing (g, e) slices and the orders a (K,) @ (K, N) product with the weights
L_in beta^k w_g w_s: O(P · 4K · N) work, nothing proportional to the grid sizes. The GA's fast path
(``pixels=``) composes only the N pixels it needs from a pixel-compressed copy of the tables,
(Ng, Ns, K, N) float32, built once per pixel set and cached on the tables object.
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError
from natscene.scatter.phase import INV_4PI

PARAM_KEYS = ("c_in", "L_in", "g", "extinction", "beta", "L_amb", "kappa_a")
DEFAULT_GROUND_ALBEDO = 0.2


try:  # a fused compiled kernel where numba is importable (it is a declared dependency); numpy otherwise
    import numba as _nb
except Exception:  # noqa: BLE001
    _nb = None

_KERNEL = None
_CHUNK = 8192


def _numba_kernel():
    """Fused Eqs. 4, 5, 8, 9 per (individual, pixel chunk), parallel over both (compiled once, cached)."""
    global _KERNEL
    if _KERNEL is None:
        @_nb.njit(parallel=True, cache=True, fastmath=True)
        def kernel(s_sun, s_amb, s_T, mult, cos_t, sky, sidx, ws, gidx, wm, gpar, a_sun, l_amb, c_in, out):
            P, N = out.shape[0], out.shape[1]
            K = mult.shape[2]
            nchunk = (N + _CHUNK - 1) // _CHUNK
            for task in _nb.prange(P * nchunk):
                j = task // nchunk
                n0 = (task - j * nchunk) * _CHUNK
                n1 = min(n0 + _CHUNK, N)
                s0, s1 = sidx[j, 0], sidx[j, 1]
                w0, w1 = ws[j, 0], ws[j, 1]
                g = gpar[j]
                c_ph = np.float32((1.0 - g * g) * 0.07957747154594767) * a_sun[j]
                opg = np.float32(1.0 + g * g)
                tg = np.float32(2.0 * g)
                la = l_amb[j]
                m = n1 - n0
                acc = np.empty(m, np.float32)
                for n in range(m):
                    q = n0 + n
                    d = opg - tg * cos_t[q]
                    acc[n] = (c_ph / (d * np.sqrt(d)) * (w0 * s_sun[s0, q] + w1 * s_sun[s1, q])
                              + la * (w0 * s_amb[s0, q] + w1 * s_amb[s1, q]))
                for u in range(2):
                    gi = gidx[j, u]
                    for v in range(2):
                        si = sidx[j, v]
                        for k in range(K):
                            w = wm[j, u, v, k]
                            if w != 0:
                                row = mult[gi, si, k]
                                for n in range(m):
                                    acc[n] += w * row[n0 + n]
                for n in range(m):
                    q = n0 + n
                    t = w0 * s_T[s0, q] + w1 * s_T[s1, q]
                    for c in range(3):
                        out[j, q, c] = acc[n] * c_in[j, c] + t * sky[q, c]
        _KERNEL = kernel
    return _KERNEL


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
            out[k] = _pop3(params, k, P, None)
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


def _bracket(grid: np.ndarray, x: float) -> tuple[int, float]:
    """(i, f): x clamped to the grid lies between grid[i] and grid[i + 1] at fraction f (f = 0 on one node)."""
    n = grid.size
    if n == 1:
        return 0, 0.0
    xc = min(max(float(x), float(grid[0])), float(grid[-1]))
    i = int(min(max(np.searchsorted(grid, xc, side="right") - 1, 0), n - 2))
    return i, float((xc - grid[i]) / (grid[i + 1] - grid[i]))


def _brackets(grid: np.ndarray, x) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_bracket` for an array of values: (i (P,) int64, f (P,) float64)."""
    x = np.atleast_1d(np.asarray(x, np.float64))
    n = grid.size
    if n == 1:
        return np.zeros(x.size, np.int64), np.zeros(x.size)
    xc = np.clip(x, grid[0], grid[-1])
    i = np.clip(np.searchsorted(grid, xc, side="right") - 1, 0, n - 2).astype(np.int64)
    return i, (xc - grid[i]) / (grid[i + 1] - grid[i])


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


def _compose_numba(p, sig, gs, orders, arrays, cos_t, sky, P, N):
    s_sun, s_amb, s_T, mult = arrays
    K = orders.size
    sidx = np.zeros((P, 2), np.int64)
    gidx = np.zeros((P, 2), np.int64)
    ws = np.zeros((P, 2), np.float32)
    wm = np.zeros((P, 2, 2, max(K, 1)), np.float32)
    for j in range(P):
        si, fs = _bracket(sig, p["extinction"][j])
        gi, fg = _bracket(gs, p["g"][j])
        sidx[j] = (si, min(si + 1, sig.size - 1))
        gidx[j] = (gi, min(gi + 1, gs.size - 1))
        ws[j] = (1.0 - fs, fs)
        if K:
            bk = p["L_in"][j] * p["beta"][j] ** orders
            wm[j] = (np.array([1.0 - fg, fg])[:, None, None] * np.array([1.0 - fs, fs])[None, :, None]
                     * bk[None, None, :])
    if K == 0:
        mult = np.zeros((gs.size, sig.size, 1, N), np.float32)
    out = np.empty((P, N, 3), np.float32)
    _numba_kernel()(s_sun, s_amb, s_T, mult, np.asarray(cos_t, np.float32), np.ascontiguousarray(sky, np.float32),
                    sidx, ws, gidx, wm, p["g"].astype(np.float32), (p["L_in"] * p["beta"]).astype(np.float32),
                    p["L_amb"].astype(np.float32), p["c_in"].astype(np.float32), out)
    return out


_KERNEL_AO = None


_CHUNK_AO = 1024


def _numba_kernel_all_orders():
    """Fused all-orders composition, parallel over pixel chunks (compiled once, cached). Each chunk composes
    every individual in turn, so the table rows of the nodes the population shares are read from main
    memory once per chunk and from cache after that."""
    global _KERNEL_AO
    if _KERNEL_AO is None:
        @_nb.njit(parallel=True, cache=True, fastmath=True)
        def kernel(s_sun, s_T, sun_ms, sky_ms, cos_t, sky, sidx, ws, gidx, wsun, wsky, gpar, a_sun, c_in, a_sky, G,
                   out):
            P, N = out.shape[0], out.shape[1]
            Bs, Bk = sun_ms.shape[2], sky_ms.shape[3]
            nchunk = (N + _CHUNK_AO - 1) // _CHUNK_AO
            for ci in _nb.prange(nchunk):
                n0 = ci * _CHUNK_AO
                n1 = min(n0 + _CHUNK_AO, N)
                m = n1 - n0
                acc = np.empty(m, np.float32)
                acc_k = np.empty((4, m), np.float32)      # the sky bands' dome R, G, B and ground light
                for j in range(P):
                    s0, s1 = sidx[j, 0], sidx[j, 1]
                    w0, w1 = ws[j, 0], ws[j, 1]
                    g = gpar[j]
                    c_ph = np.float32((1.0 - g * g) * 0.07957747154594767) * a_sun[j]
                    opg = np.float32(1.0 + g * g)
                    tg = np.float32(2.0 * g)
                    for n in range(m):
                        q = n0 + n
                        d = opg - tg * cos_t[q]
                        acc[n] = c_ph / (d * np.sqrt(d)) * (w0 * s_sun[s0, q] + w1 * s_sun[s1, q])
                    acc_k[:] = 0
                    for u in range(2):
                        gi = gidx[j, u]
                        for v in range(2):
                            si = sidx[j, v]
                            for b in range(Bs):
                                w = wsun[j, u, v, b]
                                if w != 0:
                                    row = sun_ms[gi, si, b]
                                    for n in range(m):
                                        acc[n] += w * row[n0 + n]
                            for b in range(Bk):
                                w = wsky[j, u, v, b]
                                if w != 0:
                                    for c in range(4):
                                        rc = sky_ms[gi, si, c, b]
                                        for n in range(m):
                                            acc_k[c, n] += w * rc[n0 + n]
                    for n in range(m):
                        q = n0 + n
                        t = w0 * s_T[s0, q] + w1 * s_T[s1, q]
                        gl = acc_k[3, n]
                        for c in range(3):
                            out[j, q, c] = (acc[n] * c_in[j, c] + a_sky[j, c] * acc_k[c, n] + G[j, c] * gl
                                            + t * sky[q, c])
        _KERNEL_AO = kernel
    return _KERNEL_AO


def _pop3(params: dict, key: str, P: int, default) -> np.ndarray:
    v = np.asarray(params.get(key, default), np.float64)
    if v.ndim == 0 or v.size == 1:
        v = np.full(3, float(v.reshape(-1)[0]))
    if v.ndim == 1 and v.size == 3:
        v = np.broadcast_to(v, (P, 3))
    if v.shape != (P, 3):
        raise InputError(f"compose: '{key}' must be a scalar, 3 values or (P, 3), got shape {v.shape}")
    return np.ascontiguousarray(v, np.float32)


def all_orders_weights(tables, p: dict, P: int):
    """Per individual: the (e, g) brackets and the band weights of the all-orders composition.

    Returns sidx, gidx (P, 2), ws (P, 2), wsun (P, 2, 2, B) = w_g w_s L_in c_b(beta), wsky (P, 2, 2, B')
    = w_g w_s c'_b(beta), a (P, 3) the dome's calibration, G (P, 3) the ground radiance."""
    from natscene.scatter.bands import band_weights
    sig = np.asarray(tables.extinction, np.float64)
    gs = np.asarray(tables.g, np.float64)
    sb, kb = tables.sun_bands, tables.sky_bands
    si, fs = _brackets(sig, p["extinction"])
    gi, fg = _brackets(gs, p["g"])
    sidx = np.stack([si, np.minimum(si + 1, sig.size - 1)], 1)
    gidx = np.stack([gi, np.minimum(gi + 1, gs.size - 1)], 1)
    ws = np.stack([1.0 - fs, fs], 1).astype(np.float32)
    wsun = np.zeros((P, 2, 2, len(sb)), np.float32)
    wsky = np.zeros((P, 2, 2, len(kb)), np.float32)
    sun_r, sky_r = np.asarray(tables.sun_ratios), np.asarray(tables.sky_ratios)
    for u, wg in enumerate((1.0 - fg, fg)):
        for v, wsv in enumerate((1.0 - fs, fs)):
            w = wg * wsv                                               # (P,)
            g_n, s_n = gidx[:, u], sidx[:, v]
            wsun[:, u, v] = (w * p["L_in"])[:, None] * band_weights(sb, sun_r[g_n, s_n], p["beta"])
            wsky[:, u, v] = w[:, None] * band_weights(kb, sky_r[g_n, s_n], p["beta"])
    sl = tables.meta.get("skylight", {})
    a = _pop3(p, "sky_scale", P, 1.0)
    albedo = _pop3(p, "ground_albedo", P, DEFAULT_GROUND_ALBEDO)
    e_dome = np.asarray(sl.get("irradiance_rgb", [0.0, 0.0, 0.0]), np.float64)
    sin_el = max(float(sl.get("sun_elevation_sin", 0.0)), 0.0)
    G = albedo / np.pi * (p["L_in"][:, None] * p["c_in"] * sin_el + a * e_dome[None])
    return sidx, gidx, ws, wsun, wsky, a, G.astype(np.float32)


def _compose_all_orders(tables, p: dict, P: int, arrays, cos_t, sky, N: int, backend: str) -> np.ndarray:
    """L_c (P, N, 3) of the all-orders transport; ``arrays`` = (S_sun (Ns, N), T (Ns, N), sun (Ng, Ns, B, N),
    sky (Ng, Ns, 4, B', N))."""
    s_sun, s_T, sun_ms, sky_ms = arrays
    sidx, gidx, ws, wsun, wsky, a, G = all_orders_weights(tables, p, P)
    a_sun = (p["L_in"] * p["beta"]).astype(np.float32)
    c_in = p["c_in"].astype(np.float32)
    out = np.empty((P, N, 3), np.float32)
    if _nb is not None and backend != "numpy":
        _numba_kernel_all_orders()(s_sun, s_T, sun_ms, sky_ms, np.asarray(cos_t, np.float32),
                                   np.ascontiguousarray(sky, np.float32), sidx, ws, gidx, wsun, wsky,
                                   p["g"].astype(np.float32), a_sun, c_in, a, G, out)
        return out
    for j in range(P):
        g = float(p["g"][j])
        denom = np.float32(1.0 + g * g) - np.float32(2.0 * g) * cos_t
        phase = np.float32((1.0 - g * g) * INV_4PI) / (denom * np.sqrt(denom))
        acc = a_sun[j] * phase * (ws[j, 0] * s_sun[sidx[j, 0]] + ws[j, 1] * s_sun[sidx[j, 1]])
        acc_c = np.zeros((3, N), np.float32)
        for u in range(2):
            for v in range(2):
                gi, si = gidx[j, u], sidx[j, v]
                if wsun[j, u, v].any():
                    acc += wsun[j, u, v] @ sun_ms[gi, si]
                if wsky[j, u, v].any():
                    k = np.tensordot(wsky[j, u, v], sky_ms[gi, si], axes=(0, 1))    # (4, N)
                    acc_c += a[j][:, None] * k[:3] + G[j][:, None] * k[3][None]
        t = ws[j, 0] * s_T[sidx[j, 0]] + ws[j, 1] * s_T[sidx[j, 1]]
        out[j] = (acc[:, None] * c_in[j][None] + acc_c.T + t[:, None] * sky).astype(np.float32)
    return out


def compose_cloud(tables, params: dict, sky, pixels=None, backend: str = "auto") -> np.ndarray:
    """L_c of Eq. 4 (no atmosphere) for a population of parameter sets.

    ``pixels=None``: the whole image, (P, H, W, 3). ``pixels``: a boolean (H, W) mask or flat pixel indices
    (N,): only those pixels, (P, N, 3) in index order (the GA's fast path: the tables are re-laid out once
    per pixel set as (Ng, Ns, K, N) and cached on ``tables``). ``sky``: (H, W, 3), or (N, 3) with ``pixels``.

    Per individual the (e, g) bracket is a gather of at most 2 x 2 table slices and the orders a
    weighted sum with beta^k (a (K,) @ (K, N) product per slice): the work is O(P · 4K · N), independent of
    the grid sizes Ns, Ng. ``backend``: "auto" (a fused numba kernel when numba imports) or "numpy".
    """
    P, p = population(params)
    sig = np.asarray(tables.extinction, np.float64)
    gs = np.asarray(tables.g, np.float64)
    orders = np.asarray(tables.orders, np.float64)
    K = orders.size
    H, W = tables.t_c.shape
    all_orders = getattr(tables, "transport", "dobashi") == "all_orders"
    if pixels is None:
        sky = _check_sky(tables, sky).reshape(-1, 3)
        N, Ns, Ng = H * W, sig.size, gs.size
        if all_orders:   # the pixel-compressed layout of every pixel (cached on the tables)
            pt = pixel_tables(tables, np.arange(N))
            out = _compose_all_orders(tables, p, P, (pt.single[:, 0], pt.single[:, 2], pt.sun_ms, pt.sky_ms),
                                      pt.cos_theta, sky, N, backend)
            return out.reshape(P, H, W, 3)
        single = (tables.s_sun.reshape(Ns, N), tables.s_amb.reshape(Ns, N), tables.transmittance.reshape(Ns, N))
        M = tables.multiple.reshape(K, Ng, Ns, N)
        cos_t = tables.cos_theta.reshape(N)
        get_single = lambda i: (single[0][i], single[1][i], single[2][i])  # noqa: E731
        get_mult = lambda gi, si: M[:, gi, si]                              # noqa: E731
        get_arrays = lambda: (*single, np.moveaxis(M, 0, 2))                # noqa: E731
    else:
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
        cos_t = pt.cos_theta
        if all_orders:
            return _compose_all_orders(tables, p, P, (pt.single[:, 0], pt.single[:, 2], pt.sun_ms, pt.sky_ms), cos_t,
                                       np.ascontiguousarray(sky, np.float32), N, backend)
        get_single = lambda i: pt.single[i]              # noqa: E731
        get_mult = lambda gi, si: pt.multiple[gi, si]    # noqa: E731
        get_arrays = lambda: (pt.single[:, 0], pt.single[:, 1], pt.single[:, 2], pt.multiple)  # noqa: E731
    if _nb is not None and backend != "numpy":
        out = _compose_numba(p, sig, gs, orders, get_arrays(), cos_t, sky, P, N)
        return out.reshape(P, H, W, 3) if pixels is None else out
    A = np.empty((P, N), np.float32)
    T = np.empty((P, N), np.float32)
    for j in range(P):
        si, fs = _bracket(sig, p["extinction"][j])
        gi, fg = _bracket(gs, p["g"][j])
        ws = [(si, 1.0 - fs)] + ([(si + 1, fs)] if fs > 0 else [])
        wg = [(gi, 1.0 - fg)] + ([(gi + 1, fg)] if fg > 0 else [])
        s_sun, s_amb, t = (np.float32(ws[0][1]) * x for x in get_single(ws[0][0]))
        if len(ws) > 1:
            s_sun, s_amb, t = (a + np.float32(ws[1][1]) * x for a, x in zip((s_sun, s_amb, t), get_single(ws[1][0])))
        g, beta, L_in = float(p["g"][j]), float(p["beta"][j]), float(p["L_in"][j])
        denom = np.float32(1.0 + g * g) - np.float32(2.0 * g) * cos_t
        phase = np.float32((1.0 - g * g) * INV_4PI) / (denom * np.sqrt(denom))
        a = np.float32(L_in * beta) * phase * s_sun
        if p["L_amb"][j] != 0:
            a += np.float32(p["L_amb"][j]) * s_amb
        if K:
            bk = L_in * beta ** orders
            for g_i, w_g in wg:
                for s_i, w_s in ws:
                    a += (bk * (w_g * w_s)).astype(np.float32) @ get_mult(g_i, s_i)
        A[j] = a
        T[j] = t
    out = A[:, :, None] * p["c_in"].astype(np.float32)[:, None, :]
    out += T[:, :, None] * sky[None]
    return out.reshape(P, H, W, 3) if pixels is None else out


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
