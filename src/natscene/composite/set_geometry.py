"""
Shared geometry of the set's rendering
======================================

Defines the shared geometry of the set's rendering (Dong 2007 Ch. 2): the same rays for every colour mode, so that
the modes (:mod:`natscene.composite.renderer`: hybrid and RGB; :mod:`natscene.composite.full_spectral`) differ only
in how colour is carried.

-   :class:`SetGeometry`: traces the set's rays; their geometry in :class:`Hits` and :class:`MirrorHits`
    (:data:`KIND_SKY`, :data:`KIND_GROUND`, :data:`KIND_SURFACE`, :data:`KIND_FILM`: what a ray hit).
-   :func:`stratified_offsets`: the sub-pixel offsets of the camera rays; :data:`EPS`: the offset of secondary
    ray origins.

Camera rays through fixed stratified sub-pixel positions, each with two neighbour rays one sample spacing away
(texture footprints, :mod:`natscene.composite.footprint`); closest hits with the meshes (Mitsuba,
:mod:`natscene.composite.tracer`; cut-outs by the textures' alpha skipped) and the ground plane; sun visibility by
shadow rays (front and, through translucent sheets, back); for film samples, the mirror ray and what it hits.
The set's sun (its direction, its spectrum and that spectrum's RGB value, Dong §2.3.3) is held here too: the
shadow rays need it, every shading mode uses it.

A block of rays runs as Dr.Jit kernels from the camera rays to the sun terms (float64 for directions, hit
points and footprints, float32 for the Mitsuba queries, in the order of the formulas without fused
multiply-adds); its results are copied to numpy once, for the shading.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from natscene.composite.footprint import texture_derivative
from natscene.composite.set_spec import SetSpec
from natscene.composite.texture import MipTexture
from natscene.composite.tracer import SetTracer, ground_hits
from natscene.composite.vectors import array3f64, dot
from natscene.spectral.grid import spectrum_to_rgb

__all__ = ["KIND_SKY", "KIND_GROUND", "KIND_SURFACE", "KIND_FILM", "EPS", "stratified_offsets", "Hits", "MirrorHits",
           "SetGeometry"]

KIND_SKY, KIND_GROUND, KIND_SURFACE, KIND_FILM = -1, 0, 1, 2
EPS = 2e-5  # metres: offset of secondary ray origins


def stratified_offsets(spp: int) -> np.ndarray:
    """Deterministic sub-pixel offsets (spp, 2) in [-0.5, 0.5)² (a k×k grid, k = ceil(sqrt(spp)))."""
    k = int(np.ceil(np.sqrt(spp)))
    g = (np.arange(k) + 0.5) / k - 0.5
    xx, yy = np.meshgrid(g, g)
    return np.stack([xx.ravel(), yy.ravel()], -1)[:spp]


@dataclass
class Hits:
    """Geometry of a set of rays (the same for all colour modes)."""

    origin: np.ndarray  # (M, 3) float64
    dirs: np.ndarray  # (M, 3)
    kind: np.ndarray  # KIND_* per ray
    index: np.ndarray  # surface / film index
    t: np.ndarray  # (M,) distance (inf for the sky)
    p: np.ndarray  # (M, 3) float64
    n: np.ndarray  # (M, 3) shading normal facing the ray origin
    ng: np.ndarray  # (M, 3) geometric normal facing the ray origin
    uv: np.ndarray  # (M, 2)
    duv_dx: np.ndarray | None  # (M, 2) texture footprint (None: secondary rays, coarse lookups)
    duv_dy: np.ndarray | None
    sun_front: np.ndarray  # (M,) max(n.l, 0) * V
    sun_back: np.ndarray  # (M,) max(-n.l, 0) * V (through translucent sheets)
    pixels: int = 0  # camera rays: pixels in the block (samples are sample-major, pixel = index % pixels)


@dataclass
class MirrorHits:
    """Film samples: view/sun geometry and what their mirror rays hit."""

    cos_v: np.ndarray
    cos_d: np.ndarray
    nh: np.ndarray
    hits: Hits


class SetGeometry:
    """Traces the set's rays: camera rays in blocks, closest hits with texture footprints and sun terms, mirror
    rays of film samples. ``timing["geometry"]``: seconds spent here."""

    def __init__(self, spec: SetSpec):
        self.spec = spec
        self.tracer = SetTracer([s.mesh for s in spec.shapes])
        casters = [s.mesh if s.shadows_ground else s.mesh.keep_faces(np.zeros(s.mesh.n_faces, bool))
                   for s in spec.shapes]
        self.ground_tracer = self.tracer if all(s.shadows_ground for s in spec.shapes) else SetTracer(casters)
        self.kind_of = np.array([KIND_FILM if s.film is not None else KIND_SURFACE for s in spec.shapes] + [KIND_SKY])
        self.index_of = np.array([(s.film if s.film is not None else s.surface) for s in spec.shapes] + [0])
        self.sun_dir = np.asarray(spec.sun_dir, np.float64) / np.linalg.norm(spec.sun_dir)
        self.sun_S = spec.sun_spectrum().astype(np.float32)
        # Dong §2.3.3: the RGB value of the spectral light, computed once in preprocessing
        self.sun_rgb = spectrum_to_rgb(self.sun_S.astype(np.float64), spec.grid).astype(np.float32)
        if self.sun_dir[1] <= 0:
            self.sun_rgb = np.zeros(3, np.float32)
            self.sun_S = np.zeros_like(self.sun_S)
        self.translucency = np.array([s.translucency for s in spec.surfaces] + [0.0], np.float32)
        cut = [i for i, s in enumerate(spec.surfaces) if s.cutout and s.texture is not None]
        self._cut_slot = np.full(len(spec.surfaces), -1, np.int64)  # surface -> image of the alpha atlas
        self._cut_slot[cut] = np.arange(len(cut))
        self._cut_alpha = MipTexture.atlas([spec.surfaces[i].texture.levels[0][..., -1:] for i in cut]) \
            if cut else None
        # per shape label (the last entry: no shape): the cut-out atlas image of its surface, or -1
        cut_of = [self._cut_slot[s.surface] if s.film is None else -1 for s in spec.shapes] + [-1]
        mi, dr = self.tracer.mi, self.tracer.dr
        self.mi, self.dr = mi, dr
        self._tabs = {"kind": mi.Int32(self.kind_of.astype(np.int32)),
                      "index": mi.Int32(self.index_of.astype(np.int32)),
                      "cut": mi.Int32(np.asarray(cut_of, np.int32)), "tr": mi.Float(self.translucency)}
        self.timing = {"geometry": 0.0, "shading": 0.0}

    def _lookup_label(self, table: str, label):
        """Per-ray entry of a per-shape table (kind, index, cut-out image) for Dr.Jit labels (-1: none)."""
        tab = self._tabs[table]
        return self.dr.gather(type(tab), tab, self.dr.select(label >= 0, label, len(self.spec.shapes)))

    def _mesh_hits(self, o, d) -> dict:
        """Closest mesh hits of Dr.Jit rays skipping the cut-outs: a sample on a cut-out surface whose atlas
        alpha is below 0.5 goes on from EPS past its hit (at most 16 times), evaluated."""
        mi, dr = self.mi, self.dr
        g = self.tracer.intersect_dr(o, d)
        dr.eval(*g.values())
        for _ in range(16 if self._cut_alpha is not None else 0):
            slot = self._lookup_label("cut", g["label"])
            need = slot >= 0
            sl = mi.UInt32(dr.select(need, slot, 0))
            u, v = mi.Float64(g["uv"].x), mi.Float64(g["uv"].y)
            alpha = self._cut_alpha.lookup_dr(u, v, sl, sl, mi.Float(0.0))[0]
            redo = need & (alpha < 0.5)
            dr.eval(redo)
            if not dr.any(redo):
                break
            g2 = self.tracer.intersect_dr(o + d * (g["t"] + EPS), d, redo)
            g2["t"] = g["t"] + EPS + g2["t"]
            g = {key: dr.select(redo, g2[key], g[key]) for key in g}
            dr.eval(*g.values())
        return g

    def _sun(self, kind, index, p, n, ng):
        """(front, back) sun terms (Dr.Jit Float64): max(±n.l, 0) times the shadow-ray visibility (back only for
        translucent surfaces)."""
        mi, dr = self.mi, self.dr
        M = dr.width(kind)
        if not np.any(self.sun_rgb > 0):
            return dr.zeros(mi.Float64, M), dr.zeros(mi.Float64, M)
        l = array3f64(self.sun_dir)
        lf = mi.Vector3f(l)
        nl = dot(n, l)
        surf = kind == KIND_SURFACE
        tr = dr.gather(mi.Float, self._tabs["tr"], dr.select(surf, index, len(self.spec.surfaces)))
        lit = (kind >= 0) & (nl > 0)
        behind = surf & (nl < 0) & (tr > 0)
        on_ground = kind == KIND_GROUND
        ngl = dot(ng, l)
        out = []
        for sel, sign in ((lit, 1.0), (behind, -1.0)):
            side = dr.select(ngl < 0, -sign, sign)
            start = p + ng * side * EPS * 5
            occ = self.tracer.occluded_dr(start, lf, sel & ~on_ground) | \
                self.ground_tracer.occluded_dr(start, lf, sel & on_ground)
            out.append(dr.select(sel & ~occ, dr.abs(nl), 0.0))
        return out[0], out[1]

    def trace(self, origin, dirs, ddx=None, ddy=None, pixels: int = 0) -> Hits:
        """Closest hits of rays from ``origin`` ((3,) or (M, 3)) along unit ``dirs`` (M, 3; numpy or Dr.Jit
        Array3f64): meshes and ground, texture footprints from the neighbour directions ``ddx``, ``ddy``
        (None: no footprint), sun terms; one Dr.Jit pipeline, the results copied to numpy once.
        ``pixels``: for a block of camera rays (sample-major), its number of pixels."""
        t0 = time.perf_counter()
        mi, dr = self.mi, self.dr
        d = dirs if isinstance(dirs, mi.Array3f64) else array3f64(dirs)
        M = dr.width(d)
        org = np.asarray(origin, np.float64)
        if M == 0:
            z = np.zeros((0, 3))
            return Hits(z, z, np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), z, z, z, np.zeros((0, 2)),
                        None, None, np.zeros(0, np.float32), np.zeros(0, np.float32), pixels)
        o = array3f64(org)
        g = self._mesh_hits(o, d)
        kind, index = self._lookup_label("kind", g["label"]), self._lookup_label("index", g["label"])
        t = g["t"]
        n, ng = mi.Array3f64(g["sn"]), mi.Array3f64(g["n"])
        uv = mi.Array2f64(g["uv"])
        dp_du, dp_dv = mi.Array3f64(g["dp_du"]), mi.Array3f64(g["dp_dv"])
        gr = self.spec.ground
        on = dr.full(mi.Bool, False, M)
        if gr is not None:  # the plane y = 0 (tracer.ground_hits)
            tg = ground_hits(o, d)
            on = tg < t
            kind, index, t = dr.select(on, KIND_GROUND, kind), dr.select(on, 0, index), dr.select(on, tg, t)
        p = o + d * dr.select(dr.isfinite(t), t, 0.0)
        if gr is not None:
            ex, ez = (float(e) for e in gr.extent)
            p = mi.Array3f64(p.x, dr.select(on, 0.0, p.y), p.z)
            up = mi.Array3f64(0.0, 1.0, 0.0)
            n, ng = dr.select(on, up, n), dr.select(on, up, ng)
            uv = dr.select(on, mi.Array2f64((p.x - gr.offset[0]) / ex, (p.z - gr.offset[1]) / ez), uv)
            dp_du = dr.select(on, mi.Array3f64(ex, 0.0, 0.0), dp_du)
            dp_dv = dr.select(on, mi.Array3f64(0.0, 0.0, ez), dp_dv)
        fp = []
        if ddx is not None:
            mesh = kind > KIND_GROUND
            for nd in (ddx, ddy):
                nd = nd if isinstance(nd, mi.Array3f64) else array3f64(nd)
                f = dr.select(mesh, texture_derivative(o, p, ng, nd, dp_du, dp_dv), 0.0)
                if gr is not None:  # the plane y = 0: the neighbour ray's own ground point, over the extent
                    tt = ground_hits(o, nd)
                    q = mi.Array2f64((o.x + nd.x * tt - p.x) * (1.0 / ex), (o.z + nd.z * tt - p.z) * (1.0 / ez))
                    f = dr.select(on, dr.select(dr.isfinite(tt), q, 1e6), f)
                fp.append(f)
        front, back = self._sun(kind, index, p, n, ng)
        vecs = {"p": p, "n": n, "ng": ng, "uv": uv, "dirs": d}
        dr.eval(kind, index, t, front, back, *vecs.values(), *fp)
        rows = {key: np.ascontiguousarray(np.asarray(v).T) for key, v in vecs.items()}  # (M, 3) / (M, 2) float64
        duv = [np.ascontiguousarray(np.asarray(f).T) for f in fp] or [None, None]
        self.timing["geometry"] += time.perf_counter() - t0
        return Hits(np.broadcast_to(org, (M, 3)), rows["dirs"], np.asarray(kind, np.int64), np.asarray(index, np.int64),
                    np.asarray(t, np.float64), rows["p"], rows["n"], rows["ng"], rows["uv"], duv[0], duv[1],
                    np.asarray(front, np.float32), np.asarray(back, np.float32), pixels)

    def mirror(self, h: Hits, m: np.ndarray) -> MirrorHits:
        """View/sun geometry of the film samples ``m`` and the hits of their mirror rays."""
        v = -h.dirs[m]
        n = h.n[m]
        cos_v = np.clip(np.einsum("ij,ij->i", n, v), 0.0, 1.0)
        refl = 2 * cos_v[:, None] * n - v
        refl /= np.linalg.norm(refl, axis=-1, keepdims=True)
        l = self.sun_dir[None]
        hv = l + v
        hv /= np.maximum(np.linalg.norm(hv, axis=-1, keepdims=True), 1e-12)
        cos_d = np.clip(hv @ self.sun_dir, 0.0, 1.0)
        nh = np.clip(np.einsum("ij,ij->i", n, hv), 0.0, 1.0)
        hits = self.trace(h.p[m] + h.ng[m] * EPS * 5, refl)
        return MirrorHits(cos_v.astype(np.float32), cos_d.astype(np.float32), nh.astype(np.float32), hits)

    def camera_rays(self, a: int, b: int):
        """Unit directions and their x/y neighbour directions (one sample spacing right and down; not normalised,
        which the footprint's plane intersections do not need), each a Dr.Jit Array3f64 of spp·n rays
        sample-major, for the stratified samples of the pixels a..b (row-major)."""
        mi, dr = self.mi, self.dr
        cam = self.spec.camera
        H, W = cam.height, cam.width
        offs = stratified_offsets(self.spec.spp)
        step = 1.0 / int(np.ceil(np.sqrt(self.spec.spp)))
        right, up, fwd = (array3f64(v) for v in cam.basis())
        th = float(np.tan(np.radians(cam.fov) / 2))
        ex = right * (2 * th * (W / H) / W * step)
        ey = -up * (2 * th / H * step)
        n = b - a
        i = dr.arange(mi.UInt32, offs.shape[0] * n)
        s, pix = i // n, a + i % n
        row, col = mi.Float64(pix // W), mi.Float64(pix % W)
        ox = dr.gather(mi.Float64, mi.Float64(offs[:, 0]), s)
        oy = dr.gather(mi.Float64, mi.Float64(offs[:, 1]), s)
        x = (2 * (col + 0.5 + ox) / W - 1) * th * (W / H)
        y = (1 - 2 * (row + 0.5 + oy) / H) * th
        D = right * x + up * y + fwd
        L = dr.sqrt(D.x * D.x + D.y * D.y + D.z * D.z)
        return D / L, (D + ex) / L, (D + ey) / L

    def blocks(self, block_rays: int = 1 << 18):
        """Yield (pixel slice, dirs, ddx, ddy), the directions (spp·n, 3) sample-major, over blocks of pixels.
        The default, 2^18 rays, is for the RGB modes (the hits' fields and the RGB shading arrays, several
        hundred bytes a ray): their peak memory stays below the full-spectral mode's, which passes smaller
        blocks (81 floats a ray in each of its spectral arrays). Fewer blocks mean fewer kernel launches."""
        P = self.spec.camera.height * self.spec.camera.width
        step = max(1, block_rays // self.spec.spp)
        for a in range(0, P, step):
            b = min(P, a + step)
            t0 = time.perf_counter()
            d, dx, dy = self.camera_rays(a, b)
            self.timing["geometry"] += time.perf_counter() - t0
            yield slice(a, b), d, dx, dy
