"""Where a precompute node's noise comes from: the sun's multiple scattering, the sky's first order and the sky's
higher orders, and what the sky lobe's width does to it.

A question for issue 39's precompute time: the main job's strongly forward-scattering nodes (g 0.85, 0.9) reach
the noise target's cap of 8x the collision budget even where the cloud is thin. Each node of the arguments
(``extinction,g``, /m) of the main job's precompute (``config/config.yaml``: the kite view of the cumulus, its
all-orders settings, no noise target: the budget alone) is traced with the sky lobe of the defaults (HG 0.7, share
0.2) and with variants (``--lobes g,share ...``); for the composed cloud pixel at beta 0.99 (single scattering +
the sun's and the sky's multiple scattering in luminance, as
:func:`natscene.scatter.transport.all_orders.node_noise`) it prints, per part, the median and p95 over the
footprint of the part's two-halves standard error relative to the pixel, the part's share of the summed variance,
and the node's seconds and photons:

    make run    # the main job's volumes (results/volumes/cumulus)
    .venv/bin/python experiments/noise_split/run.py 0.005,0.9 0.02,0.9 --lobes 0.7,0.2 0.9,0.2 0.9,0.5
    .venv/bin/python experiments/noise_split/run.py 0.005,0.9 --sky-order1-points 0   # the sky photons' order 1

``--settings`` takes variants of the ``precompute.all_orders`` keys as JSON (each with every lobe), ``--seeds``
repeats each run:

    .venv/bin/python experiments/noise_split/run.py 0.15,0.75 0.3,0.85 --seeds 1 2 \
        --settings '{}' '{"importance_floor": 0.02}'

Written to results/experiments/noise_split.json. Three routes that docs/stages/precompute.md measured and did not
keep are patches here (``git apply`` one, run, ``git apply -R`` it):

- ``lobe_per_point.patch`` ("Effort per source"): the lobe of each sky photon around the line from its starting
  point on the box's far faces to the camera;
- ``sky_entry_faces.patch`` ("Thick clouds: routes measured"): the sky photons' start points on the box's faces
  drawn by each face texel's importance (what a beam entering there along the inward normal scatters where the
  camera sees it), a share ``SKY_ENTRY`` (environment, e.g. 0.9) of it;
- ``sky_first_collisions.patch`` (the same section): a share ``SKY_FIRST`` of the sky photons starting at their
  first collision in the cells the camera sees (mean visibility at least ``SKY_FIRST_VIS``, default 0.01; a cell
  by its visible extinction, a point uniform in it, a dome direction and a shadow ray), the others ending where
  their first collision falls in those cells.
"""
import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from natscene.config import load_yaml_config, validate_config
from natscene.geometry import Camera, sun_direction
from natscene.phase import hg
from natscene.scatter.allorders import Lighting, Scene, settings_from_config, standard_error, view_images
from natscene.scatter.bands import band_weights, channel_weights
from natscene.scatter.medium import make_medium
from natscene.scatter.single import march_view
from natscene.scatter.transport.all_orders import skylight_dome, sky_luminance_weights
from natscene.sky.daylight import skylight
from natscene.volume.grid import load_volume

ROOT = Path(__file__).resolve().parents[2]
BETA = 0.99


def parts(vi, st, sky_w):
    """The halves of each part at BETA: sun orders >= 2, sky order 1, sky orders >= 2 (luminance)."""
    cs = band_weights(st.sun_bands, vi.sun_orders, BETA)[0]
    ck = channel_weights(st.sky_bands, vi.sky_orders, BETA)[0] * np.asarray(sky_w)[:, None]     # (4, B)
    out = {"sun_multiple": [np.tensordot(cs, vi.sun_halves[h], 1) for h in range(2)]}
    for name, sel in (("sky_order1", slice(0, 1)), ("sky_multiple", slice(1, None))):
        out[name] = [np.tensordot(ck[:, sel], vi.sky_halves[h][:, sel], 2) for h in range(2)]
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("nodes", nargs="+", help="extinction,g (1/m, HG g)")
    ap.add_argument("--lobes", nargs="+", default=["0.7,0.2"], help="sky lobe g,share")
    ap.add_argument("--settings", nargs="+", default=["{}"], help="JSON objects of precompute.all_orders keys")
    ap.add_argument("--seeds", nargs="+", type=int, default=None,
                    help="a run per seed, its shadow rays too (default: one run, seed 5, the shadow rays' seed 0)")
    ap.add_argument("--sky-order1-points", type=int, default=None,
                    help="precompute.all_orders.sky_order1_points (default: the config's; 0: the sky photons' order 1)")
    a = ap.parse_args()
    cfg = validate_config(load_yaml_config(ROOT / "config/config.yaml"), ROOT / "workflow/schemas/config.schema.yaml")
    pre, view = cfg["precompute"], cfg["views"]["kite"]
    volume = load_volume(ROOT / "results/volumes/cumulus")
    camera = Camera.from_view(view)
    med = make_medium(volume, sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"]))
    st0 = replace(settings_from_config(pre), noise_target=(0.0, 0.0))
    if a.sky_order1_points is not None:
        st0 = replace(st0, sky_order1_points=a.sky_order1_points)
    dome = skylight_dome(med.sun_dir, skylight(pre["skylight"], "precompute.skylight"))
    s_dir = np.asarray(med.sun_dir)
    sky_w = sky_luminance_weights(s_dir, dome)
    cos_q = camera.ray_directions() @ s_dir
    out = {}
    for node in a.nodes:
        e, g = (float(x) for x in node.split(","))
        sigma = e / volume.extinction_scale
        single = march_view(med, camera, [sigma], step_voxels=pre["step_voxels"], supersample=pre["supersample"],
                            rho_threshold=pre["rho_threshold"])
        foot = single["footprint"] > 0
        single_sun = BETA * hg(cos_q, g) * single["S_sun"][0]
        for lobe, over, seed in ((lb, ov, sd) for lb in a.lobes for ov in a.settings for sd in a.seeds or [None]):
            lg, share = (float(x) for x in lobe.split(","))
            over = json.loads(over)
            st = replace(st0, sky_lobe_g=lg, sky_lobe_share=share,
                         **{k: tuple(v) if isinstance(v, list) else v for k, v in over.items()})
            t0 = time.perf_counter()
            scene = Scene(volume, Lighting(s_dir, dome), st, shadow_seed=0 if seed is None else seed)
            vi = view_images(scene, camera, sigma, g, seed=5 if seed is None else seed)
            secs = time.perf_counter() - t0
            ps = parts(vi, st, sky_w)
            pixel = single_sun + sum((h[0] + h[1]) / 2 for h in ps.values())
            ok = foot & (pixel > 0)
            row = {"seconds": round(secs, 1), "stats": {k: v for k, v in vi.stats.items() if "photons" in k}}
            var = {}
            for name, (x, y) in ps.items():
                rel = (standard_error(x, y) / np.where(ok, pixel, 1.0))[ok]
                var[name] = float(np.mean(rel ** 2))
                row[name] = {"median": round(float(np.median(rel)), 4), "p95": round(float(np.percentile(rel, 95)), 4),
                             "share_of_pixel": round(float(((x + y) / 2)[ok].sum() / pixel[ok].sum()), 3)}
            tot = sum(var.values())
            for name in ps:
                row[name]["variance_share"] = round(var[name] / tot, 3)
                row[name]["variance"] = float(f"{var[name]:.4g}")
            row["single_share_of_pixel"] = round(float(single_sun[ok].sum() / pixel[ok].sum()), 3)
            key = f"{e:g}/m g {g:g} lobe {lg:g},{share:g}" + (f" {json.dumps(over)}" if over else "") + (
                f" seed {seed}" if seed is not None else "")
            out[key] = row
            print(f"{key}:", json.dumps(row), flush=True)
    dest = ROOT / "results/experiments/noise_split.json"
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    with np.errstate(divide="ignore", invalid="ignore"):
        main()
