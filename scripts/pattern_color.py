"""Rule pattern_color: flower colour expression (Dong 2007 §3.4, Eqs. 3.6-3.10)."""
import numpy as np

from natscene.io import read_exr, write_exr, write_png
from natscene.patterns.expression import express_rgb, precompute
from natscene.patterns.pigments import pigment
from natscene.runner import run


def main(snakemake, log):
    spec = snakemake.params.spec
    maps = [read_exr(f) for f in snakemake.input.maps]
    conc = np.stack([m.channel("c") for m in maps], -1) * float(spec.get("concentration", 1.0))
    mask = maps[0].channel("A")
    pig = [pigment(p) for p in spec["pigments"]]
    if len(pig) != conc.shape[-1]:
        from natscene.errors import InputError
        raise InputError(f"config key 'patterns.{snakemake.wildcards.pattern}.pigments': give {conc.shape[-1]} "
                         f"pigments (one per map; use 'blank' for a one-pigment flower)")
    table = precompute(pig, spec.get("illuminant", "D65"))
    rgb = express_rgb(table, conc)
    log.info(f"pigments {table.names}: base XYZ {table.X0.round(4)}, XA {table.XA.round(4).tolist()}")
    rgba = np.concatenate([rgb * mask[..., None], mask[..., None]], -1)
    write_exr(snakemake.output.color, rgba, channels=["R", "G", "B", "A"],
              attrs={"pigments": table.names, "X0": table.X0, "XA": table.XA}, stage="pattern_color")
    write_png(snakemake.output.preview, rgb * mask[..., None], exposure=1.0 / max(float(table.X0[1]), 1e-3))


run(snakemake, main)
