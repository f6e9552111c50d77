"""The sky's first order by paths from the camera against the sky photons' band, on the main job's nodes.

For each extinction of the arguments (1/m) and the g values of ``--g`` on the main job's kite view of the cumulus
(``config/config.yaml``'s precompute settings, no noise target: each node at its collision budget), this prints
per node: the photons' sky order-1 band and the paths' (:mod:`estimator`, ``--spp`` paths per pixel and half, one
pass serving every g) as the ratio of their means over the footprint (luminance), each one's two-halves error
relative to the composed pixel at beta 0.99 (median / p95 over the footprint), and the seconds: the node's whole
``view_images`` (both sources) and the paths' pass for all the g values:

    make run    # the main job's volumes (results/volumes/cumulus)
    .venv/bin/python experiments/sky_single/run.py 0.005 0.02 0.08 --g 0.75 0.9 --spp 32 [--forced]

Written to results/experiments/sky_single.json (``--forced``: sky_single_forced.json; collisions forced along the
camera ray, see :func:`estimator.sky_order1`).
"""
import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimator import sky_order1  # noqa: E402

from natscene.config import load_yaml_config, validate_config  # noqa: E402
from natscene.geometry import Camera, sun_direction  # noqa: E402
from natscene.phase import hg  # noqa: E402
from natscene.scatter.allorders import Lighting, Scene, settings_from_config, standard_error, view_images  # noqa: E402
from natscene.scatter.bands import band_weights, channel_weights  # noqa: E402
from natscene.scatter.single import march_view  # noqa: E402
from natscene.scatter.transport.all_orders import skylight_dome, sky_luminance_weights  # noqa: E402
from natscene.sky.daylight import skylight  # noqa: E402
from natscene.volume.grid import load_volume  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
BETA = 0.99


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("extinctions", nargs="+", type=float, help="1/m")
    ap.add_argument("--g", nargs="+", type=float, default=[0.75, 0.9])
    ap.add_argument("--spp", type=int, default=32, help="paths per pixel and half")
    ap.add_argument("--forced", action="store_true", help="collisions forced along the camera ray (estimator.py)")
    a = ap.parse_args()
    cfg = validate_config(load_yaml_config(ROOT / "config/config.yaml"), ROOT / "workflow/schemas/config.schema.yaml")
    pre, view = cfg["precompute"], cfg["views"]["kite"]
    volume = load_volume(ROOT / "results/volumes/cumulus")
    camera = Camera.from_view(view)
    s_dir = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
    st = replace(settings_from_config(pre), noise_target=(0.0, 0.0), sky_order1_points=0)   # the photons' order 1
    dome = skylight_dome(np.asarray(s_dir), skylight(pre["skylight"], "precompute.skylight"))
    scene = Scene(volume, Lighting(np.asarray(s_dir), dome), st)
    s_dir = np.asarray(scene.med.sun_dir)
    sky_w = sky_luminance_weights(s_dir, dome)
    cos_q = camera.ray_directions() @ s_dir
    out = {}
    for e in a.extinctions:
        sigma = e / volume.extinction_scale
        sig_k = sigma * volume.extinction_scale
        single = march_view(scene.med, camera, [sigma], step_voxels=pre["step_voxels"],
                            supersample=pre["supersample"], rho_threshold=pre["rho_threshold"])
        foot = single["footprint"] > 0
        t0 = time.perf_counter()
        centre = march_view(scene.med, camera, [sigma], step_voxels=pre["step_voxels"], supersample=1,
                            rho_threshold=pre["rho_threshold"])
        opacity = 1 - centre["T"][0] if a.forced else None
        paths = [sky_order1(scene.med, scene.grid, camera, sig_k, a.g, scene.sky, a.spp, seed=s, opacity=opacity)
                 for s in (1, 2)]
        t_paths = time.perf_counter() - t0
        for j, g in enumerate(a.g):
            t0 = time.perf_counter()
            vi = view_images(scene, camera, sigma, g, seed=5)
            t_node = time.perf_counter() - t0
            cs = band_weights(st.sun_bands, vi.sun_orders, BETA)[0]
            ck = channel_weights(st.sky_bands, vi.sky_orders, BETA)[0]         # (4, B)
            sun = [np.tensordot(cs, vi.sun_halves[h], 1) for h in range(2)]
            sky_all = [np.tensordot(ck * sky_w[:, None], vi.sky_halves[h], 2) for h in range(2)]
            ph1 = [np.tensordot(ck[:, 0] * sky_w, vi.sky_halves[h][:, 0], 1) for h in range(2)]
            pa1 = [np.tensordot(ck[:, 0] * sky_w, paths[h][:, j], 1) for h in range(2)]
            pixel = BETA * hg(cos_q, g) * single["S_sun"][0] + (sun[0] + sun[1]) / 2 + (sky_all[0] + sky_all[1]) / 2
            ok = foot & (pixel > 0)
            row = {"node_seconds": round(t_node, 1), "paths_seconds_all_g": round(t_paths, 1),
                   "sky_photons": int(vi.stats.get("sky_photons", 0))}
            for name, (x, y) in (("photons", ph1), ("paths", pa1)):
                rel = (standard_error(x, y) / np.where(ok, pixel, 1.0))[ok]
                row[name] = {"mean_over_footprint": float(((x + y) / 2)[ok].mean()),
                             "median": round(float(np.median(rel)), 4), "p95": round(float(np.percentile(rel, 95)), 4)}
            row["paths_over_photons"] = round(row["paths"]["mean_over_footprint"] /
                                              row["photons"]["mean_over_footprint"], 4)
            opaque = ok & (1 - single["T"][0] > 0.9)
            row["paths_over_photons_opacity_0.9"] = round(float(((pa1[0] + pa1[1]) / 2)[opaque].mean() /
                                                                ((ph1[0] + ph1[1]) / 2)[opaque].mean()), 4)
            out[f"{e:g}/m g {g:g}"] = row
            print(f"{e:g}/m g {g:g}:", json.dumps(row), flush=True)
    dest = ROOT / f"results/experiments/sky_single{'_forced' if a.forced else ''}.json"
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    with np.errstate(divide="ignore", invalid="ignore"):
        main()
