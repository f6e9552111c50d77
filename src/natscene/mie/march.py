"""
Final ray marching with the Mie/isotropic blend
===============================================

Defines the final rendering of Reimschuessel (2011, Ch. 3 "Final Rendering", Eqs. 6–8):

-   :func:`render_mie`: the Mie-blend shading of one view.
-   :func:`march_terms`: the cloud radiance per unit sun and the transmittance of one camera.
-   :func:`lattice_fields`: the solved point cloud as a brickmap on its light-aligned lattice.
-   :func:`per_sun_fields`: the final pass's per-sun inputs, cached on the solution.
-   :func:`sun_depth_lattice`: the sunlight's optical depth on a finer light-aligned lattice.
-   :func:`co_lut`: A_m for the scattered light, averaged over the solid angle of a neighbour cell.
-   :func:`mie_render`: the settings of the final pass (config ``mie.render``) as a :class:`MieRender`.

The solved point cloud is resampled on its light-aligned lattice (the thesis' brickmap: a 3-D texture
of Co, R_i, L_i) with *normalised* trilinear lookups (the interpolated fields divided by the interpolated
point indicator: only existing points count, so the cloud's surface is not darkened cell by cell), and
every camera ray is marched through the volume with step ``step_voxels`` voxels. At each sample:

- Eq. 6: ``A_m = Mie(acos(L_i · L_o))``, ``L_o`` the direction toward the camera, read from the table as
  ``4π p`` (1 = isotropic), averaged over the solid angle of a neighbour cell (L_i is a mean over
  neighbours, known to that resolution: see :func:`co_lut`). The direct-sunlight term uses the sun's
  propagation direction (= L_i before the passes, as in the input point cloud the thesis samples Ci
  from) with the sharp table: glory, fogbow and the forward peak of the silver lining come from it.
  Its ``Ci = exp(-τ_sun)`` is looked up in the sun's optical depth on a finer light-aligned lattice
  (``sun_step_voxels``, trilinear in τ: see :func:`sun_depth_lattice`), not in the points' Ci (two
  voxels apart, the lit skin of a thick cloud is thinner than that: lattice-aligned stripes);
- Eq. 7: ``A_d = exp(-ℓ_i σ_e)``, ℓ_i the density-weighted distance from the cloud surface along the
  view ray (the optical depth ∫ σ_e D dt; for a uniform cloud exactly the thesis' form);
- Eq. 8: ``Λ_i = ([mie_scale A_m R_i + iso_scale (1 - R_i)] Co_i + mie_scale A_m(sun) Ci_i) A_d``;
- the radiance is ``c_in L_in ∫ σ_e D Λ / (4π) dt`` by trapezoidal integration (σ_e D / 4π turns the
  fraction-of-sun light values and the 4π-normalised phase into radiance), plus the ambient sky term
  ``L_amb · sky_color · (1 - T)`` (light from the sky scattered through the cloud) and the sky seen
  through the cloud ``T · L_sky``.

``phase="hg"`` (by passing an HG :class:`~natscene.mie.phase.PhaseTable`) gives the same marcher with
Henyey–Greenstein: a like-for-like comparison. The kernel is compiled with numba (a dependency of
miepython), one parallel loop over pixels.

References
----------
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from natscene.errors import InputError
from natscene.geometry import ray_box
from natscene.mie.phase import PhaseTable
from natscene.mie.solver import Solution, cone_averaged_lut

__all__ = ["co_lut", "lattice_fields", "sun_depth_lattice", "MieRender", "mie_render", "per_sun_fields", "march_terms",
           "render_mie"]


def co_lut(table: PhaseTable) -> np.ndarray:
    """A_m for the scattered light Co: the table averaged over the solid angle of one neighbour cell
    (h²/h² = 1 sr), the angular resolution with which the point-to-point passes know L_i (the same
    averaging as the solver's nearest neighbours). The direct sunlight keeps the sharp table."""
    return cone_averaged_lut(table, float(np.arccos(1 - 1 / (2 * np.pi))))


def lattice_fields(sol: Solution, smooth: float = 0.0) -> np.ndarray:
    """(nc, nb, na, 8) float32 brickmap: Co (3), W (1), R (1), L (3); W = 1 at a point, 0 elsewhere.

    The marcher interpolates all channels trilinearly and divides Co and R by the interpolated W
    (normalised interpolation): only existing points contribute, so the cloud's surface, where the
    lattice cells around a sample are partly empty, is not darkened cell by cell (the lattice-aligned
    striping of a plain lookup with zeros). ``smooth`` > 0 widens the kernel from trilinear to a
    Gaussian of that many lattice spacings (Co, R, L of neighbouring points blended, W-weighted: the
    point-to-point passes leave lattice-aligned texture in them; render default 1)."""
    p = sol.points
    f = np.zeros(tuple(p.shape) + (8,), np.float32)
    c, b, a = p.index[:, 0], p.index[:, 1], p.index[:, 2]
    f[c, b, a, 0:3] = sol.co
    f[c, b, a, 3] = 1.0
    f[c, b, a, 4] = sol.ratio
    f[c, b, a, 5:8] = sol.direction
    if smooth > 0:  # kernel-weighted: Gaussian of ``smooth`` lattice spacings over the points (W-weighted)
        from scipy.ndimage import gaussian_filter
        f = gaussian_filter(f, sigma=(smooth, smooth, smooth, 0), mode="constant", truncate=2.5)
    return f


@njit(parallel=True, cache=True, fastmath=True)
def _sun_depth(dens, vlo, vinv, origin, basis, h, sigma_e, out):
    """Optical depth toward the sun at every node of a light-aligned lattice (trapezoid along w)."""
    nc, nb, na = out.shape
    for ba in prange(nb * na):
        b = ba // na
        a = ba % na
        d1 = np.zeros(1)
        tau = 0.0
        prev = 0.0
        for c in range(nc):
            px = origin[0] + a * h * basis[0, 0] + b * h * basis[1, 0] + c * h * basis[2, 0]
            py = origin[1] + a * h * basis[0, 1] + b * h * basis[1, 1] + c * h * basis[2, 1]
            pz = origin[2] + a * h * basis[0, 2] + b * h * basis[1, 2] + c * h * basis[2, 2]
            _tri(dens, (px - vlo[0]) * vinv - 0.5, (py - vlo[1]) * vinv - 0.5, (pz - vlo[2]) * vinv - 0.5, 1, d1)
            cur = sigma_e * d1[0]
            if c > 0:
                tau += 0.5 * (prev + cur) * h
            out[c, b, a] = tau
            prev = cur


def sun_depth_lattice(volume, points, step_voxels: float):
    """The sunlight's optical depth τ_sun on a light-aligned lattice of spacing ``step_voxels`` voxels
    (origin and axes of the point cloud's lattice): ``Ci = exp(-τ_sun)`` is the direct sunlight of the
    thesis' input point cloud, here known at every node (not only at points, and finer than the point
    spacing) so that its trilinear lookup is smooth: τ varies linearly through the lit skin of the cloud,
    where exp(-τ) falls by e per 1/σ_e (less than a lattice cell in thick clouds). -> (τ (nc, nb, na, 1),
    spacing)."""
    vs = float(np.min(volume.voxel_size))
    h = float(step_voxels * vs)
    ext = (np.asarray(points.shape, float) - 1) * points.spacing  # (c, b, a) extents
    nc, nb, na = (int(np.ceil(e / h)) + 1 for e in ext)
    out = np.zeros((nc, nb, na), np.float32)
    _sun_depth(volume.density[..., None].astype(np.float32), np.asarray(volume.bbox_min, float), 1.0 / vs,
               np.asarray(points.origin, float), np.asarray(points.basis, float), h, float(points.sigma_e), out)
    return out[..., None], h


@njit(cache=True, fastmath=True)
def _tri(grid, x, y, z, ch, out):
    """Trilinear lookup of ``grid[z, y, x, ch]`` (index space, cell centres at integers) into ``out``;
    zero outside. Returns False outside."""
    nz, ny, nx = grid.shape[0], grid.shape[1], grid.shape[2]
    if x < 0 or y < 0 or z < 0 or x > nx - 1 or y > ny - 1 or z > nz - 1:
        for k in range(ch):
            out[k] = 0.0
        return False
    x0 = min(int(x), nx - 2) if nx > 1 else 0
    y0 = min(int(y), ny - 2) if ny > 1 else 0
    z0 = min(int(z), nz - 2) if nz > 1 else 0
    fx, fy, fz = x - x0, y - y0, z - z0
    x1, y1, z1 = min(x0 + 1, nx - 1), min(y0 + 1, ny - 1), min(z0 + 1, nz - 1)
    for k in range(ch):
        c00 = grid[z0, y0, x0, k] * (1 - fx) + grid[z0, y0, x1, k] * fx
        c01 = grid[z0, y1, x0, k] * (1 - fx) + grid[z0, y1, x1, k] * fx
        c10 = grid[z1, y0, x0, k] * (1 - fx) + grid[z1, y0, x1, k] * fx
        c11 = grid[z1, y1, x0, k] * (1 - fx) + grid[z1, y1, x1, k] * fx
        out[k] = (c00 * (1 - fy) + c01 * fy) * (1 - fz) + (c10 * (1 - fy) + c11 * fy) * fz
    return True


@njit(cache=True, fastmath=True)
def _lut(lut, cos, out):
    n = lut.shape[0]
    c = min(1.0, max(-1.0, cos))
    x = np.arccos(c) * (n - 1) / np.pi
    i0 = min(int(x), n - 2)
    f = x - i0
    for k in range(3):
        out[k] = lut[i0, k] * (1 - f) + lut[i0 + 1, k] * f


@njit(parallel=True, cache=True, fastmath=True)
def _march(origin, dirs, t0, t1, dens, vlo, vinv, fields, forigin, fbasis, finv, taus, tinv, lut, lut_co, sun_w,
           sigma_e, step, mie_scale, iso_scale, out_rad, out_dir, out_T):
    npix = dirs.shape[0]
    for p in prange(npix):
        for k in range(3):
            out_rad[p, k] = 0.0
            out_dir[p, k] = 0.0
        out_T[p] = 1.0
        if t1[p] <= t0[p]:
            continue
        dx, dy, dz = dirs[p, 0], dirs[p, 1], dirs[p, 2]
        buf = np.zeros(8)
        d1 = np.zeros(1)
        ts = np.zeros(1)
        am = np.zeros(3)
        am_sun = np.zeros(3)
        _lut(lut, -(sun_w[0] * dx + sun_w[1] * dy + sun_w[2] * dz), am_sun)  # cos(w, -d)
        n = int(np.ceil((t1[p] - t0[p]) / step)) + 1
        tau = 0.0
        prev = np.zeros(6)
        cur = np.zeros(6)
        acc = np.zeros(6)
        prev_sig = 0.0
        for k in range(n):
            t = min(t0[p] + k * step, t1[p])
            h = step if k > 0 else 0.0
            if k == n - 1 and k > 0:
                h = t1[p] - (t0[p] + (k - 1) * step)
            px = origin[0] + t * dx
            py = origin[1] + t * dy
            pz = origin[2] + t * dz
            _tri(dens, (px - vlo[0]) * vinv - 0.5, (py - vlo[1]) * vinv - 0.5, (pz - vlo[2]) * vinv - 0.5, 1, d1)
            sig = sigma_e * d1[0]
            tau += 0.5 * (prev_sig + sig) * h  # trapezoid optical depth
            for q in range(6):
                cur[q] = 0.0
            if sig > 0:
                qx, qy, qz = px - forigin[0], py - forigin[1], pz - forigin[2]
                la = qx * fbasis[0, 0] + qy * fbasis[0, 1] + qz * fbasis[0, 2]
                lb = qx * fbasis[1, 0] + qy * fbasis[1, 1] + qz * fbasis[1, 2]
                lc = qx * fbasis[2, 0] + qy * fbasis[2, 1] + qz * fbasis[2, 2]
                a_d = np.exp(-tau)
                w = sig * a_d / (4 * np.pi)
                # direct sunlight Ci = exp(-tau_sun) (fine lattice, trilinear in tau), sharp table
                _tri(taus, la * tinv, lb * tinv, lc * tinv, 1, ts)
                ci = np.exp(-ts[0])
                for q in range(3):
                    cur[3 + q] = mie_scale * am_sun[q] * ci * w
                # scattered light Co, R, L: normalised trilinear interpolation of the points
                _tri(fields, la * finv, lb * finv, lc * finv, 8, buf)
                wt = buf[3]
                if wt > 1e-6:
                    lx, ly, lz = buf[5], buf[6], buf[7]
                    ln = np.sqrt(lx * lx + ly * ly + lz * lz)
                    if ln > 0:
                        _lut(lut_co, -(lx * dx + ly * dy + lz * dz) / ln, am)
                    else:
                        am[0] = 1.0
                        am[1] = 1.0
                        am[2] = 1.0
                    r = min(1.0, max(0.0, buf[4] / wt))
                    for q in range(3):
                        cur[q] = (mie_scale * am[q] * r + iso_scale * (1 - r)) * buf[q] / wt * w
            if k > 0:
                for q in range(6):
                    acc[q] += 0.5 * (prev[q] + cur[q]) * h
            for q in range(6):
                prev[q] = cur[q]
            prev_sig = sig
        for q in range(3):
            out_rad[p, q] = acc[q] + acc[3 + q]
            out_dir[p, q] = acc[3 + q]
        out_T[p] = np.exp(-tau)


@dataclass(frozen=True)
class MieRender:
    """The settings of the final pass (config ``mie.render``): the light of the demo shots (``c_in``, ``L_in``,
    ``L_amb``, ``sky_color``) and the march (Table 4's ``mie_scale``, ``iso_scale``; ``step_voxels``,
    ``sun_step_voxels``, ``field_smooth``), which mie_blend frames use too. No field has a default here: they are
    the schema's, ``workflow/schemas/mie.schema.yaml`` (:func:`mie_render`)."""

    c_in: tuple
    L_in: float
    L_amb: float
    sky_color: tuple
    mie_scale: float
    iso_scale: float
    step_voxels: float
    sun_step_voxels: float
    field_smooth: float

    SCHEMA = (("mie.schema.yaml", ("render",)),)


def mie_render(settings: dict | MieRender | None) -> MieRender:
    """The one place that reads ``mie.render``: a validated section (or a part of one, or None) as a
    :class:`MieRender`, each key it lacks the schema's default (:func:`natscene.config.settings_from_section`);
    a :class:`MieRender` is returned as it is."""
    if isinstance(settings, MieRender):
        return settings
    from natscene.config import settings_from_section
    return settings_from_section(MieRender, settings, "mie.render")


def per_sun_fields(volume, solution: Solution, table: PhaseTable, settings: dict | MieRender | None = None):
    """The final pass's per-sun inputs, cached on ``solution.cache`` (the thesis' reuse: they depend on the
    volume, the sun and the solution, not on the view or the light colour): the brickmap fields
    (:func:`lattice_fields`, smoothed by ``field_smooth``), the sun's optical-depth lattice
    (:func:`sun_depth_lattice`, spacing ``sun_step_voxels``) and the cone-averaged LUT of the Co term
    (:func:`co_lut`); ``settings``: :func:`mie_render`'s. Entries are keyed by their settings and hold a
    reference to the volume's density / the table they were made from, so another volume or table is
    never served a stale entry. -> (fields, (τ, spacing), lut_co)."""
    r = mie_render(settings)
    field_smooth, sun_step_voxels = r.field_smooth, r.sun_step_voxels
    c = solution.cache
    key = ("fields", float(field_smooth))
    if key not in c:
        c[key] = lattice_fields(solution, field_smooth)
    fields = c[key]
    key = ("tau", float(sun_step_voxels))
    e = c.get(key)
    if e is None or e[0] is not volume.density or not np.array_equal(e[1], np.r_[volume.bbox_min, volume.bbox_max]):
        e = c[key] = (volume.density, np.r_[volume.bbox_min, volume.bbox_max],
                      sun_depth_lattice(volume, solution.points, sun_step_voxels))
    taus = e[2]
    e = c.get("lut_co")
    if e is None or e[0] is not table:
        e = c["lut_co"] = (table, co_lut(table).astype(np.float64))
    return fields, taus, e[1]


def march_terms(volume, camera, solution: Solution, table: PhaseTable, settings: dict | MieRender | None = None,
                return_direct: bool = False):
    """(cloud radiance per unit sun (H, W, 3), transmittance T (H, W)) for one camera; with
    ``return_direct`` also the direct-sunlight (single scattering) part of the radiance (H, W, 3).
    ``settings``: the march's (``mie_scale``, ``iso_scale``, ``step_voxels``, ``sun_step_voxels``,
    ``field_smooth``) of :func:`mie_render`."""
    r = mie_render(settings)
    mie_scale, iso_scale, step_voxels = r.mie_scale, r.iso_scale, r.step_voxels
    dirs = camera.ray_directions().reshape(-1, 3)
    org = np.asarray(camera.position, np.float64)
    lo, hi = np.asarray(volume.bbox_min, float), np.asarray(volume.bbox_max, float)
    t0, t1 = ray_box(np.broadcast_to(org, dirs.shape), dirs, lo, hi)
    vs = float(np.min(volume.voxel_size))
    fields, (taus, h_tau), lut_co = per_sun_fields(volume, solution, table, r)
    p = solution.points
    rad = np.zeros((len(dirs), 3))
    direct = np.zeros((len(dirs), 3))
    T = np.ones(len(dirs))
    _march(org, np.ascontiguousarray(dirs), np.ascontiguousarray(t0, dtype=np.float64),
           np.ascontiguousarray(t1, dtype=np.float64), volume.density[..., None].astype(np.float32),
           lo, 1.0 / vs, fields, np.asarray(p.origin, float), np.asarray(p.basis, float), 1.0 / p.spacing,
           taus, 1.0 / h_tau, table.lut().astype(np.float64), lut_co,
           -np.asarray(p.sun_dir, float), float(p.sigma_e), step_voxels * vs, float(mie_scale), float(iso_scale),
           rad, direct, T)
    h, w = camera.height, camera.width
    res = (rad.reshape(h, w, 3).astype(np.float32), T.reshape(h, w).astype(np.float32))
    return res + (direct.reshape(h, w, 3).astype(np.float32),) if return_direct else res


def render_mie(volume, camera, sun_dir, solution: Solution, table: PhaseTable, params: dict | MieRender | None,
               sky: np.ndarray | None = None, terms: dict | None = None) -> np.ndarray:
    """The Mie-blend shading of one view -> (H, W, 3) linear radiance.

    ``params``: the ``mie.render`` settings (:func:`mie_render`: a validated section, a part of one or a
    :class:`MieRender`): ``c_in`` (3,) sun colour, ``L_in`` sun intensity, ``L_amb`` ambient intensity,
    ``sky_color`` (3,) (None: the mean of ``sky``) and the march's settings. ``sky``: (H, W, 3) linear L_sky
    behind the cloud, or None.
    The solution must have been solved for ``sun_dir`` (the thesis' reuse: any view, any light colour).
    ``terms``: a dict that receives ``direct`` (H, W, 3), the single-scattered sunlight part of the
    radiance (where the glory and the fogbow live), and ``T`` (H, W).
    """
    sd = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    if float(np.dot(sd, solution.points.sun_dir)) < 1 - 1e-6:
        raise InputError("render_mie: the point-cloud solution was solved for another sun direction "
                         f"({np.round(solution.points.sun_dir, 4).tolist()} vs {np.round(sd, 4).tolist()}); "
                         "rerun rule point_scatter for this sun")
    r = mie_render(params)
    cloud, T, direct = march_terms(volume, camera, solution, table, r, return_direct=True)
    h, w = camera.height, camera.width
    if sky is None:
        sky = np.zeros((h, w, 3), np.float32)
    sky = np.asarray(sky, np.float32)
    if sky.shape != (h, w, 3):
        raise InputError(f"render_mie: sky has shape {sky.shape}, expected {(h, w, 3)} for this camera")
    c_in = np.broadcast_to(np.asarray(r.c_in, np.float32), (3,))
    sky_color = np.asarray(r.sky_color, np.float32) if r.sky_color is not None else sky.reshape(-1, 3).mean(0)
    if terms is not None:
        terms["direct"] = (c_in * float(r.L_in) * direct).astype(np.float32)
        terms["T"] = T
    out = c_in * float(r.L_in) * cloud + float(r.L_amb) * sky_color * (1 - T)[..., None] + T[..., None] * sky
    return out.astype(np.float32)
