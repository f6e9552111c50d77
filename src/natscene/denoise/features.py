"""
Feature images of a cloud for the denoiser
==========================================

Defines the feature images of a cloud for a learned denoiser (Intel Open Image Denoise's ``albedo`` and
``normal`` inputs), computed from the volume and the frame's camera, without noise:

-   :func:`frame_features`: all feature images of one frame (opacity, coverage, albedo, normal).
-   :func:`denoiser_settings`: a shot's ``denoiser`` section with the schema's defaults.
-   :func:`view_features`: the opacity, normal and coverage of the cloud seen by a camera.
-   :func:`albedo_image`: the albedo image.
-   :func:`density_gradient`, :func:`empty_space_distance`: the volume's density gradient and distance to the
    nearest non-empty voxel.

OIDN asks for the "approximate colour of the surfaces independent of illumination and viewing angle" (albedo,
in [0, 1]) and their shading normals (in [-1, 1], anti-aliased by averaging, not renormalised), both with the
same pixel filter as the colour image. A cloud has no surface; its natural analogue is the distribution of the
*first scattering event* along the view ray. For a view ray through mu_t(x) = sigma_t k rho(x) (k the volume's
``extinction_scale``) the probability that the first interaction lies in the march segment i is

    w_i = T_i (1 - exp(-mu_t,i h)),   T_i = exp(-sum_{j<i} mu_t,j h),   sum_i w_i = 1 - T = alpha,

so that

- ``opacity`` alpha = 1 - T (the cloud's coverage of the pixel: how much of the pixel's light the cloud
  scatters or absorbs rather than lets through);
- ``albedo`` = alpha beta c_hat + (1 - alpha) a_sky: the scattering albedo beta tinted by the sunlight colour
  c_hat = c_in / max(c_in) where the cloud is, over the normalised sky a_sky = L_sky / max L_sky of the frame
  where it is not (the sky is noise-free structure the denoiser must keep);
- ``normal`` = sum_i w_i n_i, n_i = -grad rho / |grad rho| the outward unit normal of the density's
  iso-surface at the segment (zero where the gradient vanishes): the expected normal at the first scattering
  event. Its length is at most alpha (a thin wisp has a short normal, the sky none).

Each pixel is the box-filtered mean of ``supersample`` x ``supersample`` stratified sub-pixel rays (the colour
image's filter is a box too; a frame's: ``shots.<name>.denoiser.feature_supersample``, and its march step
``feature_step_voxels``). The march uses the trilinear density (cell-centred, like Mitsuba's
``gridvolume``) at ``step_voxels`` steps (midpoint rule), skips empty space by the Euclidean distance to the
nearest non-empty voxel (sphere tracing on :func:`empty_space_distance`) and stops once T < ``t_min``; the
kernel is compiled with numba, parallel over rays.

References
----------
-   Intel Open Image Denoise (OIDN) 2.x documentation, "RT" filter. https://www.openimagedenoise.org/documentation.html
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from natscene.geometry import ray_box

__all__ = ["density_gradient", "empty_space_distance", "view_features", "albedo_image", "frame_features",
           "denoiser_settings"]

# A trilinear lookup at p reads the 8 voxel centres within max-norm 1 of p (Euclidean sqrt 3 voxels); the
# distance map is read at the voxel centre nearest to p (up to sqrt 3 / 2 away): a step of d - SAFETY voxels
# never jumps over density.
_SAFETY = 2.6


def density_gradient(density: np.ndarray, voxel_size) -> np.ndarray:
    """Central-difference gradient of rho (per world unit), float32 (nz, ny, nx, 3) with components (x, y, z)."""
    vs = np.asarray(voxel_size, np.float64).reshape(-1)
    vs = np.broadcast_to(vs, (3,))
    gz, gy, gx = np.gradient(np.asarray(density, np.float32), vs[2], vs[1], vs[0])
    return np.ascontiguousarray(np.stack([gx, gy, gz], axis=-1), np.float32)


def empty_space_distance(density: np.ndarray, voxel_size=1.0) -> np.ndarray:
    """Euclidean distance (world units) from every voxel centre to the nearest voxel centre with density > 0,
    float32 (nz, ny, nx)."""
    from scipy.ndimage import distance_transform_edt

    vs = np.broadcast_to(np.asarray(voxel_size, np.float64).reshape(-1), (3,))
    empty = np.asarray(density) <= 0
    if not empty.any():
        return np.zeros(empty.shape, np.float32)
    if empty.all():
        return np.full(empty.shape, np.float32(1e30))
    return distance_transform_edt(empty, sampling=(vs[2], vs[1], vs[0])).astype(np.float32)


@njit(cache=True, fastmath=True)
def _tri(grid, x, y, z, ch, out):
    """Trilinear lookup of grid[z, y, x, c] at continuous voxel indices (centres at integers), clamped to the
    outermost centres (the box's outer half voxel holds the edge value, as a clamped texture)."""
    nz, ny, nx = grid.shape[0], grid.shape[1], grid.shape[2]
    x = min(max(x, 0.0), nx - 1.0)
    y = min(max(y, 0.0), ny - 1.0)
    z = min(max(z, 0.0), nz - 1.0)
    x0 = min(int(x), max(nx - 2, 0))
    y0 = min(int(y), max(ny - 2, 0))
    z0 = min(int(z), max(nz - 2, 0))
    fx, fy, fz = x - x0, y - y0, z - z0
    x1, y1, z1 = min(x0 + 1, nx - 1), min(y0 + 1, ny - 1), min(z0 + 1, nz - 1)
    for k in range(ch):
        c00 = grid[z0, y0, x0, k] * (1 - fx) + grid[z0, y0, x1, k] * fx
        c01 = grid[z0, y1, x0, k] * (1 - fx) + grid[z0, y1, x1, k] * fx
        c10 = grid[z1, y0, x0, k] * (1 - fx) + grid[z1, y0, x1, k] * fx
        c11 = grid[z1, y1, x0, k] * (1 - fx) + grid[z1, y1, x1, k] * fx
        out[k] = (c00 * (1 - fy) + c01 * fy) * (1 - fz) + (c10 * (1 - fy) + c11 * fy) * fz


@njit(parallel=True, cache=True, fastmath=True)
def _march_features(origin, dirs, t0, t1, dens, grad, dist, lo, inv_vs, margin, sigma_e, h, t_min,
                    out_alpha, out_normal):
    n = dirs.shape[0]
    nz, ny, nx = dist.shape
    for p in prange(n):
        out_alpha[p] = 0.0
        out_normal[p, 0] = 0.0
        out_normal[p, 1] = 0.0
        out_normal[p, 2] = 0.0
        if t1[p] <= t0[p]:
            continue
        dx, dy, dz = dirs[p, 0], dirs[p, 1], dirs[p, 2]
        d1 = np.zeros(1)
        g3 = np.zeros(3)
        T = 1.0
        nxa = 0.0
        nya = 0.0
        nza = 0.0
        t = t0[p]
        while t < t1[p] and T > t_min:
            hh = min(h, t1[p] - t)
            tm = t + 0.5 * hh
            px = origin[0] + tm * dx
            py = origin[1] + tm * dy
            pz = origin[2] + tm * dz
            ix = (px - lo[0]) * inv_vs[0] - 0.5
            iy = (py - lo[1]) * inv_vs[1] - 0.5
            iz = (pz - lo[2]) * inv_vs[2] - 0.5
            cx = min(max(int(ix + 0.5), 0), nx - 1)
            cy = min(max(int(iy + 0.5), 0), ny - 1)
            cz = min(max(int(iz + 0.5), 0), nz - 1)
            skip = dist[cz, cy, cx] - margin
            if skip > h:  # empty space: jump (sphere tracing on the distance map)
                t += skip
                continue
            _tri(dens, ix, iy, iz, 1, d1)
            rho = d1[0]
            if rho > 0:
                a = 1.0 - np.exp(-sigma_e * rho * hh)
                w = T * a
                _tri(grad, ix, iy, iz, 3, g3)
                gl = np.sqrt(g3[0] * g3[0] + g3[1] * g3[1] + g3[2] * g3[2])
                if gl > 1e-12:
                    nxa -= w * g3[0] / gl
                    nya -= w * g3[1] / gl
                    nza -= w * g3[2] / gl
                T *= 1.0 - a
            t += hh
        out_alpha[p] = 1.0 - T
        out_normal[p, 0] = nxa
        out_normal[p, 1] = nya
        out_normal[p, 2] = nza


def _prepared(volume):
    """(density[..., None], gradient, distance map) of a volume, cached on the density array's identity."""
    key = id(volume.density)
    hit = _CACHE.get("vol")
    if hit is not None and hit[0] == key and hit[1] is volume.density:
        return hit[2]
    d = np.ascontiguousarray(np.asarray(volume.density, np.float32)[..., None])
    prep = (d, density_gradient(volume.density, volume.voxel_size),
            empty_space_distance(volume.density, volume.voxel_size))
    _CACHE["vol"] = (key, volume.density, prep)
    return prep


_CACHE: dict = {}


def view_features(volume, camera, sigma_t: float, supersample: int, step_voxels: float,
                  t_min: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(opacity (H, W), normal (H, W, 3), coverage (H, W)) of the cloud seen by ``camera`` at ``sigma_t``.

    ``coverage``: the fraction of a pixel's sub-rays that meet any density (opacity > 0): where the cloud
    can carry Monte Carlo noise. See the module docstring for the definitions.
    """
    s = max(1, int(supersample))
    H, W = camera.height, camera.width
    dens, grad, dist = _prepared(volume)
    lo = np.asarray(volume.bbox_min, np.float64)
    hi = np.asarray(volume.bbox_max, np.float64)
    vs = np.asarray(volume.voxel_size, np.float64)
    vox = float(vs.min())
    sigma_e = float(sigma_t) * float(volume.extinction_scale)
    org = np.asarray(camera.position, np.float64)
    alpha = np.zeros(H * W)
    normal = np.zeros((H * W, 3))
    cover = np.zeros(H * W)
    a = np.empty(H * W)
    nrm = np.empty((H * W, 3))
    for j in range(s):
        for i in range(s):
            off = np.array([(i + 0.5) / s - 0.5, (j + 0.5) / s - 0.5])
            jit = np.broadcast_to(off, (H, W, 2)) if s > 1 else None
            dirs = np.ascontiguousarray(camera.ray_directions(jit).reshape(-1, 3))
            t0, t1 = ray_box(np.broadcast_to(org, dirs.shape), dirs, lo, hi)
            _march_features(org, dirs, np.ascontiguousarray(t0, np.float64), np.ascontiguousarray(t1, np.float64),
                            dens, grad, dist, lo, 1.0 / vs, _SAFETY * float(vs.max()), sigma_e, step_voxels * vox,
                            float(t_min), a, nrm)
            alpha += a
            normal += nrm
            cover += a > 0
    k = 1.0 / (s * s)
    return ((alpha * k).reshape(H, W).astype(np.float32), (normal * k).reshape(H, W, 3).astype(np.float32),
            (cover * k).reshape(H, W).astype(np.float32))


def albedo_image(opacity: np.ndarray, beta: float, c_in, sky: np.ndarray | None = None) -> np.ndarray:
    """OIDN albedo (H, W, 3) in [0, 1]: alpha beta c_in / max(c_in) over the frame-normalised sky."""
    c = np.clip(np.asarray(c_in, np.float64).reshape(-1), 0.0, None)
    c = np.broadcast_to(c, (3,))
    c_hat = c / c.max() if c.max() > 0 else np.ones(3)
    a = np.clip(np.asarray(opacity, np.float64), 0.0, 1.0)[..., None]
    cloud = float(np.clip(beta, 0.0, 1.0)) * c_hat
    if sky is None:
        bg = np.zeros(a.shape[:2] + (3,))
    else:
        s = np.clip(np.asarray(sky, np.float64), 0.0, None)
        m = float(s.max())
        bg = s / m if m > 0 else np.zeros_like(s)
    return np.clip(a * cloud + (1.0 - a) * bg, 0.0, 1.0).astype(np.float32)


def denoiser_settings(section: dict | None = None, key: str = "shots.<name>.denoiser") -> dict:
    """A shot's denoiser settings: ``section`` (a validated ``shots.<name>.denoiser``, a part of one, or None) with
    each key it lacks the schema's default (:func:`natscene.config.complete_section`: the schema's defaults are the
    only ones; a bad key or value raises :class:`natscene.errors.ConfigError` naming ``key``)."""
    from natscene.config import complete_section
    return complete_section(section, "shots.schema.yaml", ("additionalProperties", "denoiser"), key)


def frame_features(volume, camera, params: dict, sky=None, settings: dict | None = None) -> dict:
    """All feature images of one frame: {opacity, coverage, albedo, normal} for the frame's parameter set
    (``extinction`` in 1/m, ``beta``, ``c_in``) and sky (H, W, 3) (or None). ``settings``: the shot's denoiser
    section (:func:`denoiser_settings`; None: the schema's defaults), whose ``feature_supersample`` and
    ``feature_step_voxels`` are :func:`view_features`' ``supersample`` and ``step_voxels``."""
    d = denoiser_settings(settings)
    sigma_t = float(np.asarray(params["extinction"]).reshape(-1)[0]) / float(volume.extinction_scale)
    alpha, normal, cover = view_features(volume, camera, sigma_t, d["feature_supersample"], d["feature_step_voxels"])
    beta = float(np.asarray(params.get("beta", 1.0)).reshape(-1)[0])
    albedo = albedo_image(alpha, beta, params.get("c_in", (1.0, 1.0, 1.0)), sky)
    return {"opacity": alpha, "coverage": cover, "albedo": albedo, "normal": np.clip(normal, -1.0, 1.0)}
