"""Rule `composite`: hybrid RGB + spectral render of one frame of a composite (Dong 2007 Ch. 2)."""
import time

import colour
import numpy as np

from natscene.color import linear_srgb_to_lab
from natscene.composite.full_spectral import render_full_spectral
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
    t_h = time.perf_counter() - t0
    final = hybrid.final()
    attrs = {"composite": snakemake.wildcards.name, "frame": frame, "spp": spec.spp, "upsampling": spec.upsampling,
             "spectral_coverage": spectral_coverage(hybrid), "render_seconds": t_h,
             "objects": entry.get("objects", []), "variant": renderer.tracer.variant}
    log.info(f"hybrid render {t_h:.2f} s, spectral pixels {100 * spectral_coverage(hybrid):.1f}%")
    write_exr(snakemake.output.hybrid, hybrid.to_array(), hybrid.channel_names(), attrs, stage="composite")
    write_exr(snakemake.output.final, np.concatenate([final, hybrid.alpha[..., None]], -1), ["R", "G", "B", "A"],
              attrs, stage="composite")
    write_png(snakemake.output.png, final)
    if entry.get("reference"):
        t0 = time.perf_counter()
        _, ref = render_full_spectral(renderer)
        t_f = time.perf_counter() - t0
        de = colour.delta_E(linear_srgb_to_lab(final), linear_srgb_to_lab(ref), method="CIE 2000").astype(np.float32)
        log.info(f"full-spectral reference {t_f:.2f} s ({t_f / t_h:.1f}x the hybrid); CIEDE2000 <= 1 on "
                 f"{100 * np.mean(de <= 1):.2f}% of pixels, max {de.max():.2f}")
        ref_path = snakemake.output.hybrid.replace("hybrid.exr", "reference.exr")
        write_exr(ref_path, np.concatenate([ref, de[..., None]], -1), ["R", "G", "B", "dE2000"],
                  {**attrs, "render_seconds": t_f}, stage="composite")


run(snakemake, main)
