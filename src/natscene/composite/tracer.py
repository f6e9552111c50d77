"""Ray casting of the set: Mitsuba 3 for the meshes (petals, leaves, stems, beetles), the ground plane y = 0
analytically.

The meshes go into one Mitsuba scene (RGB variant; meshes built in memory with ``mi.Mesh`` and
``mi.traverse``). A query finds the closest hits of all rays (``ray_intersect_preliminary``: shape, primitive,
distance), then computes the surface fields (geometric and shading normals, uv, ∂p/∂u, ∂p/∂v) for the hits only
(``compute_surface_interaction``), one fused Dr.Jit kernel each: most camera rays see the sky or the ground.
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
        ray = self._rays(origins, dirs)
        pi = self.scene.ray_intersect_preliminary(ray)
        sid = dr.reinterpret_array(mi.UInt32, pi.shape)
        valid = pi.is_valid()
        dr.eval(valid, sid, pi.t, pi.prim_uv, pi.prim_index, pi.shape_index)
        hit = dr.compress(valid)  # most rays miss the meshes (sky, ground): the surface fields of the hits only
        out = _empty_hits(M)
        H = dr.width(hit)
        if H == 0:
            return out
        hp = dr.zeros(mi.PreliminaryIntersection3f, H)
        hp.valid = dr.full(mi.Bool, True, H)
        hp.t = dr.gather(mi.Float, pi.t, hit)
        hp.prim_uv = dr.gather(mi.Point2f, pi.prim_uv, hit)
        hp.prim_index = dr.gather(mi.UInt32, pi.prim_index, hit)
        hp.shape_index = dr.gather(mi.UInt32, pi.shape_index, hit)
        hit_sid = dr.gather(mi.UInt32, sid, hit)
        hp.shape = dr.reinterpret_array(mi.ShapePtr, hit_sid)
        si = hp.compute_surface_interaction(dr.gather(mi.Ray3f, ray, hit), mi.RayFlags.All)
        fields = {"n": si.n, "sn": si.sh_frame.n, "uv": si.uv, "dp_du": si.dp_du, "dp_dv": si.dp_dv}
        dr.eval(hit_sid, hp.t, *fields.values())
        hi = np.asarray(hit, np.int64)
        idx = np.minimum(np.asarray(hit_sid, np.int64), self._label_of_id.size - 1)
        out["label"][hi] = self._label_of_id[idx]
        out["t"][hi] = np.asarray(hp.t, np.float64)
        d = np.asarray(dirs)[hi].astype(np.float32)
        for key, val in fields.items():
            v = np.asarray(val, np.float32).T
            if key in ("n", "sn"):  # facing the ray origin
                v[np.einsum("ij,ij->i", v, d) > 0] *= -1
            out[key][hi] = v
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
