"""
Interpolation on the table nodes
================================

Defines the interpolation on the precompute tables' node grids (the extinction's, g's): linear between the two
nodes that bracket a value, the value clamped to the grid's ends (Dobashi et al. 2012, §4.3 interpolates the
tables the same way):

-   :func:`lerp_weights`: the (P, N) interpolation weights of P values on a grid of N nodes.
-   :func:`bracket`, :func:`brackets`: the lower node and the fraction of one value, or of an array of values.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

__all__ = ["bracket", "brackets", "lerp_weights"]


def lerp_weights(grid, x) -> np.ndarray:
    """(P, N) linear-interpolation weights of the values x (P,) on an increasing grid (N,), clamped."""
    grid = np.asarray(grid, np.float64)
    x = np.atleast_1d(np.asarray(x, np.float64))
    n = grid.size
    w = np.zeros((x.size, n), np.float32)
    if n == 1:
        w[:, 0] = 1
        return w
    xc = np.clip(x, grid[0], grid[-1])
    i = np.clip(np.searchsorted(grid, xc, side="right") - 1, 0, n - 2)
    f = (xc - grid[i]) / (grid[i + 1] - grid[i])
    rows = np.arange(x.size)
    w[rows, i] = 1 - f
    w[rows, i + 1] += f
    return w


def bracket(grid: np.ndarray, x: float) -> tuple[int, float]:
    """(i, f): x clamped to the grid lies between grid[i] and grid[i + 1] at fraction f (f = 0 on one node)."""
    n = grid.size
    if n == 1:
        return 0, 0.0
    xc = min(max(float(x), float(grid[0])), float(grid[-1]))
    i = int(min(max(np.searchsorted(grid, xc, side="right") - 1, 0), n - 2))
    return i, float((xc - grid[i]) / (grid[i + 1] - grid[i]))


def brackets(grid: np.ndarray, x) -> tuple[np.ndarray, np.ndarray]:
    """:func:`bracket` for an array of values: (i (P,) int64, f (P,) float64)."""
    x = np.atleast_1d(np.asarray(x, np.float64))
    n = grid.size
    if n == 1:
        return np.zeros(x.size, np.int64), np.zeros(x.size)
    xc = np.clip(x, grid[0], grid[-1])
    i = np.clip(np.searchsorted(grid, xc, side="right") - 1, 0, n - 2).astype(np.int64)
    return i, (xc - grid[i]) / (grid[i + 1] - grid[i])
