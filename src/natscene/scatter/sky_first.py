"""
The skylight's first order by shadow rays
=========================================

Defines the sky's order-1 band of the all-orders transport (:mod:`natscene.scatter.allorders`), estimated at the
fine cache's cells by shadow rays instead of from the sky photons' first flights:

-   :class:`ShadowSamples`, :func:`shadow_samples`: points stratified in every occupied cell, one light direction
    each, and their optical depths toward the dome and toward the camera: one set per view and g grid, serving
    every (extinction, g) node.
-   :func:`first_order_numerators`: one node's cache numerators C_1 for the two independent halves.

The dome's light scattered once toward the camera at x is (Eq. 5's in-scatter with the sky in place of the sun)

    S_1(x) = ∫ L(-ω) exp(-sigma_t k D(x, -ω)) p(ω · ω_cam(x), g) dω,

ω the light's direction of travel, L(-ω) the radiance arriving from -ω in the four sky channels (the dome's R, G, B
above the horizon, the unit-radiance ground below, or a frame's ground in the cloud's shadow:
:class:`natscene.scatter.photons.SkySource`, :class:`natscene.scatter.skylight.GroundLight`), D(x, -ω) = ∫ rho ds
from x back to the box toward the source and ω_cam(x) the unit vector from x toward the camera. Each point draws ω
from a mixture q (multiple importance sampling, the balance heuristic: Veach & Guibas 1995) of the g grid's HG
lobes around ω_cam(x) (the phase function's forward peak, which at g 0.9 is about ±10° wide: the dome's own
directions rarely fall into it) and the dome's luminance (at small g the bright sky around the sun is what varies),
weighted by L p(g) / q; one sample set serves every g. The optical depths are marched once; each node's transmittances follow as
exp(-sigma_t k D).

The photon cache holds C_b(cell) = ∫_cell w sigma_t S_b dV, read through Q(cell) = ∫_cell w sigma_t dV
(:func:`natscene.scatter.inscatter.cache_fields`). Here the cell's S_1 is the ratio Σ w rho S_1 / Σ w rho over its
points (points uniform in 2 x 2 x 2 strata of the cell, w = exp(-sigma_t k D̃_cam) the camera transmittance): the
mean of S_1 weighted as a view ray weights it, as the tallies are; C_1 = S_1 Q. The estimate is consistent (a ratio
estimator: its bias falls as 1 / the points per cell) and noise-free in the light's direction where the cloud
is thin; the photons' order 1 needs a dome photon whose direction falls into the forward peak.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6), Eq. 5.
-   Veach, E., & Guibas, L. J. (1995). Optimally combining sampling techniques for Monte Carlo rendering.
    SIGGRAPH '95, 419–428.
-   Spanier, J., & Gelbard, E. M. (1969). Monte Carlo Principles and Neutron Transport Problems. Addison-Wesley
    (ratio estimators, next-event estimation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

from natscene.scatter.inscatter import CameraDepth
from natscene.scatter.medium import ray_box_dr
from natscene.scatter.phase import hg, hg_sample_cos

__all__ = ["ShadowSamples", "shadow_samples", "first_order_numerators", "DOME_SHARE"]

#: share of the points whose light direction is drawn by the dome's luminance (the rest from the phase functions'
#: lobes): where the phase function is broad, the bright sky around the sun is what varies
DOME_SHARE = 0.25


@dataclass
class ShadowSamples:
    """Points of the fine cache's cells with one light direction each (:func:`shadow_samples`)."""

    index: np.ndarray           # (N,) int32: half * cells + flat cell index
    rho: np.ndarray             # (N,) density at the point
    depth_camera: np.ndarray    # (N,) D̃_cam: ∫ rho toward the camera (world units), as the tallies' (CameraDepth)
    depth_light: np.ndarray     # (N,) D: ∫ rho from the point back toward the light's source
    cos_camera: np.ndarray      # (N,) ω · ω_cam
    inv_q: np.ndarray           # (N,) 1 / the mixture's pdf of ω
    radiance: np.ndarray        # (4, N) radiance arriving from -ω: dome R, G, B, ground
    cells: tuple                # (cz, cy, cx)
    depth_ground: np.ndarray | None = None   # (N,) D toward the sun from the ground point behind -ω (a shadowed
                                             # ground, :class:`natscene.scatter.skylight.GroundLight`), else None


def _occupied_cells(density: np.ndarray, factor: int) -> np.ndarray:
    """Cells of ``factor`` voxels whose trilinear density can be non-zero (a voxel with density within one)."""
    from scipy.ndimage import binary_dilation
    from natscene.scatter.inscatter import block_sum
    live = binary_dilation(np.asarray(density) > 0, iterations=1)
    return block_sum(live, factor) > 0


def _dome_cell(dome, src: np.ndarray) -> tuple:
    """(above the horizon, flat index of the dome's cell) of the unit directions ``src`` (toward the source): cells
    uniform in cos(zenith) and azimuth, as :class:`natscene.scatter.photons.SkySource`."""
    n_t, n_p = np.asarray(dome.rgb).shape[:2]
    it = np.clip(np.floor((1.0 - src[:, 1]) * n_t), 0, n_t - 1).astype(np.int64)
    phi = np.mod(np.arctan2(src[:, 0], src[:, 2]), 2.0 * np.pi)
    ip = np.clip(np.floor(phi / (2.0 * np.pi) * n_p), 0, n_p - 1).astype(np.int64)
    return src[:, 1] > 0, it * n_p + ip


def _dome_radiance(dome, src: np.ndarray, ground_sky=None) -> np.ndarray:
    """(4, N) radiance arriving from the unit directions ``src`` (toward the source): the dome's table above the
    horizon, the unit ground below (and the ground's skylit radiance ``ground_sky`` (3,) in R, G, B, if given: the
    shadowed ground of :class:`natscene.scatter.photons.SkySource`)."""
    up, cell = _dome_cell(dome, src)
    rgb = np.asarray(dome.rgb, np.float64).reshape(-1, 3)
    below = np.zeros(3) if ground_sky is None else np.asarray(ground_sky, np.float64).reshape(3)
    out = np.zeros((4, src.shape[0]), np.float32)
    out[:3] = np.where(up, rgb[cell].T, below[:, None])
    out[3] = np.where(up, 0.0, 1.0)
    return out


def _dome_directions(dome, table, n: int, rng) -> np.ndarray:
    """``n`` unit directions toward the source drawn by the dome's luminance (``table``: the share of the ground,
    the cells' probabilities and their CDF of :class:`natscene.scatter.photons.SkySource`)."""
    n_t, n_p = np.asarray(dome.rgb).shape[:2]
    p_ground, _, cdf = table
    ground = rng.random(n) < p_ground
    cell = np.minimum(np.searchsorted(cdf, rng.random(n), side="right"), cdf.size - 1)
    it, ip = np.divmod(cell, n_p)
    mu = np.where(ground, -rng.random(n), 1.0 - (it + rng.random(n)) / n_t)
    phi = np.where(ground, 2.0 * np.pi * rng.random(n), 2.0 * np.pi * (ip + rng.random(n)) / n_p)
    s = np.sqrt(np.maximum(1.0 - mu ** 2, 0.0))
    return np.stack([s * np.sin(phi), mu, s * np.cos(phi)], -1)


def _dome_pdf(dome, table, src: np.ndarray) -> np.ndarray:
    """The pdf (per steradian) of :func:`_dome_directions` at the unit directions ``src``."""
    n_t, n_p = np.asarray(dome.rgb).shape[:2]
    p_ground, p_cell, _ = table
    up, cell = _dome_cell(dome, src)
    omega_cell = 2.0 * np.pi / (n_t * n_p)
    return np.where(up, (1.0 - p_ground) * p_cell[cell] / omega_cell, p_ground / (2.0 * np.pi))


def _hg_directions(axis: np.ndarray, g: np.ndarray, rng) -> np.ndarray:
    """Unit directions drawn from HG(g) (per row) around the unit ``axis`` rows."""
    cos_t = hg_sample_cos(rng.random(axis.shape[0]), g)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t ** 2, 0.0))
    phi = 2.0 * np.pi * rng.random(axis.shape[0])
    helper = np.where(np.abs(axis[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    t = np.cross(axis, helper)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(axis, t)
    return (sin_t * np.cos(phi))[:, None] * t + (sin_t * np.sin(phi))[:, None] * b + cos_t[:, None] * axis


def shadow_samples(med, depth_vox: np.ndarray, camera_position, sky, gs, factor: int, per_cell: int,
                   seed: int = 0, step_voxels: float = 1.0, max_camera_depth: float = np.inf,
                   chunk: int = 1 << 20) -> ShadowSamples:
    """``per_cell`` points (the setting ``precompute.all_orders.sky_order1_points``; a multiple of 16: 2 x 2 x 2
    strata, each with a point of either half) in every occupied cell of ``factor`` voxels, each with a direction of
    travel ω from the mixture q of the equal mixture of HG(g) lobes around the direction to the camera over ``gs``
    and, a share :data:`DOME_SHARE`, the dome's luminance as
    the sky photons draw it (``sky``: the :class:`natscene.scatter.photons.SkySource`, its ground share too), the
    optical depth back toward the source marched with ``step_voxels``
    steps (midpoint rule on the trilinear density, to the box), and the camera depth ``depth_vox``
    (:func:`natscene.scatter.inscatter.voxel_camera_depth`) interpolated as the tallies' weight. Cells none of
    whose voxels lies within ``max_camera_depth`` (∫ rho, world units) of the camera get no points: the smallest
    extinction they serve sees them through a transmittance below 1e-8."""
    from natscene.scatter.medium import _march_depth
    if per_cell % 16:
        raise ValueError(f"per_cell must be a multiple of 16, got {per_cell}")
    d = np.asarray(med.volume.density)
    nz, ny, nx = d.shape
    occ = _occupied_cells(d, factor)
    if np.isfinite(max_camera_depth):
        from natscene.scatter.inscatter import block_sum
        occ &= block_sum(np.asarray(depth_vox) <= max_camera_depth, factor) > 0
    cz, cy, cx = occ.shape
    cells = np.flatnonzero(occ.ravel())
    rng = np.random.default_rng(seed)
    gs = np.asarray(gs, np.float64)
    dome, table = sky.dome, (sky.p_ground, sky.p_cell, sky.cdf)
    ground_sky = None if sky.ground is None else sky.ground[0].sky
    vox = (med.bbox_max - med.bbox_min) / np.array([nx, ny, nz])
    cam = np.asarray(camera_position, np.float64)
    depth = CameraDepth(med, depth_vox, camera_position)
    lo = mi.ScalarPoint3f(*[float(e) for e in med.bbox_min])
    ext = mi.ScalarVector3f(*[float(e) for e in med.bbox_max - med.bbox_min])
    parts = []
    per = chunk // per_cell
    for c0 in range(0, cells.size, per):
        c = np.repeat(cells[c0:c0 + per], per_cell)
        k = np.tile(np.arange(per_cell), min(per, cells.size - c0))
        stratum, half = (k // 2) % 8, k % 2
        iz, rem = np.divmod(c, cy * cx)
        iy, ix = np.divmod(rem, cx)
        off = np.stack([stratum & 1, (stratum >> 1) & 1, (stratum >> 2) & 1], -1) + rng.random((c.size, 3))
        vxyz = np.stack([ix, iy, iz], -1) * factor + off * (factor / 2.0)          # voxel units
        p = med.bbox_min + vxyz * vox
        to_cam = cam - p
        to_cam /= np.linalg.norm(to_cam, axis=1, keepdims=True)
        g_pick = gs[rng.integers(0, gs.size, c.size)]
        om = _hg_directions(to_cam, g_pick, rng)                                  # direction of travel
        by_dome = rng.random(c.size) < DOME_SHARE
        om[by_dome] = -_dome_directions(dome, table, int(by_dome.sum()), rng)
        cos_cam = np.sum(om * to_cam, axis=1)
        src = -om
        q = (1.0 - DOME_SHARE) * hg(cos_cam[None], gs[:, None]).mean(0) + DOME_SHARE * _dome_pdf(dome, table, src)
        o = mi.Point3f(*[p[:, i].astype(np.float32) for i in range(3)])
        s = mi.Vector3f(*[src[:, i].astype(np.float32) for i in range(3)])
        _, t1 = ray_box_dr(o, s, med.bbox_min, med.bbox_max)
        dl = _march_depth(med, o, s, dr.maximum(t1, 0.0), med.voxel * step_voxels)
        uvw = (o - lo) / ext
        rho = med.rho(o)
        dc = depth(o, uvw)
        dr.eval(dl, rho, dc)
        # compact: 28 bytes a point, 32 with the ground's depth in a frame (the cosine and the depths in float32,
        # where the forward peak and the transmittance need the digits)
        part = dict(index=(half * (cz * cy * cx) + c).astype(np.int32), rho=np.asarray(rho, np.float16),
                    depth_camera=np.asarray(dc, np.float32), depth_light=np.asarray(dl, np.float32),
                    cos_camera=cos_cam.astype(np.float32), inv_q=(1.0 / q).astype(np.float16),
                    radiance=_dome_radiance(dome, src, ground_sky).astype(np.float16))
        if ground_sky is not None:
            part["depth_ground"] = np.asarray(med.ground_sun_depth(o, s), np.float32)
        parts.append(part)
    cat = {k: np.concatenate([pt[k] for pt in parts], axis=-1) for k in parts[0]} if parts else None
    if cat is None:
        z = np.zeros(0, np.float32)
        return ShadowSamples(np.zeros(0, np.int32), z, z, z, z, z, np.zeros((4, 0), np.float32), (cz, cy, cx),
                             None if ground_sky is None else z)
    return ShadowSamples(cells=(cz, cy, cx), **cat)


def first_order_numerators(samples: ShadowSamples, sig_k: float, g: float, weighted_integrals: np.ndarray,
                           chunk: int = 1 << 20) -> np.ndarray:
    """(2 halves, 4 channels, cz, cy, cx) float64: C_1 = S_1 Q per cell for one node (``sig_k`` = sigma_t k per
    unit density, ``g``), S_1 the ratio Σ w rho S / Σ w rho over each half's points of the cell and Q =
    ``weighted_integrals`` (∫_cell w sigma_t dV, :meth:`natscene.scatter.allorders.Scene.weighted_integrals`).
    The sums run over ``chunk`` points at a time, so that the float64 temporaries stay a few tens of MB whatever
    the number of points."""
    cz, cy, cx = samples.cells
    n = cz * cy * cx
    den = np.zeros(2 * n)
    num = np.zeros((4, 2 * n))
    for a in range(0, samples.index.size, chunk):
        part = slice(a, a + chunk)
        idx = samples.index[part]
        dc = samples.depth_camera[part].astype(np.float64)
        wr = samples.rho[part].astype(np.float64) * np.exp(-sig_k * dc)
        val = (wr * np.exp(-sig_k * samples.depth_light[part].astype(np.float64)) * hg(samples.cos_camera[part], g)
               * samples.inv_q[part].astype(np.float64))
        den += np.bincount(idx, wr, minlength=2 * n)
        for ch in range(4):
            rad = samples.radiance[ch, part].astype(np.float64)
            if ch == 3 and samples.depth_ground is not None:      # the ground in the cloud's shadow
                rad = rad * np.exp(-sig_k * samples.depth_ground[part].astype(np.float64))
            num[ch] += np.bincount(idx, val * rad, minlength=2 * n)
    out = np.divide(num, den, out=np.zeros_like(num), where=den > 0)
    q = np.asarray(weighted_integrals, np.float64).ravel()
    return (out.reshape(4, 2, n) * q).transpose(1, 0, 2).reshape(2, 4, cz, cy, cx)
