"""Benchmark of the tiles stage (Dong 2007 Ch. 5): GA sample-patch selection for N2 on a 128x128 example
with 80x80 tiles (Table 5.1: 18-43 s on a 2007 PC; target <= 5 s on 2 cores), against a baseline in the
same run (one brute-force Eq. 5.1 evaluation of a chromosome by sliding windows, no caching); and the
throughput of tiling a 4096x4096 texture (target >= 50 Mpixel/s) against a per-tile Python copy loop;
and the junction removal of the 36 tiles (graph-cut merges, §5.2) with the default refinement against the
single best-matching-patch merge of Dong's construction (candidates=1, passes=1), with the seam energies.
Writes results/benchmarks/tiles.json."""
import sys
import time
from pathlib import Path

import numpy as np

from _common import write_result

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from natscene.color import linear_to_srgb  # noqa: E402
from natscene.config import default_settings  # noqa: E402
from natscene.io import read_photo  # noqa: E402
from natscene.tiles.construct import candidate_patches, intermediate_tiles  # noqa: E402
from natscene.tiles.tile_ga import MatchCost  # noqa: E402
from natscene.tiles.graphcut import build_tile, intermediate_offsets  # noqa: E402
from natscene.tiles.tile_ga import GAParams, run_tile_ga  # noqa: E402
from natscene.tiles.omega import tile_set  # noqa: E402
from natscene.tiles.scanline import gather_texture, scanline_tiling, tiles_for  # noqa: E402


def main():
    ex = linear_to_srgb(read_photo(ROOT / "resources/textures/grass_meadow_128.png"))
    ts = tile_set("N2")
    t0 = time.perf_counter()
    r = run_tile_ga(ex, ts, 80, default_settings(GAParams), seed=0)
    ga_s = time.perf_counter() - t0
    # baseline: brute-force evaluation of one chromosome (Eq. 5.1 over all translations)
    from numpy.lib.stride_tricks import sliding_window_view
    t0 = time.perf_counter()
    tiles = intermediate_tiles(ex, r.genes, ts, 80)
    win = sliding_window_view(ex, (80, 80), axis=(0, 1)).transpose(0, 1, 3, 4, 2)
    D = [((win - t) ** 2).sum((2, 3, 4)).min() for t in tiles]
    brute_eval_s = time.perf_counter() - t0
    assert np.allclose(D, r.D, rtol=1e-6)

    # junction removal: default refinement vs the single merge
    cost = MatchCost(ex, 80)
    seams = {}
    for label, k, passes in (("single_merge", 1, 1), ("refined", 8, 3)):
        t0 = time.perf_counter()
        energy = 0.0
        for j in range(ts.m):
            off0 = intermediate_offsets(r.genes, ts.tiles[j], 80)
            best = [tuple(int(v) for v in r.matches[j])]
            quarters = list(dict.fromkeys(tuple(int(v) for v in off0[y, x])
                                          for y, x in ((0, 0), (0, 79), (79, 0), (79, 79))))
            more = [c for c in candidate_patches(cost, r.genes, ts, j, k) if c != best[0]][:k - 1]
            cands = best if k == 1 else best + quarters + more
            energy += build_tile(ex, off0, cands, 1.0, 2.0, 0.0, passes, 3.0)[2]
        seams[label] = {"seconds": time.perf_counter() - t0, "seam_energy": energy}
    seams["energy_ratio_refined_vs_single"] = seams["refined"]["seam_energy"] / seams["single_merge"]["seam_energy"]
    seams["time_ratio_refined_vs_single"] = seams["refined"]["seconds"] / seams["single_merge"]["seconds"]

    rng = np.random.default_rng(0)
    atlas = rng.random((ts.m, 80, 80, 3)).astype(np.float32)
    W = H = 4096
    nx, ny = tiles_for(W, H, 80)
    out = np.empty((H, W, 3), np.float32)
    gather_texture(atlas, scanline_tiling(ts, nx, ny, 1), W, H, out=out)  # warm-up
    times = []
    for seed in range(3):
        t0 = time.perf_counter()
        grid = scanline_tiling(ts, nx, ny, seed)
        gather_texture(atlas, grid, W, H, out=out)
        times.append(time.perf_counter() - t0)
    tile_s = min(times)
    t0 = time.perf_counter()
    for j in range(ny):  # baseline: per-tile copy loop
        for i in range(nx):
            y, x = j * 80, i * 80
            out[y:y + 80, x:x + 80] = atlas[grid[j, i], :min(80, H - y), :min(80, W - x)]
    loop_s = time.perf_counter() - t0
    res = {
        "ga_n2_128px_tile80": {"seconds": ga_s, "evaluations": r.evaluations, "generations": len(r.log) - 1,
                               "seconds_per_evaluation": ga_s / max(r.evaluations, 1),
                               "baseline_bruteforce_seconds_per_evaluation": brute_eval_s,
                               "speedup_per_evaluation": brute_eval_s / (ga_s / max(r.evaluations, 1)),
                               "paper_table_5_1_seconds": [18, 43], "target_seconds": 5.0},
        "junction_removal_n2_tile80": seams,
        "tiling_4096": {"seconds": tile_s, "mpixel_per_s": W * H / tile_s / 1e6,
                        "baseline_tile_loop_seconds": loop_s, "speedup": loop_s / tile_s,
                        "target_mpixel_per_s": 50.0},
    }
    write_result("tiles", res)


if __name__ == "__main__":
    main()
