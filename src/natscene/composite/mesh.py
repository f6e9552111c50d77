"""
Triangle meshes of the set
==========================

Defines the triangle meshes of the set (petals, leaves, stems, beetle bodies): a small container and the builders
the object modules share:

-   :class:`TriMesh`: vertices, faces, texture coordinates and normals; :func:`merge`: many meshes as one.
-   :func:`grid_surface`, :func:`grid_faces`: parametric grid surfaces.
-   :func:`tube`, :func:`frame_along`: swept tubes; :func:`superellipsoid`: super-ellipsoids.
-   :func:`vertex_normals`: area-weighted vertex normals.
-   :func:`rotation_y`, :func:`rotation_axis`: rigid rotations.
 Positions are metres in the set's frame (y up, ground y = 0); texture coordinates are
(u, v) in [0, 1]² with v up, the convention of :mod:`natscene.composite.texture`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TriMesh", "merge", "vertex_normals", "grid_faces", "grid_surface", "frame_along", "tube",
           "superellipsoid", "rotation_y", "rotation_axis"]


@dataclass
class TriMesh:
    """Vertices (V, 3), faces (F, 3) int, texture coordinates (V, 2) and unit vertex normals (V, 3)."""

    positions: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    normals: np.ndarray

    @property
    def n_faces(self) -> int:
        return int(self.faces.shape[0])

    def transformed(self, rotation: np.ndarray, translation) -> "TriMesh":
        """The mesh under x -> R x + t (R orthonormal)."""
        R = np.asarray(rotation, np.float64)
        return TriMesh(self.positions @ R.T + np.asarray(translation, np.float64), self.faces, self.uv,
                       self.normals @ R.T)

    def keep_faces(self, keep: np.ndarray) -> "TriMesh":
        """The sub-mesh of the faces where ``keep`` (F,) is true (unused vertices are dropped)."""
        f = self.faces[np.asarray(keep, bool)]
        used = np.unique(f)
        remap = np.full(self.positions.shape[0], -1, np.int64)
        remap[used] = np.arange(used.size)
        return TriMesh(self.positions[used], remap[f], self.uv[used], self.normals[used])


def merge(meshes: list[TriMesh]) -> TriMesh:
    """One mesh holding all of ``meshes`` (faces re-indexed)."""
    if not meshes:
        return TriMesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 2)), np.zeros((0, 3)))
    off = np.cumsum([0] + [m.positions.shape[0] for m in meshes[:-1]])
    return TriMesh(np.concatenate([m.positions for m in meshes]),
                   np.concatenate([m.faces + o for m, o in zip(meshes, off)]),
                   np.concatenate([m.uv for m in meshes]), np.concatenate([m.normals for m in meshes]))


def vertex_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted average of the incident face normals, normalised (V, 3)."""
    p = np.asarray(positions, np.float64)
    fn = np.cross(p[faces[:, 1]] - p[faces[:, 0]], p[faces[:, 2]] - p[faces[:, 0]])  # |fn| = 2 area
    n = np.zeros_like(p)
    for k in range(3):
        np.add.at(n, faces[:, k], fn)
    ln = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.where(ln > 0, n / np.maximum(ln, 1e-30), np.array([0.0, 1.0, 0.0]))


def grid_faces(nu: int, nv: int, wrap_u: bool = False) -> np.ndarray:
    """Two triangles per cell of an (nv, nu) vertex grid (row-major, u fastest); ``wrap_u`` closes the rows."""
    cu = nu if wrap_u else nu - 1
    j, i = np.meshgrid(np.arange(cu), np.arange(nv - 1))
    a = i * nu + j
    b = i * nu + (j + 1) % nu
    c = (i + 1) * nu + j
    d = (i + 1) * nu + (j + 1) % nu
    return np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])


def grid_surface(points: np.ndarray, uv: np.ndarray | None = None, wrap_u: bool = False) -> TriMesh:
    """A mesh from a (nv, nu, 3) grid of points (and (nv, nu, 2) texture coordinates)."""
    nv, nu = points.shape[:2]
    if uv is None:
        uu, vv = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv))
        uv = np.stack([uu, vv], -1)
    f = grid_faces(nu, nv, wrap_u)
    p = points.reshape(-1, 3).astype(np.float64)
    return TriMesh(p, f, uv.reshape(-1, 2).astype(np.float64), vertex_normals(p, f))


def frame_along(tangent: np.ndarray, up_hint=(0.0, 1.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to each row of ``tangent`` (K, 3) and to each other (rotation
    minimising for gently curved paths)."""
    t = tangent / np.linalg.norm(tangent, axis=-1, keepdims=True)
    hint = np.broadcast_to(np.asarray(up_hint, np.float64), t.shape).copy()
    near = np.abs(np.einsum("ij,ij->i", t, hint)) > 0.95
    hint[near] = [1.0, 0.0, 0.0]
    a = np.cross(t, hint)
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    b = np.cross(a, t)
    return a, b


def tube(path: np.ndarray, radius, sides: int = 8) -> TriMesh:
    """A closed-ring tube swept along the polyline ``path`` (K, 3) with ``radius`` (scalar or (K,)); open
    ends (stems, legs, antennae are seen from the side). u runs round the tube, v along it."""
    path = np.asarray(path, np.float64)
    K = path.shape[0]
    tang = np.gradient(path, axis=0)
    a, b = frame_along(tang)
    r = np.broadcast_to(np.asarray(radius, np.float64), (K,))[:, None, None]
    th = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.cos(th)[None, :, None] * a[:, None] + np.sin(th)[None, :, None] * b[:, None]
    pts = path[:, None] + r * ring
    uu, vv = np.meshgrid(np.arange(sides) / sides, np.linspace(0, 1, K))
    f = grid_faces(sides, K, wrap_u=True)
    p = pts.reshape(-1, 3)
    return TriMesh(p, f, np.stack([uu, vv], -1).reshape(-1, 2), ring.reshape(-1, 3))


def superellipsoid(radii, exponent: float = 2.0, n_lat: int = 16, n_lon: int = 24,
                   lat_range=(-np.pi / 2, np.pi / 2)) -> TriMesh:
    """A super-ellipsoid |x/a|^e + |y/b|^e + |z/c|^e = 1 (e = 2: an ellipsoid; larger: boxier), centred on
    the origin, as a latitude/longitude grid (``lat_range`` < the full range gives a dome)."""
    a, b, c = (float(r) for r in radii)
    lat = np.linspace(lat_range[0], lat_range[1], n_lat)
    lon = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    LA, LO = np.meshgrid(lat, lon, indexing="ij")
    k = 2.0 / float(exponent)

    def spow(x):
        return np.sign(x) * np.abs(x) ** k

    x = a * spow(np.cos(LA)) * spow(np.cos(LO))
    z = c * spow(np.cos(LA)) * spow(np.sin(LO))
    y = b * spow(np.sin(LA))
    pts = np.stack([x, y, z], -1)
    uu, vv = np.meshgrid(lon / (2 * np.pi), (lat - lat[0]) / max(lat[-1] - lat[0], 1e-9))
    f = grid_faces(n_lon, n_lat, wrap_u=True)
    p = pts.reshape(-1, 3)
    return TriMesh(p, f, np.stack([uu, vv], -1).reshape(-1, 2), vertex_normals(p, f))


def rotation_y(deg: float) -> np.ndarray:
    """Rotation about +y by ``deg`` (from +z toward +x, the azimuth convention of the sun)."""
    a = np.radians(deg)
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def rotation_axis(axis, deg: float) -> np.ndarray:
    """Rodrigues rotation about a unit ``axis`` by ``deg``."""
    k = np.asarray(axis, np.float64)
    k = k / np.linalg.norm(k)
    a = np.radians(deg)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
