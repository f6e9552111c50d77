"""Benchmark: compose a GA population of 20 at 320x240 from the precompute tables, kappa_a line-search
images included (11 values per channel, Dobashi §4.2). Measured: the GA fast path (``pixels=`` the cloud
footprint, 28 % of the frame like the main job's kite view), the full image, against two baselines in the
same run: the former dense (P x K·Ng·Ns) @ (K·Ng·Ns x H·W) product and a naive per-individual numpy loop.
Writes results/benchmarks/compose.json. Uses synthetic tables of the real shape (K=3, Ng=10, Ns=11) so it
needs no precompute run."""
import time

import numpy as np

from _common import write_result

import natscene  # noqa: F401
from natscene.scatter.compose import apply_atmosphere, compose_cloud
from natscene.scatter.phase import hg
from natscene.scatter.tables import Tables


def tables(H=240, W=320, K=3, Ng=10, Ns=11, seed=0):
    r = np.random.default_rng(seed)
    f = lambda *s: r.random(s, dtype=np.float32)  # noqa: E731
    return Tables(np.linspace(0, 1, Ns), np.linspace(0, 0.9, Ng), [2, 3, 4][:K], f(Ns, H, W), f(Ns, H, W),
                  f(Ns, H, W), f(K, Ng, Ns, H, W), f(H, W), f(H, W) * 2 - 1, np.ones((H, W), np.float32))


def baseline(tb, p, sky):
    out = []
    for i in range(len(p["L_in"])):
        s, g = p["extinction"][i], p["g"][i]
        si = min(int(s / 0.1), 9); fs = s / 0.1 - si
        gi = min(int(g / 0.1), 8); fg = g / 0.1 - gi
        lerp = lambda a: a[si] * (1 - fs) + a[si + 1] * fs  # noqa: E731
        m = 0
        for k in range(3):
            e = tb.multiple[k]
            m = m + p["beta"][i] ** (k + 2) * ((1 - fg) * lerp(e[gi]) + fg * lerp(e[gi + 1]))
        a = p["L_in"][i] * (p["beta"][i] * hg(tb.cos_theta, g) * lerp(tb.s_sun) + m) + p["L_amb"][i] * lerp(tb.s_amb)
        out.append(a[..., None] * p["c_in"][i] + lerp(tb.transmittance)[..., None] * sky)
    return np.stack(out)


def dense_product(tb, p, sky):
    """The former compose_cloud: lerp weights as dense rows, one big matrix product over the whole table."""
    from natscene.scatter.params import population
    from natscene.scatter.nodes import lerp_weights
    P, p = population(p)
    H, W = tb.t_c.shape
    K, Ng, Ns = tb.multiple.shape[:3]
    ws, wg = lerp_weights(tb.extinction, p["extinction"]), lerp_weights(tb.g, p["g"])
    s_sun, s_amb, T = (ws @ a.reshape(Ns, -1) for a in (tb.s_sun, tb.s_amb, tb.transmittance))
    g = p["g"].astype(np.float32)[:, None]
    d = 1 + g * g - 2 * g * tb.cos_theta.reshape(1, -1)
    A = (p["L_in"] * p["beta"]).astype(np.float32)[:, None] * (1 - g * g) / (4 * np.pi) / (d * np.sqrt(d)) * s_sun
    A += p["L_amb"].astype(np.float32)[:, None] * s_amb
    bk = p["beta"][:, None] ** np.asarray(tb.orders, float)[None]
    wm = (bk[:, :, None, None] * wg[:, None, :, None] * ws[:, None, None, :]).astype(np.float32)
    A += p["L_in"].astype(np.float32)[:, None] * (wm.reshape(P, -1) @ tb.multiple.reshape(K * Ng * Ns, -1))
    out = A[:, :, None] * p["c_in"].astype(np.float32)[:, None, :] + T[:, :, None] * sky.reshape(1, -1, 3)
    return out.reshape(P, H, W, 3)


def main():
    tb = tables()
    r = np.random.default_rng(1)
    P = 20
    p = dict(c_in=r.random((P, 3)), L_in=r.random(P) * 10, g=r.random(P) * 0.9, extinction=r.random(P),
             beta=r.random(P), L_amb=r.random(P), kappa_a=np.zeros((P, 3)))
    sky = r.random((240, 320, 3), dtype=np.float32)
    kappas = np.round(np.arange(11) * 0.1, 2)

    H, W = tb.t_c.shape
    yy, xx = np.mgrid[:H, :W]
    mask = ((xx - W / 2) / (0.3 * W)) ** 2 + ((yy - H / 2) / (0.3 * H)) ** 2 < 1  # ~28 % of the frame
    sky_n, t_n = sky[mask], tb.t_c[mask]

    def ours():
        L_c = compose_cloud(tb, p, sky)
        for k in kappas:  # line search: every individual, every channel at kappa = k
            apply_atmosphere(L_c, tb.t_c, k, sky)
        return L_c

    def fast():  # the GA: only the cloud pixels
        L_c = compose_cloud(tb, p, sky, pixels=mask)
        for k in kappas:
            apply_atmosphere(L_c, t_n, k, sky_n)
        return L_c

    def dense():
        L_c = dense_product(tb, p, sky)
        for k in kappas:
            apply_atmosphere(L_c, tb.t_c, k, sky)
        return L_c

    def naive():
        L_c = baseline(tb, p, sky)
        for k in kappas:
            sky + (L_c - sky) * np.exp(-k * tb.t_c)[..., None]
        return L_c

    assert np.allclose(ours(), naive(), rtol=1e-3, atol=1e-4)
    assert np.allclose(fast(), ours()[:, mask], rtol=1e-5, atol=1e-5)
    assert np.allclose(dense(), ours(), rtol=1e-3, atol=1e-4)
    res = {}
    for name, fn in (("compose_pixels", fast), ("compose", ours), ("baseline_dense_product", dense),
                     ("baseline_loop", naive)):
        ts = []
        for _ in range(5):
            t = time.perf_counter(); fn(); ts.append(time.perf_counter() - t)
        res[name + "_s"] = float(np.median(ts))
    t = time.perf_counter()
    for _ in range(5):
        compose_cloud(tb, p, sky)
    res["compose_cloud_only_s"] = (time.perf_counter() - t) / 5
    t = time.perf_counter()
    for _ in range(5):
        compose_cloud(tb, p, sky, pixels=mask)
    res["compose_cloud_pixels_only_s"] = (time.perf_counter() - t) / 5
    res.update(population=P, resolution=[320, 240], kappa_values=len(kappas), cloud_pixels=int(mask.sum()),
               speedup_vs_baseline=res["baseline_loop_s"] / res["compose_s"],
               speedup_pixels_vs_dense_product=res["baseline_dense_product_s"] / res["compose_pixels_s"],
               speedup_full_vs_dense_product=res["baseline_dense_product_s"] / res["compose_s"], target_s=0.030,
               tables_memory_MB=sum(a.nbytes for a in (tb.s_sun, tb.s_amb, tb.transmittance, tb.multiple)) / 1e6)
    write_result("compose", res)


if __name__ == "__main__":
    main()
