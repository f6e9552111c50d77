"""
Placement on the meadow
=======================

Defines where things go on the meadow: seeded points in the wedge of ground in front of the set's origin
(metres, the view toward +z): ``near <= r <= far``, |azimuth from +z| <= ``half_angle``; uniform over its area,
or in Gaussian patches (flowers grow in patches).

-   :func:`wedge_points`: points uniform over the wedge's area; :func:`in_wedge`: whether points lie in it.
-   :func:`patch_points`: points in Gaussian patches.
"""
from __future__ import annotations

import numpy as np

__all__ = ["wedge_points", "in_wedge", "patch_points"]


def wedge_points(rng: np.random.Generator, n: int, area: dict) -> np.ndarray:
    """``n`` points (x, z) uniform over the wedge's area."""
    r = np.sqrt(rng.uniform(area["near"] ** 2, area["far"] ** 2, n))
    a = np.radians(rng.uniform(-area["half_angle"], area["half_angle"], n))
    return np.stack([r * np.sin(a), r * np.cos(a)], -1)


def in_wedge(xz: np.ndarray, area: dict) -> np.ndarray:
    r = np.hypot(xz[:, 0], xz[:, 1])
    a = np.degrees(np.arctan2(xz[:, 0], xz[:, 1]))
    return (r >= area["near"]) & (r <= area["far"]) & (np.abs(a) <= area["half_angle"])


def patch_points(rng: np.random.Generator, n: int, area: dict, patches: int, radius: float) -> np.ndarray:
    """``n`` points in ``patches`` Gaussian patches (sigma ``radius`` at 3 m, growing with distance) whose centres
    are uniform in distance and azimuth over the wedge (as many patches per metre of depth near the camera as
    far away: the foreground is not empty), rejection keeping every point inside it."""
    m = max(1, patches)
    r = rng.uniform(area["near"], area["far"], m)
    a = np.radians(rng.uniform(-area["half_angle"], area["half_angle"], m))
    centres = np.stack([r * np.sin(a), r * np.cos(a)], -1)
    out = np.zeros((0, 2))
    for _ in range(50):
        c = centres[rng.integers(0, centres.shape[0], 4 * n)]
        p = c + rng.normal(0, radius, c.shape) * np.clip(np.hypot(c[:, :1], c[:, 1:]) / 3.0, 0.5, 3.0)
        out = np.concatenate([out, p[in_wedge(p, area)]])
        if out.shape[0] >= n:
            break
    return out[:n]
