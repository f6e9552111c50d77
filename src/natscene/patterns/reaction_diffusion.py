"""Venation-aware reaction-diffusion of Dong 2007 §3.3.2 (Eqs. 3.1, 3.3, 3.4', 3.5).

Kinetics (Schnakenberg, Eq. 3.3, in the discrete form of Eq. 3.5) for pigment concentrations a, b:

    dA = S_A (a^2 b - K_A a + beta) + D_A l^(a)
    dB = S_B (1 - K_B a^2 b)        + D_B l^(b)

with the homogeneous steady state a* = (beta + 1/K_B) / K_A, b* = 1 / (K_B a*^2).

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

Hormone supply. The pigment composition is "controlled by some key hormones ... composed in reproduction
organs ... and then transported all over the petal by the vascular system" (§3.1). The vein root (the
petal base, next to the reproductive organs) is therefore held at a supply state (a_root, b_root) =
root_supply * (a*, b*) (Dirichlet condition at the root cell); with root_supply = (1, 1) and no noise
the uniform steady state is an exact solution, so every pattern comes from the supply, the venation, the
petal shape and (for Turing-unstable parameters) the initial noise.

Time stepping: Euler on Eq. 3.5 (dt = 1 is the paper's "Delta A per iteration"), float32, with the
reaction linearised per cell on its own species (semi-implicit, diagonal: the update of a is divided by
1 + dt max(-dR_a/da, 0) = 1 + dt max(S_A (K_A - 2ab), 0), that of b by 1 + dt S_B K_B a^2; same steady
states, explicit cost, and stiff kinetics such as K_B ~ 1e8 no longer force dt ~ 1e-6), diffusion explicit
with the Laplacian split into the mesophyll part L_m (edges between two mesophyll cells) and the vascular
part L_v (every edge touching a vascular cell, including the non-adjacent links). Per step:
u' = u + dt (R(u) + D L_m u) / den, then m sub-steps u' += (dt/m) D L_v u' on the rows L_v touches.
Stability (all checked, InputError otherwise): reaction: spectral radius of the linearised semi-implicit
update at the homogeneous steady state <= 1 (``amplification``, ``stable_dt``);
mesophyll diffusion dt * D * rho(L_m) <= 1 with the Gershgorin bound rho <= 2 max|diag L_m| (which also
keeps the update monotone, so concentrations stay >= 0 for the diffusion part); vascular sub-steps
m = ceil(dt * D * 2 max|diag L_v|) so each sub-step satisfies the same bound.
Convergence ("a stable pattern"): the max relative change per unit time,
max |u^{n+1} - u^n| / (dt * max|u^n|) over both species, checked every ``check_every`` steps, < tol.
"""
from __future__ import annotations

from dataclasses import dataclass, field, asdict

import numpy as np
import scipy.sparse as sp

from natscene.errors import InputError
from natscene.patterns.venation import Venation

P_MM, P_MV, P_VV = 1.0, 2.0, 10.0


@dataclass
class RDParams:
    """Parameters of Eq. 3.5 (Table 3.1/3.3 names). S sets S_A = S_B unless they are given."""

    S: float = 0.1
    D_A: float = 0.15
    D_B: float = 0.1
    t: float = 2.0
    K_A: float = 1.0
    K_B: float = 1.0
    beta: float = 0.5
    S_A: float | None = None
    S_B: float | None = None
    p_mm: float = P_MM
    p_mv: float = P_MV
    p_vv: float = P_VV
    root_supply: tuple = (1.0, 1.0)
    noise: float = 0.01
    dt: float = 1.0
    max_steps: int = 4000
    tol: float = 1e-4
    check_every: int = 10
    n_dyadic: int = 8
    seed: int = 0
    #: "explicit" (Euler, dt ~ 1, the paper's per-iteration update) or "implicit" (Strang splitting: exact-ish
    #: local reaction by implicit Euler + implicit diffusion with a cached sparse LU; dt up to ~1/rate, for the
    #: slow kinetics of the Fig. 3.3 presets; its ``tol`` applies to the relative change per step)
    scheme: str = "explicit"
    #: implicit scheme only: Anderson mixing depth (0 = plain Strang steps)
    anderson: int = 0

    @property
    def sa(self) -> float:
        return self.S if self.S_A is None else self.S_A

    @property
    def sb(self) -> float:
        return self.S if self.S_B is None else self.S_B

    def steady_state(self) -> tuple[float, float]:
        a = (self.beta + 1.0 / self.K_B) / self.K_A
        return a, 1.0 / (self.K_B * a * a)

    def jacobian(self) -> np.ndarray:
        """Reaction Jacobian of Eq. 3.5 at the homogeneous steady state."""
        a, b = self.steady_state()
        return np.array([[self.sa * (2 * a * b - self.K_A), self.sa * a * a],
                         [-self.sb * self.K_B * 2 * a * b, -self.sb * self.K_B * a * a]])

    def to_dict(self) -> dict:
        d = asdict(self)
        d["root_supply"] = list(self.root_supply)
        return d


def transport(wa, wb, va, vb, p_mm=P_MM, p_mv=P_MV, p_vv=P_VV, dist=1.0):
    """Eq. 3.1: I(a, b) for cells with widths wa, wb and vascular flags va, vb (arrays), distance dist."""
    wa, wb = np.asarray(wa, float), np.asarray(wb, float)
    va, vb = np.asarray(va, bool), np.asarray(vb, bool)
    one = np.where(va, wa, wb)
    return np.where(va & vb, p_vv * 0.5 * (wa + wb), np.where(va | vb, p_mv * one, p_mm)) / dist


def _edges(mask, venation, t, p_mm=P_MM, p_mv=P_MV, p_vv=P_VV, n_dyadic=8):
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


def _assemble(n, edges):
    i, j, k = (np.concatenate(x) if x else np.zeros(0) for x in edges)
    i, j = i.astype(np.int64), j.astype(np.int64)
    W = sp.csr_matrix((np.r_[k, k], (np.r_[i, j], np.r_[j, i])), shape=(n, n))
    deg = np.asarray(W.sum(axis=1)).ravel()
    return (0.25 * (W - sp.diags(deg))).tocsr()


def laplacian(mask: np.ndarray, venation: Venation | None, t: float, p_mm=P_MM, p_mv=P_MV, p_vv=P_VV,
              n_dyadic: int = 8):
    """The modified Laplacian of Eq. 3.4' as a sparse (N, N) matrix over the petal cells (see module
    docstring), and the flat indices of those cells in the (H, W) grid."""
    cells, _, mes, vsc = _edges(mask, venation, t, p_mm, p_mv, p_vv, n_dyadic)
    n = cells.size
    return _assemble(n, mes) + _assemble(n, vsc), cells


def amplification(p: RDParams, dt: float | None = None) -> np.ndarray:
    """Per-step amplification matrix of the reaction update at the homogeneous steady state: the
    semi-implicit scheme ``u' = u + dt R(u) / (1 + dt max(-dR_i/du_i, 0))`` linearised, i.e.
    ``G = I + dt diag(1 / (1 + dt max(-J_ii, 0))) J``."""
    dt = p.dt if dt is None else dt
    J = p.jacobian()
    den = 1.0 + dt * np.maximum(-np.diag(J), 0.0)
    return np.eye(2) + dt * J / den[:, None]


def _reaction_stable(p: RDParams, dt: float) -> bool:
    grow = float(np.linalg.eigvals(p.jacobian()).real.max())
    bound = max(1.0, float(np.exp(min(dt * grow, 50.0))))
    return float(np.abs(np.linalg.eigvals(amplification(p, dt))).max()) <= bound * (1 + 1e-9)


def stable_dt(p: RDParams) -> float:
    """Largest dt for which the semi-implicit reaction update is linearly stable at the homogeneous steady
    state (spectral radius of ``amplification`` <= 1, or <= exp(dt max Re lambda(J)) where the kinetics
    themselves grow), found on a log grid 1e-6..1e6 (every smaller grid dt must pass too)."""
    best = 0.0
    for dt in np.logspace(-6, 6, 481):
        if not _reaction_stable(p, float(dt)):
            break
        best = float(dt)
    return best


@dataclass
class RDResult:
    a: np.ndarray  # (H, W), NaN-free, 0 outside the petal
    b: np.ndarray
    steps: int
    converged: bool
    residual: float
    history: list = field(default_factory=list)


def schnakenberg_constants(a_m: float, b_m: float, K_A: float) -> dict:
    """K_A, K_B, beta of Eq. 3.5 for the classical non-dimensional Schnakenberg kinetics u' = a - u + u^2 v,
    v' = b - u^2 v (Murray 2003, Eq. 2.8; steady state u* = a + b, v* = b / (a + b)^2) on the time scale 1/(S K_A).
    Eq. 3.5 with S_A = S_B = S maps onto it by a = lambda u, b = mu v with lambda = sqrt(K_A / K_B),
    mu = sqrt(K_A K_B), tau = S K_A t, hence K_B = 1 / (b^2 K_A^3) and beta = a b K_A^3."""
    return dict(K_A=float(K_A), K_B=float(1.0 / (b_m * b_m * K_A ** 3)), beta=float(a_m * b_m * K_A ** 3))


def _react_implicit(a, b, dt, sa, sb, ka, kb, beta, iters=4):
    """Implicit Euler on the local kinetics of Eq. 3.5 (no diffusion), Newton on the 2x2 system per cell."""
    a0, b0 = a, b
    a, b = a.copy(), b.copy()
    for _ in range(iters):
        ab = a * b
        a2b = ab * a
        fa = a - a0 - dt * sa * (a2b - ka * a + beta)
        fb = b - b0 - dt * sb * (1.0 - kb * a2b)
        j11 = 1.0 - dt * sa * (2.0 * ab - ka)
        j12 = -dt * sa * a * a
        j21 = 2.0 * dt * sb * kb * ab
        j22 = 1.0 + dt * sb * kb * a * a
        det = j11 * j22 - j12 * j21
        a = np.maximum(a - (j22 * fa - j12 * fb) / det, 1e-3 * a)
        b = np.maximum(b - (j11 * fb - j21 * fa) / det, 1e-3 * b)
    return a, b


def _strang_step(lus, a, b, p, root, ra, rb):
    """One Strang step of Eq. 3.5: half-step implicit diffusion, implicit-Euler kinetics, half-step diffusion."""
    an, bn = lus[0].solve(a), lus[1].solve(b)
    an, bn = _react_implicit(an, bn, p.dt, p.sa, p.sb, p.K_A, p.K_B, p.beta)
    if root is not None:
        an[root], bn[root] = ra, rb
    return lus[0].solve(an), lus[1].solve(bn)


def _anderson(hist_x, hist_g, x, g):
    """Anderson acceleration (type II, Walker & Ni 2011, Eq. for AA(m)) of the fixed-point map Phi with residual
    g = Phi(x) - x: x' = x + g - (dX + dG) gamma, gamma = argmin ||g - dG gamma|| over the last m differences."""
    dX = np.diff(np.array(hist_x), axis=0).T
    dG = np.diff(np.array(hist_g), axis=0).T
    gamma = np.linalg.lstsq(dG, g, rcond=None)[0]
    return x + g - (dX + dG) @ gamma


def _simulate_implicit(p, cells, L, a, b, root, ra, rb, logger, progress_every):
    """Strang splitting of Eq. 3.5: half a step of diffusion (I - dt/2 D L) u' = u (sparse LU, factorised once
    per species), a full step of the local kinetics by implicit Euler, the other half step of diffusion. Both
    parts are unconditionally stable, so dt can be a sizeable fraction of 1 / (S K_A) and a slow-kinetics
    pattern (reaction lengths of tens of cells) settles in tens of steps instead of ~1e5 explicit iterations.
    The root (Dirichlet supply) row is the identity. The steps are a fixed-point iteration u <- Phi(u) whose fixed
    point is the stable pattern; with ``anderson`` = m > 0 it is accelerated by Anderson mixing over the last m
    steps (same fixed point, so the same pattern, in fewer steps); a mixed iterate that leaves the positive
    cone or raises the residual tenfold is dropped for the plain step and the history restarted."""
    import scipy.sparse.linalg as spl
    n = cells.size
    fix = np.zeros(n, bool)
    if root is not None:
        fix[root] = True
    keep = sp.diags((~fix).astype(float))
    Lk = (keep @ L).tocsc()
    eye = sp.identity(n, format="csc")
    # symmetric pattern (the root row aside): minimum-degree ordering on A + A^T halves the LU fill of COLAMD
    lus = [spl.splu((eye - 0.5 * p.dt * D * Lk).tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options=dict(SymmetricMode=True)) for D in (p.D_A, p.D_B)]
    a_ref, b_ref = (max(float(v), 1e-300) for v in p.steady_state())
    m = int(p.anderson)
    hist_x, hist_g = [], []
    steps, res, history, converged, best = 0, np.inf, [], False, np.inf
    for steps in range(1, p.max_steps + 1):
        an, bn = _strang_step(lus, a, b, p, root, ra, rb)
        # max relative change per step (not per unit time: dt is ~1e5 here, which would hide any change)
        res = float(max(np.abs(an - a).max() / max(float(a.max()), 1e-300),
                        np.abs(bn - b).max() / max(float(b.max()), 1e-300)))
        history.append((steps, res))
        if not np.isfinite(res):
            raise InputError("reaction-diffusion diverged (non-finite values); lower dt")
        if logger is not None and steps % max(progress_every // 50, 1) == 0:
            logger.info(f"reaction-diffusion (implicit) step {steps}/{p.max_steps}: max relative change "
                        f"{res:.3g} per step (tol {p.tol:g})")
        if res < p.tol:
            a, b = an, bn
            converged = True
            break
        if m <= 0:
            a, b = an, bn
            continue
        x = np.concatenate([a / a_ref, b / b_ref])
        g = np.concatenate([an / a_ref, bn / b_ref]) - x
        if res > 10.0 * best:
            hist_x, hist_g = [], []
        best = min(best, res)
        hist_x.append(x)
        hist_g.append(g)
        if len(hist_x) > m + 1:
            hist_x.pop(0)
            hist_g.pop(0)
        if len(hist_x) < 2:
            a, b = an, bn
            continue
        xn = _anderson(hist_x, hist_g, x, g)
        am, bm = xn[:n] * a_ref, xn[n:] * b_ref
        if (am > 0).all() and (bm > 0).all():
            if root is not None:
                am[root], bm[root] = ra, rb
            a, b = am, bm
        else:
            hist_x, hist_g = [], []
            a, b = an, bn
    return a, b, steps, converged, res, history


def _initial_state(mask, venation, p, cells, init, dtype):
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


def simulate(mask: np.ndarray, venation: Venation | None, p: RDParams, init=None, logger=None,
             progress_every: int = 500) -> RDResult:
    """Run Eq. 3.5 on the petal ``mask`` until stable (or ``max_steps``). ``init``: optional (a, b) maps."""
    mask = np.asarray(mask, np.float32)
    if mask.ndim != 2 or (mask > 0.5).sum() < 4:
        raise InputError("petal mask must be a 2-D image with at least 4 petal pixels (white = petal)")
    for name in ("S", "D_A", "D_B", "K_A", "K_B", "dt"):
        if not getattr(p, name) > 0:
            raise InputError(f"reaction-diffusion parameter '{name}' must be > 0 (got {getattr(p, name)})")
    if p.scheme not in ("explicit", "implicit"):
        raise InputError(f"reaction-diffusion parameter 'scheme' must be 'explicit' or 'implicit' (got {p.scheme!r})")
    if p.scheme == "implicit":
        return _simulate_implicit_entry(mask, venation, p, init, logger, progress_every)
    if not _reaction_stable(p, p.dt):
        raise InputError(f"reaction-diffusion dt = {p.dt} exceeds the reaction stability limit "
                         f"{stable_dt(p):.4g} (spectral radius of the semi-implicit reaction update <= 1); "
                         f"lower 'dt' or 'S'")
    cells, _, mes, vsc = _edges(mask, venation, p.t, p.p_mm, p.p_mv, p.p_vv, p.n_dyadic)
    n = cells.size
    Lm = _assemble(n, mes)
    Dmax = max(p.D_A, p.D_B)
    rho_m = 2.0 * float(np.abs(Lm.diagonal()).max()) if n else 0.0
    if p.dt * Dmax * rho_m > 1.0 + 1e-9:
        raise InputError(f"reaction-diffusion dt = {p.dt} with D = {Dmax} exceeds the explicit diffusion "
                         f"limit dt * D * {rho_m:g} <= 1; lower 'dt' or the diffusion coefficients")
    Lm = Lm.astype(np.float32)
    Lv = _assemble(n, vsc)
    rows = np.unique(Lv.indices) if Lv.nnz else np.zeros(0, np.int64)
    if rows.size:
        Lv = Lv[rows][:, rows].tocsr().astype(np.float32)
        m_sub = max(1, int(np.ceil(p.dt * Dmax * 2.0 * float(np.abs(Lv.diagonal()).max()))))
    else:
        m_sub = 0
    a, b, root, ra, rb = _initial_state(mask, venation, p, cells, init, np.float32)
    h, w = mask.shape
    f32 = np.float32
    sa, sb, ka, kb, beta, dt = f32(p.sa), f32(p.sb), f32(p.K_A), f32(p.K_B), f32(p.beta), f32(p.dt)
    dA, dB = f32(p.dt * p.D_A), f32(p.dt * p.D_B)
    sA, sB = f32(p.dt * p.D_A / max(m_sub, 1)), f32(p.dt * p.D_B / max(m_sub, 1))
    steps, res, history, converged = 0, np.inf, [], False
    for steps in range(1, p.max_steps + 1):
        a2b = a * a * b
        # reaction linearised per cell on its own species (diagonal Jacobian), diffusion explicit
        den_a = 1 + dt * np.maximum(sa * (ka - 2 * a * b), 0)
        den_b = 1 + dt * sb * kb * a * a
        an = a + (dt * sa * (a2b - ka * a + beta) + dA * (Lm @ a)) / den_a
        bn = b + (dt * sb * (1 - kb * a2b) + dB * (Lm @ b)) / den_b
        if m_sub:
            av, bv = an[rows], bn[rows]
            for _ in range(m_sub):
                av += sA * (Lv @ av)
                bv += sB * (Lv @ bv)
            an[rows], bn[rows] = av, bv
        np.maximum(an, 0, out=an)
        np.maximum(bn, 0, out=bn)
        if root is not None:
            an[root], bn[root] = ra, rb
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
    A = np.zeros(h * w, np.float32)
    B = np.zeros(h * w, np.float32)
    A[cells], B[cells] = a, b
    return RDResult(A.reshape(h, w), B.reshape(h, w), steps, converged, res, history)


def _simulate_implicit_entry(mask, venation, p, init, logger, progress_every):
    cells, _, mes, vsc = _edges(mask, venation, p.t, p.p_mm, p.p_mv, p.p_vv, p.n_dyadic)
    n = cells.size
    L = (_assemble(n, mes) + _assemble(n, vsc)).tocsr()
    a, b, root, ra, rb = _initial_state(mask, venation, p, cells, init, np.float64)
    h, w = mask.shape
    a, b, steps, converged, res, history = _simulate_implicit(p, cells, L, a, b, root, ra, rb,
                                                              logger, progress_every)
    A = np.zeros(h * w, np.float32)
    B = np.zeros(h * w, np.float32)
    A[cells], B[cells] = a, b
    return RDResult(A.reshape(h, w), B.reshape(h, w), steps, converged, res, history)


def normalise(conc: np.ndarray, mask: np.ndarray, c0: float | None = None, mode: str = "max") -> np.ndarray:
    """Pigment distribution map (§3.3.2), 0 off-petal, clipped to [0, 1].

    ``mode="max"``: c = C / C_0 (the paper's normalisation), C_0 = the highest concentration on the petal unless
    given. ``mode="range"``: c = (C - C_min) / (C_0 - C_min), i.e. the lowest concentration on the petal is taken
    as the pigment-free level. A steady state of Eq. 3.5 sits on the positive homogeneous state a*, b* and the
    patterns are deviations of 10-60 % from it, so C / C_max keeps the whole pattern in the top of the colour
    range; "range" maps it onto the full range of the pigment database (Fig. 3.3's dark-on-white maps)."""
    inside = np.asarray(mask) > 0.5
    if mode not in ("max", "range"):
        raise InputError(f"pigment map normalisation '{mode}': use 'max' (C / C_0) or 'range'")
    c0 = float(conc[inside].max()) if c0 is None else float(c0)
    lo = float(conc[inside].min()) if mode == "range" else 0.0
    span = c0 - lo
    out = np.where(inside, (conc - lo) / span if span > 0 else 0.0, 0.0)
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def growth_rate(p: RDParams, q: np.ndarray) -> np.ndarray:
    """Largest real part of the eigenvalues of J - (q^2 / 4) diag(D_A, D_B) (per step) for wavenumbers q
    (rad/pixel): the linear stability of Eq. 3.5 with the continuum limit of the 5-point l (= grad^2 / 4)."""
    J = p.jacobian()
    q = np.atleast_1d(np.asarray(q, float))
    mu = q * q / 4.0
    tr = J[0, 0] + J[1, 1] - mu * (p.D_A + p.D_B)
    det = (J[0, 0] - p.D_A * mu) * (J[1, 1] - p.D_B * mu) - J[0, 1] * J[1, 0]
    disc = tr * tr / 4 - det
    return np.where(disc >= 0, tr / 2 + np.sqrt(np.maximum(disc, 0)), tr / 2)


def fastest_wavelength(p: RDParams) -> float:
    """Wavelength (pixels) of the fastest-growing mode; inf when no mode grows (no Turing instability)."""
    q = np.linspace(1e-3, np.pi, 20000)
    g = growth_rate(p, q)
    i = int(np.argmax(g))
    return float(2 * np.pi / q[i]) if g[i] > 0 else float("inf")


def dominant_wavelength(field2d: np.ndarray) -> float:
    """Wavelength (pixels) of the radially averaged power-spectrum peak of a square field (mean removed)."""
    f = np.asarray(field2d, float)
    f = f - f.mean()
    n = min(f.shape)
    P = np.abs(np.fft.fft2(f[:n, :n])) ** 2
    k = np.fft.fftfreq(n) * n
    kr = np.hypot(*np.meshgrid(k, k, indexing="ij"))
    bins = np.rint(kr).astype(int)
    power = np.bincount(bins.ravel(), P.ravel()) / np.maximum(np.bincount(bins.ravel()), 1)
    power[0] = 0
    power = power[: n // 2]
    i = int(np.argmax(power))
    # sub-bin refinement: power-weighted mean over the peak's neighbours
    lo, hi = max(i - 1, 1), min(i + 2, power.size)
    kk = np.arange(lo, hi)
    kpk = float((power[lo:hi] * kk).sum() / power[lo:hi].sum())
    return n / kpk
