"""Benchmark: hybrid RGB + spectral vs full-spectral render of the same set (Dong 2007 Table 2.1: ~10-15x).

Writes results/benchmarks/composite.json: seconds of both modes (same rays, same process), their ratio,
the spectral object's frame coverage and the CIEDE2000 agreement (fraction of pixels <= 1).
"""
import json
import sys
import time
from pathlib import Path

import colour
import numpy as np

from natscene.color import linear_srgb_to_lab
from natscene.composite.full_spectral import render_full_spectral
from natscene.composite.scene import FilmObject, Leaf, SetRenderer, SetSpec, spectral_coverage, sun_spectrum_from_rgb
from natscene.geometry import Camera


def main(W=160, H=120, spp=4, out="results/benchmarks/composite.json"):
    cam = Camera((0, 0.6, -1.6), (0, 0.1, 0), fov=40, width=W, height=H)
    yy = np.linspace(0, 1, H)[:, None, None]
    bg = np.broadcast_to(np.array([0.3, 0.45, 0.8]) * (1 - yy) + np.array([0.7, 0.75, 0.8]) * yy, (H, W, 3)).copy()
    ck = ((np.indices((8, 8)).sum(0) % 2)[..., None] * np.array([0.3, 0.25, 0.1]) + np.array([0.1, 0.3, 0.05]))
    leaf = np.zeros((32, 64, 3)) + np.array([0.6, 0.1, 0.4])
    leaf[:, :32] = [0.9, 0.8, 0.1]
    spec = SetSpec(cam, bg, ck, leaves=[Leaf(leaf, (-0.35, 0.08, 0.1), (0.5, 0.25), 30, 15)],
                   objects=[FilmObject((0.15, 0.12, 0.0), 0.12)], spp=spp,
                   sun_spd=sun_spectrum_from_rgb([1.0, 0.9, 0.75], 3.0))
    r = SetRenderer(spec)
    r.render_hybrid()  # warm-up: kernel compilation
    t0 = time.perf_counter()
    hy = r.render_hybrid()
    t_h = time.perf_counter() - t0
    t0 = time.perf_counter()
    _, full = render_full_spectral(r)
    t_f = time.perf_counter() - t0
    de = colour.delta_E(linear_srgb_to_lab(hy.final()), linear_srgb_to_lab(full), method="CIE 2000")
    res = {"resolution": [W, H], "spp": spp, "hybrid_s": t_h, "full_spectral_s": t_f, "speedup": t_f / t_h,
           "spectral_coverage": spectral_coverage(hy), "frac_dE2000_le_1": float(np.mean(de <= 1)),
           "dE2000_p99": float(np.percentile(de, 99)), "target_speedup": 10.0, "paper_speedup_table_2_1": [10.5, 14.7, 14.7]}
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    Path(out).write_text(json.dumps(res, indent=2))
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
