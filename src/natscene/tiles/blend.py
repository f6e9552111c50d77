"""
Poisson blending of a tile
==========================

Defines the gradient-domain blending of a merged tile across its seams (Pérez et al. 2003 Poisson editing, used
by Dong 2007, §5.6 for embedment; Kwatra et al. 2003, §3 hide the remaining seam steps by blending too):

-   :func:`poisson_blend`: the tile of a source map blended in the gradient domain, its border band fixed.
-   :func:`guidance`: the guidance g(p, q) of a source map.

A tile is a source map (see :mod:`natscene.tiles.graphcut`): pixel p shows ``example[p + o(p)]``. For
every 4-neighbour pair (p, q) the guidance g(p, q) is the difference each source shows across the pair,
averaged over the two sources with each *continued* across the pair:

    g(p, q) = ½ [(Xp(q) − Xp(p)) + (Xq(q) − Xq(p))]      (= the example's own difference inside a source)

(one continuation outside the example: the other alone). The blended tile u minimises
Σ (u(q) − u(p) − g(p, q))² with u fixed to the source map's pixels on the pinned set (the tile border
band: the edge constraints of the ω-tiles stay exact), i.e. the discrete Poisson equation
Δu = div g with Dirichlet values. Inside a source nothing changes but the low-frequency correction that
spreads each seam's intensity step over the tile; across a seam the step itself is replaced by the
mean of the two sources' differences. The system matrix depends only on the pinned set, so one sparse
LU factorisation serves every tile and channel.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Kwatra, V., Schödl, A., Essa, I., Turk, G., & Bobick, A. (2003). Graph-cut textures: image and video synthesis
    using graph cuts. ACM Transactions on Graphics, 22(3), 277–286.
-   Pérez, P., Gangnet, M., & Blake, A. (2003). Poisson image editing. ACM Transactions on Graphics, 22(3),
    313–318.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from natscene.tiles.graphcut import _pair_values, render

__all__ = ["poisson_blend", "guidance"]


def _incidence(s: int):
    """Sparse D (pairs x pixels), row k = e_q - e_p, pairs ordered axis 1 then axis 0 (as
    :func:`_pair_values`, row-major)."""
    idx = np.arange(s * s).reshape(s, s)
    rows = []
    for axis in (1, 0):
        p = idx[:, :-1] if axis == 1 else idx[:-1]
        q = idx[:, 1:] if axis == 1 else idx[1:]
        rows.append((p.ravel(), q.ravel()))
    p = np.concatenate([r[0] for r in rows])
    q = np.concatenate([r[1] for r in rows])
    k = np.arange(len(p))
    return sp.csr_matrix((np.r_[-np.ones(len(p)), np.ones(len(q))], (np.r_[k, k], np.r_[p, q])),
                         shape=(len(p), s * s))


@lru_cache(maxsize=8)
def _solver(s: int, fixed_bytes: bytes):
    fixed = np.frombuffer(fixed_bytes, bool)
    D = _incidence(s).tocsc()
    free = np.flatnonzero(~fixed)
    Df, Dx = D[:, free], D[:, np.flatnonzero(fixed)]
    solve = spla.factorized((Df.T @ Df).tocsc())
    return free, Df, Dx, solve


def guidance(example: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(pairs, C) guidance g(p, q) of a source map, pairs in :func:`_incidence` order."""
    out = []
    for axis, (Ap, Aq, Xp_q, Xq_p) in _pair_values(example, offsets).items():
        g1, g2 = Xp_q - Ap, Aq - Xq_p
        g = np.where(np.isfinite(g1) & np.isfinite(g2), 0.5 * (g1 + g2),
                     np.where(np.isfinite(g1), g1, np.where(np.isfinite(g2), g2, 0.0)))
        out.append(g.reshape(-1, g.shape[-1]))
    return np.concatenate(out)


def poisson_blend(example: np.ndarray, offsets: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """The tile (s, s, C) of the source map ``offsets`` blended in the gradient domain, pixels where
    ``fixed`` (s, s) kept exactly as the source map shows them. ``example`` (H, W, C), any encoding
    (blend in the space where differences should be spread evenly)."""
    ex = np.asarray(example, np.float64)
    if ex.ndim == 2:
        ex = ex[..., None]
    s = offsets.shape[0]
    fixed = np.ascontiguousarray(fixed, bool).ravel()
    if not fixed.any():
        raise ValueError("poisson_blend needs at least one fixed pixel (the Dirichlet boundary)")
    base = render(ex, offsets).reshape(s * s, -1)
    free, Df, Dx, solve = _solver(s, fixed.tobytes())
    g = guidance(ex, offsets)
    rhs = Df.T @ (g - Dx @ base[fixed])
    out = base.copy()
    for c in range(out.shape[1]):
        out[free, c] = solve(np.ascontiguousarray(rhs[:, c]))
    return out.reshape(s, s, -1)
