"""Long Mitsuba 3 ``volpath`` renders of the all-orders transport test's cloud: tests/data/transport_volpath.npz.

tests/test_transport.py compares the all-orders transport with ``volpath`` (every order, Russian roulette off)
on a 48x32x48 procedural heap seen at 48x36 pixels, for sigma_t 0.2 / 0.5 / 1, g 0 / 0.85, beta 0.9 / 0.99 /
0.999. At g = 0.85 volpath's next-event estimate toward the sun is heavy-tailed (the phase function's forward
peak): two 256-spp renders of the same scene differ by 1-2 % in their mean over the cloud and by up to 15 % in
single 8x8 blocks, as much as the tolerances under test. This script renders each case with 8192 samples per
pixel (8 seeds of 1024: 4096-sample halves agree within 1 % in the mean and 4 % per 8x8 block) and writes
them once; it takes about 25 minutes on 2 cores. The test checks that a fresh short volpath run still agrees
with the stored images (the same cloud, camera and Mitsuba), so a stale file fails loudly.

    .venv/bin/python tools/transport_references.py            # writes tests/data/transport_volpath.npz
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "data" / "transport_volpath.npz"
SEEDS = tuple(range(100, 108))
SPP_PER_SEED = 1024


def key(sigma: float, g: float, beta: float) -> str:
    return f"s{sigma:g}_g{g:g}_b{beta:g}"


def main() -> int:
    sys.path.insert(0, str(ROOT / "src"))
    import mitsuba as mi
    from natscene.scatter.reference_scene import BETAS, CAM, GS, SIGMAS, SUN, blob_volume
    from natscene.scatter.mitsuba_scene import render_reference
    vol = blob_volume()
    out = {}
    for s in SIGMAS:
        for g in GS:
            for b in BETAS:
                t0 = time.perf_counter()
                imgs = np.array([render_reference(vol, CAM, SUN, s, g, b, orders=100_000, spp=SPP_PER_SEED,
                                                  seed=k)[..., 0] for k in SEEDS], np.float32)
                out[key(s, g, b)] = imgs.mean(0)
                print(f"{key(s, g, b)}: {time.perf_counter() - t0:.0f} s", flush=True)
    out["spp"] = np.array(SPP_PER_SEED * len(SEEDS))
    out["mitsuba"] = np.array(mi.__version__)
    tmp = OUT.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, **out)
    tmp.replace(OUT)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
