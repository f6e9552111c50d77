"""Benchmark: time to generate the 194x122x194 cumulonimbus with the production modeller (issue target <= 5 s on
2 cores), as a ratio against the previous smooth metaball generator (metaballs.generate_smooth) in the same run.

Numba caches its kernels on disk (a first small call loads them); both are timed best of 3, the load average of
the (shared) machine is recorded beside them.
"""
import os

import numpy as np

from _common import best_of, write_result
from natscene.volume.metaballs import generate_smooth
from natscene.volume.procedural import generate

RES = (194, 122, 194)


def main():
    generate("cumulonimbus", (32, 24, 32), seed=3)            # load the compiled kernels
    t_new = best_of(lambda: generate("cumulonimbus", RES, seed=3, threads=2), repeat=3)
    t_old = best_of(lambda: generate_smooth("cumulonimbus", RES, seed=3), repeat=3)
    write_result("volume", {
        "resolution": RES, "seconds_cumulonimbus": round(t_new, 3), "target_seconds": 5.0,
        "baseline": "previous smooth generator (metaballs.generate_smooth)",
        "baseline_seconds": round(t_old, 3), "ratio_to_baseline": round(t_new / t_old, 2),
        "voxels_per_second": round(np.prod(RES) / t_new),
        "load_average_1min": round(os.getloadavg()[0], 2),
    })


if __name__ == "__main__":
    main()
