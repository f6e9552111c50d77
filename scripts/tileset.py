"""Rule `tileset`: GA-optimised ω-tile set from an example texture (Dong 2007 Ch. 5)."""
from pathlib import Path

import numpy as np

from natscene.config import relative_to_root, settings_from_section
from natscene.errors import InputError
from natscene.io import read_photo, write_exr, write_png, write_yaml
from natscene.runner import run
from natscene.tiles.construct import construct, diagram, to_atlas
from natscene.tiles.embed import embed, grabcut_object
from natscene.tiles.tile_ga import GAParams, max_tile_size, min_example_side, min_patch_positions
from natscene.tiles.omega import tile_set


def main(snakemake, log):
    spec = snakemake.params.spec
    name = snakemake.wildcards.texture
    example = read_photo(snakemake.input.example)
    s = int(spec["tile_size"])
    H, W = example.shape[:2]
    ts = tile_set(spec["set"])
    best = max_tile_size(H, W, ts.n)  # advice that runs: the largest size the GA has enough patches for
    if best is None:
        side = min_example_side(ts.n)
        raise InputError(f"config key 'tiles.{name}.path': the example {snakemake.input.example} ({W}x{H}) is too "
                         f"small for set {ts.name} ({ts.n} sample patches): even the smallest tile size, 4, leaves "
                         f"{max(H - 3, 0) * max(W - 3, 0)} patch positions and the GA needs "
                         f"{min_patch_positions(ts.n)}. Use an example of at least {side}x{side} px")
    if s > best:
        raise InputError(f"config key 'tiles.{name}.tile_size': {s} is too large for the example "
                         f"{snakemake.input.example} ({W}x{H}) with set {ts.name}: it leaves "
                         f"{max(H - s + 1, 0) * max(W - s + 1, 0)} patch positions, the GA needs "
                         f"{min_patch_positions(ts.n)}; choose at most {best}")
    params = settings_from_section(GAParams, spec["ga"], f"tiles.{name}.ga")
    log.info(f"{name}: example {W}x{H}, set {ts.name} ({ts.m} tiles, {ts.n} patches), tile {s}px")
    seams = spec["seams"]
    b = construct(example, ts, s, params, seed=int(spec["seed"]), margin=float(spec["margin"]),
                  core=float(seams["core"]), normalise=float(seams["normalise"]),
                  junction_weight=float(seams["junction_weight"]), candidates=int(seams["candidates"]),
                  passes=int(seams["passes"]), region=str(seams["region"]),
                  anisotropic=bool(seams["anisotropic"]), blend=str(seams["blend"]))
    log.info(f"seams: energy {b.seam_costs.sum():.1f} over {ts.m} tiles, "
             f"{np.mean([len(v) for v in b.extra['sources']]):.1f} merged sources per tile")
    if b.extra["axis_weights"]:
        log.info(f"seam weights per direction: {b.extra['axis_weights']}")
    log.info(f"GA: E {b.ga.initial_best_E:.2f} (best initial) -> {b.ga.E:.2f} after "
             f"{len(b.ga.log) - 1} generations, {b.ga.evaluations} evaluations")
    tiles = b.tiles
    if tiles.shape[-1] == 1:
        tiles = np.repeat(tiles, 3, -1)
    embedded = []
    for k, item in enumerate(spec.get("embed", [])):
        j = int(item["tile"])
        if j >= ts.m:
            raise InputError(f"config key 'tiles.{name}.embed[{k}].tile': {j} >= {ts.m} tiles in set {ts.name}")
        try:
            obj, mask = grabcut_object(read_photo(snakemake.input.embed[k]), item["rect"])
        except ValueError as e:
            raise InputError(f"config key 'tiles.{name}.embed[{k}]': {e}") from e
        tiles[j] = embed(tiles[j], obj, mask, float(item.get("size", 0.6)), float(spec["margin"]))
        embedded.append(j)
    attrs = {"set": ts.name, "tile_size": s, "tiles": ts.m}
    write_exr(snakemake.output.atlas, to_atlas(tiles), channels=["R", "G", "B"], attrs=attrs,
              stage="tileset")
    write_png(snakemake.output.png, diagram(tiles, ts), encoded=True)
    write_yaml(snakemake.output.meta, {
        "set": ts.name, "tile_size": s, "colours": list(ts.colours),
        "tiles": [{"index": j, "corners": list(t), "label": lab, "matching_patch": b.ga.matches[j],
                   "D": b.ga.D[j], "seam_cost": b.seam_costs[j], "embedded": j in embedded,
                   "merged_sources": [list(v) for v in b.extra["sources"][j]]}
                  for j, (t, lab) in enumerate(zip(ts.as_tuples(), ts.labels()))],
        "patches": {c: b.ga.genes[i] for i, c in enumerate(ts.colours)},
        "example": relative_to_root(snakemake.input.example, Path(snakemake.scriptdir).parent), "example_size": [W, H],
        "seams": dict(seams),
        "ga": {"params": vars(params), "seed": int(spec["seed"]), "E": b.ga.E,
               "initial_best_E": b.ga.initial_best_E, "initial_mean_E": b.ga.initial_mean_E,
               "evaluations": b.ga.evaluations, "log": b.ga.log},
    })


run(snakemake, main)
