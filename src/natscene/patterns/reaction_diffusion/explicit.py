"""
Explicit reaction-diffusion update
==================================

Defines Dong's (2007) reaction-diffusion update, Eq. 3.5, stepped explicitly (§3.3.2):

-   :func:`eq35_step`: one step of Eq. 3.5 on the petal cells, with the operators of :class:`Eq35Operators`.
-   :func:`simulate_explicit`: Eq. 3.5 stepped on a petal until the pattern is stable.

Time stepping: Euler on Eq. 3.5 (dt = 1 is the paper's "Delta A per iteration"), float32, with the
reaction linearised per cell on its own species (semi-implicit, diagonal: the update of a is divided by
1 + dt max(-dR_a/da, 0) = 1 + dt max(S_A (K_A - 2ab), 0), that of b by 1 + dt S_B K_B a^2; same steady
states, explicit cost, and stiff kinetics such as K_B ~ 1e8 no longer force dt ~ 1e-6), diffusion explicit
with the Laplacian split into the mesophyll part L_m (edges between two mesophyll cells) and the vascular
part L_v (every edge touching a vascular cell, including the non-adjacent links). Per step:
u' = u + dt (R(u) + D L_m u) / den, then m sub-steps u' += (dt/m) D L_v u' on the rows L_v touches.

Stability (all checked, InputError otherwise): reaction: spectral radius of the linearised semi-implicit
update at the homogeneous steady state <= 1 (:mod:`natscene.patterns.reaction_diffusion.stability`);
mesophyll diffusion dt * D * rho(L_m) <= 1 with the Gershgorin bound rho <= 2 max|diag L_m| (which also
keeps the update monotone, so concentrations stay >= 0 for the diffusion part); vascular sub-steps
m = ceil(dt * D * 2 max|diag L_v|) so each sub-step satisfies the same bound.

Convergence ("a stable pattern"): the max relative change per unit time,
max |u^{n+1} - u^n| / (dt * max|u^n|) over both species, checked every ``check_every`` steps, < tol.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from natscene.errors import InputError
from natscene.patterns.reaction_diffusion.laplacian import assemble, laplacian_edges
from natscene.patterns.reaction_diffusion.parameters import RDParams
from natscene.patterns.reaction_diffusion.stability import reaction_stable, stable_dt
from natscene.patterns.reaction_diffusion.state import RDResult, initial_state, on_grid

__all__ = ["Eq35Operators", "eq35_step", "simulate_explicit"]


class Eq35Operators(NamedTuple):
    """What one step of Eq. 3.5 needs besides the state (a, b): the float32 constants (S_A, S_B, K_A, K_B,
    beta, dt; dt D_A and dt D_B for the mesophyll diffusion, dt D / m per vascular sub-step), the split
    Laplacian (L_m over all cells, L_v over its ``rows``, ``m_sub`` sub-steps) and the vein-root supply."""

    sa: np.float32
    sb: np.float32
    ka: np.float32
    kb: np.float32
    beta: np.float32
    dt: np.float32
    dA: np.float32
    dB: np.float32
    sA: np.float32
    sB: np.float32
    Lm: object
    Lv: object
    rows: np.ndarray
    m_sub: int
    root: int | None
    ra: np.float32
    rb: np.float32


def eq35_step(a: np.ndarray, b: np.ndarray, op: Eq35Operators) -> tuple[np.ndarray, np.ndarray]:
    """One step of Dong's Eq. 3.5 on the petal cells (float32 (N,) each):
    a' = a + dt (S_A (a^2 b - K_A a + beta) + D_A l^(a)) / den_a, b' = b + dt (S_B (1 - K_B a^2 b) + D_B l^(b)) / den_b
    with the mesophyll Laplacian, then the vascular sub-steps, clipped at 0, the vein root held at its supply."""
    sa, sb, ka, kb, beta, dt = op.sa, op.sb, op.ka, op.kb, op.beta, op.dt
    dA, dB, sA, sB, Lm, Lv, rows = op.dA, op.dB, op.sA, op.sB, op.Lm, op.Lv, op.rows
    a2b = a * a * b
    # reaction linearised per cell on its own species (diagonal Jacobian), diffusion explicit
    den_a = 1 + dt * np.maximum(sa * (ka - 2 * a * b), 0)
    den_b = 1 + dt * sb * kb * a * a
    an = a + (dt * sa * (a2b - ka * a + beta) + dA * (Lm @ a)) / den_a
    bn = b + (dt * sb * (1 - kb * a2b) + dB * (Lm @ b)) / den_b
    if op.m_sub:
        av, bv = an[rows], bn[rows]
        for _ in range(op.m_sub):
            av += sA * (Lv @ av)
            bv += sB * (Lv @ bv)
        an[rows], bn[rows] = av, bv
    np.maximum(an, 0, out=an)
    np.maximum(bn, 0, out=bn)
    if op.root is not None:
        an[op.root], bn[op.root] = op.ra, op.rb
    return an, bn


def simulate_explicit(mask: np.ndarray, venation, p: RDParams, init=None, logger=None,
                      progress_every: int = 500) -> RDResult:
    """Eq. 3.5 stepped by :func:`eq35_step` until stable (or ``max_steps``), after the stability checks."""
    if not reaction_stable(p, p.dt):
        raise InputError(f"reaction-diffusion dt = {p.dt} exceeds the reaction stability limit "
                         f"{stable_dt(p):.4g} (spectral radius of the semi-implicit reaction update <= 1); "
                         f"lower 'dt' or 'S'")
    cells, _, mes, vsc = laplacian_edges(mask, venation, p.t, p.p_mm, p.p_mv, p.p_vv, p.n_dyadic)
    n = cells.size
    Lm = assemble(n, mes)
    Dmax = max(p.D_A, p.D_B)
    rho_m = 2.0 * float(np.abs(Lm.diagonal()).max()) if n else 0.0
    if p.dt * Dmax * rho_m > 1.0 + 1e-9:
        raise InputError(f"reaction-diffusion dt = {p.dt} with D = {Dmax} exceeds the explicit diffusion "
                         f"limit dt * D * {rho_m:g} <= 1; lower 'dt' or the diffusion coefficients")
    Lm = Lm.astype(np.float32)
    Lv = assemble(n, vsc)
    rows = np.unique(Lv.indices) if Lv.nnz else np.zeros(0, np.int64)
    if rows.size:
        Lv = Lv[rows][:, rows].tocsr().astype(np.float32)
        m_sub = max(1, int(np.ceil(p.dt * Dmax * 2.0 * float(np.abs(Lv.diagonal()).max()))))
    else:
        m_sub = 0
    a, b, root, ra, rb = initial_state(mask, venation, p, cells, init, np.float32)
    f32 = np.float32
    op = Eq35Operators(f32(p.sa), f32(p.sb), f32(p.K_A), f32(p.K_B), f32(p.beta), f32(p.dt),
                       f32(p.dt * p.D_A), f32(p.dt * p.D_B),
                       f32(p.dt * p.D_A / max(m_sub, 1)), f32(p.dt * p.D_B / max(m_sub, 1)),
                       Lm, Lv, rows, m_sub, root, ra, rb)
    steps, res, history, converged = 0, np.inf, [], False
    for steps in range(1, p.max_steps + 1):
        an, bn = eq35_step(a, b, op)
        if steps % p.check_every == 0 or steps == p.max_steps:
            res = float(max(np.abs(an - a).max() / max(float(a.max()), 1e-30),
                            np.abs(bn - b).max() / max(float(b.max()), 1e-30)) / p.dt)
            history.append((steps, res))
            if logger is not None and steps % progress_every == 0:
                logger.info(f"reaction-diffusion step {steps}/{p.max_steps}: max relative change {res:.3g} "
                            f"per unit time (tol {p.tol:g})")
            if not np.isfinite(res):
                raise InputError("reaction-diffusion diverged (non-finite values); lower dt or S")
        a, b = an, bn
        if res < p.tol:
            converged = True
            break
    return RDResult(on_grid(a, cells, mask.shape), on_grid(b, cells, mask.shape), steps, converged, res, history)
