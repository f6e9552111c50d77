"""
Tile-set construction
=====================

Defines the construction of an ω-tile set from an example texture (Dong 2007, §5.4.3 working flow):

-   :func:`construct`: the whole construction, a :class:`TileSetBuild`.
-   :func:`intermediate_tiles`: the tiles made of the four patch quarters named by their corner colours.
-   :func:`candidate_patches`: the best matching patches of a tile by Eq. 5.1.
-   :func:`to_atlas`, :func:`from_atlas`: tiles to an atlas image and back.
-   :func:`diagram`: the preview of a tile set with its corner colours.

The construction: GA selection of the sample patches, the
intermediate tiles cut from the centre of the 2x2 patch blocks, and junction removal by merging each
tile's best matching patch with a circle-constrained graph-cut seam (§5.2), refined by further merges of
the tile's own sample patches continued past their quarters and of the next-best matching patches, each
kept only where it lowers the seam energy (:func:`natscene.tiles.graphcut.build_tile`).

Matching errors and seams are computed on display-encoded (sRGB) values, where squared differences are
closer to perceived differences; the tiles themselves are cut from the linear example with the same
coordinates and masks.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from natscene.color import linear_to_srgb, srgb_to_linear
from natscene.tiles.tile_ga import GAParams, GAResult, MatchCost, quarter_layout, run_tile_ga
from natscene.tiles.blend import poisson_blend
from natscene.tiles.graphcut import axis_weights, build_tile, constraint_masks, intermediate_offsets, render
from natscene.tiles.omega import TileSet

__all__ = ["construct", "TileSetBuild", "intermediate_tiles", "candidate_patches", "to_atlas", "from_atlas",
           "diagram"]


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


def candidate_patches(cost: MatchCost, genes: np.ndarray, ts: TileSet, j: int, k: int,
                      spacing: int = 3) -> list[tuple[int, int]]:
    """The ``k`` best matching patches (top-left (y, x)) of tile ``j`` by Eq. 5.1, best first, at least
    ``spacing`` pixels apart (Chebyshev) so they are not near-copies of each other."""
    maps = cost.gene_maps(genes[np.unique(ts.tiles[j])])
    idx = {c: i for i, c in enumerate(np.unique(ts.tiles[j]).tolist())}
    total = sum(maps[idx[c], q] for q, c in enumerate(ts.tiles[j].tolist()))
    out: list[tuple[int, int]] = []
    for f in np.argsort(total, axis=None, kind="stable"):
        c = divmod(int(f), cost.PW)
        if all(max(abs(c[0] - d[0]), abs(c[1] - d[1])) >= spacing for d in out):
            out.append(c)
            if len(out) >= k:
                break
    return out


def construct(example_linear: np.ndarray, ts: TileSet, tile_size: int, params: GAParams | None = None,
              seed: int = 0, margin: float = 1.0, core: float = 2.0, normalise: float = 0.0,
              junction_weight: float = 3.0, candidates: int = 8, passes: int = 3,
              region: str = "circle", anisotropic: bool = False, blend: str = "none") -> TileSetBuild:
    """Build the ω-tile set ``ts`` from a linear example image (H, W, C).

    ``margin``, ``core``, ``normalise``, ``junction_weight``, ``passes``, ``region``: the graph-cut
    settings of :func:`natscene.tiles.graphcut.build_tile`; ``anisotropic``: seam prices weighted per
    direction by :func:`natscene.tiles.graphcut.axis_weights` of the example; ``candidates``: how many
    best matching patches are tried (the first is Dong's matching patch, merged with the centre
    pinned); the tile's own four sample patches, continued past their quarters, are tried after the
    first. ``blend="poisson"``: each merged tile is then blended in the gradient domain
    (:func:`natscene.tiles.blend.poisson_blend`, on display-encoded values) with its pinned border
    band fixed, which spreads the seams' remaining intensity steps."""
    if blend not in ("none", "poisson"):
        raise ValueError(f"blend must be 'none' or 'poisson', got {blend!r}")
    lin = np.asarray(example_linear, np.float32)
    if lin.ndim == 2:
        lin = lin[..., None]
    enc = linear_to_srgb(lin)
    if params is None:
        from natscene.config import default_settings
        params = default_settings(GAParams)
    p = params
    cost = MatchCost(enc, tile_size, p.metric, p.mu)
    ga = run_tile_ga(enc, ts, tile_size, p, seed=seed, cost=cost)
    s = int(tile_size)
    color_cost = cost if p.metric == "color" else MatchCost(enc, s)
    inter_lin = intermediate_tiles(lin, ga.genes, ts, s)
    tiles = np.empty_like(inter_lin)
    masks = np.zeros((ts.m, s, s), bool)
    costs = np.zeros(ts.m)
    sources = []
    aw = axis_weights(enc) if anisotropic else None
    keep_a = constraint_masks(s, margin, core, region)[0]
    for j in range(ts.m):
        off0 = intermediate_offsets(ga.genes, ts.tiles[j], s)
        best = [tuple(int(v) for v in ga.matches[j])]
        more = [c for c in candidate_patches(color_cost, ga.genes, ts, j, max(int(candidates), 1))
                if c != best[0]]
        quarters = list(dict.fromkeys(tuple(int(v) for v in off0[y, x])
                                      for y, x in ((0, 0), (0, s - 1), (s - 1, 0), (s - 1, s - 1))))
        cands = best + quarters + more[:max(int(candidates) - 1, 0)]
        off, changed, costs[j], accepted = build_tile(enc, off0, cands, margin, core, normalise, passes,
                                                      junction_weight, region, aw)
        tiles[j] = render(lin, off)
        if blend == "poisson":
            t = srgb_to_linear(np.clip(poisson_blend(enc, off, keep_a), 0.0, 1.0))
            tiles[j] = np.where(keep_a[..., None], tiles[j], t)
        masks[j] = changed
        sources.append(accepted)
    return TileSetBuild(tiles, inter_lin, masks, costs, ga, ts, s,
                        {"sources": sources, "axis_weights": aw, "keep": keep_a})


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
