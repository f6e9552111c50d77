"""Rule `composite`: hybrid RGB + spectral render of one frame of a composite (Dong 2007 Ch. 2)."""
import time

import numpy as np

from natscene.composite.inputs import build_set, sun_c_in_from_product
from natscene.composite.scene import SetRenderer, spectral_coverage
from natscene.io import write_exr, write_png
from natscene.runner import run


def main(snakemake, log):
    entry = snakemake.params.entry
    frame = int(snakemake.wildcards.frame)
    spec = build_set(entry, frame, snakemake.params.results, snakemake.params.root,
                     sun_c_in_from_product(entry, snakemake.params.results))
    log.info(f"composite {snakemake.wildcards.name} frame {frame}: {spec.camera.width}x{spec.camera.height}, "
             f"{spec.spp} spp, {len(spec.leaves)} leaves, {len(spec.objects)} film objects")
    t0 = time.perf_counter()
    renderer = SetRenderer(spec)
    hybrid = renderer.render_hybrid()
    final = hybrid.final()
    t_h = time.perf_counter() - t0
    cov = spectral_coverage(hybrid)
    attrs = {"composite": snakemake.wildcards.name, "frame": frame, "spp": spec.spp, "upsampling": spec.upsampling,
             "spectral_coverage": cov, "objects": entry.get("objects", []),
             "variant": renderer.tracer.variant}
    log.info(f"hybrid render {t_h:.2f} s (first call in the process: includes kernel compilation), spectral "
             f"pixels {100 * cov:.1f}%")
    write_exr(snakemake.output.hybrid, hybrid.to_array(), hybrid.channel_names(), attrs, stage="composite")
    write_exr(snakemake.output.final, np.concatenate([final, hybrid.alpha[..., None]], -1), ["R", "G", "B", "A"],
              attrs, stage="composite")
    write_png(snakemake.output.png, final)


run(snakemake, main)
