"""Benchmark of the Mie shading (issue 10): point-cloud solve of the 194x122x194 cumulonimbus and one
640x480 frame, on the machine's cores. Targets: solve <= 60 s, frame <= 10 s (Reimschuessel reports
2-10 min per frame). Baselines in the same run: the thesis' all-pairs exchange (O(n²), timed on a
subset for one pass and extrapolated to n points and all passes) against the KD-tree neighbourhood
solve, and the Henyey-Greenstein frame (same marcher) against the Mie frame.

Usage: .venv/bin/python benchmarks/mie.py [volume_dir]   (default: results/volumes/cumulonimbus, built by
`snakemake results/volumes/cumulonimbus/density.vol`). Writes results/benchmarks/mie.json.
"""
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from natscene.geometry import sun_direction
from natscene.io import write_text
from natscene.mie.cameras import effect_camera
from natscene.mie.march import render_mie
from natscene.mie.phase import compute_mie_table, hg_table
from natscene.mie.points import generate_points
from natscene.mie.solver import solve
from natscene.volume.grid import load_volume


def all_pairs_pass_seconds(pts, table, n_sub=4000, seed=0):
    """One pass of the thesis' nested loops (vectorised per source row) over n_sub points."""
    rng = np.random.default_rng(seed)
    idx = rng.choice(len(pts.density), size=min(n_sub, len(pts.density)), replace=False)
    p, d, ci = pts.position[idx], pts.density[idx], pts.ci0[idx]
    L = -pts.sun_dir.astype(np.float32)
    co = np.zeros((len(idx), 3), np.float32)
    t = time.perf_counter()
    for i in range(len(idx)):
        delta = p - p[i]
        dist = np.linalg.norm(delta, axis=1) + 1e-12
        a_d = np.exp(-dist * (d + d[i]) * 0.5 * pts.sigma_e)
        a_m = table.a_m((delta @ L) / dist)
        co += (a_d[:, None] * a_m) * ci[i]
    return time.perf_counter() - t, len(idx)


def main():
    vdir = Path(sys.argv[1] if len(sys.argv) > 1 else "results/volumes/cumulonimbus")
    vol = load_volume(vdir)
    sun = sun_direction(130, 35)
    out = {"volume": str(vdir), "resolution": list(vol.resolution)}
    t = time.perf_counter()
    table = compute_mie_table(spectral_nm=())
    out["table_rgb_seconds"] = time.perf_counter() - t
    t = time.perf_counter()
    pts = generate_points(vol, sun, sigma_t=0.3, spacing_voxels=2.0)
    sol = solve(pts, table, passes=6)
    out["solve_seconds"] = time.perf_counter() - t
    out["points"] = int(len(pts.density))
    naive, n_sub = all_pairs_pass_seconds(pts, table)
    out["all_pairs_estimate_seconds"] = naive * (len(pts.density) / n_sub) ** 2 * 6
    out["solve_speedup_vs_all_pairs"] = out["all_pairs_estimate_seconds"] / out["solve_seconds"]
    cam = effect_camera("fogbow", vol, sun, resolution=(640, 480))
    cam2 = effect_camera("silver_lining", vol, sun, resolution=(640, 480))
    params = {"L_in": 6.0, "L_amb": 0.25, "sky_color": [0.25, 0.38, 0.62]}
    # JIT warm-up on a copy of the solution (its per-sun cache stays empty for the timed first frame)
    render_mie(vol, effect_camera("glory", vol, sun, resolution=(16, 12)), sun, replace(sol, cache={}), table, params)
    # first frame of this sun: builds the per-sun fields (brickmap, sun optical depth, cone LUT) and caches
    # them on the solution; later frames (any view or light colour, same sun) reuse them
    t = time.perf_counter()
    render_mie(vol, cam, sun, sol, table, params)
    out["frame_640x480_first_seconds"] = time.perf_counter() - t
    t = time.perf_counter()
    render_mie(vol, cam2, sun, sol, table, {**params, "c_in": [1.4, 0.9, 0.5]})
    out["frame_640x480_seconds"] = time.perf_counter() - t
    hg = hg_table(float(table.g[1]))
    sol_hg = solve(pts, hg, passes=6)
    render_mie(vol, cam, sun, sol_hg, hg, params)
    t = time.perf_counter()
    render_mie(vol, cam2, sun, sol_hg, hg, {**params, "c_in": [1.4, 0.9, 0.5]})
    out["frame_hg_seconds"] = time.perf_counter() - t
    out["frame_mie_over_hg"] = out["frame_640x480_seconds"] / out["frame_hg_seconds"]
    out["targets"] = {"solve_seconds": 60, "frame_seconds": 10, "thesis_frame_seconds": [120, 600]}
    Path("results/benchmarks").mkdir(parents=True, exist_ok=True)
    write_text("results/benchmarks/mie.json", json.dumps(out, indent=2))
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
