"""First-order similarity for the high orders of the all-orders transport: time and error against volpath.

From order ``similarity_order`` on a photon walks the similar medium (extinction (1 - g) mu_t, isotropic, each
collision a geometric number of real ones; ``precompute.all_orders.similarity_order``, Zhao, Ramamoorthi & Bala
2014 use such relations for the high orders). Traces the sun's light through the blob of
natscene.scatter.reference_scene at 12 M collisions against the stored 8192-spp Mitsuba volpath renders
(tests/data/transport_volpath.npz):

    .venv/bin/python experiments/similarity/run.py 0 32 16 8 4

Each argument is ``order`` or ``order:max_order`` (0 is the exact walk). Printed per case: seconds, photons, the
mean ratio to volpath over the cloud, the range of the 8x8 block ratios, the median relative half-difference of
two halves. The thick references (mean optical depth 100 and 300) are compared by tests/test_thick.py
(``pytest -s -k similarity``).
"""
import sys
import time
from pathlib import Path

import numpy as np

from natscene.config import default_settings
from natscene.phase import hg
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene, view_images
from natscene.scatter.bands import band_weights
from natscene.scatter.reference_scene import CAM, SUN, blob_volume, block_ratios
from natscene.scatter.single import march_view

ROOT = Path(__file__).resolve().parents[2]
CASES = [(1.0, 0.85, 0.999), (0.5, 0.85, 0.999), (1.0, 0.0, 0.999)]     # sigma_t (x 80 /unit), g, beta


def main(args):
    vol = blob_volume()
    refs = np.load(ROOT / "tests" / "data" / "transport_volpath.npz")
    for cfg in args:
        order, _, most = cfg.partition(":")
        extra = dict(similarity_order=int(order), **({"max_order": int(most)} if most else {}))
        st = default_settings(AllOrdersSettings, sun_collisions=12_000_000, sky_collisions=200_000, fine_voxels=1,
                              coarse_voxels=1, camera_lobe=0.6, **extra)
        scene = Scene(vol, Lighting(SUN, None), st)
        for s, g, b in CASES:
            t0 = time.perf_counter()
            vi = view_images(scene, CAM, s, g, seed=3)
            dt = time.perf_counter() - t0
            single = march_view(scene.med, CAM, [s])
            s1 = b * hg(CAM.ray_directions() @ SUN, g) * single["S_sun"][0]
            c = band_weights(st.sun_bands, vi.sun_orders, b)[0]
            img, ha, hb = (s1 + np.tensordot(c, x, 1) for x in (vi.sun, vi.sun_halves[0], vi.sun_halves[1]))
            ref = refs[f"s{s:g}_g{g:g}_b{b:g}"]
            ref = ref[..., 0] if ref.ndim == 3 else ref
            m = (single["footprint"] > 0) & (ref > 0)
            blk = block_ratios(img, ref, m)
            half = np.median(np.abs(ha - hb)[m] / 2 / img[m])
            print(f"similarity {cfg:>5s}  sigma_t {s} g {g}: {dt:5.1f} s, {vi.stats['sun_photons']} photons, "
                  f"mean {img[m].mean() / ref[m].mean():.4f}, blocks {blk.min():.3f}..{blk.max():.3f}, "
                  f"half-difference {half:.4f}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:] or ["0", "32", "16", "8", "4"])
