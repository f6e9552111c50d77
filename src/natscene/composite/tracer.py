"""
Ray casting of the set
======================

Defines the ray casting of the set: Mitsuba 3 for the meshes (petals, leaves, stems, beetles), the ground plane
y = 0 analytically:

-   :class:`SetTracer`: closest hits and occlusion of rays with the set's meshes.
-   :func:`ground_hits`: the distance along rays to the ground plane.

The meshes go into one Mitsuba scene (RGB variant; meshes built in memory with ``mi.Mesh`` and
``mi.traverse``). The queries take and return Dr.Jit arrays (:meth:`SetTracer.intersect_dr`: shape label,
distance, geometric and shading normals facing the ray origin, uv, ∂p/∂u, ∂p/∂v; :meth:`SetTracer.occluded_dr`),
so that the renderer's geometry runs as one Dr.Jit pipeline; :meth:`SetTracer.intersect` and
:meth:`SetTracer.occluded` are the same queries on numpy arrays.
The ground is not a mesh: a plane to the horizon in float32 would lose the centimetres of the near field at
kilometres of extent, so its hit is t = −o_y / d_y in float64 (d_y < 0) and its texture coordinates are
(x, z) divided by the texture's extent in metres.
"""
from __future__ import annotations

import numpy as np

from natscene.composite.mesh import TriMesh
from natscene.composite.vectors import array3f64, dot

__all__ = ["SetTracer", "ground_hits"]


class SetTracer:
    """Closest hits of rays with the set's meshes (``shapes``: list of TriMesh, one Mitsuba shape each)."""

    def __init__(self, shapes: list[TriMesh]):
        from natscene.variant import select_variant
        self.variant = select_variant(spectral=False)
        import drjit as dr
        import mitsuba as mi
        self.mi, self.dr = mi, dr
        d = {"type": "scene"}
        for i, m in enumerate(shapes):
            if m.n_faces == 0:
                continue
            d[f"s{i:05d}"] = self._mesh(f"s{i:05d}", m)
        self.scene = mi.load_dict(d)
        self.n_shapes = len(shapes)
        sh = list(self.scene.shapes())
        ids = [int(np.asarray(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(s)))[0]) for s in sh]
        self._label_of_id = np.full((max(ids) + 1) if ids else 1, -1, np.int64)
        if ids:
            self._label_of_id[ids] = [int(s.id()[1:]) for s in sh]
        self._label_table = None  # the Dr.Jit copy, made on first query

    def _mesh(self, name: str, m: TriMesh):
        mi = self.mi
        mesh = mi.Mesh(name, vertex_count=int(m.positions.shape[0]), face_count=int(m.n_faces),
                       has_vertex_normals=True, has_vertex_texcoords=True)
        p = mi.traverse(mesh)
        p["vertex_positions"] = mi.Float(np.ascontiguousarray(m.positions, np.float32).ravel())
        p["faces"] = mi.UInt32(np.ascontiguousarray(m.faces, np.uint32).ravel())
        p["vertex_texcoords"] = mi.Float(np.ascontiguousarray(m.uv, np.float32).ravel())
        p["vertex_normals"] = mi.Float(np.ascontiguousarray(m.normals, np.float32).ravel())
        p.update()
        return mesh

    @staticmethod
    def _rays(origins: np.ndarray, dirs: np.ndarray):
        return array3f64(np.broadcast_to(np.asarray(origins, np.float64), np.shape(dirs))), array3f64(dirs)

    def _empty(self):
        return self.n_shapes == 0 or self._label_of_id.size == 1 and self._label_of_id[0] < 0

    def intersect_dr(self, o, d, active=True) -> dict:
        """Closest mesh hits of Dr.Jit rays (origins ``o``, directions ``d``: Array3f64, cast to float32 for the
        query; ``active``: which rays to trace), unevaluated: ``label`` (Int32, shape index, -1: none), ``t``
        (Float64, inf: none), ``n`` (geometric normal), ``sn`` (shading normal), both facing the ray origin,
        ``uv``, ``dp_du``, ``dp_dv`` (float32, zero for misses)."""
        mi, dr = self.mi, self.dr
        M = dr.width(d)
        if self._empty():
            z3 = dr.zeros(mi.Vector3f, M)
            return {"label": dr.full(mi.Int32, -1, M), "t": dr.full(mi.Float64, dr.inf, M), "n": z3, "sn": z3,
                    "uv": dr.zeros(mi.Point2f, M), "dp_du": z3, "dp_dv": z3}
        if self._label_table is None:
            self._label_table = mi.Int32(self._label_of_id.astype(np.int32))
        si = self.scene.ray_intersect(mi.Ray3f(mi.Point3f(o), mi.Vector3f(d)), active)
        valid = si.is_valid()
        sid = dr.minimum(dr.reinterpret_array(mi.UInt32, si.shape), self._label_of_id.size - 1)
        out = {"label": dr.select(valid, dr.gather(mi.Int32, self._label_table, sid, valid), -1),
               "t": dr.select(valid, mi.Float64(si.t), dr.inf)}
        d32 = mi.Vector3f(d)
        for key, v in (("n", si.n), ("sn", si.sh_frame.n)):
            v = dr.select(dot(v, d32) > 0, -v, v)
            out[key] = dr.select(valid, v, 0.0)
        out["uv"] = dr.select(valid, si.uv, 0.0)
        out["dp_du"] = dr.select(valid, si.dp_du, 0.0)
        out["dp_dv"] = dr.select(valid, si.dp_dv, 0.0)
        return out

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> dict:
        """:meth:`intersect_dr` of rays (M, 3) as numpy arrays: ``label`` (M,) int64, ``t`` float64, the other
        fields (M, 3) / (M, 2) float32."""
        M = np.shape(dirs)[0]
        if M == 0 or self._empty():
            return _empty_hits(M)
        h = self.intersect_dr(*self._rays(origins, dirs))
        self.dr.eval(*h.values())
        out = {"label": np.asarray(h["label"], np.int64), "t": np.asarray(h["t"], np.float64)}
        for key in ("n", "sn", "uv", "dp_du", "dp_dv"):
            out[key] = np.ascontiguousarray(np.asarray(h[key], np.float32).T)
        return out

    def occluded_dr(self, o, direction, active=True):
        """Whether Dr.Jit rays from ``o`` (Array3f64) toward ``direction`` hit any mesh (Bool, unevaluated)."""
        mi, dr = self.mi, self.dr
        if self._empty():
            return dr.full(mi.Bool, False, dr.width(o))
        return self.scene.ray_test(mi.Ray3f(mi.Point3f(o), mi.Vector3f(direction)), active)

    def occluded(self, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """Whether rays from ``origins`` (M, 3) toward ``direction`` (3,) or (M, 3) hit any mesh."""
        M = np.shape(origins)[0]
        if M == 0 or self._empty():
            return np.zeros(M, bool)
        o, d = self._rays(origins, np.broadcast_to(np.asarray(direction, np.float64), np.shape(origins)))
        hit = self.occluded_dr(o, d)
        self.dr.eval(hit)
        return np.asarray(hit, bool)


def _empty_hits(M: int) -> dict:
    return {"label": np.full(M, -1, np.int64), "t": np.full(M, np.inf), "n": np.zeros((M, 3), np.float32),
            "sn": np.zeros((M, 3), np.float32), "uv": np.zeros((M, 2), np.float32),
            "dp_du": np.zeros((M, 3), np.float32), "dp_dv": np.zeros((M, 3), np.float32)}


def ground_hits(o, d):
    """Distance (Float64) along unit Dr.Jit directions ``d`` from ``o`` (Array3f64, above y = 0) to the ground
    plane y = 0 (inf: none)."""
    import drjit as dr
    t = dr.select(d.y < 0, -o.y / d.y, dr.inf)
    return dr.select(t > 0, t, dr.inf)
