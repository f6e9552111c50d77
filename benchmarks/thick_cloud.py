"""Equal-error comparison with Mitsuba 3 ``volpath`` on the thick cumulonimbus (issue 39, item 5).

The scene is tools/thick_references.py's ``cb_day``: the main job's cumulonimbus from the first camera of the
``day_to_sunset`` shot at 160x120, the day sun (azimuth 120, elevation 30), the kite fit's droplets at
extinction 0.0244 /m (optical depth up to about 120 through the core), g 0.70, beta 0.9999, sun only. The
converged reference is the stored GPU render (tests/data/transport_volpath_thick.npz, about 190k spp; its
two halves give its own noise, which is taken out of every error below in quadrature).

In one run on this machine:

- natscene's forward renderer (``render``) at the shot's settings (config ``shots.day_to_sunset.render``:
  the all-orders transport's default caches and budgets) and, beside it, at cache cells of one voxel: the wall
  time and the relative RMSE against the reference over the cloud's pixels (opacity > 0.1), per pixel and for
  8x8-block means, and the ratio to the reference in the opacity bands 0.1-0.5, 0.5-0.9, 0.9-0.99, > 0.99
  (its bias by band, averaged over ``--seeds`` runs);
- with ``--baseline DIR`` (a checkout of an older version, e.g. ``git worktree add /tmp/base 9c1d408``): that
  version's forward renderer on the same volume, view and droplets (its unitless sigma_t = extinction /
  extinction_scale) at its own shot settings, run in a subprocess on its own code: the same figures;
- ``volpath`` (every order, llvm variant, the same threads) at a few sample counts: time and the same errors;
  the time it needs to reach natscene's error is extrapolated from its own runs (error ~ 1/sqrt(spp), fitted
  over the runs), per pixel and for block means. The speed-up is that time over natscene's.

Writes results/benchmarks/thick_cloud.json.   nice .venv/bin/python benchmarks/thick_cloud.py
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _common import ROOT, write_result

import natscene  # noqa: F401
from natscene.config import load_yaml_config
from natscene.geometry import Camera
from natscene.scatter.reference_scene import band_ratios

REFS = ROOT / "tests" / "data" / "transport_volpath_thick.npz"


def scene():
    from natscene.scatter.medium import make_medium
    from natscene.scatter.single import march_view
    from natscene.volume.build import build_volume
    cfg = load_yaml_config(ROOT / "config" / "config.yaml")
    vol, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    with np.load(REFS) as z:
        c = z["cb_day.camera"]
        cam = Camera(tuple(c[0:3]), tuple(c[3:6]), tuple(c[6:9]), float(c[9]), int(c[10]), int(c[11]))
        sun, (sigma, g, beta) = z["cb_day.sun"], z["cb_day.params"]
        a, b = z["cb_day.half_a"].astype(np.float64), z["cb_day.half_b"].astype(np.float64)
    opacity = 1 - march_view(make_medium(vol), cam, [float(sigma)])["T"][0]
    return cfg, vol, cam, sun, float(sigma), float(g), float(beta), a, b, opacity


def block_means(img, mask, size=8):
    H, W = img.shape
    out = []
    for i in range(0, H - size + 1, size):
        for j in range(0, W - size + 1, size):
            if mask[i:i + size, j:j + size].mean() >= 0.5:
                out.append(img[i:i + size, j:j + size].mean())
    return np.array(out)


def errors(img, ref, ref_noise, mask) -> dict:
    """Relative RMSE over the cloud per pixel and of the 8x8-block means, the reference's own noise taken out."""
    m = ref[mask].mean()
    pix = np.mean((img[mask] - ref[mask]) ** 2) - ref_noise["pixel"] ** 2
    blk = np.mean((block_means(img, mask) - block_means(ref, mask)) ** 2) - ref_noise["block"] ** 2
    return {"pixel": float(np.sqrt(max(pix, 0.0)) / m), "block": float(np.sqrt(max(blk, 0.0)) / m),
            "mean_ratio": float(img[mask].mean() / m)}


BASELINE_SCRIPT = """
import json, sys, time
import numpy as np
import natscene
assert natscene.__file__.startswith(json.loads(sys.argv[1])["root"]), natscene.__file__
from natscene.config import load_yaml_config
from natscene.geometry import Camera
from natscene.scatter.render import render
from natscene.variant import select_variant
from natscene.volume.grid import Volume
select_variant(threads=2)
a = json.loads(sys.argv[1])
z = np.load(a["scene"])
vol = Volume(z["density"], z["lo"], z["hi"], float(z["scale"]))
c = z["camera"]
cam = Camera(tuple(c[0:3]), tuple(c[3:6]), tuple(c[6:9]), float(c[9]), int(c[10]), int(c[11]))
shot = dict(load_yaml_config(a["root"] + "/config/config.yaml")["shots"]["day_to_sunset"]["render"])
p = dict(c_in=[1.0] * 3, L_in=1.0, g=a["g"], sigma_t=a["sigma"], beta=a["beta"], kappa_a=[0.0] * 3,
         sky_scale=[0.0] * 3, ground_albedo=0.0)
import inspect
if "settings" in inspect.signature(render).parameters:   # render(..., settings): the shot's render section
    go = lambda seed, **over: render(vol, cam, z["sun"], p, np.zeros(3, np.float32), {**shot, **over, "seed": seed},
                                     skylight=False)
else:                                                   # older versions: the settings as keywords
    go = lambda seed, **over: render(vol, cam, z["sun"], p, np.zeros(3, np.float32), seed=seed, skylight=False,
                                     **{**shot, **over})
go(0, spp=1)
out = {}
for seed in range(a["seeds"]):
    t0 = time.perf_counter()
    img = go(seed)[..., 0]
    out[f"img{seed}"] = img
    out[f"t{seed}"] = time.perf_counter() - t0
np.savez(a["out"], **out)
"""


def baseline_runs(base: Path, vol, cam, sun, sigma, g, beta, seeds: int) -> list:
    """(seconds, image) of the baseline version's forward renderer, run on its own code in a subprocess."""
    with tempfile.TemporaryDirectory() as tmp:
        scene_f, out_f = Path(tmp, "scene.npz"), Path(tmp, "out.npz")
        np.savez(scene_f, density=np.asarray(vol.density, np.float32), lo=vol.bbox_min, hi=vol.bbox_max,
                 scale=vol.extinction_scale, sun=np.asarray(sun, np.float64),
                 camera=np.array([*cam.position, *cam.look_at, *cam.up, cam.fov, cam.width, cam.height]))
        arg = json.dumps({"scene": str(scene_f), "out": str(out_f), "root": str(base), "g": g, "beta": beta,
                          "sigma": sigma, "seeds": seeds})
        subprocess.run([sys.executable, "-c", BASELINE_SCRIPT, arg], check=True,
                       env={**os.environ, "PYTHONPATH": str(base / "src")})
        with np.load(out_f) as z:
            return [(float(z[f"t{s}"]), z[f"img{s}"].astype(np.float64)) for s in range(seeds)]


def summary(runs: list, ref, ref_noise, mask, opacity) -> dict:
    rows = [{"seconds": t, **errors(img, ref, ref_noise, mask), "bands": band_ratios(img, ref, opacity)}
            for t, img in runs]
    return {"seconds": float(np.mean([r["seconds"] for r in rows])),
            "pixel_rmse": float(np.mean([r["pixel"] for r in rows])),
            "block_rmse": float(np.mean([r["block"] for r in rows])),
            "mean_ratio": float(np.mean([r["mean_ratio"] for r in rows])),
            "bands": {k: float(np.mean([r["bands"][k] for r in rows])) for k in rows[0]["bands"]}}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=2, help="natscene runs per setting")
    ap.add_argument("--volpath-spp", type=int, nargs="+", default=[16, 64])
    ap.add_argument("--baseline", type=Path, help="checkout of the version to compare with (its src/ and config/)")
    a = ap.parse_args()
    from dataclasses import replace

    from natscene.scatter.allorders import frame_settings
    from natscene.scatter.mitsuba_scene import render_reference
    from natscene.scatter.render import render
    from natscene.variant import select_variant
    variant = select_variant(threads=2)
    cfg, vol, cam, sun, sigma, g, beta, ha, hb, opacity = scene()
    ref = (ha + hb) / 2
    mask = opacity > 0.1
    # the mean of two independent halves: its noise is |a - b| / 2 per pixel (in quadrature over the pixels)
    ref_noise = {"pixel": float(np.sqrt(np.mean((ha[mask] - hb[mask]) ** 2)) / 2),
                 "block": float(np.sqrt(np.mean((block_means(ha, mask) - block_means(hb, mask)) ** 2)) / 2)}
    p = dict(c_in=[1.0] * 3, L_in=1.0, g=g, extinction=sigma * vol.extinction_scale, beta=beta, kappa_a=[0.0] * 3,
             sky_scale=[0.0] * 3, ground_albedo=0.0)
    shot = dict(cfg["shots"]["day_to_sunset"]["render"])
    res = {"variant": variant, "scene": "cb_day (tools/thick_references.py), 160x120, sun only",
           "extinction_per_m": sigma * vol.extinction_scale, "g": g, "beta": beta,
           "cloud_pixels": int(mask.sum()),
           "reference_spp": int(np.load(REFS)["cb_day.spp"].sum()),
           "reference_noise_relative": {k: v / ref[mask].mean() for k, v in ref_noise.items()}}
    render(vol, cam, sun, p, np.zeros(3, np.float32), {**shot, "seed": 0, "spp": 1}, skylight=False)   # compile
    runs = {}
    shot_st = frame_settings(shot)
    for name, st in (("shot_settings", shot_st), ("cells_1_voxel", replace(shot_st, fine_voxels=1, coarse_voxels=1))):
        runs[name] = []
        for seed in range(a.seeds):
            t0 = time.perf_counter()
            img = render(vol, cam, sun, p, np.zeros(3, np.float32), {**shot, "seed": seed}, skylight=False,
                         all_orders=st)[..., 0]
            runs[name].append((time.perf_counter() - t0, img.astype(np.float64)))
        res[f"natscene_{name}"] = summary(runs[name], ref, ref_noise, mask, opacity)
        print(name, res[f"natscene_{name}"], flush=True)
    if a.baseline:
        runs["baseline"] = baseline_runs(a.baseline, vol, cam, sun, sigma, g, beta, a.seeds)
        res["natscene_baseline"] = {"version": str(a.baseline),
                                    **summary(runs["baseline"], ref, ref_noise, mask, opacity)}
        print("baseline", res["natscene_baseline"], flush=True)
    vp = []
    for spp in a.volpath_spp:
        t0 = time.perf_counter()
        img = render_reference(vol, cam, sun, sigma, g, beta, orders=100_000, spp=spp, seed=99)[..., 0]
        dt = time.perf_counter() - t0
        vp.append({"spp": spp, "seconds": dt, **errors(img.astype(np.float64), ref, ref_noise, mask)})
        print("volpath", vp[-1], flush=True)
    res["volpath"] = vp
    # error^2 * time is constant for an unbiased Monte Carlo renderer: fit it over the runs (seconds per unit of
    # 1/error^2), then the time to reach natscene's error
    for name in runs:
        ns = res[f"natscene_{name}"]
        for kind in ("pixel", "block"):
            c = float(np.median([r["seconds"] * r[kind] ** 2 for r in vp]))
            need = c / ns[f"{kind}_rmse"] ** 2
            ns[f"volpath_seconds_to_equal_{kind}_error"] = need
            ns[f"speedup_equal_{kind}_error"] = need / ns["seconds"]
    write_result("thick_cloud", res)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
