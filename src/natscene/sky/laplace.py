"""
Sky behind the clouds
=====================

Defines the sky behind the clouds (Dobashi et al. 2012, §4.1): ∇²L_sky(q, λ) = 0 over the removed (cloud)
pixels with the surrounding sky pixels as fixed (Dirichlet) boundary values, as in Pérez et al. 2003 (Poisson
image editing with a zero guidance field):

-   :func:`solve_laplace`: the harmonic interpolation of the unknown pixels.
-   :func:`laplace_system`: the 5-point system A x = b of the unknown pixels.
-   :func:`laplace_residual`: the discrete Laplace residual at the unknown pixels.

Discretisation: the 5-point Laplacian on the pixel grid. For every unknown pixel p with in-image
4-neighbours N(p):

    |N(p)| · L_p − Σ_{q ∈ N(p), q unknown} L_q = Σ_{q ∈ N(p), q known} S_q

which is Pérez et al.'s Eq. (7) with v = 0. Neighbours outside the image are simply absent, which is the
natural (zero-gradient, Neumann) boundary for clouds touching the image border. The matrix is symmetric
positive definite whenever every connected unknown region touches at least one known pixel. It is solved
for all channels either by smoothed-aggregation multigrid preconditioned CG to a relative residual of 1e-9
(``method="multigrid"``, the default: O(n), :mod:`natscene.sky.multigrid`) or by a SuperLU factorisation
(``method="direct"``); both are exact solutions of the discrete system (to solver tolerance), not an
approximate inpainting filter. Linear (and any discrete-harmonic) sky gradients are reproduced exactly.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Pérez, P., Gangnet, M., & Blake, A. (2003). Poisson image editing. ACM Transactions on Graphics, 22(3),
    313–318.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from natscene.errors import InputError
from natscene.sky.multigrid import solve_pcg

__all__ = ["laplace_system", "solve_laplace", "laplace_residual"]


def laplace_system(unknown: np.ndarray, known_values: np.ndarray):
    """Assemble ``A x = b`` for the unknown pixels. Returns ``(A csc, b (n, C), flat indices of unknowns)``."""
    unknown = np.asarray(unknown, bool)
    h, w = unknown.shape
    vals = np.asarray(known_values, np.float64).reshape(h, w, -1)
    nch = vals.shape[-1]
    flat = np.flatnonzero(unknown)
    n = flat.size
    idx = np.full(h * w, -1, np.int64)
    idx[flat] = np.arange(n)
    idx = idx.reshape(h, w)
    ys, xs = np.divmod(flat, w)
    diag = np.zeros(n)
    b = np.zeros((n, nch))
    rows, cols = [], []
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        ny, nx = ys + dy, xs + dx
        inside = (ny >= 0) & (ny < h) & (nx >= 0) & (nx < w)
        diag += inside
        r = np.flatnonzero(inside)
        nb = idx[ny[r], nx[r]]
        unk = nb >= 0
        rows.append(r[unk])
        cols.append(nb[unk])
        kr = r[~unk]
        np.add.at(b, kr, vals[ny[kr], nx[kr]])
    rows = np.concatenate(rows + [np.arange(n)])
    cols = np.concatenate(cols + [np.arange(n)])
    data = np.concatenate([-np.ones(rows.size - n), diag])
    A = sp.csc_matrix((data, (rows, cols)), shape=(n, n))
    return A, b, flat


def solve_laplace(values: np.ndarray, unknown: np.ndarray, method: str = "multigrid",
                  rtol: float = 1e-9) -> np.ndarray:
    """Harmonic interpolation: ``values`` (H, W[, C]) kept where ``~unknown``, ∇²L = 0 solved where ``unknown``.

    ``method``: "multigrid" (SA-multigrid PCG to relative residual ``rtol``) or "direct" (SuperLU).

    Raises InputError when no pixel is known (nothing to interpolate from).
    """
    v = np.asarray(values)
    unknown = np.asarray(unknown, bool)
    squeeze = v.ndim == 2
    v3 = v[..., None] if squeeze else v
    h, w, nch = v3.shape
    out = v3.astype(np.float64, copy=True)
    if not unknown.any():
        return v.astype(np.float32)
    if unknown.all():
        raise InputError("no sky pixels: the sky behind the clouds cannot be interpolated; use a photo "
                         "showing some blue sky, or mark sky pixels in a hand-painted mask (black)")
    A, b, flat = laplace_system(unknown, v3)
    if method == "direct":
        x = splu(A, permc_spec="MMD_AT_PLUS_A").solve(b)
    elif method == "multigrid":
        x = solve_pcg(A, b, np.stack(np.divmod(flat, w), 1), rtol=rtol)
    else:
        raise ValueError(f"unknown Laplace solver method {method!r} (multigrid or direct)")
    out.reshape(h * w, nch)[flat] = x
    out = out.astype(np.float32)
    return out[..., 0] if squeeze else out


def laplace_residual(field: np.ndarray, unknown: np.ndarray) -> np.ndarray:
    """Discrete Laplace residual ``|N(p)| L_p − Σ_{q ∈ N(p)} L_q`` at the unknown pixels (n, C)."""
    f = np.asarray(field, np.float64)
    f = f[..., None] if f.ndim == 2 else f
    h, w, _ = f.shape
    res = np.zeros_like(f)
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        src = np.zeros_like(f)
        has = np.zeros((h, w, 1))
        ys = slice(max(dy, 0), h + min(dy, 0))
        yd = slice(max(-dy, 0), h + min(-dy, 0))
        xs = slice(max(dx, 0), w + min(dx, 0))
        xd = slice(max(-dx, 0), w + min(-dx, 0))
        src[yd, xd] = f[ys, xs]
        has[yd, xd] = 1.0
        res += has * f - src
    return res[np.asarray(unknown, bool)]
