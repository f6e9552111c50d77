"""Rule `feature_synthesis`: a texture of the output size whose feature maps follow the target's (Dong 2007
§6.6: texture optimisation with the control energy of Eq. 6.3, or hierarchical quilting), beside plain texture
optimisation on request."""
import time
from dataclasses import replace

import numpy as np

from natscene import io
from natscene.color import linear_to_srgb, srgb_to_linear
from natscene.errors import InputError
from natscene.features.colour import recolour_regions, region_colours, transfer_to_largest
from natscene.features.entry import feature_stack, optimisation_settings, quilting_settings, target_stack
from natscene.features.maps import resample_labels
from natscene.features.optimisation import synthesise
from natscene.features.quilting import quilt
from natscene.features.scale import scale_preview
from natscene.features.type_map import type_map
from natscene.runner import run


def main(snakemake, log):
    entry, name = snakemake.params.entry, snakemake.wildcards.name
    key = f"textures.{name}"
    out_cfg = entry["output"]
    W, H = out_cfg["size"]
    feats = io.read_exr(snakemake.input.features)
    srgb = feats.channel("sR", "sG", "sB")
    maps = {"scale": feats.channel("scale") if "scale" in feats.channels else None,
            "types": np.rint(feats.channel("type")).astype(np.int32) if "type" in feats.channels else None,
            "colour": np.rint(feats.channel("colour")).astype(np.int32) if "colour" in feats.channels else None}
    stats = (io.read_yaml(snakemake.input.colour) or {}).get("regions")
    scale_img = io.read_mask(snakemake.input.scale_image) if snakemake.input.get("scale_image") else None
    colour_img = io.read_image_u8(snakemake.input.colour_image)[..., 0] if snakemake.input.get("colour_image") else None
    f_ex, names = feature_stack(maps)
    f_t, targets = target_stack(maps, out_cfg, (W, H), scale_img, colour_img, key)
    types_t = None
    if maps["types"] is not None:
        types_t = resample_labels(maps["types"], (W, H)) if not snakemake.input.get("types_image") else \
            type_map(io.read_image_u8(snakemake.input.types_image)[..., 0], (H, W), f"config key '{key}.output.types'")
    if types_t is not None:
        missing = sorted(set(np.unique(types_t).tolist()) - set(np.unique(maps["types"]).tolist()))
        if missing:
            raise InputError(f"config key '{key}.output.types': types {missing} are not in the example's type map "
                             f"('{key}.types.labels')")
    example = srgb
    consistent = entry["colour"]["transfer_to_largest"] and maps["colour"] is not None
    if consistent:  # §6.5 (3), Fig. 6.15 d: synthesise from the colour-consistent example, the colour map still a
        # feature (the regions' structure follows the target map), then give the regions their colours back
        example = linear_to_srgb(np.clip(transfer_to_largest(srgb_to_linear(srgb), maps["colour"]), 0, None))
    st = optimisation_settings(entry, key)
    t0 = time.perf_counter()
    if entry["method"] == "quilting":
        res = quilt(example, (H, W), f_ex, f_t, quilting_settings(entry, key), example_types=maps["types"],
                    target_types=types_t, log=log.info)
    else:
        res = synthesise(example, (H, W), f_ex, f_t, st, example_types=maps["types"], target_types=types_t,
                         log=log.info)
    t_ours = time.perf_counter() - t0
    out = res.image
    if consistent:
        out = linear_to_srgb(np.clip(recolour_regions(srgb_to_linear(out), targets["colour"], stats), 0, None))
    log.info(f"{name}: {W}x{H} from {srgb.shape[1]}x{srgb.shape[0]} by {entry['method']}, features "
             f"{names or 'none'}{', types ' + st.type_mode if maps['types'] is not None else ''}: {t_ours:.1f} s "
             f"(search {res.timings['search_s']:.1f} s)")
    attrs = {"texture": name, "method": entry["method"], "features": names, "energy": res.energies[-1][2]}
    attrs.update({"lambda": st.lam} if entry["method"] == "optimisation" else {"alpha": entry["quilting"]["alpha"]})
    io.write_exr(snakemake.output.exr, srgb_to_linear(out), ["R", "G", "B"], attrs=attrs, stage="feature_synthesis")
    io.write_png(snakemake.output.png, out, encoded=True)
    # the comparison: example | target scale, colour map (if any) | output | plain texture optimisation (lambda 0)
    panels = [srgb]
    if "scale" in targets:
        panels.append(np.repeat(scale_preview(targets["scale"])[..., None], 3, -1))
    if "colour" in targets:
        panels.append(linear_to_srgb(region_colours(targets["colour"], stats)))
    panels.append(out)
    if out_cfg["baseline"]:
        base = synthesise(example, (H, W), None, None, replace(st, lam=0.0))  # no feature, no type
        panels.append(base.image)
        log.info(f"plain texture optimisation (lambda 0) for comparison: energy {base.energies[-1][2]:.4g}")
    h = max(p.shape[0] for p in panels)
    pad = lambda p: np.pad(p, ((0, h - p.shape[0]), (0, 0), (0, 0)), constant_values=1.0)  # noqa: E731
    sheet = np.concatenate([x for p in panels for x in (pad(p), np.ones((h, 6, 3)))][:-1], 1)
    io.write_png(snakemake.output.compare, sheet, encoded=True)


run(snakemake, main)
