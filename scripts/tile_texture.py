"""Rule `tile_texture`: a texture of any size by seeded scan-line ω-tiling (Dong 2007 §5.4.3)."""
import numpy as np

from natscene.io import read_exr, read_yaml, write_exr, write_png
from natscene.runner import run
from natscene.tiles.construct import from_atlas
from natscene.tiles.omega import tile_set
from natscene.tiles.scanline import gather_texture, scanline_tiling, tiles_for, tiling_violations


def main(snakemake, log):
    meta = read_yaml(snakemake.input.meta)
    ts = tile_set(meta["set"])
    s = int(meta["tile_size"])
    tiles = from_atlas(read_exr(snakemake.input.atlas).pixels, ts.m, s)
    W, H = int(snakemake.wildcards.w), int(snakemake.wildcards.h)
    nx, ny = tiles_for(W, H, s)
    seed = int(snakemake.params.seed)
    grid = scanline_tiling(ts, nx, ny, seed=seed)
    bad = tiling_violations(ts, grid)
    if bad:
        raise RuntimeError(f"tiling violates {bad} edge constraints")
    tex = gather_texture(tiles, grid, W, H)
    log.info(f"{W}x{H}: {nx}x{ny} tiles of {s}px from set {ts.name}, seed {seed}")
    write_exr(snakemake.output.exr, tex, channels=["R", "G", "B"],
              attrs={"set": ts.name, "tile_size": s, "seed": seed, "grid": grid.tolist() if grid.size <= 4096 else None},
              stage="tile_texture")
    write_png(snakemake.output.png, tex, exposure=1.0)


run(snakemake, main)
