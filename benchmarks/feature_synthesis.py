"""Benchmark of the feature-aware synthesis (Dong 2007 Ch. 6): a 512x512 output from a 256x256 example with
texture optimisation and the control energy of Eq. 6.3 (target <= 20 s on 2 cores), the time of one EM
iteration against the nearest-neighbour search alone, plain texture optimisation (lambda 0) on the same
input as the baseline in the same run, and the hierarchical-quilting variant of §6.6.1 (target <= 5 s). The example is the bundled perspective meadow photo, 256x256 from its
middle, with its scale map from slant 50 deg; the target is scale 1 everywhere (the photo made isotropic).
Writes results/benchmarks/feature_synthesis.json."""
import time
from dataclasses import replace

import numpy as np

from _common import ROOT, write_result

from natscene.color import linear_to_srgb
from natscene.config import default_settings
from natscene.features.optimisation import OptimisationSettings, synthesise
from natscene.features.quilting import QuiltingSettings, quilt
from natscene.features.scale import grey_from_scale, scale_from_angles
from natscene.io import read_photo


def main():
    photo = linear_to_srgb(read_photo(ROOT / "resources/textures/grass_meadow_perspective.jpg"))
    h, w = photo.shape[:2]
    ex = np.ascontiguousarray(photo[(h - 256) // 2:(h + 256) // 2, (w - 256) // 2:(w + 256) // 2, :3])
    f_ex = grey_from_scale(scale_from_angles(256, 256, 50.0, 0.0))
    f_t = np.full((512, 512), grey_from_scale(np.float32(1.0)), np.float32)
    st = default_settings(OptimisationSettings)
    out = {}
    for name, lam in (("eq_6_3", st.lam), ("plain_lambda0", 0.0)):
        t0 = time.perf_counter()
        r = synthesise(ex, (512, 512), f_ex if lam else None, f_t if lam else None, replace(st, lam=lam))
        total = time.perf_counter() - t0
        n_iter = len(r.energies)
        out[name] = {"seconds": round(total, 2), "em_iterations": n_iter,
                     "seconds_per_iteration": round(total / n_iter, 3),
                     "search_seconds": round(r.timings["search_s"], 2),
                     "estep_seconds": round(r.timings["estep_s"], 2),
                     "search_share": round(r.timings["search_s"] / total, 3),
                     "final_energy": round(r.energies[-1][2], 1)}
        print(name, out[name], flush=True)
    out["target_seconds"] = 20.0
    t0 = time.perf_counter()
    r = quilt(ex, (512, 512), f_ex, f_t, default_settings(QuiltingSettings))
    total = time.perf_counter() - t0
    out["quilting"] = {"seconds": round(total, 2), "block_search_seconds": round(r.timings["search_s"], 2),
                       "seam_seconds": round(r.timings["seam_s"], 2), "target_seconds": 5.0,
                       "speedup_over_eq_6_3": round(out["eq_6_3"]["seconds"] / total, 1)}
    print("quilting", out["quilting"], flush=True)
    write_result("feature_synthesis", {"example": "grass_meadow_perspective.jpg, 256x256 from its middle",
                                       "output": [512, 512], **out})


if __name__ == "__main__":
    main()
