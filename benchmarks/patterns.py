"""Benchmark: a 549x528 petal to a stable pattern (Dong 2007 Table 3.2: petunia, 466 s on a 2007 PC;
target <= 10 s on 2 cores). Baseline in the same run: the explicit Euler scheme of Eq. 3.5 (the paper's
direct discretisation) on the same petal, timed per step and extrapolated to the step count the
explicit scheme's stability limit (dt * D * max_row_sum|L| <= 1) needs for the same simulated time.
Writes results/benchmarks/patterns.json."""
import json
import time
from pathlib import Path

import numpy as np

from natscene.io import read_mask
from natscene.patterns.presets import TABLE_3_3
from natscene.patterns.reaction_diffusion import RDParams, laplacian, simulate
from natscene.patterns.venation import radial_venation_spec, venation_from_nodes

ROOT = Path(__file__).resolve().parents[1]
mask = (read_mask(ROOT / "resources/patterns/petunia_petal_549x528.png") > 0.5).astype(np.float32)
ven = venation_from_nodes(mask.shape, radial_venation_spec(n_veins=9, opening_deg=90), vein_px=4)
p = RDParams(**TABLE_3_3["centre_spot"], root_supply=(4, 4), dt=2.5, max_steps=60, tol=1e-4)  # capped: see README (LU fill-in from the root star edges)
t0 = time.perf_counter()
r = simulate(mask, ven, p)
t_semi = time.perf_counter() - t0
# explicit baseline: per-step cost and the stable step
L, cells = laplacian(mask, ven, p.t)
dt_exp = min(p.dt, 1.0 / (max(p.D_A, p.D_B) * float(abs(L.diagonal()).max()) * 2))
a = np.ones(cells.size)
b = np.ones(cells.size)
t0 = time.perf_counter()
for _ in range(20):
    a2b = a * a * b
    a = a + dt_exp * (p.sa * (a2b - p.K_A * a + p.beta) + p.D_A * (L @ a))
    b = b + dt_exp * (p.sb * (1 - p.K_B * a2b) + p.D_B * (L @ b))
per_step = (time.perf_counter() - t0) / 20
t_explicit = per_step * r.steps * p.dt / dt_exp
out = {"petal": list(mask.shape[::-1]), "cells": int(cells.size), "steps": r.steps, "converged": r.converged,
       "residual": r.residual, "seconds_semi_implicit": t_semi, "explicit_dt": dt_exp,
       "seconds_explicit_extrapolated": t_explicit, "speedup": t_explicit / t_semi,
       "paper_seconds_2007": 466.0, "target_seconds": 10.0}
Path("results/benchmarks").mkdir(parents=True, exist_ok=True)
Path("results/benchmarks/patterns.json").write_text(json.dumps(out, indent=2))
print(json.dumps(out, indent=2))
