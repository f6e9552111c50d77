"""The isotropic slab's sun-lit radiance over seeds: what one run of ``tests/test_slab.py`` scatters by.

``tests/test_slab.py`` compares one photon run per case with adding-doubling (iadpython) within 2 %. This repeats its
isotropic radiance case (g 0, the sun along the normal, the view 30 degrees from it, above or below the slab; the
same slab, camera and transport settings) for several seeds and prints ours / adding-doubling per seed at beta
0.99, 0.9999 and 1, and their mean and standard deviation. Run it on this code (the trilinear camera depth) and with
``exact_depth.patch`` applied (the exact depth in a box-filling volume) to compare the two beyond one seed's noise:

    .venv/bin/python experiments/camera_depth/run.py --tau 100 --seeds 11 12 13 14
    git apply experiments/camera_depth/exact_depth.patch && .venv/bin/python experiments/camera_depth/run.py --tau 100
"""
import argparse

import iadpython as iad
import numpy as np

import natscene  # noqa: F401
from natscene.config import default_settings
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene, view_images
from natscene.scatter.bands import band_weights
from natscene.scatter.reference_scene import slab_camera, slab_volume
from natscene.scatter.single import march_view

BETAS = (0.99, 0.9999, 1.0)
MU = float(np.cos(np.radians(30)))
SETTINGS = dict(sun_collisions=4_000_000, sky_collisions=0, fine_voxels=1, coarse_voxels=1, camera_lobe=0.0,
                importance=False)        # tests/test_slab.py's SETTINGS


def reference(tau: float, beta: float, above: bool) -> float:
    """pi L / E of adding-doubling at the view MU under a normal sun: mu0 R(MU, 1) or mu0 T(MU, 1), unscattered
    beam excluded (cubic in the quadrature angles)."""
    from scipy.interpolate import CubicSpline
    s = iad.Sample(a=beta, b=tau, g=0.0, d=1.0, n=1.0, n_above=1.0, n_below=1.0, quad_pts=32)
    R, _, T, _ = s.rt_matrices()
    nu, w2 = np.asarray(s.nu), np.asarray(s.twonuw)
    M = R if above else T - np.diag(np.exp(-tau / nu) / w2)
    col = np.array([CubicSpline(nu, M[i])(1.0) for i in range(len(nu))])
    return float(CubicSpline(nu, col)(MU))


def ours(tau: float, above: bool, seed: int) -> dict:
    """pi L / E per beta of the all-orders transport (orders >= 2 in bands, order 1 marched), as the test's."""
    vol = slab_volume(tau=tau, n=(48, max(16, int(np.ceil(tau / 2))), 48), width=12.0)
    sun = np.array([0.0, 1.0, 0.0])
    cam = slab_camera(MU, above, res=8)
    st = default_settings(AllOrdersSettings, **SETTINGS)
    scene = Scene(vol, Lighting(sun, None), st)
    vi = view_images(scene, cam, 1.0, 0.0, seed=seed)
    single = march_view(scene.med, cam, [1.0])["S_sun"][0] / (4 * np.pi)
    return {b: float(np.pi * (b * single + np.tensordot(band_weights(st.sun_bands, vi.sun_orders, b)[0], vi.sun, 1)
                              ).mean()) for b in BETAS}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tau", type=float, default=10.0)
    ap.add_argument("--below", action="store_true", help="the transmitted light (the view below the slab)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[11, 12, 13, 14, 15])
    args = ap.parse_args()
    refs = {b: reference(args.tau, b, not args.below) for b in BETAS}
    rows = []
    for seed in args.seeds:
        got = ours(args.tau, not args.below, seed)
        rows.append([got[b] / refs[b] for b in BETAS])
        print(f"seed {seed}: " + "  ".join(f"beta {b}: {r:.4f}" for b, r in zip(BETAS, rows[-1])), flush=True)
    r = np.array(rows)
    print("mean " + "  ".join(f"beta {b}: {m:.4f}" for b, m in zip(BETAS, r.mean(0))))
    print("sd   " + "  ".join(f"beta {b}: {m:.4f}" for b, m in zip(BETAS, r.std(0, ddof=1))))


if __name__ == "__main__":
    main()
