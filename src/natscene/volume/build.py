"""The `volume` stage: a config entry -> a placed, validated density grid with its extinction scale.

``extinction_scale`` (DESIGN §3: mu_t = sigma_t * rho * extinction_scale) is fixed per volume so that
sigma_t in [0, 1] spans thin to opaque clouds: unless the config gives it, it is chosen so that at
sigma_t = 1 the mean optical depth through the cloud along z (a horizontal line of sight) equals
``reference_optical_depth`` (default 60; sigma_t = 0.02 then gives a mean optical depth ~1).
"""
from __future__ import annotations

import numpy as np

from natscene.io import InputError
from natscene.volume.grid import Volume, import_grid, mean_optical_depth, placement
from natscene.volume.procedural import generate, statistics

PROCEDURAL_KEYS = ("blobs", "octaves", "lacunarity", "gain", "base_frequency", "warp", "billow",
                   "worley_cells", "detail", "softness")


def build_volume(spec: dict, name: str = "volume", grid_path: str | None = None) -> tuple[Volume, dict]:
    """Generate (or import) the volume described by a validated ``volumes.<name>`` entry; return it and stats."""
    kind = spec.get("kind", "cumulus")
    if kind == "file":
        if not grid_path:
            raise InputError(f"config key 'volumes.{name}.path' is required when kind is 'file'")
        density = import_grid(grid_path, spec.get("axes", "zyx"))
    else:
        res = spec.get("resolution", [128, 96, 128])
        if len(res) != 3 or any(int(r) < 1 or int(r) > 1024 for r in res):
            raise InputError(f"config key 'volumes.{name}.resolution': {res} must be 3 integers in 1..1024")
        kwargs = {k: spec[k] for k in PROCEDURAL_KEYS if k in spec}
        density = generate(kind, res, seed=int(spec.get("seed", 1)), **kwargs)
        if density.max() <= 0:
            raise InputError(f"volumes.{name}: the generated cloud is empty; raise 'blobs' or lower 'softness'")
    nz, ny, nx = density.shape
    lo, hi = placement((nx, ny, nz), float(spec.get("size", 1.0)))
    voxel = float((hi - lo)[0] / nx)
    scale = spec.get("extinction_scale")
    tau = mean_optical_depth(density, voxel, axis=0)
    if scale is None:
        scale = float(spec.get("reference_optical_depth", 60.0)) / tau
    stats = statistics(density)
    stats["mean_optical_depth_z_at_sigma1"] = float(tau * scale)
    return Volume(density, lo, hi, float(scale)), stats
