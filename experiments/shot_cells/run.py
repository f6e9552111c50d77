"""The shots' cache cells: error against volpath on the thick cumulonimbus, by cell size, raw and with OIDN.

The all-orders transport caches the orders <= 4 in cells of ``fine_voxels`` and the higher orders in cells of
``coarse_voxels`` (``shots.<name>.render``); coarse cells average the cloud's diffuse inside into its thin edges.
Renders the main job's cumulonimbus from the day shot's first camera at 160x120, sun only, at the kite fit's
0.0244 /m (g 0.70, beta 0.9999), with the day shot's render settings and each pair of cells of the arguments
(``fine,coarse`` or ``fine,coarse,collision_scale``), seeds 0 and 1, against the stored converged Mitsuba
``volpath`` render (tests/data/transport_volpath_thick.npz, ``cb_day``; tools/thick_references.py):

    .venv/bin/python experiments/shot_cells/run.py 2,4 2,2 1,1 1,1,0.61

Printed per render: seconds; raw and denoised (OIDN fed the view's opacity and normals) the relative RMSE per
pixel over the cloud (opacity >= 0.5, the reference's own noise taken out), of 8x8-block means, and the ratio to
volpath by opacity band (0.1-0.5, 0.5-0.9, 0.9-0.99, > 0.99). Quoted in docs/stages/precompute.md.
"""
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from natscene.config import load_yaml_config, validate_config
from natscene.denoise.features import view_features
from natscene.denoise.oidn import OIDN
from natscene.geometry import Camera
from natscene.scatter.allorders import frame_settings
from natscene.scatter.medium import make_medium
from natscene.scatter.reference_scene import NOSKY, band_ratios
from natscene.scatter.render import render
from natscene.scatter.single import march_view
from natscene.volume.build import build_volume

ROOT = Path(__file__).resolve().parents[2]


def _blocks(x: np.ndarray) -> np.ndarray:
    H, W = x.shape
    return x[:H // 8 * 8, :W // 8 * 8].reshape(H // 8, 8, W // 8, 8).mean((1, 3))


def main(args):
    with np.load(ROOT / "tests" / "data" / "transport_volpath_thick.npz") as z:
        refs = {k: z[k] for k in z.files if k.startswith("cb_day")}
    cfg = validate_config(load_yaml_config(ROOT / "config" / "config.yaml"),
                          ROOT / "workflow" / "schemas" / "config.schema.yaml")
    vol, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    c = refs["cb_day.camera"]
    cam = Camera(tuple(c[0:3]), tuple(c[3:6]), tuple(c[6:9]), float(c[9]), int(c[10]), int(c[11]))
    sigma, g, beta = (float(x) for x in refs["cb_day.params"])
    p = dict(c_in=[1.0] * 3, L_in=1.0, g=g, extinction=sigma * vol.extinction_scale, beta=beta, kappa_a=[0.0] * 3,
             **NOSKY)
    ref = (refs["cb_day.half_a"].astype(np.float64) + refs["cb_day.half_b"]) / 2
    ref_noise = np.abs(refs["cb_day.half_a"].astype(np.float64) - refs["cb_day.half_b"]) / 2
    opacity = 1 - march_view(make_medium(vol), cam, [sigma])["T"][0]
    cloud = opacity >= 0.5
    full = _blocks(cloud.astype(float)) > 0.99
    alpha, normal, cover = view_features(vol, cam, sigma, 2, 1.0)
    oidn = OIDN(threads=2, quality="high")
    shot = cfg["shots"]["day_to_sunset"]["render"]
    level = ref[cloud].mean()
    for arg in args:
        fine, coarse, *scale = (float(x) for x in arg.split(","))
        st0 = frame_settings(shot)
        st = replace(st0, fine_voxels=int(fine), coarse_voxels=int(coarse),
                     sun_collisions=int(st0.sun_collisions * (scale[0] if scale else 1.0)))
        for seed in (0, 1):
            t0 = time.perf_counter()
            raw = render(vol, cam, refs["cb_day.sun"], p, np.zeros(3, np.float32), dict(shot, seed=seed),
                         skylight=False, all_orders=st)[..., 0]
            seconds = time.perf_counter() - t0
            den = oidn(np.repeat(raw[..., None], 3, -1).astype(np.float32),
                       np.repeat(alpha[..., None], 3, -1).astype(np.float32), normal).mean(-1)
            den = raw + cover * (den - raw)
            parts = []
            for name, img in (("raw", raw), ("oidn", den)):
                e2 = np.mean(((img - ref)[cloud] / level) ** 2) - np.mean((ref_noise[cloud] / level) ** 2)
                blocks = np.sqrt(np.mean(((_blocks(img) - _blocks(ref)) / _blocks(ref))[full] ** 2))
                bands = band_ratios(img, ref, opacity).values()
                parts.append(f"{name}: pixel {np.sqrt(max(e2, 0.0)):.4f}, blocks {blocks:.4f}, bands "
                             + " / ".join(f"{b:.3f}" for b in bands))
            print(f"cells {arg} seed {seed}: {seconds:.1f} s | " + " | ".join(parts), flush=True)


if __name__ == "__main__":
    with np.errstate(divide="ignore", invalid="ignore"):  # the blocks outside the cloud are masked after dividing
        main(sys.argv[1:] or ["2,4", "2,2"])
