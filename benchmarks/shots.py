"""Benchmark: one frame of the main shot (cumulonimbus 194x122x194, 640x480, 16 spp, orders up to 4, the kite
fit's parameters at keyframe 0) with the forward renderer, against a baseline in the same run: the same frame
with single scattering only (orders = 1: sun optical-depth volume + ray march, no path tracing), so the ratio
is the cost of multiple scattering. Also the per-frame interpolation and the Preetham sky, and the shot time
extrapolated to the main job's 24 frames.

Usage: .venv/bin/python benchmarks/shots.py [--volume results/volumes/cumulonimbus] [--repeat 1]
(the volume is generated from the main config's spec when the directory does not exist).
"""
import argparse
import time
from pathlib import Path

import numpy as np

from _common import ROOT, best_of, write_result
from natscene.config import load_yaml_config
from natscene.geometry import Camera, sun_direction
from natscene.keyframes.shot import frame_state
from natscene.keyframes.sky import sky_image
from natscene.scatter.render import render
from natscene.variant import select_variant
from natscene.volume.grid import load_volume

PARAMS = {"L_in": 9.94, "g": 0.229, "sigma_t": 0.551, "beta": 0.966, "L_amb": 0.643,
          "kappa_a": np.array([0.2, 0.2, 0.5]), "c_in": np.array([0.97, 1.0, 1.06])}  # the kite fit
CAM = {"position": [0.15, 0.25, -1.45], "look_at": [0.0, 0.32, 0.0], "up": [0, 1, 0], "fov": 38}  # the kite view


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--volume", default=str(ROOT / "results" / "volumes" / "cumulonimbus"))
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--orders", type=int, default=4)
    a = ap.parse_args()
    variant = select_variant(threads=2)
    if Path(a.volume, "density.vol").is_file():
        vol = load_volume(a.volume)
    else:
        from natscene.volume.build import build_volume

        spec = load_yaml_config(ROOT / "config" / "config.yaml")["volumes"]["cumulonimbus"]
        vol, _ = build_volume(spec, "cumulonimbus")
    cam = Camera(tuple(CAM["position"]), tuple(CAM["look_at"]), fov=CAM["fov"], width=640, height=480)
    sun = sun_direction(120, 30)
    sky = sky_image(cam, sun, {"model": "preetham"})
    render(vol, Camera(cam.position, cam.look_at, fov=38, width=32, height=24), sun, PARAMS, sky[:24, :32],
           orders=2, spp=1)  # compile kernels once
    t_full = best_of(lambda: render(vol, cam, sun, PARAMS, sky, orders=a.orders, spp=a.spp, seed=0), a.repeat)
    t_single = best_of(lambda: render(vol, cam, sun, PARAMS, sky, orders=1, spp=1, seed=0), a.repeat)
    t_sky = best_of(lambda: sky_image(cam, sun, {"model": "preetham"}), 3)
    keys = [{"at": 0, "params": {**PARAMS, "kappa_a": [0.2, 0.2, 0.5], "c_in": [0.97, 1.0, 1.06]},
             "sun": {"azimuth": 120, "elevation": 30}, "camera": CAM},
            {"at": 23, "params": {**PARAMS, "L_in": 4.5, "kappa_a": [0.05, 0.12, 0.25], "c_in": [1.45, 0.92, 0.48]},
             "sun": {"azimuth": 100, "elevation": 3}, "camera": {**CAM, "position": [0.42, 0.22, -1.5]}}]
    t0 = time.perf_counter()
    for f in range(24):
        frame_state(f, keys)
    t_interp = (time.perf_counter() - t0) / 24
    write_result("shots", {
        "variant": variant, "resolution": [640, 480], "spp": a.spp, "orders": a.orders,
        "seconds_frame": round(t_full, 2),
        "baseline_seconds_single_scattering_frame": round(t_single, 2),
        "ratio_to_baseline": round(t_full / t_single, 2),
        "seconds_preetham_sky_640x480": round(t_sky, 4),
        "seconds_interpolate_per_frame": round(t_interp, 6),
        "extrapolated_minutes_24_frames_serial": round(24 * t_full / 60, 1),
        "target_minutes_main_job": 30,
    })


if __name__ == "__main__":
    main()
