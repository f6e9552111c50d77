"""The hybrid rendering of the set (Dong 2007 Ch. 2, §2.3-2.5, Fig. 2.3) and its shared geometry.

Geometry (the same for every colour mode, so that the modes differ only in how colour is carried): camera
rays through fixed stratified sub-pixel positions, each with two neighbour rays one sample spacing away
(texture footprints, :mod:`natscene.composite.footprint`); closest hits with the meshes (Mitsuba, cut-outs by
the textures' alpha skipped) and the ground plane; sun visibility by shadow rays; for film samples, the mirror
ray and what it hits.

Shading of RGB materials (ground, petals, leaves, stems; Dong: "RGB materials lit in RGB by the RGB value of
every light", the spectral sun converted once, §2.3.3): L = ρ/π · (E_sun·max(n·l, 0)·V + E_sky(n))
+ τ ρ/π · (E_sun·max(−n·l, 0)·V + E_sky(−n)) for a sheet of translucency τ (light through a petal from
behind), E_sky from :class:`natscene.composite.sky_dome.SkyDome`. Every surface sample then takes the
aerial perspective of Dobashi Eq. 3 with the frame's κ_a over its distance
(:func:`natscene.scatter.compose.apply_atmosphere`, the function the cloud frames use), toward the frame's
sky radiance in the ray's direction, so the ground fades into the same horizon haze as the clouds.

Spectral materials (thin films, §2.5) in hybrid mode: R_film(θ_v, λ)·L_env(λ) of what the mirror ray sees
(its RGB radiance upsampled, Fig. 2.3(b)) plus the sun lobe R_film(θ_d, λ)·E_sun(λ)·(e+8)/(8π)(n·h)^e cosθ V,
with Dong's RGB highlight in the RGB part. Their aerial perspective: the spectral part is scaled by the
luminance-weighted transmittance, the in-scattered sky goes to the RGB part (the set's objects are metres
away; the grey factor differs from per-channel e^{−κ t} by < 1e−4 there). Mode ``"rgb"`` shades the films in
RGB instead (the film reflectance tables integrated to RGB under D65): the baseline of the cost benchmark.

Rays that leave the set show the background plate (the shot's cloud frame, rendered from the same camera).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from natscene.composite.footprint import texture_derivatives
from natscene.composite.hybrid import HybridImage
from natscene.composite.set_spec import SetSpec
from natscene.composite.sky_dome import SkyDome
from natscene.composite.tracer import SetTracer, ground_hits
from natscene.spectral.grid import reflectance_to_rgb, spectrum_to_rgb
from natscene.spectral.illuminants import d65
from natscene.spectral.thin_film import FilmTable, film_table
from natscene.spectral.upsampling import rgb_to_radiance

KIND_SKY, KIND_GROUND, KIND_SURFACE, KIND_FILM = -1, 0, 1, 2
EPS = 2e-5  # metres: offset of secondary ray origins
HAZE_MIN = 1e-4  # in-scattered fraction below which the aerial perspective is not evaluated


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


class SetRenderer:
    """Traces the set's rays once (shared geometry) and shades them in ``hybrid`` or ``rgb`` mode
    (:func:`natscene.composite.full_spectral.render_full_spectral` shades the same rays spectrally).
    ``timing``: seconds in the shared geometry (``geometry``) and in the mode's shading (``shading``)."""

    def __init__(self, spec: SetSpec):
        self.spec = spec
        self.tracer = SetTracer([s.mesh for s in spec.shapes])
        casters = [s.mesh if s.shadows_ground else s.mesh.keep_faces(np.zeros(s.mesh.n_faces, bool))
                   for s in spec.shapes]
        self.ground_tracer = self.tracer if all(s.shadows_ground for s in spec.shapes) else SetTracer(casters)
        self.kind_of = np.array([KIND_FILM if s.film is not None else KIND_SURFACE for s in spec.shapes] + [KIND_SKY])
        self.index_of = np.array([(s.film if s.film is not None else s.surface) for s in spec.shapes] + [0])
        self.tables: list[FilmTable] = [film_table(f.layers, f.substrate, grid=spec.grid,
                                                   angle_step_deg=spec.angle_step_deg) for f in spec.films]
        for t in self.tables:
            t.R = t.R.astype(np.float32)
        self.sun_dir = np.asarray(spec.sun_dir, np.float64) / np.linalg.norm(spec.sun_dir)
        self.sun_S = spec.sun_spectrum().astype(np.float32)
        # Dong §2.3.3: the RGB value of the spectral light, computed once in preprocessing
        self.sun_rgb = spectrum_to_rgb(self.sun_S.astype(np.float64), spec.grid).astype(np.float32)
        if self.sun_dir[1] <= 0:
            self.sun_rgb = np.zeros(3, np.float32)
            self.sun_S = np.zeros_like(self.sun_S)
        g_albedo = spec.ground.texture.mean()[:3] if spec.ground is not None else np.zeros(3)
        self.dome = SkyDome(spec.sky, self.sun_dir, self.sun_rgb, g_albedo)
        self.surface_color = np.array([np.asarray(s.color, np.float32)[:3] for s in spec.surfaces] or
                                      np.zeros((0, 3)), np.float32).reshape(-1, 3)
        self.translucency = np.array([s.translucency for s in spec.surfaces] + [0.0], np.float32)
        self.timing = {"geometry": 0.0, "shading": 0.0}
        self._film_rgb = None

    # ------------------------------------------------------------------------------ geometry
    def _classify(self, label):
        lab = np.where(label >= 0, label, len(self.spec.shapes))
        return self.kind_of[lab], self.index_of[lab]

    def _cut(self, index: np.ndarray, uv: np.ndarray) -> np.ndarray:
        """Whether surface samples fall in a transparent part of their cut-out texture."""
        drop = np.zeros(index.size, bool)
        for i, s in enumerate(self.spec.surfaces):
            if not s.cutout or s.texture is None:
                continue
            m = index == i
            if m.any():
                drop[m] = s.texture.bilinear(uv[m])[:, -1] < 0.5
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

    def camera_rays(self):
        """Unit directions and their x/y neighbour directions (one sample spacing right and down; not normalised,
        which the footprint's plane intersections do not need), each (spp, H·W, 3), for the stratified samples."""
        cam = self.spec.camera
        H, W = cam.height, cam.width
        offs = stratified_offsets(self.spec.spp)
        step = 1.0 / int(np.ceil(np.sqrt(self.spec.spp)))
        right, up, fwd = cam.basis()
        th = np.tan(np.radians(cam.fov) / 2)
        ex = right * (2 * th * (W / H) / W * step)
        ey = -up * (2 * th / H * step)
        d, dx, dy = [], [], []
        for off in offs:
            jj, ii = np.meshgrid(np.arange(W) + 0.5 + off[0], np.arange(H) + 0.5 + off[1])
            x = ((2 * jj / W - 1) * th * (W / H)).reshape(-1, 1)
            y = ((1 - 2 * ii / H) * th).reshape(-1, 1)
            D = x * right + y * up + fwd
            L = np.linalg.norm(D, axis=-1, keepdims=True)
            d.append(D / L)
            dx.append((D + ex) / L)
            dy.append((D + ey) / L)
        return np.stack(d), np.stack(dx), np.stack(dy)

    def blocks(self, block_rays: int = 1 << 17):
        """Yield (pixel slice, dirs, ddx, ddy), the directions (spp·n, 3) sample-major, over blocks of pixels."""
        t0 = time.perf_counter()
        d, dx, dy = self.camera_rays()
        self.timing["geometry"] += time.perf_counter() - t0
        spp, P = d.shape[:2]
        step = max(1, block_rays // spp)
        for a in range(0, P, step):
            b = min(P, a + step)
            yield slice(a, b), d[:, a:b].reshape(-1, 3), dx[:, a:b].reshape(-1, 3), dy[:, a:b].reshape(-1, 3)

    # ------------------------------------------------------------------------------ materials
    def albedo_rgb(self, h: Hits, sel: np.ndarray, coarse: bool = False) -> np.ndarray:
        """RGB albedo (len(sel), 3) of ground/surface samples ``sel``: filtered texture lookups over their
        footprints (``coarse``: secondary rays, the texture's level ``max_level - 4``)."""
        out = np.zeros((sel.size, 3), np.float32)
        kind, index = h.kind[sel], h.index[sel]
        spec = self.spec
        g = kind == KIND_GROUND
        if g.any() and spec.ground is not None:
            if coarse or h.duv_dx is None or not h.pixels or spec.spp == 1:
                out[g] = self.texture_lookup(spec.ground.texture, h, sel[g], coarse)[:, :3]
            else:
                out[g] = self._ground_per_pixel(h, sel[g])
        for i, s in enumerate(spec.surfaces):
            k = (kind == KIND_SURFACE) & (index == i)
            if k.any():
                out[k] = self.texture_lookup(s.texture, h, sel[k], coarse)[:, :3] if s.texture is not None \
                    else self.surface_color[i]
        return out

    def texture_lookup(self, tex, h: Hits, idx: np.ndarray, coarse: bool = False) -> np.ndarray:
        """Filtered lookup of ``tex`` (any channels) for samples ``idx`` over their footprints (``coarse`` or no
        footprint: the texture's level ``max_level - 4``, for secondary rays)."""
        uv = h.uv[idx]
        if coarse or h.duv_dx is None:
            return tex.trilinear(uv, np.full(uv.shape[0], max(tex.max_level - 4, 0)))
        return tex.filtered(uv, h.duv_dx[idx], h.duv_dy[idx], self.spec.max_aniso)

    def _ground_per_pixel(self, h: Hits, gs: np.ndarray) -> np.ndarray:
        """Ground albedo of samples ``gs`` filtered once per pixel where every sample of the pixel sees the
        ground (multisample-style: one lookup at the samples' mean (u, v) over the whole pixel's footprint,
        k = ceil(sqrt(spp)) sample spacings), per sample elsewhere (pixels at an object's edge)."""
        P, spp = h.pixels, self.spec.spp
        tex = self.spec.ground.texture
        pix = gs % P
        full = np.bincount(pix, minlength=P) == spp
        out = np.empty((gs.size, 3), np.float32)
        per = full[pix]
        if per.any():
            fp = np.flatnonzero(full)
            w = np.float64(1.0 / spp)
            g_in = gs[per]
            p_in = pix[per]
            uv = np.stack([np.bincount(p_in, weights=h.uv[g_in, c], minlength=P)[fp] for c in (0, 1)], -1) * w
            k = float(np.ceil(np.sqrt(spp)))
            dx = np.stack([np.bincount(p_in, weights=h.duv_dx[g_in, c], minlength=P)[fp] for c in (0, 1)], -1) * w * k
            dy = np.stack([np.bincount(p_in, weights=h.duv_dy[g_in, c], minlength=P)[fp] for c in (0, 1)], -1) * w * k
            vals = tex.filtered(uv, dx, dy, self.spec.max_aniso)[:, :3]
            slot = np.full(P, -1, np.int64)
            slot[fp] = np.arange(fp.size)
            out[per] = vals[slot[p_in]]
        if (~per).any():
            e = gs[~per]
            out[~per] = tex.filtered(h.uv[e], h.duv_dx[e], h.duv_dy[e], self.spec.max_aniso)[:, :3]
        return out

    def irradiance_rgb(self, h: Hits, sel: np.ndarray) -> np.ndarray:
        """Irradiance (len(sel), 3) on the front side plus τ times the back side's (sun and sky dome)."""
        n = h.n[sel]
        E = self.sun_rgb[None] * h.sun_front[sel, None] + self.dome.irradiance(n)
        tr = np.where(h.kind[sel] == KIND_SURFACE, self.translucency[np.where(h.kind[sel] == KIND_SURFACE,
                                                                                h.index[sel], -1)], 0.0)
        back = np.flatnonzero(tr > 0)
        if back.size:
            Eb = self.sun_rgb[None] * h.sun_back[sel[back], None] + self.dome.irradiance(-n[back])
            E[back] += tr[back, None] * Eb
        return E

    def transmittance(self, h: Hits, sel: np.ndarray) -> np.ndarray:
        """e^{-κ_a t / d_ref} (len(sel), 3) of Dobashi Eq. 3 over the samples' distances (1 without air)."""
        at = self.spec.atmosphere
        if at is None:
            return np.ones((sel.size, 3), np.float32)
        tc = (h.t[sel] / at.reference_distance).astype(np.float32)
        return np.exp(-np.asarray(at.kappa, np.float32)[None] * tc[:, None])

    def hazy(self, h: Hits, sel: np.ndarray) -> np.ndarray:
        """Which samples ``sel`` are far enough for the haze to matter: 1 - e^{-κ t / d_ref} >= ``HAZE_MIN`` in
        some channel (nearer ones keep their radiance, changed by less than 1e-4 of the sky-minus-surface
        difference)."""
        at = self.spec.atmosphere
        return h.t[sel] * float(np.max(at.kappa)) / at.reference_distance >= HAZE_MIN

    def aerial(self, L: np.ndarray, h: Hits, sel: np.ndarray) -> np.ndarray:
        """Dobashi Eq. 3 over the samples ``sel``: L e^{-κ t} + (1 - e^{-κ t}) L_sky(direction)."""
        at = self.spec.atmosphere
        if at is None:
            return L
        from natscene.scatter.compose import apply_atmosphere
        far = self.hazy(h, sel)
        if far.any():
            f = sel[far]
            L[far] = apply_atmosphere(L[far], (h.t[f] / at.reference_distance).astype(np.float32), at.kappa,
                                      self.dome.radiance(h.dirs[f]))
        return L

    def radiance_rgb(self, h: Hits, sel: np.ndarray, coarse: bool = False) -> np.ndarray:
        """RGB radiance arriving along rays ``sel`` that hit ground or RGB surfaces (aerial perspective included)."""
        L = self.albedo_rgb(h, sel, coarse) / np.float32(np.pi) * self.irradiance_rgb(h, sel)
        return self.aerial(L, h, sel)

    def gather_mirror_rgb(self, mh: MirrorHits) -> np.ndarray:
        """RGB radiance along the mirror rays of film samples: set geometry or the sky (a film seen in a film
        shows the sky behind it, every mode)."""
        h = mh.hits
        out = self.dome.radiance(h.dirs).astype(np.float32)
        surf = np.flatnonzero((h.kind == KIND_GROUND) | (h.kind == KIND_SURFACE))
        if surf.size:
            out[surf] = self.radiance_rgb(h, surf, coarse=True)
        return out

    def lobe(self, i: int, nh: np.ndarray, sun_cos: np.ndarray) -> np.ndarray:
        """Normalised Blinn-Phong sun lobe (e+8)/(8π) (n·h)^e cosθ V of film ``i``."""
        e = self.spec.films[i].gloss
        return ((e + 8) / (8 * np.pi) * nh ** e * sun_cos).astype(np.float32)

    def film_spectra(self, h: Hits, fm: np.ndarray, mh: MirrorHits, L_env: np.ndarray,
                     highlight_spectra=None) -> tuple[np.ndarray, np.ndarray]:
        """Spectral radiance (F, N) of film samples ``fm``: the tabulated film reflectance times the environment
        spectrum ``L_env`` the mirror ray brings, plus the sun's SPD through the glossy lobe (Eqs. 1.14-1.25
        tables, §2.2). ``highlight_spectra[i]`` (N,) is added to film i's sun reflectance (the full-spectral
        mode's upsampled highlight; the hybrid keeps the highlight in RGB). Also returns the lobe (F,)."""
        F = fm.size
        S = np.zeros((F, self.spec.grid.size), np.float32)
        lobe = np.zeros(F, np.float32)
        idx = h.index[fm]
        sun_cos = h.sun_front[fm]
        for i in range(len(self.spec.films)):
            k = idx == i
            if not k.any():
                continue
            tab = self.tables[i]
            lobe[k] = self.lobe(i, mh.nh[k], sun_cos[k])
            sun_refl = tab.reflectance(mh.cos_d[k])
            if highlight_spectra is not None:
                sun_refl = sun_refl + highlight_spectra[i][None]
            S[k] = tab.reflectance(mh.cos_v[k]) * L_env[k] + sun_refl * (self.sun_S[None] * lobe[k][:, None])
        return S, lobe

    def highlight_rgb(self, h: Hits, fm: np.ndarray, lobe: np.ndarray) -> np.ndarray:
        """Dong's RGB highlight (F, 3): highlight_rgb · E_sun,rgb · lobe."""
        hl = np.array([f.highlight_rgb for f in self.spec.films], np.float32).reshape(-1, 3)
        return hl[h.index[fm]] * self.sun_rgb[None] * lobe[:, None]

    def film_rgb_tables(self) -> list[np.ndarray]:
        """Film reflectance per table angle integrated to linear RGB under D65 (the RGB baseline)."""
        if self._film_rgb is None:
            ill = d65(self.spec.grid)
            self._film_rgb = [reflectance_to_rgb(t.R.astype(np.float64), ill, self.spec.grid).astype(np.float32)
                              for t in self.tables]
        return self._film_rgb

    def shade_film_rgb(self, h: Hits, fm: np.ndarray, mh: MirrorHits) -> np.ndarray:
        """Films shaded in RGB: R_rgb(θ_v)·L_env,rgb + (R_rgb(θ_d) + highlight)·E_sun,rgb·lobe."""
        env = self.gather_mirror_rgb(mh)
        out = np.zeros((fm.size, 3), np.float32)
        idx = h.index[fm]
        tabs = self.film_rgb_tables()
        for i in range(len(self.spec.films)):
            k = idx == i
            if not k.any():
                continue
            tab = self.tables[i]
            R = tabs[i]
            lobe = self.lobe(i, mh.nh[k], h.sun_front[fm][k])
            Rv = _interp_rows(tab, R, mh.cos_v[k])
            Rd = _interp_rows(tab, R, mh.cos_d[k])
            hl = np.asarray(self.spec.films[i].highlight_rgb, np.float32)
            out[k] = Rv * env[k] + (Rd + hl[None]) * self.sun_rgb[None] * lobe[:, None]
        return out

    # ------------------------------------------------------------------------------ renders
    def render_hybrid(self, film_mode: str = "spectral") -> HybridImage:
        """Dong §2.3-2.4: the RGB part for RGB materials, the spectral part only on the film samples
        (``film_mode="rgb"``: films in RGB too, the spectral part stays empty)."""
        spec = self.spec
        H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
        self.timing = {"geometry": 0.0, "shading": 0.0}
        t_start = time.perf_counter()
        spp = spec.spp
        rgb = np.zeros((H * W, 3), np.float32)
        S = np.zeros((H * W, N), np.float32)
        A = np.zeros(H * W, np.float32)
        has_s = np.zeros(H * W, bool)
        plate = spec.plate.reshape(-1, 3).astype(np.float32)
        origin = np.asarray(spec.camera.position, np.float64)
        for sl, dirs, ddx, ddy in self.blocks():
            h = self.trace(origin, dirs, ddx, ddy, pixels=sl.stop - sl.start)
            n = sl.stop - sl.start
            out = np.zeros((dirs.shape[0], 3), np.float32)
            bg = h.kind == KIND_SKY
            out[bg] = np.tile(plate[sl], (spp, 1))[bg]
            rm = np.flatnonzero((h.kind == KIND_GROUND) | (h.kind == KIND_SURFACE))
            out[rm] = self.radiance_rgb(h, rm)
            fm = np.flatnonzero(h.kind == KIND_FILM)
            if fm.size:
                mh = self.mirror(h, fm)
                T = self.transmittance(h, fm)
                sky_in = (1 - T) * self.dome.radiance(h.dirs[fm])
                if film_mode == "rgb":
                    out[fm] = self.shade_film_rgb(h, fm, mh) * T + sky_in
                else:
                    env = self.gather_mirror_rgb(mh)
                    L_env = rgb_to_radiance(env, spec.grid, spec.upsampling).astype(np.float32)
                    s, lobe = self.film_spectra(h, fm, mh, L_env)
                    Tg = T @ np.array([0.2126, 0.7152, 0.0722], np.float32)
                    out[fm] = self.highlight_rgb(h, fm, lobe) * T + sky_in
                    s *= Tg[:, None]
                    for j in range(spp):  # scatter the film samples' spectra into their pixels
                        k = (fm >= j * n) & (fm < (j + 1) * n)
                        px = sl.start + fm[k] - j * n
                        np.add.at(S, px, s[k])
                        has_s[px] = True
            rgb[sl] = out.reshape(spp, n, 3).sum(0)
            A[sl] = (~bg).reshape(spp, n).sum(0)
        w = np.float32(1.0 / spp)
        S[has_s] *= w  # the spectral part is sparse: only the film objects' pixels are touched
        out = HybridImage((rgb * w).reshape(H, W, 3), S.reshape(H, W, N), (A * w).reshape(H, W), spec.grid,
                          has_s.reshape(H, W))
        self.timing["shading"] = time.perf_counter() - t_start - self.timing["geometry"]
        return out


def _interp_rows(tab: FilmTable, R: np.ndarray, cos_theta: np.ndarray) -> np.ndarray:
    """Rows of a per-angle table ``R`` (n_angles, C) interpolated like :meth:`FilmTable.reflectance`."""
    th = np.degrees(np.arccos(np.clip(cos_theta, 0.0, 1.0)))
    ang = np.asarray(tab.angles_deg, np.float64)
    x = np.interp(th, ang, np.arange(ang.size))
    i0 = np.clip(np.floor(x).astype(int), 0, ang.size - 2)
    f = (x - i0).astype(np.float32)[:, None]
    return R[i0] * (1 - f) + R[i0 + 1] * f


def spectral_coverage(hybrid: HybridImage) -> float:
    """Fraction of pixels with a non-zero spectral part."""
    if hybrid.mask is not None:
        return float(np.mean(hybrid.mask & np.any(hybrid.spectral != 0, axis=-1)))
    return float(np.mean(np.any(hybrid.spectral != 0, axis=-1)))
