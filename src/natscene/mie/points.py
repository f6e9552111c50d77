"""
Point cloud of the Mie shading
==============================

Defines the point cloud generation by ray marching the volume from the sun (Reimschuessel 2011, Ch. 3
"Generating the point cloud", Fig. 5, Table 1):

-   :func:`generate_points`: march the volume from the sun on a light-aligned lattice into a :class:`PointCloud`.
-   :func:`light_basis`: the light's propagation direction and the plane across it.
-   :func:`sample_density`: the trilinear density at world points.

The thesis renders the cloud with the sun as the camera and adds a point at every ray-marching step. Here
the sun's "camera" is orthographic (the sun is a parallel light): rays parallel to the light's
propagation direction ``w = -sun_dir``, spaced ``h`` apart on a square grid perpendicular to ``w`` and
covering the volume's bounding box, are marched with step ``h``. The samples form a regular lattice
aligned with the light (indices ``[c, b, a]``: c along ``w``, b along ``v``, a along ``u``). At every
lattice sample with density ``D_i`` above a threshold a point is created with (Table 1):

- ``P_i``: its world position;
- ``D_i``: the density in [0, 1] (trilinear in the grid);
- ``Ci_i``: the sunlight reaching it, ``exp(-Σ_{j<i} σ_e D_j h)`` along its ray (left Riemann sum: the
  light entering the point's cell), as a fraction of the sun's irradiance;
- ``L_i``: the prominent light direction, the sunlight's propagation direction ``w``;
- ``R_i = 1`` (pure Mie scattering).

Each point stands for a cell of side ``h``; the fraction of the light entering it that interacts there is
``s_i = 1 - exp(-σ_e D_i h)``, so that ``Σ_i Ci_i s_i`` over a ray telescopes to ``1 - T_ray`` exactly:
the sunlight that entered the cloud (used by the energy checks). σ_e = ``sigma_t · extinction_scale``
(the project's extinction convention, DESIGN §3).

References
----------
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import map_coordinates

from natscene.errors import InputError

__all__ = ["light_basis", "sample_density", "PointCloud", "generate_points"]


def light_basis(sun_dir) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v, w): w = propagation direction of sunlight (-sun_dir), u, v spanning the plane across it."""
    w = -np.asarray(sun_dir, np.float64)
    w = w / np.linalg.norm(w)
    ref = np.array([0.0, 1.0, 0.0]) if abs(w[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(ref, w)
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    return u, v, w


def sample_density(volume, points: np.ndarray) -> np.ndarray:
    """Trilinear density at world points (..., 3); 0 outside the box. Voxel centres at (i + 0.5)·voxel."""
    lo = np.asarray(volume.bbox_min, np.float64)
    vs = volume.voxel_size
    g = (np.asarray(points, np.float64) - lo) / vs - 0.5  # continuous voxel index (x, y, z)
    shp = g.shape[:-1]
    g = g.reshape(-1, 3)
    coords = np.stack([g[:, 2], g[:, 1], g[:, 0]])  # density is [z, y, x]
    out = map_coordinates(volume.density, coords, order=1, mode="constant", cval=0.0, prefilter=False)
    return out.reshape(shp).astype(np.float32)


@dataclass
class PointCloud:
    """The initial point cloud (Table 1) on the light-aligned lattice."""

    position: np.ndarray      # (N, 3) world P_i
    density: np.ndarray       # (N,) D_i
    ci0: np.ndarray           # (N,) Ci_i: sunlight entering the point's cell (fraction of the sun)
    index: np.ndarray         # (N, 3) lattice indices (c, b, a)
    origin: np.ndarray        # (3,) world position of lattice index (0, 0, 0)
    basis: np.ndarray         # (3, 3) rows u, v, w (w = light propagation direction)
    shape: tuple              # lattice shape (nc, nb, na)
    spacing: float            # h (world units)
    sigma_e: float            # extinction coefficient at D = 1 (1/world units)
    sun_dir: np.ndarray       # (3,) toward the sun
    sun_in: float             # sunlight entering the cloud: Σ_rays h² (1 - T_ray) (world area units)

    @property
    def interact(self) -> np.ndarray:
        """s_i = 1 - exp(-σ_e D_i h): fraction of the light entering a cell that scatters there."""
        return (1.0 - np.exp(-self.sigma_e * self.density.astype(np.float64) * self.spacing)).astype(np.float32)

    def world_to_lattice(self, p: np.ndarray) -> np.ndarray:
        """Continuous lattice coordinates (c, b, a) of world points (..., 3)."""
        q = np.asarray(p, np.float64) - self.origin
        a = q @ self.basis[0] / self.spacing
        b = q @ self.basis[1] / self.spacing
        c = q @ self.basis[2] / self.spacing
        return np.stack([c, b, a], axis=-1)


def generate_points(volume, sun_dir, sigma_t: float = 0.3, spacing_voxels: float = 2.0,
                    density_threshold: float = 0.02) -> PointCloud:
    """March the volume from the sun on a light-aligned lattice of spacing ``spacing_voxels`` voxels."""
    if sigma_t <= 0 or spacing_voxels <= 0:
        raise InputError(f"mie.solver: sigma_t ({sigma_t}) and spacing_voxels ({spacing_voxels}) must be > 0")
    sun_dir = np.asarray(sun_dir, np.float64) / np.linalg.norm(sun_dir)
    u, v, w = light_basis(sun_dir)
    h = float(spacing_voxels * np.min(volume.voxel_size))
    lo, hi = np.asarray(volume.bbox_min, float), np.asarray(volume.bbox_max, float)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    pu, pv, pw = corners @ u, corners @ v, corners @ w
    na = int(np.ceil((pu.max() - pu.min()) / h)) + 1
    nb = int(np.ceil((pv.max() - pv.min()) / h)) + 1
    nc = int(np.ceil((pw.max() - pw.min()) / h)) + 1
    origin = pu.min() * u + pv.min() * v + pw.min() * w
    sigma_e = float(sigma_t * volume.extinction_scale)
    # March slab by slab along w (memory: one (nb, na) slab at a time).
    ai, bi = np.arange(na) * h, np.arange(nb) * h
    plane = origin + bi[:, None, None] * v + ai[None, :, None] * u  # (nb, na, 3)
    tau = np.zeros((nb, na))
    dens = np.empty((nc, nb, na), np.float32)
    ci0 = np.empty((nc, nb, na), np.float32)
    for c in range(nc):
        d = sample_density(volume, plane + c * h * w)
        dens[c] = d
        ci0[c] = np.exp(-tau)
        tau += sigma_e * d * h
    sun_in = float(np.sum(1.0 - np.exp(-tau)) * h * h)
    keep = dens > density_threshold
    if not keep.any():
        raise InputError(f"mie.solver: no lattice point has density > density_threshold ({density_threshold}); "
                         f"lower it or check the volume")
    idx = np.argwhere(keep)
    pos = origin + idx[:, 0:1] * h * w + idx[:, 1:2] * h * v + idx[:, 2:3] * h * u
    return PointCloud(pos.astype(np.float32), dens[keep], ci0[keep], idx.astype(np.int32), origin,
                      np.stack([u, v, w]), (nc, nb, na), h, sigma_e, sun_dir, sun_in)
