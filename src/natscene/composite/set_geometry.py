"""The shared geometry of the set's rendering (Dong 2007 Ch. 2): the same rays for every colour mode, so that
the modes (:mod:`natscene.composite.renderer`: hybrid and RGB; :mod:`natscene.composite.full_spectral`) differ only
in how colour is carried.

Camera rays through fixed stratified sub-pixel positions, each with two neighbour rays one sample spacing away
(texture footprints, :mod:`natscene.composite.footprint`); closest hits with the meshes (Mitsuba,
:mod:`natscene.composite.tracer`; cut-outs by the textures' alpha skipped) and the ground plane; sun visibility by
shadow rays (front and, through translucent sheets, back); for film samples, the mirror ray and what it hits.
The set's sun (its direction, its spectrum and that spectrum's RGB value, Dong §2.3.3) is held here too: the
shadow rays need it, every shading mode uses it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from natscene.composite.footprint import texture_derivatives
from natscene.composite.set_spec import SetSpec
from natscene.composite.texture import MipTexture
from natscene.composite.tracer import SetTracer, ground_hits
from natscene.spectral.grid import spectrum_to_rgb

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
        self.timing = {"geometry": 0.0, "shading": 0.0}

    def _classify(self, label):
        lab = np.where(label >= 0, label, len(self.spec.shapes))
        return self.kind_of[lab], self.index_of[lab]

    def _cut(self, index: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """Whether surface samples fall in a transparent part (alpha < 0.5) of their cut-out texture (one
        lookup in the atlas of the cut-out textures' alpha channels)."""
        drop = np.zeros(index.size, bool)
        slot = self._cut_slot[index]
        m = np.flatnonzero(slot >= 0)
        if m.size:
            drop[m] = self._cut_alpha.bilinear(uv[m], slot[m])[:, 0] < 0.5
        return drop

    def _mesh_hits(self, origins: np.ndarray, dirs: np.ndarray) -> dict:
        """Closest mesh hits skipping the cut-outs (the ray goes on through transparent texels)."""
        o = np.broadcast_to(origins, dirs.shape).astype(np.float64)
        g = self.tracer.intersect(o, dirs)
        kind, index = self._classify(g["label"])
        g["t"] = np.asarray(g["t"], np.float64)
        for _ in range(16):
            sm = np.flatnonzero(kind == KIND_SURFACE)
            if sm.size == 0:
                break
            ids = sm[self._cut(index[sm], g["uv"][sm])]
            if ids.size == 0:
                break
            start = o[ids] + dirs[ids] * (g["t"][ids] + EPS)[:, None]
            g2 = self.tracer.intersect(start, dirs[ids])
            g2["t"] = g["t"][ids] + EPS + g2["t"]
            for key in g:
                g[key][ids] = g2[key]
            kind[ids], index[ids] = self._classify(g2["label"])
        g["kind"], g["index"] = kind, index
        return g

    def _sun(self, kind, index, p, n, ng):
        """(front, back) sun terms: max(±n.l, 0) times the shadow-ray visibility (back only for translucent
        surfaces)."""
        M = kind.shape[0]
        front, back = np.zeros(M, np.float32), np.zeros(M, np.float32)
        if not np.any(self.sun_rgb > 0):
            return front, back
        l = self.sun_dir
        nl = n @ l
        lit = np.flatnonzero((kind >= 0) & (nl > 0))
        tr = self.translucency[np.where(kind == KIND_SURFACE, index, -1)]
        behind = np.flatnonzero((kind == KIND_SURFACE) & (nl < 0) & (tr > 0))
        for sel, sign, out in ((lit, 1.0, front), (behind, -1.0, back)):
            if sel.size == 0:
                continue
            side = sign * np.sign(ng[sel] @ l)[:, None]
            side[side == 0] = sign
            start = p[sel] + ng[sel] * side * EPS * 5
            on_ground = kind[sel] == KIND_GROUND
            occ = np.zeros(sel.size, bool)
            occ[~on_ground] = self.tracer.occluded(start[~on_ground], l)
            occ[on_ground] = self.ground_tracer.occluded(start[on_ground], l)
            vis = sel[~occ]
            out[vis] = np.abs(nl[vis])
        return front, back

    def trace(self, origin, dirs: np.ndarray, ddx: np.ndarray | None = None, ddy: np.ndarray | None = None,
              pixels: int = 0) -> Hits:
        """Closest hits of rays from ``origin`` ((3,) or (M, 3)) along unit ``dirs`` (M, 3): meshes and ground,
        texture footprints from the neighbour directions ``ddx``, ``ddy`` (None: no footprint), sun terms.
        ``pixels``: for a block of camera rays (sample-major), its number of pixels."""
        t0 = time.perf_counter()
        dirs = np.asarray(dirs, np.float64)
        M = dirs.shape[0]
        o = np.broadcast_to(np.asarray(origin, np.float64), (M, 3))
        g = self._mesh_hits(o, dirs)
        kind, index = g["kind"], g["index"]
        t = g["t"]
        p = o + dirs * np.where(np.isfinite(t), t, 0.0)[:, None]
        n = g["sn"].astype(np.float64)
        ng = g["n"].astype(np.float64)
        uv = g["uv"].astype(np.float64)
        dp_du, dp_dv = g["dp_du"].astype(np.float64), g["dp_dv"].astype(np.float64)
        gr = self.spec.ground
        if gr is not None:
            tg = ground_hits(o, dirs)
            on = np.flatnonzero(tg < t)
            if on.size:
                kind[on], index[on], t[on] = KIND_GROUND, 0, tg[on]
                p[on] = o[on] + dirs[on] * tg[on, None]
                p[on, 1] = 0.0
                n[on] = ng[on] = [0.0, 1.0, 0.0]
                ex, ez = gr.extent
                uv[on] = np.stack([(p[on, 0] - gr.offset[0]) / ex, (p[on, 2] - gr.offset[1]) / ez], -1)
                dp_du[on] = [ex, 0.0, 0.0]
                dp_dv[on] = [0.0, 0.0, ez]
        duv_dx = duv_dy = None
        if ddx is not None:
            duv_dx = np.zeros((M, 2))
            duv_dy = np.zeros((M, 2))
            s = np.flatnonzero(kind > KIND_GROUND)
            if s.size:
                duv_dx[s], duv_dy[s] = texture_derivatives(o[s], p[s], ng[s], ddx[s], ddy[s], dp_du[s], dp_dv[s])
            s = np.flatnonzero(kind == KIND_GROUND)
            if s.size:  # the plane y = 0: the neighbour rays' own ground points, over the texture's extent
                inv = np.array([1.0 / gr.extent[0], 1.0 / gr.extent[1]])
                for nd, out in ((ddx, duv_dx), (ddy, duv_dy)):
                    dd = nd[s]
                    with np.errstate(divide="ignore", invalid="ignore"):
                        tt = np.where(dd[:, 1] < 0, -o[s, 1] / dd[:, 1], np.inf)
                    q = o[s][:, [0, 2]] + dd[:, [0, 2]] * tt[:, None]
                    out[s] = np.where(np.isfinite(tt)[:, None], (q - p[s][:, [0, 2]]) * inv, 1e6)
        front, back = self._sun(kind, index, p, n, ng)
        self.timing["geometry"] += time.perf_counter() - t0
        return Hits(o, dirs, kind, index, t, p, n, ng, uv, duv_dx, duv_dy, front, back, pixels)

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
        which the footprint's plane intersections do not need), each (spp·n, 3) sample-major, for the stratified
        samples of the pixels a..b (row-major)."""
        cam = self.spec.camera
        H, W = cam.height, cam.width
        offs = stratified_offsets(self.spec.spp)
        step = 1.0 / int(np.ceil(np.sqrt(self.spec.spp)))
        right, up, fwd = cam.basis()
        th = np.tan(np.radians(cam.fov) / 2)
        ex = right * (2 * th * (W / H) / W * step)
        ey = -up * (2 * th / H * step)
        n = b - a
        d, dx, dy = (np.empty((offs.shape[0] * n, 3)) for _ in range(3))
        row, col = np.divmod(np.arange(a, b), W)
        col, row = col.astype(np.float64), row.astype(np.float64)
        for s, off in enumerate(offs):
            x = ((2 * (col + 0.5 + off[0]) / W - 1) * th * (W / H))[:, None]
            y = ((1 - 2 * (row + 0.5 + off[1]) / H) * th)[:, None]
            D = x * right + y * up + fwd
            L = np.linalg.norm(D, axis=-1, keepdims=True)
            k = slice(s * n, (s + 1) * n)
            np.divide(D, L, out=d[k])
            np.divide(D + ex, L, out=dx[k])
            np.divide(D + ey, L, out=dy[k])
        return d, dx, dy

    def blocks(self, block_rays: int = 1 << 17):
        """Yield (pixel slice, dirs, ddx, ddy), the directions (spp·n, 3) sample-major, over blocks of pixels."""
        P = self.spec.camera.height * self.spec.camera.width
        step = max(1, block_rays // self.spec.spp)
        for a in range(0, P, step):
            b = min(P, a + step)
            t0 = time.perf_counter()
            d, dx, dy = self.camera_rays(a, b)
            self.timing["geometry"] += time.perf_counter() - t0
            yield slice(a, b), d, dx, dy
