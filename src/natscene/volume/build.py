"""
Volume stage
============

Defines the ``volume`` stage: a config entry -> a placed, validated density grid with its extinction scale:

-   :func:`build_volume`: generate (or import) the volume of a ``volumes.<name>`` entry, and its statistics.
-   :func:`world_box`: the world box of a procedural entry; :data:`DEFAULT_SIZE_M`, :data:`DEFAULT_ALTITUDE_M`.

World placement (DESIGN §3, metres, y up, ground y = 0): the box has cubic voxels, its longest side ``size``
metres (kind defaults in :data:`DEFAULT_SIZE_M`: a 2 km cumulus, a 10 km cumulonimbus), centred on x = z = 0,
its floor at ``altitude`` metres (default 1500, a typical cumulus base). An imported ``.vdb`` keeps its own
transform unless ``size``/``altitude`` are given.

``extinction_scale`` (mu_t [1/m] = sigma_t * rho * extinction_scale) is fixed per volume so that sigma_t in
[0, 1] spans thin to opaque clouds and means the same for every volume, whatever its size in metres: unless the
config gives it, it is chosen so that at sigma_t = 1 the mean optical depth through the cloud along
``reference_axis`` (default z, a horizontal line of sight; y, vertical, for a deck seen from above), over the
rays that hit it, equals ``reference_optical_depth`` (default 60; sigma_t = 0.02 then gives a mean optical
depth ~1). For a 2 km cumulus this is ~0.2 /m at rho = 1 and sigma_t = 1 (real cumulus: 0.02-0.15 /m).
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError
from natscene.volume.grid import Volume, import_grid, mean_optical_depth, placement

__all__ = ["build_volume", "world_box", "DEFAULT_SIZE_M", "DEFAULT_ALTITUDE_M"]

PROCEDURAL_KEYS = ("blobs", "octaves", "lacunarity", "gain", "base_frequency", "billow", "warp", "edge",
                   "erosion", "interior", "streak", "coverage", "thickness", "cells", "relief", "heap_min", "heap_max")
AXES = {"z": 0, "y": 1}                                   # reference_axis -> grid axis of [z, y, x]
DEFAULT_SIZE_M = {"cumulus": 2000.0, "cumulonimbus": 10000.0, "stratocumulus": 6000.0,
                  "cumulus_field": 12000.0, "file": None}
DEFAULT_ALTITUDE_M = 1500.0


def world_box(spec: dict, resolution) -> tuple[np.ndarray, np.ndarray]:
    """World bounding box of a procedural ``volumes.<name>`` entry of ``resolution`` (nx, ny, nz): longest side
    ``size`` (the kind's default when null), floor at ``altitude`` (default 1500 m)."""
    size = spec.get("size")
    if size is None:
        size = DEFAULT_SIZE_M.get(spec.get("kind", "cumulus")) or 1000.0
    altitude = spec.get("altitude")
    lo, hi = placement(resolution, float(size))
    alt = np.array([0.0, DEFAULT_ALTITUDE_M if altitude is None else float(altitude), 0.0])
    return lo + alt, hi + alt


def build_volume(spec: dict, name: str = "volume", grid_path: str | None = None, threads: int | None = None,
                 progress=None) -> tuple[Volume, dict]:
    """Generate (or import) the volume described by a validated ``volumes.<name>`` entry; return it and stats."""
    from natscene.volume.procedural import KINDS, generate, statistics   # numba, scipy: not for world_box
    kind = spec.get("kind", "cumulus")
    size = spec.get("size")
    altitude = spec.get("altitude")
    file_box = None
    if kind == "file":
        if not grid_path:
            raise InputError(f"config key 'volumes.{name}.path' is required when kind is 'file'")
        density, file_box = import_grid(grid_path, spec.get("axes", "zyx"), spec.get("grid", "density"))
    elif kind in KINDS:
        res = spec.get("resolution", [128, 96, 128])
        if len(res) != 3 or any(int(r) < 1 or int(r) > 1024 for r in res):
            raise InputError(f"config key 'volumes.{name}.resolution': {res} must be 3 integers in 1..1024")
        kwargs = {k: spec[k] for k in PROCEDURAL_KEYS if spec.get(k) is not None}
        density = generate(kind, res, seed=int(spec.get("seed", 1)), threads=threads, progress=progress, **kwargs)
        if density.max() <= 0:
            raise InputError(f"volumes.{name}: the generated cloud is empty; raise 'blobs' or 'coverage'")
    else:
        raise InputError(f"config key 'volumes.{name}.kind': unknown kind {kind!r} (one of {', '.join(KINDS)}, file)")
    nz, ny, nx = density.shape
    if file_box is not None and size is None and altitude is None:
        lo, hi = file_box                                      # the file's own transform (metres assumed)
    else:
        lo, hi = world_box(spec, (nx, ny, nz))
    voxel = float((hi - lo)[2] / nz)
    scale = spec.get("extinction_scale")
    axis = spec.get("reference_axis", "z")
    if axis not in AXES:
        raise InputError(f"config key 'volumes.{name}.reference_axis': {axis!r} is not one of z, y")
    tau = mean_optical_depth(density, voxel, axis=AXES[axis])
    if scale is None:
        scale = float(spec.get("reference_optical_depth", 60.0)) / tau
    stats = statistics(density)
    stats[f"mean_optical_depth_{axis}_at_sigma1"] = float(tau * scale)
    return Volume(density, np.asarray(lo, np.float64), np.asarray(hi, np.float64), float(scale)), stats
