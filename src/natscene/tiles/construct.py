"""Tile-set construction (Dong 2007 §5.4.3 working flow): GA selection of the sample patches, the
intermediate tiles cut from the centre of the 2x2 patch blocks, and junction removal by merging each
tile's best matching patch with a circle-constrained graph-cut seam.

Matching errors and seams are computed on display-encoded (sRGB) values, where squared differences are
closer to perceived differences; the tiles themselves are cut from the linear example with the same
coordinates and masks.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from natscene.color import linear_to_srgb
from natscene.tiles.genetic import GAParams, GAResult, MatchCost, quarter_layout, run_ga
from natscene.tiles.graphcut import merge
from natscene.tiles.omega import TileSet


def intermediate_tiles(example: np.ndarray, genes: np.ndarray, ts: TileSet, s: int) -> np.ndarray:
    """(m, s, s, C): each tile made of the four patch quarters named by its corner colours."""
    ex = np.asarray(example)
    if ex.ndim == 2:
        ex = ex[..., None]
    h = s // 2
    out = np.empty((ts.m, s, s, ex.shape[-1]), ex.dtype)
    for j, corners in enumerate(ts.tiles.tolist()):
        for q, ((sy, sx), (oy, ox)) in enumerate(quarter_layout(s)):
            gy, gx = genes[corners[q]]
            out[j, oy:oy + h, ox:ox + h] = ex[gy + sy:gy + sy + h, gx + sx:gx + sx + h]
    return out


@dataclass
class TileSetBuild:
    tiles: np.ndarray            # (m, s, s, C) final ω-tiles, linear
    intermediate: np.ndarray     # (m, s, s, C) before junction removal, linear
    masks: np.ndarray            # (m, s, s) True where the matching patch was used
    seam_costs: np.ndarray       # (m,)
    ga: GAResult
    tileset: TileSet
    tile_size: int
    extra: dict = field(default_factory=dict)


def construct(example_linear: np.ndarray, ts: TileSet, tile_size: int, params: GAParams | None = None,
              seed: int = 0, margin: float = 1.0) -> TileSetBuild:
    """Build the ω-tile set ``ts`` from a linear example image (H, W, C)."""
    lin = np.asarray(example_linear, np.float32)
    if lin.ndim == 2:
        lin = lin[..., None]
    enc = linear_to_srgb(lin)
    p = params or GAParams()
    cost = MatchCost(enc, tile_size, p.metric, p.mu)
    ga = run_ga(enc, ts, tile_size, p, seed=seed, cost=cost)
    s = int(tile_size)
    inter_enc = intermediate_tiles(enc, ga.genes, ts, s)
    inter_lin = intermediate_tiles(lin, ga.genes, ts, s)
    tiles = np.empty_like(inter_lin)
    masks = np.zeros((ts.m, s, s), bool)
    costs = np.zeros(ts.m)
    for j in range(ts.m):
        ty, tx = ga.matches[j]
        _, mask, costs[j] = merge(inter_enc[j], enc[ty:ty + s, tx:tx + s], margin)
        masks[j] = mask
        tiles[j] = np.where(mask[..., None], lin[ty:ty + s, tx:tx + s], inter_lin[j])
    return TileSetBuild(tiles, inter_lin, masks, costs, ga, ts, s)


def atlas_layout(m: int) -> tuple[int, int]:
    """(columns, rows) of the atlas grid."""
    cols = int(np.ceil(np.sqrt(m)))
    return cols, -(-m // cols)


def to_atlas(tiles: np.ndarray) -> np.ndarray:
    """Tiles (m, s, s, C) packed row-major into an atlas (rows*s, cols*s, C), zero padded."""
    m, s, _, c = tiles.shape
    cols, rows = atlas_layout(m)
    atlas = np.zeros((rows * s, cols * s, c), tiles.dtype)
    for k in range(m):
        r, q = divmod(k, cols)
        atlas[r * s:(r + 1) * s, q * s:(q + 1) * s] = tiles[k]
    return atlas


def from_atlas(atlas: np.ndarray, m: int, s: int) -> np.ndarray:
    """Inverse of :func:`to_atlas`."""
    cols, rows = atlas_layout(m)
    if atlas.shape[0] < rows * s or atlas.shape[1] < cols * s:
        raise ValueError(f"atlas {atlas.shape[1]}x{atlas.shape[0]} too small for {m} tiles of {s}px")
    a = atlas[:rows * s, :cols * s].reshape(rows, s, cols, s, -1).transpose(0, 2, 1, 3, 4)
    return np.ascontiguousarray(a.reshape(rows * cols, s, s, -1)[:m])


def diagram(tiles: np.ndarray, ts: TileSet, gap: int = 4, marker: float = 0.12) -> np.ndarray:
    """Display-encoded preview (float sRGB in [0, 1]) of the tile set with each tile's corner colour
    squares drawn in its corners, tiles separated by ``gap`` white pixels."""
    from natscene.tiles.omega import SQUARE_RGB
    enc = linear_to_srgb(tiles if tiles.shape[-1] == 3 else np.repeat(tiles[..., :1], 3, -1))
    m, s = enc.shape[:2]
    cols, rows = atlas_layout(m)
    out = np.ones((rows * (s + gap) + gap, cols * (s + gap) + gap, 3), np.float32)
    k = max(3, int(round(marker * s)))
    for j in range(m):
        r, q = divmod(j, cols)
        y0, x0 = gap + r * (s + gap), gap + q * (s + gap)
        t = enc[j].copy()
        for corner, (cy, cx) in enumerate([(0, 0), (0, s - k), (s - k, 0), (s - k, s - k)]):
            t[cy:cy + k, cx:cx + k] = SQUARE_RGB[ts.colours[ts.tiles[j, corner]]]
        out[y0:y0 + s, x0:x0 + s] = t
    return out
