"""
Multigrid-preconditioned CG
===========================

Defines smoothed-aggregation multigrid preconditioned conjugate gradients for the sky's Laplace system
(Dobashi et al. 2012, §4.1 names no solver; this one solves the discrete system exactly, to tolerance):

-   :func:`solve_pcg`: solve A X = B by SA-multigrid preconditioned CG.
-   :class:`SAMultigrid`: the smoothed-aggregation hierarchy (the V-cycle preconditioner).
-   :func:`pcg`: preconditioned conjugate gradients for all columns at once.

The 5-point Laplace matrix of :mod:`natscene.sky.laplace` is symmetric positive definite. Aggregates are the
unknown pixels of each 2x2 block (geometric aggregation on the pixel grid); the tentative prolongation P0
(piecewise constant) is smoothed by one damped-Jacobi step, P = (I − ω D⁻¹A) P0 with ω = 2/3 (D⁻¹A has
spectral radius ≤ 2 by Gershgorin), and coarse operators are Galerkin products Pᵀ A P (Vaněk, Mandel &
Brezina 1996). A symmetric V-cycle (damped Jacobi pre/post smoothing, exact SuperLU solve on the coarsest
level) preconditions conjugate gradients, iterated until the residual ‖b − A x‖ ≤ rtol ‖b‖.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Vaněk, P., Mandel, J., & Brezina, M. (1996). Algebraic multigrid by smoothed aggregation for second and
    fourth order elliptic problems. Computing, 56(3), 179–196.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, splu

__all__ = ["solve_pcg", "SAMultigrid", "pcg"]


class _Level:
    def __init__(self, A, P=None):
        self.A = A.tocsr()
        self.dinv = (1.0 / self.A.diagonal())[:, None]
        self.P = P
        self.R = P.T.tocsr() if P is not None else None


def _aggregate(coords: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """2x2 block aggregation of grid points (n, 2) -> (aggregate id per point, coarse coords)."""
    blocks = coords // 2
    key = blocks[:, 0].astype(np.int64) * (int(blocks[:, 1].max()) + 1) + blocks[:, 1]
    uniq, agg = np.unique(key, return_inverse=True)
    first = np.zeros(uniq.size, np.int64)
    first[agg] = np.arange(agg.size)
    return agg, blocks[first]


class SAMultigrid:
    """Smoothed-aggregation hierarchy for an SPD grid matrix ``A`` whose unknowns sit at ``coords`` (row, col)."""

    def __init__(self, A, coords, coarse_size: int = 1500, omega: float = 2.0 / 3.0, sweeps: int = 1):
        self.omega, self.sweeps = omega, sweeps
        self.levels = []
        A = A.tocsr()
        coords = np.asarray(coords, np.int64)
        while A.shape[0] > coarse_size and len(self.levels) < 20:
            agg, coords_c = _aggregate(coords)
            n, nc = A.shape[0], coords_c.shape[0]
            if nc >= n:  # cannot coarsen further
                break
            P0 = sp.csr_matrix((np.ones(n), (np.arange(n), agg)), shape=(n, nc))
            dinv = 1.0 / A.diagonal()  # (n,)
            P = (P0 - omega * sp.diags(dinv) @ (A @ P0)).tocsr()
            self.levels.append(_Level(A, P))
            A = (P.T @ A @ P).tocsr()
            coords = coords_c
        self.levels.append(_Level(A))
        self.coarse = splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A")

    def _smooth(self, lvl, x, b):
        for _ in range(self.sweeps):
            x = x + self.omega * lvl.dinv * (b - lvl.A @ x)
        return x

    def vcycle(self, b, k=0):
        """One symmetric V-cycle from x = 0 for right-hand sides b (n, C)."""
        lvl = self.levels[k]
        if k == len(self.levels) - 1:
            return self.coarse.solve(b)
        x = self.omega * lvl.dinv * b  # first Jacobi sweep from x = 0
        x = self._smooth(lvl, x, b) if self.sweeps > 1 else x
        r = b - lvl.A @ x
        x = x + lvl.P @ self.vcycle(lvl.R @ r, k + 1)
        return self._smooth(lvl, x, b)

    def preconditioner(self) -> LinearOperator:
        n = self.levels[0].A.shape[0]
        return LinearOperator((n, n), matvec=lambda v: self.vcycle(np.asarray(v).reshape(-1, 1))[:, 0], dtype=np.float64)


def solve_pcg(A, B: np.ndarray, coords: np.ndarray, rtol: float = 1e-10, maxiter: int = 500) -> np.ndarray:
    """Solve ``A X = B`` (B (n, C)) by SA-multigrid preconditioned CG to relative residual ``rtol``."""
    mg = SAMultigrid(A, coords)
    x, _ = pcg(mg.levels[0].A, np.asarray(B, np.float64).reshape(A.shape[0], -1), mg.vcycle, rtol, maxiter)
    return x

def pcg(A, b: np.ndarray, precond, rtol: float = 1e-10, maxiter: int = 500) -> tuple[np.ndarray, int]:
    """Preconditioned conjugate gradients from x = 0 for all columns of ``b`` (n, C) at once.

    Stops when every column satisfies ‖b − A x‖ ≤ rtol ‖b‖; returns (x, iterations).
    """
    x = np.zeros_like(b)
    r = b.copy()
    bnorm = np.linalg.norm(b, axis=0)
    bnorm[bnorm == 0] = 1.0
    z = precond(r)
    p = z.copy()
    rz = np.einsum("ij,ij->j", r, z)
    for it in range(1, maxiter + 1):
        Ap = A @ p
        pAp = np.einsum("ij,ij->j", p, Ap)
        alpha = np.divide(rz, pAp, out=np.zeros_like(rz), where=pAp != 0)
        x += alpha * p
        r -= alpha * Ap
        if np.all(np.linalg.norm(r, axis=0) <= rtol * bnorm):
            return x, it
        z = precond(r)
        rz_new = np.einsum("ij,ij->j", r, z)
        beta = np.divide(rz_new, rz, out=np.zeros_like(rz), where=rz != 0)
        p = z + beta * p
        rz = rz_new
    raise RuntimeError(f"multigrid-preconditioned CG did not converge in {maxiter} iterations")
