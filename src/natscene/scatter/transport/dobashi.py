"""
Transport ``dobashi``
=====================

Defines the paper's transport: multiple scattering of orders 2..n_m by path tracing plus the ambient term:

-   :class:`Dobashi`: the transport model (precompute, composition, direct render).

Dobashi et al. 2012, §4.3 Eqs. 6-8: E_m^(k)(q, g, sigma_t), the light of scattering order k = 2..n_m (n_m = 4 in
the paper) per pixel, traced with directions importance-sampled from HG(g) (:mod:`natscene.scatter.multiple`);
the orders above n_m are replaced by a constant ambient term L_amb S_amb (Eq. 5). The composition (Eq. 4 with
Eqs. 5, 8, 9) weights the orders by beta^k:

    L_c = c_in [L_in beta p(θ_q, g) S_sun + L_amb S_amb + L_in Σ_{k=2..n_m} beta^k E_m^(k)] + T L_sky,

interpolated linearly in the extinction and g between the tables' nodes. The GA searches L_in, g, the extinction,
beta and L_amb (the paper's five).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import time

import numpy as np

from natscene.io import read_exr, write_exr
from natscene.scatter.nodes import bracket
from natscene.scatter.phase import INV_4PI, hg
from natscene.scatter.transport.base import Arrays, RenderOptions, Transport, noise_stats as _stats

try:  # a fused compiled kernel where numba is importable (it is a declared dependency); numpy otherwise
    import numba as _nb
except Exception:  # noqa: BLE001
    _nb = None

__all__ = ["Dobashi"]

_KERNEL = None
_CHUNK = 8192


def _kernel():
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


def _compose_numba(p, sig, gs, orders, arrays, cos_t, sky, P, N):
    """The fused kernel's call: brackets and order weights per individual."""
    s_sun, s_amb, s_T, mult = arrays
    K = orders.size
    sidx = np.zeros((P, 2), np.int64)
    gidx = np.zeros((P, 2), np.int64)
    ws = np.zeros((P, 2), np.float32)
    wm = np.zeros((P, 2, 2, max(K, 1)), np.float32)
    for j in range(P):
        si, fs = bracket(sig, p["extinction"][j])
        gi, fg = bracket(gs, p["g"][j])
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
    _kernel()(s_sun, s_amb, s_T, mult, np.asarray(cos_t, np.float32), np.ascontiguousarray(sky, np.float32),
              sidx, ws, gidx, wm, p["g"].astype(np.float32), (p["L_in"] * p["beta"]).astype(np.float32),
              p["L_amb"].astype(np.float32), p["c_in"].astype(np.float32), out)
    return out


def _multiple(med, camera, sigmas, gs, single, n_m, spp, seed, batch_spp, with_error, log):
    """E_m^(k) (K, Ng, Ns, H, W) by per-order path tracing (Eq. 7) and its noise figures (``sigmas``: the volume's
    unitless sigma_t of each node, extinction / extinction_scale)."""
    from natscene.scatter.multiple import trace_orders
    from scipy.ndimage import binary_dilation
    orders = list(range(2, n_m + 1))
    H, W = camera.height, camera.width
    multiple = np.zeros((len(orders), len(gs), len(sigmas), H, W), np.float32)
    single_cos = camera.ray_directions() @ (med.sun_dir / np.linalg.norm(med.sun_dir))
    foot = single["footprint"] > 0
    # only pixels whose view rays meet any density can score (T < 1 at the largest extinction), dilated by
    # one pixel for jittered rays at the silhouette; the others are exactly 0 and are not traced
    traced = np.flatnonzero(binary_dilation(single["T"][-1] < 1, iterations=1)) if sigmas[-1] > 0 else None
    rel_se = {k: [] for k in orders}
    weighted = {k: [] for k in orders}
    weighted_sum = []
    for i, s in enumerate(sigmas):
        if s <= 0 or not orders:
            continue
        ts = time.perf_counter()
        out = trace_orders(med, camera, float(s), gs, n_max=n_m, spp=spp, seed=seed * 1000 + i,
                           batch_spp=batch_spp, with_error=with_error, pixels=traced)
        est, se = out if with_error else (out, None)
        multiple[:, :, i] = est[1:]
        if with_error:
            for ki, k in enumerate(orders):
                e, u = est[k - 1][:, foot], se[k - 1][:, foot]
                ok = e > 0
                rel_se[k].append((u[ok] / e[ok]).astype(np.float32))
            # the same noise relative to the pixel's composed cloud radiance at beta = 1, L_amb = 0:
            # L = p(theta_q, g) S_sun + sum_k E^(k) (what the noise does to the image the GA sees)
            L = hg(single_cos[foot][None], gs[:, None]) * single["S_sun"][i][foot][None] + est[1:][:, :, foot].sum(0)
            okL = L > 0
            for ki, k in enumerate(orders):
                weighted[k].append((se[k - 1][:, foot][okL] / L[okL]).astype(np.float32))
            tot = np.sqrt((se[1:][:, :, foot] ** 2).sum(0))
            weighted_sum.append((tot[okL] / L[okL]).astype(np.float32))
        log(f"multiple scattering extinction={s * med.scale:g}/m: orders {orders[0]}..{n_m}, {len(gs)} g, {spp} spp "
            f"in {time.perf_counter() - ts:.1f} s")
    meta = {"orders": orders, "n_m": int(n_m), "spp": int(spp)}
    if with_error and orders:
        meta["relative_standard_error"] = {f"k{k}": _stats(v) for k, v in rel_se.items()}
        # standard error of E^(k) divided by the pixel's composed radiance (beta = 1, no ambient), and of
        # sum_k E^(k) (orders' errors combined in quadrature), over cloud pixels, all extinctions > 0 and g
        meta["pixel_relative_standard_error"] = {**{f"k{k}": _stats(v) for k, v in weighted.items()},
                                                 "sum": _stats(weighted_sum)}
        meta["traced_pixels"] = int(H * W if traced is None else traced.size)
    return orders, multiple, meta


def _tag(x: float) -> str:
    return f"{float(x):g}"


def _names(orders, gs, extinctions) -> list[str]:
    return [f"k{k}.g{_tag(g)}.e{_tag(s)}" for k in orders for g in gs for s in extinctions]


class Dobashi(Transport):
    """The paper's transport (see the module docstring)."""

    name = "dobashi"
    fit_params = ("L_in", "g", "extinction", "beta", "L_amb")
    tables_file = "multiple.exr"

    def describe(self, section: dict) -> str:
        return f"n_m={section['n_m']}, {section['spp']} spp"

    def preview_rows(self, tables, si: int, gis: list) -> list:
        """One row per order k: E_m^(k)."""
        return [[(f"E{k}", tables.multiple[ki, gi, si]) for gi in gis] for ki, k in enumerate(tables.orders)]

    def values_per_node(self, section: dict) -> int:
        return max(int(section["n_m"]) - 1, 1)

    def precompute(self, volume, med, camera, sigmas, gs, single, *, settings=None, skylight=None, n_m=4,
                   spp=256, seed=0, batch_spp=None, with_error=True, log=None):
        orders, multiple, meta = _multiple(med, camera, sigmas, gs, single, n_m, spp, seed, batch_spp, with_error,
                                           log or (lambda msg: None))
        return {"orders": orders, "multiple": multiple}, meta

    def save(self, directory, tables, attrs: dict) -> None:
        K, Ng, Ns = tables.multiple.shape[:3]
        H, W = tables.t_c.shape
        path = f"{directory}/{self.tables_file}"
        if K:
            write_exr(path, tables.multiple.reshape(K * Ng * Ns, H, W).transpose(1, 2, 0),
                      _names(tables.orders, tables.g, tables.extinction), attrs=attrs, stage="precompute")
        else:
            write_exr(path, np.zeros((H, W, 1), np.float32), ["none"], attrs=attrs, stage="precompute")

    def load(self, directory, meta: dict, extinctions, gs, orders, shape) -> dict:
        H, W = shape
        multiple = np.zeros((0, len(gs), len(extinctions), H, W), np.float32)
        if orders:
            img = read_exr(f"{directory}/{self.tables_file}")
            names = _names(orders, gs, extinctions)
            stack = np.moveaxis(img.channel(*names).reshape(H, W, -1), -1, 0)
            multiple = np.ascontiguousarray(stack.reshape(len(orders), len(gs), len(extinctions), H, W))
        return {"multiple": multiple}

    def compose(self, tables, p: dict, P: int, arrays: Arrays, sky: np.ndarray, backend: str) -> np.ndarray:
        sig = np.asarray(tables.extinction, np.float64)
        gs = np.asarray(tables.g, np.float64)
        orders = np.asarray(tables.orders, np.float64)
        K = orders.size
        N = arrays.n
        cos_t = arrays.cos_t
        if _nb is not None and backend != "numpy":
            return _compose_numba(p, sig, gs, orders, (arrays.s_sun, arrays.s_amb, arrays.T, arrays.multiple), cos_t,
                                  sky, P, N)
        get_single = lambda i: (arrays.s_sun[i], arrays.s_amb[i], arrays.T[i])  # noqa: E731
        get_mult = lambda gi, si: arrays.multiple[gi, si]                       # noqa: E731
        A = np.empty((P, N), np.float32)
        T = np.empty((P, N), np.float32)
        for j in range(P):
            si, fs = bracket(sig, p["extinction"][j])
            gi, fg = bracket(gs, p["g"][j])
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
        return out

    def render(self, volume, med, camera, sigma: float, single: dict, cos_t, p: dict, sky,
               options: RenderOptions):
        H, W = camera.height, camera.width
        g, beta = float(p["g"][0]), float(p["beta"][0])
        L_in, L_amb = float(p["L_in"][0]), float(p["L_amb"][0])
        c_in = p["c_in"][0].astype(np.float32)
        orders, spp, seed, batch_spp = options.orders, options.spp, options.seed, options.batch_spp
        from natscene.scatter.multiple import trace_orders
        a_s = L_in * beta * hg(cos_t, g) * single["S_sun"][0] + L_amb * single["S_amb"][0]
        a_m = np.zeros((H, W))
        if orders >= 2 and sigma > 0:
            e = trace_orders(med, camera, sigma, [g], n_max=orders, spp=spp, seed=seed, batch_spp=batch_spp)
            for k in range(2, orders + 1):
                a_m += beta ** k * e[k - 1, 0]
            a_m *= L_in
        L_s = a_s[..., None].astype(np.float32) * c_in
        L_m = a_m[..., None].astype(np.float32) * c_in
        cloud = L_s + L_m
        return cloud, {"L_s": L_s, "L_m": L_m}
