"""Rule pigment_maps: venation-aware reaction-diffusion on a petal (Dong 2007 §3.3)."""
from pathlib import Path

import numpy as np

from natscene.io import write_exr, write_png
from natscene.patterns.presets import petal_shape, rd_params, venation
from natscene.patterns.reaction_diffusion import normalise, simulate
from natscene.runner import run


def main(snakemake, log):
    spec = snakemake.params.spec
    size = spec["size"]
    mask = petal_shape(spec["shape"], size, lambda q: str(Path(snakemake.params.root) / q))
    ven = venation(spec["venation"], size)
    p = rd_params(spec["rd"], snakemake.params.seed, size[1], f"patterns.{snakemake.wildcards.pattern}.rd")
    log.info(f"pattern {snakemake.wildcards.pattern}: {size[0]}x{size[1]}, {int(mask.sum())} petal cells, "
             f"{0 if ven is None else int(ven.vascular.sum())} vascular; {p.to_dict()}")
    r = simulate(mask, ven, p, logger=log)
    log.info(f"{'converged' if r.converged else 'stopped'} after {r.steps} steps (residual {r.residual:.3g})")
    mode = spec.get("normalise", "max")
    maps = [normalise(r.a, mask, mode=mode), normalise(r.b, mask, mode=mode)]
    for k, (c, raw) in enumerate(zip(maps, (r.a, r.b))):
        v = raw[mask > 0.5]
        log.info(f"pigment {k}: C in [{v.min():.4g}, {v.max():.4g}] (C_min / C_max = {v.min() / v.max():.3f}); "
                 f"normalised '{mode}'")
    attrs = {"rd": p.to_dict(), "steps": r.steps, "converged": int(r.converged), "normalise": mode}
    for k, (out, c) in enumerate(zip(snakemake.output.maps, maps)):
        write_exr(out, np.stack([c, mask], -1), channels=["c", "A"], attrs={**attrs, "pigment": k},
                  stage="pigment_maps")
    vis = []
    for c in maps:  # preview: contrast-stretched, dark = more pigment (Dong's convention)
        lo, hi = c[mask > 0].min(), c[mask > 0].max()
        vis.append(np.where(mask > 0, 1 - (c - lo) / max(hi - lo, 1e-9), 0))
    write_png(snakemake.output.preview, np.concatenate(vis, axis=1), exposure=None)


run(snakemake, main)
