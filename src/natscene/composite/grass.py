"""
Grass blades of the set
=======================

Defines the grass blades in the near field: the ground texture (the ω-tiled grass) stands up as geometry where the
camera can resolve single blades, and lies flat beyond.

-   :func:`grass_blades`: a mesh of grass blades over the wedge of ground.

Each blade is a tapered, bent strip: root r on the ground, height h, lean direction c (horizontal unit) and
bend b, centre line P(s) = r + h·(s·ŷ + b·s²·c), s ∈ [0, 1], width w(s) = w₀·(1 − s)^0.7 across the horizontal
direction perpendicular to c turned by a random twist; ``segments`` segments (two triangles each, the tip a
point). Its texture coordinates are the ground texture's at the root plus the blade's own extent, (u, v) =
uv(r) + (x_across / e_x, s·h / e_z), so every blade shows the strip of the grass texture that lies under it
and the colours of the flat ground and of the blades agree. Roots are uniform over the wedge with density
``density`` per m², thinned by a smoothstep between ``fade`` (start, end) metres, and none within the
``clearings`` (x, z, radius) (the beetles' spots).
"""
from __future__ import annotations

import numpy as np

from natscene.composite.placement import in_wedge, wedge_points
from natscene.composite.mesh import TriMesh

__all__ = ["grass_blades"]


def grass_blades(rng: np.random.Generator, area: dict, density: float, height=(0.04, 0.11), width: float = 0.004,
                 fade=(2.0, 4.0), clearings=(), extent=(1.0, 1.0), offset=(0.0, 0.0), segments: int = 4) -> TriMesh:
    """A mesh of grass blades over the wedge ``area`` (metres, set frame) up to ``fade[1]`` metres."""
    far = min(float(area["far"]), float(fade[1]))
    sub = {**area, "far": far}
    wedge_area = np.radians(sub["half_angle"]) * (far ** 2 - sub["near"] ** 2)
    n = int(rng.poisson(max(density * wedge_area, 0.0)))
    roots = wedge_points(rng, n, sub)
    r = np.hypot(roots[:, 0], roots[:, 1])
    t = np.clip((r - fade[0]) / max(fade[1] - fade[0], 1e-9), 0, 1)
    keep = rng.uniform(0, 1, n) < 1 - t * t * (3 - 2 * t)
    for cx, cz, cr in clearings:
        keep &= np.hypot(roots[:, 0] - cx, roots[:, 1] - cz) > cr
    roots = roots[keep & in_wedge(roots, sub)]
    n = roots.shape[0]
    if n == 0:
        return TriMesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 2)), np.zeros((0, 3)))
    h = rng.uniform(height[0], height[1], n)
    lean_az = rng.uniform(0, 2 * np.pi, n)
    c = np.stack([np.sin(lean_az), np.zeros(n), np.cos(lean_az)], -1)
    bend = rng.uniform(0.05, 0.6, n)
    twist = rng.uniform(-0.6, 0.6, n)
    side = np.stack([np.cos(lean_az + twist), np.zeros(n), -np.sin(lean_az + twist)], -1)  # horizontal, ~ ⟂ c
    w0 = width * rng.uniform(0.6, 1.4, n)
    s = np.linspace(0, 1, segments + 1)
    root3 = np.stack([roots[:, 0], np.zeros(n), roots[:, 1]], -1)
    centre = root3[:, None] + h[:, None, None] * (s[None, :, None] * np.array([0.0, 1.0, 0.0]) +
                                                   (bend[:, None] * s[None] ** 2)[..., None] * c[:, None])
    wid = w0[:, None] * (1 - s[None]) ** 0.7
    left = centre - 0.5 * wid[..., None] * side[:, None]
    right = centre + 0.5 * wid[..., None] * side[:, None]
    pos = np.stack([left, right], 2).reshape(n, -1, 3)  # per blade: (s0 L, s0 R, s1 L, s1 R, ...)
    # normals: across x along
    tang = np.gradient(centre, axis=1)
    nrm = np.cross(side[:, None].repeat(segments + 1, 1), tang)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=-1, keepdims=True), 1e-12)
    nrm = np.repeat(nrm, 2, axis=1)
    uv0 = np.stack([(roots[:, 0] - offset[0]) / extent[0], (roots[:, 1] - offset[1]) / extent[1]], -1)
    du = np.stack([-0.5 * wid, 0.5 * wid], 2).reshape(n, -1) / extent[0]
    dv = np.repeat(s[None] * h[:, None], 2, axis=1) / extent[1]
    uv = uv0[:, None] + np.stack([du, dv], -1)
    k = np.arange(segments)
    a, b, cc, d = 2 * k, 2 * k + 1, 2 * k + 2, 2 * k + 3
    f = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, cc], -1)])  # (2 segments, 3)
    V = pos.shape[1]
    faces = (f[None] + (np.arange(n) * V)[:, None, None]).reshape(-1, 3)
    return TriMesh(pos.reshape(-1, 3), faces, uv.reshape(-1, 2), nrm.reshape(-1, 3))
