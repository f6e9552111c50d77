"""Junction removal: the matching patch merged into the intermediate tile by a graph-cut seam
constrained to a circle (Dong 2007 §5.2, Fig. 5.2(b); Ng et al. 2005; seam costs of Kwatra et al. 2003).

Pixels outside the circle (radius s/2 - margin about the tile centre) keep the intermediate tile, so
every tile border is that of its sample patches and matches its neighbours; the cross where the four
quarters meet (the two 2-pixel bands along the mid-lines, inside the circle) is forced to the matching
patch, so the junction disappears; in between, a minimum cut with edge cost
M(p, q) = |A(p) - B(p)| + |A(q) - B(q)| (A: intermediate tile, B: matching patch) chooses the seam.
"""
from __future__ import annotations

import maxflow
import numpy as np

INF = 1e12


def constraint_masks(s: int, margin: float = 1.0):
    """(keep_tile, keep_patch) boolean masks (s, s): outside the circle / the junction cross."""
    h = s // 2
    yy, xx = np.mgrid[0:s, 0:s]
    c = (s - 1) / 2.0
    r = s / 2.0 - float(margin)
    inside = (yy - c) ** 2 + (xx - c) ** 2 <= r * r
    cross = ((yy >= h - 1) & (yy <= h)) | ((xx >= h - 1) & (xx <= h))
    return ~inside, cross & inside


def merge(tile: np.ndarray, patch: np.ndarray, margin: float = 1.0):
    """Merge ``patch`` into ``tile`` (both (s, s, C)) with the circle-constrained min-cut seam.

    Returns (merged tile, mask (s, s) True where the patch is used, seam cost = cut value).
    """
    A = np.asarray(tile, np.float64)
    B = np.asarray(patch, np.float64)
    if A.ndim == 2:
        A, B = A[..., None], B[..., None]
    if A.shape != B.shape or A.shape[0] != A.shape[1]:
        raise ValueError(f"tile and patch must be the same square shape, got {A.shape}, {B.shape}")
    s = A.shape[0]
    keep_a, keep_b = constraint_masks(s, margin)
    diff = np.sqrt(((A - B) ** 2).sum(-1))
    g = maxflow.Graph[float]()
    ids = g.add_grid_nodes((s, s))
    wr = np.zeros((s, s))
    wr[:, :-1] = diff[:, :-1] + diff[:, 1:]
    wd = np.zeros((s, s))
    wd[:-1, :] = diff[:-1, :] + diff[1:, :]
    right = np.array([[0, 0, 0], [0, 0, 1], [0, 0, 0]])
    down = np.array([[0, 0, 0], [0, 0, 0], [0, 1, 0]])
    g.add_grid_edges(ids, weights=wr + 1e-9, structure=right, symmetric=True)
    g.add_grid_edges(ids, weights=wd + 1e-9, structure=down, symmetric=True)
    g.add_grid_tedges(ids, np.where(keep_a, INF, 0.0), np.where(keep_b, INF, 0.0))
    cut = g.maxflow()
    use_b = g.get_grid_segments(ids)  # True: sink side = patch B
    out = np.where(use_b[..., None], B, A)
    return out.astype(np.float32), use_b, float(cut)
