"""
Transport and modified Laplacian
================================

Defines the transport and the modified Laplacian of Dong (2007, §3.3.2, Eqs. 3.1, 3.4, 3.4'):

-   :func:`transport`: Eq. 3.1, the transport I between two cells.
-   :func:`laplacian`: the modified Laplacian of Eq. 3.4' as a sparse matrix over the petal cells.
-   :func:`laplacian_edges`: its edge lists, mesophyll and vascular parts; :func:`assemble`: a part as a sparse
    matrix.

Transport (Eq. 3.1): between two cells a, b at distance ||a, b||,
I = p_mm/||a,b|| (both mesophyll), p_mv w/||a,b|| (one vascular, vein width w),
p_vv w_ab/||a,b|| (both vascular, mean width), with p_mm = 1, p_mv = 2, p_vv = 10.

Modified Laplacian (Eq. 3.4'). Read literally, Eq. 3.4' scales the neighbour values by t I but not the
centre term, which is not conservative (a uniform field gets a source (sum_n t I - 4) u / 4, which makes
the system blow up along veins for t >= 1) and does not reduce to Eq. 3.4 at t = 0. We use the
conservative, symmetric form that does both: a graph Laplacian over the petal cells

    l_i = 1/4 * sum_j kappa_ij (u_j - u_i)

with, for the 4 grid neighbours, kappa = p_mm between mesophyll cells (Eq. 3.4 exactly) and
kappa = max(p_mm, t I) on an edge touching a vascular cell (I = p_mv w mesophyll-vein, Eq. 3.1b;
p_vv w_ab vein-vein, Eq. 3.1c), so t scales the vascular transport. The non-adjacent connections of
Eq. 3.1c ("proportional to the vein width, inversely proportional to the distance", between vascular
cells "connected by the vein") are taken along each vein's centreline: cell k is linked to the cells
2, 4, 8, ..., 2^n_dyadic steps further along the same root-to-tip path with kappa = t p_vv w_ab / ||a, b||
(a dyadic subset of all vein pairs, O(N log N) links instead of O(N^2); the root is simply the first
cell of every path). Cells outside the petal are not in the graph: no flux crosses the petal edge.

The edges come in two parts (:func:`laplacian_edges`): the mesophyll part L_m (edges between two mesophyll
cells) and the vascular part L_v (every edge touching a vascular cell, including the non-adjacent links), which
the explicit scheme steps separately.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from natscene.patterns.reaction_diffusion.parameters import P_MM, P_MV, P_VV
from natscene.patterns.venation import Venation

__all__ = ["transport", "laplacian_edges", "assemble", "laplacian"]


def transport(wa, wb, va, vb, p_mm=P_MM, p_mv=P_MV, p_vv=P_VV, dist=1.0):
    """Eq. 3.1: I(a, b) for cells with widths wa, wb and vascular flags va, vb (arrays), distance dist."""
    wa, wb = np.asarray(wa, float), np.asarray(wb, float)
    va, vb = np.asarray(va, bool), np.asarray(vb, bool)
    one = np.where(va, wa, wb)
    return np.where(va & vb, p_vv * 0.5 * (wa + wb), np.where(va | vb, p_mv * one, p_mm)) / dist


def laplacian_edges(mask, venation, t, p_mm=P_MM, p_mv=P_MV, p_vv=P_VV, n_dyadic=8):
    """Edge lists of the modified Laplacian: (cells, idx, mesophyll (i, j, kappa), vascular (i, j, kappa))."""
    inside = np.asarray(mask) > 0.5
    h, w = inside.shape
    idx = np.full((h, w), -1, np.int64)
    cells = np.flatnonzero(inside)
    idx.ravel()[cells] = np.arange(cells.size)
    if venation is None:
        venation = Venation.empty((h, w))
    vas = venation.vascular & inside
    wid = np.where(vas, venation.width, 0.0)
    mes, vsc = [[], [], []], [[], [], []]
    for di, dj in ((0, 1), (1, 0)):
        a = idx[: h - di, : w - dj]
        b = idx[di:, dj:]
        ok = (a >= 0) & (b >= 0)
        va, vb = vas[: h - di, : w - dj][ok], vas[di:, dj:][ok]
        wa, wb = wid[: h - di, : w - dj][ok], wid[di:, dj:][ok]
        I = transport(wa, wb, va, vb, p_mm, p_mv, p_vv)
        touch = va | vb
        k = np.where(touch, np.maximum(p_mm, t * I), p_mm)
        for out, sel in ((mes, ~touch), (vsc, touch)):
            out[0].append(a[ok][sel])
            out[1].append(b[ok][sel])
            out[2].append(k[sel])
    if t > 0 and venation.paths and n_dyadic > 0:
        pairs = {}
        for P in venation.paths:
            ii = idx[P[:, 0], P[:, 1]]
            for e in range(1, n_dyadic + 1):
                d = 2 ** e
                if d >= len(P):
                    break
                i, j = ii[:-d], ii[d:]
                ok = (i >= 0) & (j >= 0) & vas[P[:-d, 0], P[:-d, 1]] & vas[P[d:, 0], P[d:, 1]]
                dist = np.hypot(*(P[d:] - P[:-d]).T.astype(float))
                wab = 0.5 * (wid[P[:-d, 0], P[:-d, 1]] + wid[P[d:, 0], P[d:, 1]])
                ok &= dist > 1.5  # adjacent cells are already linked above
                lo, hi = np.minimum(i, j)[ok], np.maximum(i, j)[ok]
                pairs.update(zip(zip(lo.tolist(), hi.tolist()), (t * p_vv * wab[ok] / dist[ok]).tolist()))
        if pairs:
            ij = np.array(list(pairs.keys()), np.int64)
            vsc[0].append(ij[:, 0])
            vsc[1].append(ij[:, 1])
            vsc[2].append(np.array(list(pairs.values())))
    return cells, idx, mes, vsc


def assemble(n, edges):
    i, j, k = (np.concatenate(x) if x else np.zeros(0) for x in edges)
    i, j = i.astype(np.int64), j.astype(np.int64)
    W = sp.csr_matrix((np.r_[k, k], (np.r_[i, j], np.r_[j, i])), shape=(n, n))
    deg = np.asarray(W.sum(axis=1)).ravel()
    return (0.25 * (W - sp.diags(deg))).tocsr()


def laplacian(mask: np.ndarray, venation: Venation | None, t: float, p_mm=P_MM, p_mv=P_MV, p_vv=P_VV,
              n_dyadic: int = 8):
    """The modified Laplacian of Eq. 3.4' as a sparse (N, N) matrix over the petal cells (see module
    docstring), and the flat indices of those cells in the (H, W) grid."""
    cells, _, mes, vsc = laplacian_edges(mask, venation, t, p_mm, p_mv, p_vv, n_dyadic)
    n = cells.size
    return assemble(n, mes) + assemble(n, vsc), cells
