"""Benchmark: time to generate the 194x122x194 cumulonimbus (issue target <= 10 s on 2 cores).

Baseline in the same run: one pass of the fBm octaves alone on the same grid, so the ratio says how much of
the cost is the shaping beyond the noise.
"""
import numpy as np

from _common import best_of, write_result
from natscene.volume.noise import fbm
from natscene.volume.procedural import generate

RES = (194, 122, 194)


def main():
    t_gen = best_of(lambda: generate("cumulonimbus", RES, seed=3), repeat=3)
    ext = np.array(RES[::-1], float) / max(RES)
    t_fbm = best_of(lambda: fbm(RES[::-1], ext, 8.0, 5, rng=np.random.default_rng(0)), repeat=3)
    write_result("volume", {
        "resolution": RES, "seconds_cumulonimbus": round(t_gen, 3), "target_seconds": 10.0,
        "baseline_seconds_fbm_5_octaves": round(t_fbm, 3), "ratio_to_baseline": round(t_gen / t_fbm, 2),
        "voxels_per_second": round(np.prod(RES) / t_gen),
    })


if __name__ == "__main__":
    main()
