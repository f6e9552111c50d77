"""
Flowers of the set
==================

Defines the flowers for the set, built from Dong's pattern-map petals (Dong 2007, Ch. 3: the petal colour maps of
Fig. 3.3 are the textures): several curved petal meshes arranged radially round a centre, a domed centre
(the stamens) and a stem:

-   :func:`flower`: the meshes of one flower (:class:`FlowerParts`); :func:`merge_flowers`: those of many.
-   :func:`petal_mesh`: one petal of a :class:`PetalShape` over a :class:`PetalTexture`.
-   :func:`petal_base`: the base and extent of a petal texture's opaque region.

Petal surface. The pattern map's alpha gives the petal outline; its base (the vein root, Table 3.2's petal
base) is the centre of the lowest opaque row. A texel at (u, v) lies at the across-petal offset
x = (u − u_base)·s·(w/h) and the along-petal arc length d = (v − v_base)·s (``s`` = the petal length over
the opaque height), on a centre line that leaves the flower centre at elevation ``opening`` and bends
outward, elevation e(d) = e₀ − bend·d/L (a circular arc: P(d) = ((sin e₀ − sin e)/κ, (cos e − cos e₀)/κ) in
the (radial, up) plane, κ = bend/L); the petal is cupped across its width by ``cup``·x²/(W/2) along the
local normal (−sin e, cos e). Petal k sits at azimuth 2πk/n + φ₀ (``jitter`` degrees of seeded noise);
alternate petals open ``stagger`` degrees apart so that overlapping neighbours do not intersect.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from natscene.composite.maple import cell_keep
from natscene.composite.mesh import TriMesh, grid_surface, merge, rotation_axis, superellipsoid, tube

__all__ = ["petal_base", "PetalShape", "PetalTexture", "petal_mesh", "FlowerParts", "flower", "merge_flowers"]


def petal_base(alpha: np.ndarray, threshold: float = 0.5) -> tuple[float, float, float, float, float]:
    """(u_base, v_base, v_top, u_min, u_max) of a petal texture's opaque region (uv, v up)."""
    a = np.asarray(alpha) > threshold
    if not a.any():
        raise ValueError("petal texture has no opaque texel (alpha > 0.5)")
    h, w = a.shape
    rows = np.flatnonzero(a.any(1))
    cols = np.flatnonzero(a.any(0))
    low = rows[-1]  # lowest opaque image row = the base (v up: smallest v)
    xs = np.flatnonzero(a[low])
    u_base = (xs.mean() + 0.5) / w
    return u_base, 1 - (low + 1) / h, 1 - rows[0] / h, cols[0] / w, (cols[-1] + 1) / w


@dataclass
class PetalShape:
    length: float = 0.035  # metres, base to tip
    opening: float = 55.0  # elevation of the petal at its base (deg above the flower's plane)
    bend: float = 50.0  # how much the petal bends outward from base to tip (deg)
    cup: float = 0.25  # rise of the petal's edges, fraction of its half-width
    centre_radius: float = 0.004  # the petals start this far from the axis (m)
    n: int = 12  # grid vertices per side


class PetalTexture:
    """A pattern map's alpha as a petal outline: its base and extent (:func:`petal_base`) and, per grid size,
    which grid cells hold any opaque texel (the same for every petal cut from it)."""

    def __init__(self, alpha: np.ndarray, aspect: float):
        self.alpha = np.asarray(alpha, np.float32)
        self.aspect = float(aspect)
        self.base = petal_base(self.alpha)
        self._keep = {}

    def grid(self, n: int):
        u_b, v_b, v_t, u0, u1 = self.base
        uu, vv = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v_b, v_t, n))
        if n not in self._keep:
            probe = grid_surface(np.zeros((n, n, 3)), np.stack([uu, vv], -1))
            self._keep[n] = cell_keep(probe, self.alpha)
        return uu, vv, self._keep[n]


def petal_mesh(petal: PetalTexture, shape: PetalShape) -> TriMesh:
    """One petal in its own frame: base at (centre_radius, 0, 0), extending along +x (radial), up +y, width
    along z."""
    u_b, v_b, v_t, u0, u1 = petal.base
    aspect = petal.aspect
    s = shape.length / max(v_t - v_b, 1e-6)
    n = shape.n
    uu, vv, keep = petal.grid(n)
    x = (uu - u_b) * s * aspect  # across
    d = (vv - v_b) * s  # along
    e0 = np.radians(shape.opening)
    kap = np.radians(shape.bend) / shape.length
    e = e0 - kap * d
    if abs(kap) > 1e-9:
        pr, py = (np.sin(e0) - np.sin(e)) / kap, (np.cos(e) - np.cos(e0)) / kap
    else:
        pr, py = d * np.cos(e0), d * np.sin(e0)
    half = max(abs((u0 - u_b) * s * aspect), abs((u1 - u_b) * s * aspect), 1e-6)
    c = shape.cup * x ** 2 / half
    radial = shape.centre_radius + pr - c * np.sin(e)
    up = py + c * np.cos(e)
    pts = np.stack([radial, up, x], -1)
    return grid_surface(pts, np.stack([uu, vv], -1)).keep_faces(keep)


@dataclass
class FlowerParts:
    """The meshes of one flower, by material: ``petals`` (one mesh per petal, all of the flower's pattern),
    ``centre`` and ``stem``; ``axis`` the head's unit axis and ``head`` its centre (for tests and placement)."""

    petals: list
    centre: TriMesh
    stem: TriMesh
    head: np.ndarray
    axis: np.ndarray
    azimuths: np.ndarray  # radians, per petal, about the head axis (before the head's tilt)


def flower(petal: PetalTexture, n_petals: int, position, height: float, tilt: float = 0.0,
           facing: float = 0.0, shape: PetalShape | None = None, phase: float = 0.0, jitter: float = 0.0,
           stagger: float = 6.0, rng: np.random.Generator | None = None, stem_radius: float = 0.0022) -> FlowerParts:
    """A flower standing at ground point ``position`` (x, z) with its head ``height`` metres up, tilted
    ``tilt`` degrees from vertical toward azimuth ``facing`` (degrees from +z toward +x)."""
    shape = shape or PetalShape()
    rng = rng or np.random.default_rng(0)
    base = petal_mesh(petal, shape)
    az = np.radians(phase) + 2 * np.pi * np.arange(n_petals) / n_petals
    if jitter:
        az = az + np.radians(jitter) * rng.uniform(-1, 1, n_petals)
    # head frame: +y -> axis (tilt toward the facing azimuth)
    fa = np.radians(facing)
    toward = np.array([np.sin(fa), 0.0, np.cos(fa)])
    axis = np.cos(np.radians(tilt)) * np.array([0.0, 1.0, 0.0]) + np.sin(np.radians(tilt)) * toward
    Rh = rotation_axis(np.cross([0.0, 1.0, 0.0], toward), tilt) if tilt else np.eye(3)
    g = np.array([position[0], 0.0, position[1]], np.float64)
    head = g + np.array([0.0, height, 0.0]) + 0.25 * height * np.sin(np.radians(tilt)) * toward
    petals = []
    for k, a in enumerate(az):
        p = base
        if stagger and k % 2:
            p = petal_mesh(petal, PetalShape(**{**shape.__dict__, "opening": shape.opening + stagger}))
        Ra = rotation_axis([0.0, 1.0, 0.0], np.degrees(a) - 90.0)  # radial +x -> azimuth a (from +z to +x)
        petals.append(p.transformed(Rh @ Ra, head))
    cr = shape.centre_radius * 1.6
    dome = superellipsoid((cr, cr * 0.7, cr), 2.0, 8, 12, lat_range=(0.0, np.pi / 2))
    centre = dome.transformed(Rh, head)
    # stem: a cubic Bezier from the ground to the head, arriving along the head's axis
    P0, P3 = g, head - axis * cr * 0.2
    P1 = g + np.array([0.0, height * 0.45, 0.0])
    P2 = P3 - axis * height * 0.3
    t = np.linspace(0, 1, 12)[:, None]
    path = (1 - t) ** 3 * P0 + 3 * (1 - t) ** 2 * t * P1 + 3 * (1 - t) * t ** 2 * P2 + t ** 3 * P3
    stem = tube(path, np.linspace(stem_radius * 1.2, stem_radius * 0.8, 12), sides=6)
    return FlowerParts(petals, centre, stem, head, axis, az)


def merge_flowers(flowers: list[FlowerParts]) -> dict:
    """{"petals": merged petals, "centres": ..., "stems": ...} of a list of flowers of one pattern."""
    return {"petals": merge([p for f in flowers for p in f.petals]),
            "centres": merge([f.centre for f in flowers]), "stems": merge([f.stem for f in flowers])}
