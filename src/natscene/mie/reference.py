"""
Mitsuba 3 reference of the Mie shading
======================================

Defines a path-traced reference of the Mie/isotropic shading of Reimschuessel (2011, Ch. 3):

-   :func:`render_reference_mie`: the ``volpath`` image of the cloud lit by the sun.
-   :func:`reference_scene`: the loaded Mitsuba scene of one channel.
-   :func:`ratio_grid`: R_i resampled on the volume's voxel centres.
-   :func:`tabphase_values`: the ``values`` string of a ``tabphase`` for one channel of the table.

The same cloud, sun and camera as :func:`natscene.mie.march.render_mie`, rendered by path tracing
(``volpath``) with the phase function the point-cloud solution implies:

- the medium is the project's reference scene (:func:`natscene.scatter.mitsuba_scene.scene_dict`: a
  ``heterogeneous`` medium, ``gridvolume`` density mapped to the bbox, scale σ_e = σ_t · extinction_scale,
  albedo ω, a ``directional`` sun of irradiance ``c_in · L_in``, a ``perspective`` camera);
- its phase function is a ``blendphase``: ``phase1`` = ``isotropic``, ``phase2`` = ``tabphase`` fed the
  Mie table, ``weight`` = a ``gridvolume`` of the solved ratio R_i on the density grid, i.e.
  ``p = (1 - R) / 4π + R · p_Mie``, the blend of Eqs. 4 and 8;
- ``tabphase`` takes one table (values regularly spaced in cos θ, ``n_cos`` of them: 100,001 resolve
  ≈ 0.26° next to θ = 0° and 180°, fine enough for the glory's rings at ≈ 1.5° and 2.5° from the
  antisolar point), so R, G and B are rendered one at a time with their own table and recombined.

``max_depth = 2`` gives single scattering only (DESIGN, Mitsuba facts): comparable pixel for pixel with the
marcher's direct-sunlight term (sharp table, ``Ci = exp(-τ_sun)``) when R = 1 (a solution with 0 passes). With
more depth it is the path-traced answer to the question the point-to-point passes approximate (multiple
scattering with a Mie/isotropic phase), comparable only loosely (see tests/test_mie_reference.py).

References
----------
-   Reimschuessel, C. A. (2011). Rendering Realistic Cloud Effects for Computer Generated Films. MSc thesis,
    Brigham Young University.
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import map_coordinates

import natscene.variant  # noqa: F401  (LLVM library path before Mitsuba loads)
import mitsuba as mi

from natscene.mie.march import lattice_fields
from natscene.mie.phase import PhaseTable
from natscene.mie.solver import Solution
from natscene.scatter.medium import active_mitsuba
from natscene.scatter.mitsuba_scene import scene_dict

__all__ = ["ratio_grid", "tabphase_values", "reference_scene", "render_reference_mie"]


def ratio_grid(volume, solution: Solution) -> np.ndarray:
    """R_i resampled on the volume's voxel centres -> float32 [nz, ny, nx]: normalised trilinear
    interpolation of the points on their light-aligned lattice (as the marcher does), 1 (pure Mie, the
    initial R_i) where no point is near."""
    p = solution.points
    f = lattice_fields(solution)
    nx, ny, nz = (int(n) for n in volume.resolution)
    vs = volume.voxel_size
    lo = np.asarray(volume.bbox_min, np.float64)
    zz, yy, xx = np.meshgrid(*(np.arange(n) + 0.5 for n in (nz, ny, nx)), indexing="ij")
    world = lo + np.stack([xx * vs[0], yy * vs[1], zz * vs[2]], axis=-1)
    lat = p.world_to_lattice(world.reshape(-1, 3)).T  # (c, b, a)
    w = map_coordinates(f[..., 3], lat, order=1, mode="constant", cval=0.0)
    r = map_coordinates(f[..., 4], lat, order=1, mode="constant", cval=0.0)
    out = np.where(w > 1e-6, r / np.maximum(w, 1e-6), 1.0)
    return np.clip(out, 0.0, 1.0).reshape(nz, ny, nx).astype(np.float32)


def tabphase_values(table: PhaseTable, channel: int, n_cos: int = 100_001) -> str:
    """The ``values`` string of a ``tabphase``: the table's channel on a regular grid of cos θ in
    [-1, 1] (θ between propagation directions: cos θ = 1 is forward, Mitsuba's convention)."""
    mu = np.linspace(-1.0, 1.0, int(n_cos))
    p = np.interp(np.arccos(mu), table.theta, table.rgb[:, channel])
    return ",".join(f"{v:.7g}" for v in p)


def reference_scene(volume, camera, sun_dir, solution: Solution, table: PhaseTable, channel: int,
                    irradiance: float = 1.0, albedo: float = 1.0, max_depth: int = 64, spp: int = 256,
                    ratio: np.ndarray | None = None, n_cos: int = 100_001):
    """The loaded Mitsuba scene of one channel (``ratio``: a precomputed :func:`ratio_grid`)."""
    active_mitsuba()
    p = solution.points
    sigma_t = p.sigma_e / float(volume.extinction_scale)
    d = scene_dict(volume, camera, sun_dir, sigma_t, 0.0, albedo, (irradiance,) * 3, max_depth, spp)
    d["integrator"]["rr_depth"] = max(int(max_depth) + 1, 64) if max_depth > 0 else 10_000
    medium = d["cloud"]["interior"]
    if ratio is None:
        ratio = ratio_grid(volume, solution)
    medium["phase"] = {
        "type": "blendphase",
        "weight": {"type": "gridvolume", "data": mi.TensorXf(np.ascontiguousarray(ratio[..., None])),
                   "to_world": medium["sigma_t"]["to_world"]},
        "phase1": {"type": "isotropic"},
        "phase2": {"type": "tabphase", "values": tabphase_values(table, channel, n_cos)},
    }
    return mi.load_dict(d)


def render_reference_mie(volume, camera, sun_dir, solution: Solution, table: PhaseTable, params: dict | None = None,
                         max_depth: int = 64, spp: int = 256, seed: int = 0, channels=(0, 1, 2),
                         albedo: float = 1.0) -> np.ndarray:
    """volpath image (H, W, 3) of the cloud lit by the sun (``params``: ``c_in``, ``L_in``; no sky,
    no ambient term), channels not in ``channels`` left 0. ``max_depth = 2``: single scattering only."""
    params = params or {}
    sd = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    if float(np.dot(sd, solution.points.sun_dir)) < 1 - 1e-6:
        from natscene.errors import InputError
        raise InputError("mie.reference: the solution was solved for another sun direction; rerun point_scatter")
    c_in = np.broadcast_to(np.asarray(params.get("c_in", (1.0, 1.0, 1.0)), np.float64), (3,))
    L_in = float(params.get("L_in", 1.0))
    ratio = ratio_grid(volume, solution)
    out = np.zeros((camera.height, camera.width, 3), np.float32)
    for c in channels:
        scene = reference_scene(volume, camera, sd, solution, table, int(c), float(c_in[c] * L_in), albedo,
                                max_depth, spp, ratio)
        img = np.asarray(mi.render(scene, seed=seed + 1000 * int(c)), np.float32)
        out[..., c] = img[..., c]
    return out
