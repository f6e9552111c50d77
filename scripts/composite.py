"""Rule `composite`: hybrid RGB + spectral render of one frame of a composite (Dong 2007 Ch. 2)."""
import time

import numpy as np

from natscene.composite.inputs import build_set, sun_c_in_from_product
from natscene.composite.renderer import SetRenderer, spectral_coverage
from natscene.io import write_exr
from natscene.runner import run


def main(snakemake, log):
    entry, shot = snakemake.params.entry, snakemake.params.shot
    frame = int(snakemake.wildcards.frame)
    t0 = time.perf_counter()
    spec = build_set(entry, frame, snakemake.params.results, snakemake.params.root, shot,
                     sun_c_in_from_product(entry, snakemake.params.results))
    t_b = time.perf_counter() - t0
    n_tri = sum(s.mesh.n_faces for s in spec.shapes)
    log.info(f"composite {snakemake.wildcards.name} frame {frame}: {spec.camera.width}x{spec.camera.height}, "
             f"{spec.spp} spp, {len(spec.shapes)} meshes ({n_tri} triangles), {len(spec.films)} film objects; "
             f"set built in {t_b:.1f} s")
    t0 = time.perf_counter()
    renderer = SetRenderer(spec)
    hybrid = renderer.render_hybrid()
    final = hybrid.final()
    t_h = time.perf_counter() - t0
    cov = spectral_coverage(hybrid)
    attrs = {"composite": snakemake.wildcards.name, "frame": frame, "shot": entry.get("shot") or "",
             "spp": spec.spp, "upsampling": spec.upsampling, "spectral_coverage": cov,
             "triangles": n_tri, "variant": renderer.tracer.variant, "camera_set_frame": list(spec.camera.position),
             "origin": list(entry.get("origin", [0, 0, 0]))}
    log.info(f"hybrid render {t_h:.2f} s (geometry {renderer.timing['geometry']:.2f} s, shading "
             f"{renderer.timing['shading']:.2f} s; includes kernel compilation), spectral pixels {100 * cov:.2f}%")
    write_exr(snakemake.output.hybrid, hybrid.to_array(), hybrid.channel_names(), attrs, stage="composite")
    write_exr(snakemake.output.final, np.concatenate([final, hybrid.alpha[..., None]], -1), ["R", "G", "B", "A"],
              attrs, stage="composite")


run(snakemake, main)
