"""The slab's top face seen at grazing angles: ours / adding-doubling as the view tilts toward the horizon.

A face-dense slab (``natscene.scatter.reference_scene.comparison_slab``, 12 thicknesses wide) under a normal sun, seen
from ``--angles`` degrees off its normal by an 8 x 8-pixel camera aimed at the middle of its top face, whose field
(0.6 degrees times cos(zenith)) covers 4.2 thicknesses along the view's azimuth at every angle, so the footprint
stays on the top face. Prints per angle: the ray-marched order 1 against its closed form for an unbounded slab, the
cache's orders >= 2 against adding-doubling's reflection less that closed form, and the total's ratio (beta 1).

    .venv/bin/python experiments/camera_depth/grazing.py --tau 10 --angles 89.2 85 80 70 60
"""
import argparse

import numpy as np

import natscene  # noqa: F401
from natscene.config import default_settings
from natscene.phase import hg
from natscene.scatter.allorders import AllOrdersSettings, Lighting, Scene, view_images
from natscene.scatter.bands import band_weights
from natscene.scatter.reference_scene import adding_doubling, comparison_slab, slab_camera, slab_sun
from natscene.scatter.single import march_view

SETTINGS = default_settings(AllOrdersSettings, sun_collisions=1_500_000, sky_collisions=0, fine_voxels=1,
                            coarse_voxels=1, camera_lobe=0.0, importance=False)     # tests/test_slab.py's FLUX


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tau", type=float, default=10.0)
    ap.add_argument("--g", type=float, default=0.0)
    ap.add_argument("--angles", type=float, nargs="+", default=[89.2, 85.0, 80.0, 70.0, 60.0])
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    tau, g = args.tau, args.g
    vol, sun = comparison_slab(tau), slab_sun(0.0)
    for angle in args.angles:
        mu = float(np.cos(np.radians(angle)))
        cam = slab_camera(mu, res=8, fov=0.6 * mu, height=1.0)
        scene = Scene(vol, Lighting(sun, None), SETTINGS)
        vi = view_images(scene, cam, 1.0, g, seed=args.seed)
        single = np.pi * hg(cam.ray_directions() @ sun, g) * march_view(scene.med, cam, [1.0])["S_sun"][0]
        multi = np.pi * np.tensordot(band_weights(SETTINGS.sun_bands, vi.sun_orders, 1.0)[0], vi.sun, 1)
        exact1 = np.pi * float(hg(np.array([-mu]), g)[0]) / (1 + mu) * (1 - np.exp(-tau * (1 + 1 / mu)))
        ref = adding_doubling(tau, g, 1.0, 1.0, mu)[0]
        print(f"{angle:5.1f} deg (mu {mu:.4f}): order 1 {single.mean():.4f} (closed form {exact1:.4f}), orders >= 2 "
              f"{multi.mean():.4f} (adding-doubling {ref - exact1:.4f}: {multi.mean() / (ref - exact1):.3f}), "
              f"total {(single + multi).mean() / ref:.3f}", flush=True)


if __name__ == "__main__":
    main()
