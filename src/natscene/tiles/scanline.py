"""
Scan-line tiling
================

Defines the run-time ω-tiling (Dong 2007, §5.3.1, §5.4.3; Ng et al. 2005): seeded scan-line tile placement with
corner-colour (edge) constraints, and the texture as one vectorised gather from the tile atlas:

-   :func:`scanline_tiling`: a random valid tiling (:class:`TilingDeadEnd` where a set is not completable).
-   :func:`tiling_violations`: the tile borders whose corner colours disagree.
-   :func:`gather_texture`: the texture of a tiling from the tiles; :func:`tiles_for`: the tiles a size needs.

Scan-line order: the top-left tile is drawn at random; every other tile is drawn uniformly among the
tiles whose TL, TR (shared with the tile above) and BL (shared with the tile on the left) match; the
first row constrains only (TL, BL), the first column only (TL, TR).

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Ng, T.-Y., Wen, C., Tan, T.-S., Zhang, X., & Kim, Y. J. (2005). Generating an ω-tile set for texture
    synthesis. Proceedings of Computer Graphics International 2005 (CGI'05), 177–184.
"""
from __future__ import annotations

import numpy as np

from natscene.tiles.omega import TileSet, build_lookup

__all__ = ["scanline_tiling", "TilingDeadEnd", "tiling_violations", "gather_texture", "tiles_for"]


class TilingDeadEnd(RuntimeError):
    """No tile satisfies the constraints at some position (the set is not completable)."""


def scanline_tiling(ts: TileSet, nx: int, ny: int, seed: int = 0) -> np.ndarray:
    """Tile indices (ny, nx) of a random valid scan-line tiling with ``ts``."""
    if nx < 1 or ny < 1:
        raise ValueError(f"tiling size must be >= 1x1 tiles, got {nx}x{ny}")
    rng = np.random.default_rng(seed)
    lk = build_lookup(ts)
    u = rng.random((ny, nx))
    tiles = ts.tiles.tolist()
    grid = np.empty((ny, nx), np.int64)
    for j in range(ny):
        for i in range(nx):
            if i == 0 and j == 0:
                cand = np.arange(ts.m)
            elif j == 0:
                lt = tiles[grid[0, i - 1]]
                cand = lk.first_row.get((lt[1], lt[3]))
            elif i == 0:
                at = tiles[grid[j - 1, 0]]
                cand = lk.first_col.get((at[2], at[3]))
            else:
                lt = tiles[grid[j, i - 1]]
                at = tiles[grid[j - 1, i]]
                cand = lk.interior.get((at[2], at[3], lt[3]))
            if cand is None:
                raise TilingDeadEnd(f"tile set {ts.name}: no tile fits at ({i}, {j})")
            grid[j, i] = cand[int(u[j, i] * len(cand))]
    return grid


def tiling_violations(ts: TileSet, grid: np.ndarray) -> int:
    """Number of tile borders whose shared corner colours disagree (0 for a valid tiling)."""
    c = ts.tiles[np.asarray(grid)]  # (ny, nx, 4): TL, TR, BL, BR
    h = (c[:, :-1, 1] != c[:, 1:, 0]).sum() + (c[:, :-1, 3] != c[:, 1:, 2]).sum()
    v = (c[:-1, :, 2] != c[1:, :, 0]).sum() + (c[:-1, :, 3] != c[1:, :, 1]).sum()
    return int(h + v)


def gather_texture(tiles: np.ndarray, grid: np.ndarray, width: int | None = None,
                   height: int | None = None, out: np.ndarray | None = None) -> np.ndarray:
    """The texture of a tiling: ``tiles`` (m, s, s, C) gathered by ``grid`` (ny, nx), cropped to
    ``height`` x ``width`` (default: the whole grid). One fancy-index gather per tile row (no per-pixel
    Python loop)."""
    tiles = np.asarray(tiles)
    m, s, s2, ch = tiles.shape
    ny, nx = grid.shape
    width = nx * s if width is None else int(width)
    height = ny * s if height is None else int(height)
    if width > nx * s or height > ny * s:
        raise ValueError(f"grid {nx}x{ny} of {s}px tiles is smaller than {width}x{height}")
    if out is None:
        out = np.empty((height, width, ch), tiles.dtype)
    for j in range(-(-height // s)):
        rows = min(s, height - j * s)
        block = tiles[grid[j], :rows]                      # (nx, rows, s, C)
        block = block.transpose(1, 0, 2, 3).reshape(rows, nx * s, ch)
        out[j * s:j * s + rows] = block[:, :width]
    return out


def tiles_for(width: int, height: int, tile_size: int) -> tuple[int, int]:
    """Number of tiles (nx, ny) covering width x height."""
    return -(-int(width) // tile_size), -(-int(height) // tile_size)
