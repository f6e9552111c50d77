"""Benchmark: a 549x528 petal to a stable pattern (Dong 2007 Table 3.2: petunia, 466 s on a 2007 PC;
target <= 10 s on 2 cores). Measured: the four Fig. 3.3 presets (Table 3.3 + ``FIG_3_3_STATE``) with the
implicit (Strang-split, Anderson-accelerated) scheme of ``simulate``, run until the max relative change per step < tol. Baseline in
the same run: the explicit scheme (dt = 1, the paper's per-iteration update, or its stability limit if smaller) on the same problem, timed per
step over 20 steps and extrapolated to the same simulated time (steps x dt of the implicit run).
Writes results/benchmarks/patterns.json."""
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _common import write_result

from natscene.io import read_mask
from natscene.patterns.presets import FIG_3_3_STATE, rd_params
from natscene.patterns.reaction_diffusion import simulate, stable_dt
from natscene.patterns.venation import radial_venation_spec, venation_from_nodes

ROOT = Path(__file__).resolve().parents[1]
mask = (read_mask(ROOT / "resources/patterns/petunia_petal_549x528.png") > 0.5).astype(np.float32)
ven = venation_from_nodes(mask.shape, radial_venation_spec(n_veins=9, opening_deg=90), vein_px=4)
out = {"petal": list(mask.shape[::-1]), "presets": {}, "paper_seconds_2007": 466.0, "target_seconds": 10.0}
for name in FIG_3_3_STATE:
    p = rd_params({"preset": name}, 0, mask.shape[0])
    t0 = time.perf_counter()
    r = simulate(mask, ven, p)
    sec = time.perf_counter() - t0
    ex = replace(p, scheme="explicit", dt=min(1.0, 0.9 * stable_dt(replace(p, scheme="explicit"))),
                 max_steps=20, tol=0.0)
    t0 = time.perf_counter()
    simulate(mask, ven, ex)
    per_step = (time.perf_counter() - t0) / 20
    explicit_s = per_step * r.steps * p.dt / ex.dt
    out["presets"][name] = {"seconds": sec, "steps": r.steps, "dt": p.dt, "converged": r.converged,
                            "residual": r.residual, "explicit_dt": ex.dt, "explicit_per_step_s": per_step,
                            "explicit_extrapolated_s": explicit_s, "speedup_vs_explicit": explicit_s / sec}
    print(name, f"{sec:.1f} s, {r.steps} steps; explicit would take {explicit_s:.3g} s")
write_result("patterns", out)
