"""The main job's transport figures of one version of natscene, measured on that version's own code (issue 39,
item 5: every figure of benchmarks/transport.py beside the code of 9c1d408, run in the same benchmark).

Run by ``benchmarks/transport.py --baseline DIR`` once for this checkout and once for DIR, each in a subprocess
whose ``PYTHONPATH`` is that version's ``src/`` (this file imports nothing of the benchmark's own directory, so
the version's code is the one measured). On the version's own ``config/config.yaml``:

- ``precompute_s``, ``noise``: the main job's precompute (volume ``cumulus``, view ``kite``, the version's
  extinction / sigma_t and g grid, its all-orders settings and noise target) and its own noise estimate
  (``meta.yaml``'s ``pixel_relative_standard_error``), the nodes' budget scales;
- ``ga_iteration_ms``: one GA iteration of the kite fit on those tables (30 iterations of 20 candidates after a
  warm-up iteration, as benchmarks/transport.py measures it);
- ``frame_640x480``: the first frame of the ``day_to_sunset`` shot at 640x480 (the version's shot render
  settings, the Preetham sky, OIDN) at the thick cloud's extinction in 1/m (``--extinction``; a unitless version
  is given sigma_t = extinction / the volume's ``extinction_scale``, the same cloud), rendered with seeds 0 and 1:
  the seconds of the seed-0 frame and the noise figure (natscene.denoise.noise.noise_figure) before and after the
  denoiser.

Usage (normally through benchmarks/transport.py):
    PYTHONPATH=DIR/src python benchmarks/transport_version.py --root DIR --out figures.json --extinction 0.0243
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

# the kite fit of the main job (benchmarks/shots.py's PARAMS) but for its extinction, given on the command line
FRAME_PARAMS = {"L_in": 6.35, "g": 0.698, "beta": 0.9998, "L_amb": 0.0, "kappa_a": [0.0, 0.1, 0.6],
                "c_in": [0.971, 1.002, 1.065]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", type=Path, required=True, help="the version's checkout (its src/ must be on PYTHONPATH)")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--extinction", type=float, required=True, help="the shot frame's cloud extinction, 1/m")
    a = ap.parse_args()
    root = a.root.resolve()

    import natscene
    if not Path(natscene.__file__).resolve().is_relative_to(root):
        raise SystemExit(f"natscene is imported from {natscene.__file__}, not from {root}: set PYTHONPATH")
    from natscene.config import load_yaml_config, resolve_path, validate_config
    from natscene.denoise.noise import cloud_pixels, noise_figure
    from natscene.denoise.oidn import OIDN
    from natscene.fit.keyframe import fit_keyframe
    from natscene.geometry import Camera, sun_direction
    from natscene.io import read_photo
    from natscene.keyframes.frame import render_shot_frame
    from natscene.scatter.allorders import settings_from_config
    from natscene.scatter.tables import precompute
    from natscene.sky.extract import extract_sky
    from natscene.sky.resample import area_resample, resample_labels
    from natscene.variant import select_variant
    from natscene.volume.build import build_volume

    select_variant(threads=2)
    cfg = load_yaml_config(root / "config" / "config.yaml")
    validate_config(cfg, root / "workflow" / "schemas" / "config.schema.yaml")
    pre = cfg["precompute"]
    physical = "extinction" in pre                      # 1/m nodes (issue 39) or unitless sigma_t (before it)
    view = cfg["views"]["kite"]
    camera = Camera.from_view(view)
    sun = sun_direction(view["sun"]["azimuth"], view["sun"]["elevation"])
    vol, _ = build_volume(cfg["volumes"]["cumulus"], "cumulus")
    out = {"version": str(root), "physical_units": physical}

    # --- the main job's precompute
    grid = {"extinctions": pre["extinction"]} if physical else {"sigmas": pre["sigma_t"]}
    t0 = time.perf_counter()
    tables = precompute(vol, camera, sun, gs=pre["g"], n_m=pre["n_m"], spp=pre["spp"], seed=pre["seed"],
                        step_voxels=pre["step_voxels"], supersample=pre["supersample"], transport="all_orders",
                        all_orders=settings_from_config(pre), skylight=pre.get("skylight"), log=print, **grid)
    out["precompute_s"] = round(time.perf_counter() - t0, 1)
    meta = tables.meta
    out["grid"] = {"extinction" if physical else "sigma_t": grid[next(iter(grid))], "g": pre["g"]}
    out["noise"] = meta["pixel_relative_standard_error"]
    scales = [float(v) for v in meta.get("budget_scale", [])]       # one per photon node
    if scales:
        cap = float(pre["all_orders"].get("max_budget_scale", 8))
        out["budget_scale"] = {"nodes": len(scales), "mean": round(float(np.mean(scales)), 2),
                               "at_cap": int(sum(s >= cap - 1e-6 for s in scales))}
    print("precompute:", out["precompute_s"], "s", flush=True)

    # --- one GA iteration of the kite fit on those tables
    res = extract_sky(read_photo(resolve_path(cfg["photos"]["kite"]["path"], root)))
    w, h = camera.width, camera.height
    photo, sky = area_resample(res.photo, w, h), area_resample(res.sky, w, h)
    cloud = resample_labels(res.labels.astype(np.float32), w, h) == 1
    c_in = np.asarray(res.sun.c_in)
    fit_settings = dict(cfg["fit"], n_max=30, epsilon_O=0.0, n_suc=0)
    fit_keyframe(tables, photo, cloud, sky, c_in, dict(fit_settings, n_max=1), seed=0)     # warm-up
    t0 = time.perf_counter()
    fit = fit_keyframe(tables, photo, cloud, sky, c_in, fit_settings, seed=0)
    out["ga_iteration_ms"] = round(1000 * (time.perf_counter() - t0) / (fit["result"].iterations + 1), 2)
    out["fit_O"] = round(float(fit["result"].best.objective), 4)
    print("GA iteration:", out["ga_iteration_ms"], "ms", flush=True)
    del tables

    # --- the day_to_sunset shot's first frame, 640x480, at the thick cloud's extinction
    day = cfg["shots"]["day_to_sunset"]
    cb, _ = build_volume(cfg["volumes"]["cumulonimbus"], "cumulonimbus")
    params = dict(FRAME_PARAMS)
    if physical:
        params["extinction"] = a.extinction
    else:
        params["sigma_t"] = a.extinction / float(cb.extinction_scale)
    cam = dict(day["keyframes"][0]["camera"])
    cam.setdefault("up", [0, 1, 0])
    state = {"params": params, "camera": cam,
             "sun": {"direction": sun_direction(120.0, 30.0).tolist(), "azimuth": 120.0, "elevation": 30.0}}
    oidn = OIDN(key="benchmark", threads=2)
    shot = {**day, "phase": "hg", "denoise": "oidn"}
    render_shot_frame(cb, state, {**shot, "resolution": [32, 24], "render": {**shot["render"], "spp": 1}},
                      denoiser=oidn)                                              # compile the kernels once
    frames, seconds = [], None
    for seed in (0, 1):
        t0 = time.perf_counter()
        frames.append(render_shot_frame(cb, state, {**shot, "resolution": [640, 480],
                                                    "render": {**shot["render"], "seed": seed}}, denoiser=oidn))
        seconds = seconds or round(time.perf_counter() - t0, 2)
    pix = cloud_pixels(frames[0]["features"]["opacity"])
    out["frame_640x480"] = {
        "extinction_per_m": a.extinction, "params": params, "seconds": seconds, "cloud_pixels": int(pix.sum()),
        "noise_figure_raw": round(float(noise_figure(frames[0]["raw"], frames[1]["raw"], pix)), 4),
        "noise_figure_denoised": round(float(noise_figure(frames[0]["final"], frames[1]["final"], pix)), 4)}
    print("frame:", out["frame_640x480"], flush=True)
    a.out.write_text(json.dumps(out, indent=2, default=float))


if __name__ == "__main__":
    main()
