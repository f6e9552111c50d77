"""Rule `composite_reference`: the full-spectral reference of a composite frame (Dong 2007 §2.5), compared
with the hybrid render of the same rays: reference.exr (R, G, B, dE2000) and compare.yaml (agreement; the times go
to the log and benchmarks/composite.py). Rule `composite_compare` draws them as compare.png."""
import time

import colour
import numpy as np

from natscene.color import linear_srgb_to_lab
from natscene.composite.full_spectral import render_full_spectral
from natscene.composite.inputs import build_set, sun_c_in_from_product
from natscene.composite.renderer import SetRenderer, spectral_coverage
from natscene.io import write_exr, write_yaml
from natscene.runner import run


def main(snakemake, log):
    entry, shot = snakemake.params.entry, snakemake.params.shot
    frame = int(snakemake.wildcards.frame)
    spec = build_set(entry, frame, snakemake.params.results, snakemake.params.root, shot,
                     sun_c_in_from_product(entry, snakemake.params.results))
    r = SetRenderer(spec)
    r.render_hybrid()  # warm-up (kernel compilation), so the two timings below compare like with like
    t0 = time.perf_counter()
    hy = r.render_hybrid()
    final = hy.final()
    t_h, split_h = time.perf_counter() - t0, dict(r.timing)
    t0 = time.perf_counter()
    _, ref = render_full_spectral(r)
    t_f, split_f = time.perf_counter() - t0, dict(r.timing)
    de = colour.delta_E(linear_srgb_to_lab(final), linear_srgb_to_lab(ref), method="CIE 2000").astype(np.float32)
    # times go to the log only (a cached output must not change when rerun); benchmarks/composite.py measures them
    log.info(f"times: hybrid {split_h}, full-spectral {split_f}")
    stats = {"spectral_coverage": spectral_coverage(hy),
             "frac_dE2000_le_1": float(np.mean(de <= 1)), "dE2000_median": float(np.median(de)),
             "dE2000_p99": float(np.percentile(de, 99)), "dE2000_max": float(de.max()),
             "dE2000_max_on_spectral_pixels": float(de[hy.mask].max()) if hy.mask.any() else 0.0}
    log.info(f"hybrid {t_h:.2f} s, full-spectral {t_f:.2f} s ({t_f / t_h:.1f}x); CIEDE2000 <= 1 on "
             f"{100 * stats['frac_dE2000_le_1']:.2f}% of pixels (median {stats['dE2000_median']:.2f}, "
             f"max {stats['dE2000_max']:.2f}; on the spectral object's pixels max "
             f"{stats['dE2000_max_on_spectral_pixels']:.2f})")
    write_exr(snakemake.output.exr, np.concatenate([ref, de[..., None]], -1), ["R", "G", "B", "dE2000"],
              {"composite": snakemake.wildcards.name, "frame": frame, **{k: v for k, v in stats.items()
                                                                        if not isinstance(v, dict)}},
              stage="composite_reference")
    write_yaml(snakemake.output.yaml, stats)


run(snakemake, main)
