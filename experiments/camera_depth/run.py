"""The isotropic slab's sun-lit radiance over seeds: what one run of ``tests/test_slab.py`` scatters by.

``tests/test_slab.py`` compares one photon run per case with adding-doubling (iadpython) within 2 %. This repeats its
isotropic radiance case (g 0, the sun along the normal, the view 30 degrees from it, above or below the slab; the
same slab, camera and transport settings: ``natscene.scatter.reference_scene.slab_sun_radiance``) for several seeds
and prints ours / adding-doubling per seed at beta 0.99, 0.9999 and 1, and their mean and standard deviation.
``--view 0.3 8`` is the narrower view the test had before (2.1 thicknesses in 8 x 8 pixels, where one run scatters
by 1 % at tau 10 against 0.4 % at the test's 4.2 in 16 x 16):

    .venv/bin/python experiments/camera_depth/run.py --tau 100 --seeds 11 12 13
    .venv/bin/python experiments/camera_depth/run.py --tau 10 --seeds 11 12 13 14 15 --view 0.3 8
"""
import argparse

import numpy as np

import natscene  # noqa: F401
from natscene.config import default_settings
from natscene.scatter.allorders import AllOrdersSettings
from natscene.scatter.reference_scene import SLAB_VIEW, adding_doubling, slab_sun_radiance

BETAS = (0.99, 0.9999, 1.0)
MU = float(np.cos(np.radians(30)))
SETTINGS = default_settings(AllOrdersSettings, sun_collisions=4_000_000, sky_collisions=0, fine_voxels=1,
                            coarse_voxels=1, camera_lobe=0.0, importance=False)     # tests/test_slab.py's SETTINGS


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tau", type=float, default=10.0)
    ap.add_argument("--below", action="store_true", help="the transmitted light (the view below the slab)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[11, 12, 13, 14, 15])
    ap.add_argument("--view", type=float, nargs=2, default=SLAB_VIEW, metavar=("FOV", "PIXELS"),
                    help="the camera's field of view in degrees and its pixels across (default: the test's)")
    args = ap.parse_args()
    view = (args.view[0], int(args.view[1]))
    refs = {b: adding_doubling(args.tau, 0.0, b, 1.0, MU)[1 if args.below else 0] for b in BETAS}
    rows = []
    for seed in args.seeds:
        got = slab_sun_radiance(args.tau, 0.0, 0.0, MU, not args.below, seed, SETTINGS, BETAS, view)
        rows.append([got[b] / refs[b] for b in BETAS])
        print(f"seed {seed}: " + "  ".join(f"beta {b}: {r:.4f}" for b, r in zip(BETAS, rows[-1])), flush=True)
    r = np.array(rows)
    print("mean " + "  ".join(f"beta {b}: {m:.4f}" for b, m in zip(BETAS, r.mean(0))))
    if len(rows) > 1:
        print("sd   " + "  ".join(f"beta {b}: {m:.4f}" for b, m in zip(BETAS, r.std(0, ddof=1))))


if __name__ == "__main__":
    main()
