"""Benchmark: compose a GA population of 20 at 320x240 from the precompute tables, kappa_a line-search
images included (11 values per channel, Dobashi §4.2), against a baseline: a naive per-individual loop
with np.interp-style gathers. Writes results/benchmarks/compose.json. Uses synthetic tables of the real
shape (K=3, Ng=10, Ns=11) so it needs no precompute run."""
import json
import time
from pathlib import Path

import numpy as np

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
        s, g = p["sigma_t"][i], p["g"][i]
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


def main():
    tb = tables()
    r = np.random.default_rng(1)
    P = 20
    p = dict(c_in=r.random((P, 3)), L_in=r.random(P) * 10, g=r.random(P) * 0.9, sigma_t=r.random(P),
             beta=r.random(P), L_amb=r.random(P), kappa_a=np.zeros((P, 3)))
    sky = r.random((240, 320, 3), dtype=np.float32)
    kappas = np.round(np.arange(11) * 0.1, 2)

    def ours():
        L_c = compose_cloud(tb, p, sky)
        for k in kappas:  # line search: every individual, every channel at kappa = k
            apply_atmosphere(L_c, tb.t_c, k, sky)
        return L_c

    def naive():
        L_c = baseline(tb, p, sky)
        for k in kappas:
            sky + (L_c - sky) * np.exp(-k * tb.t_c)[..., None]
        return L_c

    assert np.allclose(ours(), naive(), rtol=1e-3, atol=1e-4)
    res = {}
    for name, fn in (("compose", ours), ("baseline_loop", naive)):
        ts = []
        for _ in range(5):
            t = time.perf_counter(); fn(); ts.append(time.perf_counter() - t)
        res[name + "_s"] = float(np.median(ts))
    t = time.perf_counter()
    for _ in range(5):
        compose_cloud(tb, p, sky)
    res["compose_cloud_only_s"] = (time.perf_counter() - t) / 5
    res.update(population=P, resolution=[320, 240], kappa_values=len(kappas),
               speedup_vs_baseline=res["baseline_loop_s"] / res["compose_s"], target_s=0.030,
               tables_memory_MB=sum(a.nbytes for a in (tb.s_sun, tb.s_amb, tb.transmittance, tb.multiple)) / 1e6)
    out = Path("results/benchmarks/compose.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=2))
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
