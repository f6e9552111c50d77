"""How a shot frame's noise and time follow its collision budgets: the split between the sun and the sky, and a
reduced budget with and without the denoiser.

A question for issue 39's frame target (1 % in 20 s): would a per-frame split of the budget between the sun's and
the sky's photons (each source's collisions in proportion to the square root of its variance per collision, as
the precompute's top-ups split theirs) lower the noise at the same time? The benchmark's thick day frame
(``benchmarks/transport_version.py``: the ``day_to_sunset`` shot's first camera, the cumulonimbus at 0.0243 /m,
its parameters, the sun at azimuth 120 and elevation 30, 640x480) is rendered with seeds 0 and 1 for each set of
``render:`` overrides given as JSON; per set it prints the seconds of each frame and the noise figure
(:func:`natscene.denoise.noise.noise_figure`) before and after OIDN:

    make run    # the main job's volumes (results/volumes/cumulonimbus)
    .venv/bin/python experiments/frame_budget/run.py '{}' '{"sun_collisions": 62000000}' \
        '{"sky_collisions": 46000000}' '{"sun_collisions": 7750000, "sky_collisions": 5750000}'

With noise figures N_0 (the defaults), N_sun (the sun's collisions doubled) and N_sky (the sky's doubled), the
sun's share of the variance at the defaults is 2 (N_0² - N_sun²) / N_0² and the sky's 2 (N_0² - N_sky²) / N_0².
``--all-orders JSON`` sets transport settings that a shot's ``render:`` section does not hold (the fields of
:class:`natscene.scatter.allorders.AllOrdersSettings`, e.g. ``'{"importance_floor": 0.02}'``) on top of the frame's
(:func:`natscene.scatter.allorders.frame_settings`), for every set of overrides.

Each row also holds the two frames' mean pixel by opacity band (0.1-0.5, 0.5-0.9, 0.9-0.99, above): a setting's
bias at the thin edges shows as a shift of the thin bands against the defaults' (the opaque bands stay put).
``sky_coarse_cells.patch`` (``git apply`` it; ``SKYC=4`` in the environment) puts the sky's orders >= 2 in cells of
4 voxels while the sun keeps the shot's cells:

    SKYC=4 .venv/bin/python experiments/frame_budget/run.py '{}'

Written to results/experiments/frame_budget.json.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))

from natscene.config import load_yaml_config, validate_config  # noqa: E402
from natscene.denoise.noise import cloud_pixels, noise_figure  # noqa: E402
from natscene.denoise.oidn import OIDN  # noqa: E402
from natscene.geometry import sun_direction  # noqa: E402
from natscene.keyframes.frame import render_shot_frame  # noqa: E402
from natscene.scatter.reference_scene import OPACITY_BANDS  # noqa: E402
from natscene.variant import select_variant  # noqa: E402
from natscene.volume.grid import load_volume  # noqa: E402
from transport_version import FRAME_PARAMS  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("overrides", nargs="+", help="JSON objects of shots.day_to_sunset.render keys")
    ap.add_argument("--extinction", type=float, default=0.0243, help="the cloud's extinction, 1/m")
    ap.add_argument("--results", default=str(ROOT / "results"))
    ap.add_argument("--all-orders", default="{}", help="JSON of AllOrdersSettings fields set on every frame")
    a = ap.parse_args()
    extra = json.loads(a.all_orders)
    if extra:      # the frames' settings come from frame_settings(render): set these fields on what it returns
        from dataclasses import replace

        import natscene.scatter.allorders as allorders
        plain = allorders.frame_settings
        allorders.frame_settings = lambda render: replace(plain(render), **extra)
    select_variant(threads=2)
    cfg = load_yaml_config(ROOT / "config" / "config.yaml")
    validate_config(cfg, ROOT / "workflow" / "schemas" / "config.schema.yaml")
    day = cfg["shots"]["day_to_sunset"]
    vol_dir = Path(a.results) / "volumes" / day["volume"]
    if not (vol_dir / "meta.yaml").exists():
        raise SystemExit(f"{vol_dir}: no volume; run make run first (it makes results/volumes/{day['volume']})")
    cloud = load_volume(vol_dir)
    cam = {"up": [0, 1, 0], **day["keyframes"][0]["camera"]}
    state = {"params": {**FRAME_PARAMS, "extinction": a.extinction}, "camera": cam,
             "sun": {"direction": sun_direction(120.0, 30.0).tolist(), "azimuth": 120.0, "elevation": 30.0}}
    oidn = OIDN(key="frame_budget", threads=2)
    shot = {**day, "phase": "hg", "denoise": "oidn"}
    render_shot_frame(cloud, state, {**shot, "resolution": [32, 24], "render": {**shot["render"], "spp": 1}},
                      denoiser=oidn)                                              # compile the kernels once
    rows = []
    for text in a.overrides:
        over = json.loads(text)
        frames, seconds = [], []
        for seed in (0, 1):
            t0 = time.perf_counter()
            frames.append(render_shot_frame(cloud, state, {**shot, "resolution": [640, 480],
                                                           "render": {**shot["render"], **over, "seed": seed}},
                                            denoiser=oidn))
            seconds.append(round(time.perf_counter() - t0, 2))
        opacity = frames[0]["features"]["opacity"]
        pix = cloud_pixels(opacity)
        mean = np.mean([f["raw"] for f in frames], axis=0).mean(-1)
        row = {"render": over, "seconds": seconds,
               "noise_figure_raw": round(noise_figure(frames[0]["raw"], frames[1]["raw"], pix), 5),
               "noise_figure_denoised": round(noise_figure(frames[0]["final"], frames[1]["final"], pix), 5),
               # the two frames' mean pixel (R, G, B averaged) by opacity band: a setting's bias at the thin edges
               "mean_by_opacity": {f"{lo}-{min(hi, 1)}": round(float(mean[(opacity >= lo) & (opacity < hi)].mean()), 5)
                                   for lo, hi in OPACITY_BANDS}}
        print(json.dumps(row), flush=True)
        rows.append(row)
    out = Path(a.results) / "experiments" / "frame_budget.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"extinction_per_m": a.extinction, "all_orders": extra, "rows": rows}, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
