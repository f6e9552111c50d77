"""Rule `composite_compare`: compare.png of a composite frame, the hybrid render | the full-spectral reference |
their CIEDE2000 map, at the shot's exposure (auto without a shot), in a rule of its own so that a new exposure
redraws the strip and renders nothing."""
import numpy as np

from natscene.io import auto_exposure, read_exr, write_png
from natscene.runner import run


def main(snakemake, log):
    final = read_exr(snakemake.input.final).channel("R", "G", "B")
    reference = read_exr(snakemake.input.reference)
    ref, de = reference.channel("R", "G", "B"), reference.channel("dE2000")
    e = snakemake.params.exposure
    if e == "auto":
        e = auto_exposure(np.concatenate([final, ref], 1))
    heat = np.stack([np.clip(de / 2, 0, 1), np.clip(1 - np.abs(de - 1), 0, 1) * 0.6, np.clip(1 - de, 0, 1) * 0.3],
                    -1) / e  # dE 0 dark blue-green, 1 yellow-green, >= 2 red (linear, shown at the same exposure)
    write_png(snakemake.output.png, np.concatenate([final, ref, heat.astype(np.float32)], 1), exposure=e)
    log.info(f"{snakemake.output.png}: hybrid | full-spectral | dE2000 at exposure {e:.4g}")


run(snakemake, main)
