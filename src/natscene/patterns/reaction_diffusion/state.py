"""
State of the reaction-diffusion
===============================

Defines the state of Dong's (2007) reaction-diffusion (§3.3.2) on the petal cells:

-   :func:`initial_state`: the initial state and the vein-root supply.
-   :class:`RDResult`: the result on the (H, W) grid; :func:`on_grid`: cell values back on the grid.

Hormone supply. The pigment composition is "controlled by some key hormones ... composed in reproduction
organs ... and then transported all over the petal by the vascular system" (§3.1). The vein root (the
petal base, next to the reproductive organs) is therefore held at a supply state (a_root, b_root) =
root_supply * (a*, b*) (Dirichlet condition at the root cell); with root_supply = (1, 1) and no noise
the uniform steady state is an exact solution, so every pattern comes from the supply, the venation, the
petal shape and (for Turing-unstable parameters) the initial noise.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["RDResult", "initial_state", "on_grid"]


@dataclass
class RDResult:
    a: np.ndarray  # (H, W), NaN-free, 0 outside the petal
    b: np.ndarray
    steps: int
    converged: bool
    residual: float
    history: list = field(default_factory=list)


def initial_state(mask, venation, p, cells, init, dtype):
    """Initial (a, b) on the petal cells (steady state x (1 + noise), or ``init`` maps), the root cell's index
    (None when the vein root is off the petal) and the root supply (ra, rb), already applied at the root."""
    a0, b0 = p.steady_state()
    n = cells.size
    if init is None:
        rng = np.random.default_rng(p.seed)
        a = (a0 * (1.0 + p.noise * rng.standard_normal(n))).astype(dtype)
        b = (b0 * (1.0 + p.noise * rng.standard_normal(n))).astype(dtype)
    else:
        a = np.asarray(init[0], dtype).ravel()[cells].copy()
        b = np.asarray(init[1], dtype).ravel()[cells].copy()
    h, w = mask.shape
    r0, c0 = venation.root if venation is not None else (-1, -1)
    root = None
    if 0 <= r0 < h and 0 <= c0 < w and mask[r0, c0] > 0.5:
        root = int(np.searchsorted(cells, r0 * w + c0))
    ra, rb = dtype(a0 * p.root_supply[0]), dtype(b0 * p.root_supply[1])
    if root is not None:
        a[root], b[root] = ra, rb
    return a, b, root, ra, rb


def on_grid(values: np.ndarray, cells: np.ndarray, shape) -> np.ndarray:
    """Cell values (N,) back on the (H, W) grid, float32, 0 off the petal."""
    h, w = shape
    out = np.zeros(h * w, np.float32)
    out[cells] = values
    return out.reshape(h, w)
