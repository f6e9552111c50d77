"""Rule `texture_completion`: a hole of a textured photo filled by feature-aware synthesis from the rest of the
photo (Dong 2007 §6.7, Fig. 6.16), beside OpenCV's exemplar-free inpainting."""
import time

import numpy as np

from natscene import io
from natscene.color import srgb_to_linear
from natscene.errors import InputError
from natscene.features.completion import complete, inpaint_baseline
from natscene.features.entry import feature_stack, optimisation_settings
from natscene.runner import run


def main(snakemake, log):
    entry, name = snakemake.params.entry, snakemake.wildcards.name
    key = f"textures.{name}"
    feats = io.read_exr(snakemake.input.features)
    srgb = feats.channel("sR", "sG", "sB")
    h, w = srgb.shape[:2]
    x, y, hw, hh = entry["complete"]["hole"]
    if x + hw > w or y + hh > h or hw < 1 or hh < 1:
        raise InputError(f"config key '{key}.complete.hole': [{x}, {y}, {hw}, {hh}] leaves the {w}x{h} photo "
                         f"(working_size)")
    hole = np.zeros((h, w), bool)
    hole[y:y + hh, x:x + hw] = True
    maps = {"scale": feats.channel("scale") if "scale" in feats.channels else None, "colour": None}
    f, names = feature_stack(maps)
    st = optimisation_settings(entry, key)
    t0 = time.perf_counter()
    res = complete(srgb, hole, f, st, log=log.info)
    log.info(f"{name}: {hw}x{hh} hole filled in {time.perf_counter() - t0:.1f} s (features {names or 'none'})")
    base = inpaint_baseline(srgb, hole)
    io.write_exr(snakemake.output.exr, srgb_to_linear(res.image), ["R", "G", "B"],
                 attrs={"texture": name, "hole": [x, y, hw, hh]}, stage="texture_completion")
    io.write_png(snakemake.output.png, res.image, encoded=True)
    marked = srgb.copy()
    marked[hole] = marked[hole] * 0.3 + np.array([0.7, 0.0, 0.0])  # the hole shown in red
    gap = np.ones((h, 6, 3))
    io.write_png(snakemake.output.compare, np.concatenate([marked, gap, res.image, gap, base], 1), encoded=True)


run(snakemake, main)
