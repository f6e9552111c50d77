"""Benchmark: a 549x528 petal to a stable pattern (Dong 2007 Table 3.2: petunia, 466 s on a 2007 PC;
target <= 10 s on 2 cores). Measured: the explicit split scheme of ``simulate`` (float32 CSR stencil +
vascular sub-steps) run until the max relative change per unit time < tol. Baseline in the same run: the
previous semi-implicit scheme (sparse LU of I - dt D L, one solve per species per step), timed per step
over a few steps and extrapolated to the same simulated time. Writes results/benchmarks/patterns.json."""
import time
from pathlib import Path

import numpy as np

from _common import write_result
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from natscene.io import read_mask
from natscene.patterns.presets import TABLE_3_3
from natscene.patterns.reaction_diffusion import RDParams, laplacian, simulate
from natscene.patterns.venation import radial_venation_spec, venation_from_nodes

ROOT = Path(__file__).resolve().parents[1]
mask = (read_mask(ROOT / "resources/patterns/petunia_petal_549x528.png") > 0.5).astype(np.float32)
ven = venation_from_nodes(mask.shape, radial_venation_spec(n_veins=9, opening_deg=90), vein_px=4)
out = {"petal": list(mask.shape[::-1]), "presets": {}}
for name in ("centre_spot", "marginal_band"):
    p = RDParams(**TABLE_3_3[name], root_supply=(4, 4), dt=1.0, max_steps=20000, tol=1e-6)
    t0 = time.perf_counter()
    r = simulate(mask, ven, p)
    out["presets"][name] = {"seconds": time.perf_counter() - t0, "steps": r.steps, "converged": r.converged,
                            "residual": r.residual}
# baseline: semi-implicit LU scheme, per-step cost
p = RDParams(**TABLE_3_3["centre_spot"], dt=1.0)
L, cells = laplacian(mask, ven, p.t)
t0 = time.perf_counter()
eye = sp.identity(cells.size, format="csc")
sa_ = spla.factorized((eye - p.dt * p.D_A * L).tocsc())
sb_ = spla.factorized((eye - p.dt * p.D_B * L).tocsc())
t_fact = time.perf_counter() - t0
a = np.ones(cells.size)
b = np.ones(cells.size)
t0 = time.perf_counter()
for _ in range(5):
    a2b = a * a * b
    a, b = sa_(a + p.dt * p.sa * (a2b - p.K_A * a + p.beta)), sb_(b + p.dt * p.sb * (1 - p.K_B * a2b))
per_step = (time.perf_counter() - t0) / 5
ref = out["presets"]["centre_spot"]
out.update({"cells": int(cells.size), "baseline_lu_factorise_s": t_fact, "baseline_lu_per_step_s": per_step,
            "baseline_lu_extrapolated_s": t_fact + per_step * ref["steps"],
            "speedup_vs_lu": (t_fact + per_step * ref["steps"]) / ref["seconds"],
            "paper_seconds_2007": 466.0, "target_seconds": 10.0})
write_result("patterns", out)
