"""Benchmark: precompute of a 194x122x194 volume at 320x240, n_m = 4, 11 sigma_t x 10 g (Dobashi: 21 min
on a 2011 GPU; target <= 5 min on 2 CPU cores), with the relative standard error of each order per cloud
pixel, table sizes, and render at 640x480 (orders <= 4; Dobashi ~30 s; target <= 10 s). Baseline in the
same run: Mitsuba volpath at the same resolution / orders / spp for ONE (sigma_t, g) (what a per-g,
per-sigma_t approach would pay 110 times). Writes results/benchmarks/precompute.json.
Usage: python benchmarks/precompute.py [volume_dir] [spp]   (default: a synthetic 194x122x194 cloud)."""
import sys
import time

import numpy as np

from _common import write_result

import natscene  # noqa: F401
from natscene.geometry import Camera, sun_direction
from natscene.scatter.mitsuba_scene import render_reference
from natscene.scatter.render import render
from natscene.scatter.tables import precompute, save_tables
from natscene.volume.grid import Volume, load_volume, placement


def synthetic():
    nx, ny, nz = 194, 122, 194
    lo, hi = placement((nx, ny, nz))
    r = np.random.default_rng(0)
    z, y, x = np.meshgrid(np.linspace(-1, 1, nz), np.linspace(0, 1, ny), np.linspace(-1, 1, nx), indexing="ij")
    d = np.zeros((nz, ny, nx), np.float32)
    for _ in range(12):
        c = r.uniform([-0.5, 0.3, -0.5], [0.5, 0.6, 0.5]); rad = r.uniform(0.2, 0.4)
        d += np.clip(1 - ((x - c[0]) ** 2 + ((y - c[1]) / 0.6) ** 2 + (z - c[2]) ** 2) / rad ** 2, 0, 1)
    return Volume(np.clip(d, 0, 1).astype(np.float32), lo, hi, 150.0)


def main():
    vol = load_volume(sys.argv[1]) if len(sys.argv) > 1 else synthetic()
    spp = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    cam = Camera((0.0, 0.25, -2.4), (0.0, 0.3, 0.0), (0.0, 1.0, 0.0), fov=36, width=320, height=240)
    sun = sun_direction(130, 35)
    t = time.perf_counter()
    tb = precompute(vol, cam, sun, n_m=4, spp=spp, log=print)
    t_pre = time.perf_counter() - t
    meta = save_tables("results/benchmarks/precompute_tables", tb)
    t = time.perf_counter()
    render_reference(vol, cam, sun, 0.5, 0.5, 0.9, orders=4, spp=spp)
    t_ref = time.perf_counter() - t
    cam2 = Camera(cam.position, cam.look_at, cam.up, fov=36, width=640, height=480)
    p = dict(c_in=[1, 1, 1], L_in=5.0, g=0.5, sigma_t=0.5, beta=0.9, L_amb=0.1, kappa_a=[0.1] * 3)
    t = time.perf_counter()
    render(vol, cam2, sun, p, np.zeros(3, np.float32), {"orders": 4, "spp": 32})
    t_render = time.perf_counter() - t
    res = {"precompute_s": t_pre, "timings": tb.meta["timings"], "spp": spp,
           "volpath_one_param_set_s": t_ref, "ratio_precompute_vs_110_volpath": t_pre / (110 * t_ref),
           "relative_standard_error": tb.meta.get("relative_standard_error"),
           "pixel_relative_standard_error": tb.meta.get("pixel_relative_standard_error"),
           "traced_pixels": tb.meta.get("traced_pixels"), "footprint_pixels": tb.meta.get("footprint_pixels"),
           "tables_memory_MB": tb.nbytes() / 1e6, "tables_disk_MB": sum(meta["files_bytes"].values()) / 1e6,
           "render_640x480_s": t_render, "render_spp": 32, "targets": {"precompute_s": 300, "render_s": 10}}
    write_result("precompute", res)


if __name__ == "__main__":
    main()
