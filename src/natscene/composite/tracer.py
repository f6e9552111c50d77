"""Ray casting of the set: Mitsuba 3 for the meshes (petals, leaves, stems, beetles), the ground plane y = 0
analytically.

The meshes go into one Mitsuba scene (RGB variant; meshes built in memory with ``mi.Mesh`` and
``mi.traverse``); a query is one fused Dr.Jit kernel whose fields (shape, validity, distance, geometric and
shading normals, uv, ∂p/∂u, ∂p/∂v) are evaluated together; only the hits' fields are copied to numpy (most
camera rays see the sky or the ground).
The ground is not a mesh: a plane to the horizon in float32 would lose the centimetres of the near field at
kilometres of extent, so its hit is t = −o_y / d_y in float64 (d_y < 0) and its texture coordinates are
(x, z) divided by the texture's extent in metres.
"""
from __future__ import annotations

import numpy as np

from natscene.composite.mesh import TriMesh


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

    def _rays(self, origins: np.ndarray, dirs: np.ndarray):
        mi = self.mi
        o = np.ascontiguousarray(np.broadcast_to(np.asarray(origins, np.float32), np.shape(dirs)).T)
        v = np.ascontiguousarray(np.asarray(dirs, np.float32).T)
        return mi.Ray3f(mi.Point3f(o[0], o[1], o[2]), mi.Vector3f(v[0], v[1], v[2]))

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> dict:
        """Closest mesh hits of rays (M, 3): ``label`` (M,) shape index or -1, ``t`` (inf: none), ``n``
        (geometric normal), ``sn`` (shading normal), both facing the ray origin, ``uv``, ``dp_du``, ``dp_dv``
        (zero for misses)."""
        M = np.shape(dirs)[0]
        if M == 0 or self.n_shapes == 0 or self._label_of_id.size == 1 and self._label_of_id[0] < 0:
            return _empty_hits(M)
        mi, dr = self.mi, self.dr
        si = self.scene.ray_intersect(self._rays(origins, dirs))
        sid = dr.reinterpret_array(mi.UInt32, si.shape)
        valid = si.is_valid()
        fields = {"t": si.t, "n": si.n, "sn": si.sh_frame.n, "uv": si.uv, "dp_du": si.dp_du, "dp_dv": si.dp_dv}
        dr.eval(sid, valid, *fields.values())
        hit = dr.compress(valid)  # most rays miss the meshes (sky, ground): copy out the hits only
        out = _empty_hits(M)
        if dr.width(hit) == 0:
            return out
        hi = np.asarray(hit, np.int64)
        idx = np.minimum(np.asarray(dr.gather(mi.UInt32, sid, hit), np.int64), self._label_of_id.size - 1)
        out["label"][hi] = self._label_of_id[idx]
        out["t"][hi] = np.asarray(dr.gather(mi.Float, si.t, hit), np.float64)
        for key in ("n", "sn", "uv", "dp_du", "dp_dv"):
            val = fields[key]
            out[key][hi] = np.asarray(dr.gather(type(val), val, hit), np.float32).T
        d = np.asarray(dirs, np.float32)[hi]
        for key in ("n", "sn"):
            flip = hi[np.einsum("ij,ij->i", out[key][hi], d) > 0]
            out[key][flip] *= -1
        return out

    def occluded(self, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """Whether rays from ``origins`` (M, 3) toward ``direction`` (3,) or (M, 3) hit any mesh."""
        M = np.shape(origins)[0]
        if M == 0 or self._label_of_id.size == 1 and self._label_of_id[0] < 0:
            return np.zeros(M, bool)
        dd = np.broadcast_to(np.asarray(direction, np.float32), np.shape(origins))
        hit = self.scene.ray_test(self._rays(origins, dd))
        self.dr.eval(hit)
        return np.asarray(hit, bool)


def _empty_hits(M: int) -> dict:
    return {"label": np.full(M, -1, np.int64), "t": np.full(M, np.inf), "n": np.zeros((M, 3), np.float32),
            "sn": np.zeros((M, 3), np.float32), "uv": np.zeros((M, 2), np.float32),
            "dp_du": np.zeros((M, 3), np.float32), "dp_dv": np.zeros((M, 3), np.float32)}


def ground_hits(origin, dirs: np.ndarray) -> np.ndarray:
    """Distance (M,) along unit ``dirs`` from ``origin`` ((3,) or (M, 3), above y = 0) to the ground plane
    y = 0 (inf: none)."""
    o_y = np.asarray(origin, np.float64)[..., 1]
    d_y = np.asarray(dirs, np.float64)[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d_y < 0, -o_y / d_y, np.inf)
    return np.where(t > 0, t, np.inf)
