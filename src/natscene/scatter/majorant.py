"""
Local majorants
===============

Defines free-flight sampling through a grid of local majorants (delta tracking with a DDA traversal):

-   :class:`MajorantGrid`, :func:`majorant_grid`: the per-cell density majorants of a volume.
-   :func:`flight_event`: one event of delta tracking (a tentative collision or a cell crossed).

Delta (Woodcock) tracking samples a free flight in a heterogeneous medium mu_t(x) = sigma_t k rho(x) by
tentative collisions at the rate of a majorant mu_bar >= mu_t, each accepted with probability
mu_t(x) / mu_bar (Woodcock et al. 1965; Novák et al. 2018, "Monte Carlo methods for volumetric light
transport simulation", §3). With one global majorant, a cloud that fills a fifth of its box wastes most
tentative collisions in empty space. Here the box is divided into cells of ``block`` voxels; each cell's
majorant is the largest density of its voxels and their neighbours (the trilinear density inside a cell
never exceeds it), and a ray crosses the cells with a 3-D DDA (Amanatides & Woo 1987): within a cell the
exponential optical depth is consumed at the cell's rate. Empty space is skipped: in an empty cell whose
nearest occupied cell is d cells away (chessboard distance), the ray jumps (d - 1) cell widths at once and
the DDA restarts there. Unbiased: every tentative collision is accepted with mu_t / mu_bar_cell <= 1, and
nothing can collide in empty cells.

References
----------
-   Amanatides, J., & Woo, A. (1987). A fast voxel traversal algorithm for ray tracing. Eurographics '87, 3–10.
-   Novák, J., Georgiev, I., Hanika, J., & Jarosz, W. (2018). Monte Carlo methods for volumetric light transport
    simulation. Computer Graphics Forum, 37(2).
-   Woodcock, E., Murphy, T., Hemmings, P., & Longworth, S. (1965). Techniques used in the GEM code for Monte Carlo
    neutronics calculations in reactors and other systems of complex geometry. Proceedings of the Conference on
    Applications of Computing Methods to Reactor Problems, Argonne National Laboratory.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import natscene.variant  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit loads)
import drjit as dr
import mitsuba as mi

__all__ = ["MajorantGrid", "majorant_grid", "flight_event"]



@dataclass
class MajorantGrid:
    """Per-cell density majorants of a volume: ``values`` (cz, cy, cx), cells of ``block`` voxels."""

    block: int
    shape: tuple            # (cx, cy, cz)
    origin: np.ndarray      # world position of the grid corner (= bbox_min)
    cell: np.ndarray        # world size of a cell (3,)
    values: np.ndarray      # float32 (cz, cy, cx)
    dr_values: object       # mi.Float, flat
    dr_skip: object = None  # mi.Float, flat: safe jump through an empty cell (chessboard distance - 1, cells)

    def empty_jump(self, p):
        """At points ``p`` (mi.Point3f): the distance that a ray from ``p`` can travel in any direction without
        meeting density where ``p``'s cell is empty (its chessboard distance to the nearest occupied cell, less
        one, in cell widths), -1 where the cell holds density."""
        cx, cy, cz = self.shape
        lo = mi.ScalarVector3f(*[float(v) for v in self.origin])
        cell = mi.ScalarVector3f(*[float(v) for v in self.cell])
        c = (p - lo) / cell
        ix = mi.UInt32(dr.clip(dr.floor(c.x), 0, cx - 1))
        iy = mi.UInt32(dr.clip(dr.floor(c.y), 0, cy - 1))
        iz = mi.UInt32(dr.clip(dr.floor(c.z), 0, cz - 1))
        flat = (iz * cy + iy) * cx + ix
        empty = dr.gather(mi.Float, self.dr_values, flat) <= 0
        return dr.select(empty, dr.gather(mi.Float, self.dr_skip, flat), -1.0)

    def empty_steps(self, p, h):
        """Steps of length ``h`` that a march sampling at ``p`` advances: every step within ``p``'s safe jump
        (:meth:`empty_jump`) when its cell is empty, else one."""
        return dr.maximum(dr.floor(self.empty_jump(p) / dr.maximum(h, 1e-30)), 1.0)

    def occupied_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World box of the cells with a non-zero majorant (where anything can collide)."""
        nz = np.argwhere(self.values > 0)
        if nz.size == 0:
            return self.origin.copy(), self.origin.copy()
        lo_c = nz.min(0)[::-1]
        hi_c = nz.max(0)[::-1] + 1
        return self.origin + lo_c * self.cell, self.origin + hi_c * self.cell


def majorant_grid(density: np.ndarray, bbox_min, bbox_max, block: int = 4) -> MajorantGrid:
    """Cell maxima of ``density`` [nz, ny, nx], dilated by one voxel (the trilinear lookup's support)."""
    from scipy.ndimage import maximum_filter
    d = np.asarray(density, np.float32)
    nz, ny, nx = d.shape
    block = max(1, int(block))
    dil = maximum_filter(d, size=3, mode="nearest")
    cz, cy, cx = -(-nz // block), -(-ny // block), -(-nx // block)
    pad = np.zeros((cz * block, cy * block, cx * block), np.float32)
    pad[:nz, :ny, :nx] = dil
    m = pad.reshape(cz, block, cy, block, cx, block).max(axis=(1, 3, 5))
    lo = np.asarray(bbox_min, np.float64)
    voxel = (np.asarray(bbox_max, np.float64) - lo) / np.array([nx, ny, nz])
    # empty-space skipping: every cell within chessboard distance d - 1 of an empty cell whose nearest occupied
    # cell is d cells away is empty, so a ray in it can advance (d - 1) cell widths without meeting density
    from scipy.ndimage import distance_transform_cdt
    if (m > 0).any():
        dist = distance_transform_cdt(m <= 0, metric="chessboard").astype(np.float32)
    else:
        dist = np.full(m.shape, float(max(m.shape)), np.float32)
    skip = np.maximum(dist - 1.0, 0.0) * float(np.min(voxel * block))
    return MajorantGrid(block, (cx, cy, cz), lo, voxel * block, m, mi.Float(m.ravel()), mi.Float(skip.ravel()))


def _dda_state(p, w, t, grid: MajorantGrid):
    """Cell index and per-axis boundary parameters of the ray p + w t at parameter t."""
    cx, cy, cz = grid.shape
    lo = mi.ScalarVector3f(*[float(v) for v in grid.origin])
    cell = mi.ScalarVector3f(*[float(v) for v in grid.cell])
    q = (p + w * (t + 1e-6 * float(np.min(grid.cell))) - lo) / cell
    ix = mi.Int32(dr.clip(dr.floor(q.x), 0, cx - 1))
    iy = mi.Int32(dr.clip(dr.floor(q.y), 0, cy - 1))
    iz = mi.Int32(dr.clip(dr.floor(q.z), 0, cz - 1))
    big = 1e30
    okx, oky, okz = dr.abs(w.x) > 1e-12, dr.abs(w.y) > 1e-12, dr.abs(w.z) > 1e-12
    inv_x = dr.select(okx, dr.rcp(w.x), 0.0)
    inv_y = dr.select(oky, dr.rcp(w.y), 0.0)
    inv_z = dr.select(okz, dr.rcp(w.z), 0.0)
    tmx = dr.select(okx, (lo.x + (mi.Float(ix) + dr.select(w.x >= 0, 1.0, 0.0)) * cell.x - p.x) * inv_x, big)
    tmy = dr.select(oky, (lo.y + (mi.Float(iy) + dr.select(w.y >= 0, 1.0, 0.0)) * cell.y - p.y) * inv_y, big)
    tmz = dr.select(okz, (lo.z + (mi.Float(iz) + dr.select(w.z >= 0, 1.0, 0.0)) * cell.z - p.z) * inv_z, big)
    return ix, iy, iz, tmx, tmy, tmz


def flight_event(med, grid: MajorantGrid, p, w, sig_k, rng, running, restart, t, t1, tau, cells, rate_floor):
    """One event of delta tracking along the flight p + w s (s in [t, t1] inside the volume box): a tentative
    collision or a crossing into the next majorant cell (an empty-space jump counts as a crossing).

    ``cells`` = (ix, iy, iz, tmx, tmy, tmz), the DDA state (Amanatides & Woo 1987); lanes with ``restart`` set
    it up at t (a new flight). ``sig_k`` = sigma_t · extinction_scale (mu_t = sig_k · rho); ``tau`` the
    exponential optical depth left to the next tentative collision; ``rate_floor`` (1/world units) raises every
    non-empty cell's majorant to at least that rate (more null collisions: thin cloud still gets tally samples
    along each flight, and the flight's distribution is unchanged, since any majorant >= mu_t samples it exactly).

    Returns (t, tau, cells, x, ratio, inside, accept, escaped): ``inside`` marks the lanes whose event is a
    tentative collision at x, with ratio = mu_t(x) / mu_bar(x), ``accept`` the real ones among them (probability
    ratio), ``escaped`` the lanes whose flight left the box. The tentative collisions are a Poisson process of rate
    mu_bar along the flight, each reached with the transmittance T(x), so Σ ratio f(x) over them estimates the
    flight's track integral ∫ T mu_t f ds without bias (the expected-value estimator of delta tracking).
    """
    cx, cy, cz = grid.shape
    cell = mi.ScalarVector3f(*[float(v) for v in grid.cell])
    ix, iy, iz, tmx, tmy, tmz = cells
    big = 1e30
    sx = dr.select(w.x >= 0, 1, -1)
    sy = dr.select(w.y >= 0, 1, -1)
    sz = dr.select(w.z >= 0, 1, -1)
    dtx = dr.select(dr.abs(w.x) > 1e-12, cell.x / dr.abs(w.x), big)
    dty = dr.select(dr.abs(w.y) > 1e-12, cell.y / dr.abs(w.y), big)
    dtz = dr.select(dr.abs(w.z) > 1e-12, cell.z / dr.abs(w.z), big)
    # skip empty space: restart the DDA ``jump`` further on (nothing can collide on the way); a jump past the box
    # face ends the flight (restarting the DDA exactly at the face can cycle in float32). A new flight restarts
    # the DDA where it enters the box.
    go = running & ~restart
    flat = mi.UInt32((iz * cy + iy) * cx + ix)
    m = dr.gather(mi.Float, grid.dr_values, flat, go) * sig_k
    jump = dr.gather(mi.Float, grid.dr_skip, flat, go)
    skip = go & (m <= 0) & (jump > 0)
    leaves = skip & (t + jump >= t1)
    running = running & ~leaves
    skip = (skip & ~leaves) | restart
    t_j = dr.select(restart, t, t + jump)
    jx, jy, jz, jtx, jty, jtz = _dda_state(p, w, t_j, grid)
    t = dr.select(leaves, t1, dr.select(skip, t_j, t))
    ix, iy, iz = dr.select(skip, jx, ix), dr.select(skip, jy, iy), dr.select(skip, jz, iz)
    tmx, tmy, tmz = dr.select(skip, jtx, tmx), dr.select(skip, jty, tmy), dr.select(skip, jtz, tmz)
    flat = mi.UInt32((iz * cy + iy) * cx + ix)
    m = dr.gather(mi.Float, grid.dr_values, flat, running) * sig_k
    m = dr.select(m > 0, dr.maximum(m, rate_floor), m)
    t_next = dr.minimum(dr.minimum(dr.minimum(tmx, tmy), tmz), t1)
    seg = dr.maximum(t_next - t, 0.0)
    inside = running & (m * seg > tau)
    tc = t + tau / dr.maximum(m, 1e-30)
    x = p + w * tc
    r = med.rho(x)
    ratio = sig_k * r / dr.maximum(m, 1e-30)
    accept = inside & (rng.next_float32() * m < sig_k * r)
    # a rejected tentative collision restarts the exponential from tc in the same cell
    t = dr.select(inside, tc, t_next)
    tau = dr.select(inside, -dr.log(1.0 - rng.next_float32()), tau - m * seg)
    adv = running & ~inside
    ax = adv & (tmx <= tmy) & (tmx <= tmz)
    ay = adv & ~ax & (tmy <= tmz)
    az = adv & ~ax & ~ay
    ix = dr.select(ax, ix + sx, ix)
    tmx = dr.select(ax, tmx + dtx, tmx)
    iy = dr.select(ay, iy + sy, iy)
    tmy = dr.select(ay, tmy + dty, tmy)
    iz = dr.select(az, iz + sz, iz)
    tmz = dr.select(az, tmz + dtz, tmz)
    left = (ix < 0) | (ix >= cx) | (iy < 0) | (iy >= cy) | (iz < 0) | (iz >= cz) | (t >= t1)
    escaped = leaves | (adv & left)
    return t, tau, (ix, iy, iz, tmx, tmy, tmz), x, ratio, inside, accept, escaped
