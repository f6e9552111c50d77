"""The set of the final shot and its hybrid rendering (Dong 2007 Ch. 2, §2.3-2.5, Fig. 2.3).

A Mitsuba 3 scene (RGB variant) holds the geometry: a ground rectangle textured with the tile texture,
a few leaves/petals (rectangles with an elliptical cut-out) textured with pattern colour maps, and thin-film
objects (spheres; Dong's "gold bug": a gold film on copper). Mitsuba traces every ray (camera rays,
sun shadow rays, mirror rays leaving the film objects); shading is the project's own and deterministic
(fixed stratified sub-pixel samples), so the hybrid and the full-spectral renders differ only by their
colour representation, which is what Dong compares (§2.5):

- RGB materials (ground, leaves) are lit in RGB by the RGB value of every light (spectral lights are
  converted once, §2.3.3): L = ρ/π · E_sun cosθ · V + ρ · L_sky (1 + n_y)/2 (sun + uniform sky dome);
- spectral materials (thin films) are lit by spectra only, and only where a ray hits them: mirror
  reflection R_film(θ_v, λ) · L_env(λ) of what the reflected ray sees (RGB radiance converted to a spectrum
  by upsampling, Fig. 2.3(b)) plus a glossy sun lobe R_film(θ_d, λ) E_sun(λ) (e+8)/(8π) (n·h)^e cosθ V,
  with R_film tabulated per (angle, wavelength) by :mod:`natscene.spectral.thin_film`; Dong's RGB
  highlight (§2.5 "the specular value for the high light is an RGB value") goes to the RGB part;
- rays that leave the set show the background plate (the shot's cloud frame) in screen space.

The result is a :class:`natscene.composite.hybrid.HybridImage`; :mod:`natscene.composite.full_spectral`
shades the same rays spectrally everywhere.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from natscene.composite.hybrid import HybridImage
from natscene.geometry import Camera, sun_direction
from natscene.spectral.grid import DEFAULT_GRID, WavelengthGrid, spectrum_to_rgb, spectrum_to_rgb_matrix
from natscene.spectral.illuminants import d65, sun_spd
from natscene.spectral.thin_film import FilmTable, film_table
from natscene.spectral.upsampling import rgb_to_radiance, rgb_to_reflectance

log = logging.getLogger("natscene")


# ------------------------------------------------------------------------------------------ the set
@dataclass
class Leaf:
    """A textured leaf/petal: a rectangle cut out by the texture's alpha (an inscribed ellipse without one),
    lambertian, two-sided."""

    texture: np.ndarray  # (h, w, 3) linear albedo (alpha channel optional as 4th)
    center: tuple = (0.0, 0.05, 0.0)
    size: tuple = (0.4, 0.25)  # (length, width)
    yaw: float = 0.0  # degrees about y
    tilt: float = 10.0  # degrees: rotation about the leaf's length axis


@dataclass
class FilmObject:
    """A sphere coated with a multilayer film (Dong's gold bug: Au film on Cu)."""

    center: tuple = (0.0, 0.1, 0.0)
    radius: float = 0.1
    layers: list = field(default_factory=lambda: [("Au", 500.0)])
    substrate: str = "Cu"
    gloss: float = 200.0  # Blinn-Phong exponent of the sun lobe
    highlight_rgb: tuple = (0.04, 0.04, 0.04)  # Dong's RGB specular highlight


@dataclass
class SetSpec:
    camera: Camera
    background: np.ndarray  # (H, W, 3) linear plate at the camera resolution
    ground_texture: np.ndarray  # (h, w, 3) linear albedo
    ground_size: float = 6.0
    ground_repeat: float = 6.0
    leaves: list = field(default_factory=list)
    objects: list = field(default_factory=list)
    sun_dir: np.ndarray = field(default_factory=lambda: sun_direction(130, 35))
    sun_spd: np.ndarray | None = None  # spectral sun irradiance on the grid (None: D65 * sun_scale)
    sun_scale: float = 3.0
    sky_zenith: np.ndarray = field(default_factory=lambda: np.array([0.25, 0.35, 0.6]))
    sky_horizon: np.ndarray = field(default_factory=lambda: np.array([0.55, 0.6, 0.7]))
    spp: int = 4
    grid: WavelengthGrid = DEFAULT_GRID
    upsampling: str = "mallett2019"
    angle_step_deg: float = 1.0

    def sun_spectrum(self) -> np.ndarray:
        return (d65(self.grid) * self.sun_scale) if self.sun_spd is None else np.asarray(self.sun_spd, np.float64)


def sun_spectrum_from_rgb(c_in, L_in: float, grid: WavelengthGrid = DEFAULT_GRID, kind: str = "matched") -> np.ndarray:
    """Spectral sun irradiance: ``"d65"`` (Dong §2.5) scaled to luminance L_in·Y(c_in), or ``"matched"``
    (a daylight SPD matched to c_in, :func:`natscene.spectral.illuminants.sun_spd`) times L_in."""
    c = np.asarray(c_in, np.float64)
    if kind == "d65":
        return d65(grid) * float(L_in) * float(c @ np.array([0.2126, 0.7152, 0.0722]))
    return sun_spd(c, grid) * float(L_in)


# --------------------------------------------------------------------------------------- Mitsuba
def _frame_matrix(center, size, yaw, tilt):
    import mitsuba as mi
    T = mi.ScalarTransform4f
    return (T().translate(list(map(float, center))) @ T().rotate([0, 1, 0], float(yaw)) @
            T().rotate([1, 0, 0], float(tilt)) @ T().rotate([1, 0, 0], -90.0) @
            T().scale([float(size[0]) / 2, float(size[1]) / 2, 1.0]))


class SetTracer:
    """The Mitsuba scene of a set and ray queries returning numpy G-buffers.

    Each query is one fused Dr.Jit kernel: every field the shading needs (shape id, validity, position,
    normal, uv) is evaluated together with ``dr.eval`` before it is copied to numpy (converting the lazy
    fields one by one would relaunch the intersection kernel once per field).
    """

    def __init__(self, spec: SetSpec):
        from natscene.variant import select_variant
        self.variant = select_variant(spectral=False)
        import drjit as dr
        import mitsuba as mi
        self.mi, self.dr = mi, dr
        T = mi.ScalarTransform4f
        d = {"type": "scene",
             "ground": {"type": "rectangle",
                        "to_world": T().rotate([1, 0, 0], -90.0).scale([spec.ground_size / 2, spec.ground_size / 2, 1])}}
        for i, lf in enumerate(spec.leaves):
            d[f"leaf{i:03d}"] = {"type": "rectangle", "to_world": _frame_matrix(lf.center, lf.size, lf.yaw, lf.tilt)}
        for i, ob in enumerate(spec.objects):
            d[f"film{i:03d}"] = {"type": "sphere", "center": list(map(float, ob.center)), "radius": float(ob.radius)}
        self.scene = mi.load_dict(d)
        shapes = list(self.scene.shapes())
        self.names = [s.id() for s in shapes]
        ids = [int(np.asarray(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(s)))[0]) for s in shapes]
        self._label_of_id = np.full(max(ids) + 1, -1, np.int64)
        self._label_of_id[ids] = np.arange(len(shapes))

    def _rays(self, origins: np.ndarray, dirs: np.ndarray):
        mi = self.mi
        o = np.ascontiguousarray(np.asarray(origins, np.float32).T)
        v = np.ascontiguousarray(np.asarray(dirs, np.float32).T)
        return mi.Ray3f(mi.Point3f(o[0], o[1], o[2]), mi.Vector3f(v[0], v[1], v[2]))

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> dict:
        """Closest hits of rays (M, 3): ``label`` (M,) shape index or -1, ``p``, ``n`` (geometric normal facing
        the ray origin), ``uv`` (float32)."""
        mi, dr = self.mi, self.dr
        si = self.scene.ray_intersect(self._rays(origins, dirs))
        sid = dr.reinterpret_array(mi.UInt32, si.shape)
        valid = si.is_valid()
        dr.eval(sid, valid, si.p, si.n, si.uv)
        valid = np.asarray(valid, bool)
        label = np.where(valid, self._label_of_id[np.minimum(np.asarray(sid, np.int64), self._label_of_id.size - 1)], -1)
        p = np.asarray(si.p, np.float32).T.copy()
        n = np.asarray(si.n, np.float32).T.copy()
        uv = np.asarray(si.uv, np.float32).T.copy()
        flip = np.einsum("ij,ij->i", n, np.asarray(dirs, np.float32)) > 0
        n[flip] *= -1
        return {"label": label, "p": p, "n": n, "uv": uv}

    def occluded(self, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
        dd = np.broadcast_to(np.asarray(direction, np.float32), np.shape(origins))
        hit = self.scene.ray_test(self._rays(origins, dd))
        self.dr.eval(hit)
        return np.asarray(hit, bool)


# ------------------------------------------------------------------------------------ shading bits
def sample_texture(tex: np.ndarray, uv: np.ndarray, repeat: float = 1.0) -> np.ndarray:
    """Bilinear lookup with wrap-around, uv in [0,1]² (v up), (M, 2) -> (M, C), in the texture's dtype.

    The texture is addressed as a flat (h·w, C) table with ``np.take`` (one gather of whole rows per tap)."""
    h, w = tex.shape[:2]
    flat = tex.reshape(h * w, -1)
    u = np.asarray(uv, np.float32)
    x = (u[:, 0] * np.float32(repeat)) % 1.0 * w - 0.5
    y = (1.0 - (u[:, 1] * np.float32(repeat)) % 1.0) * h - 0.5
    xf, yf = np.floor(x), np.floor(y)
    fx, fy = (x - xf).astype(tex.dtype)[:, None], (y - yf).astype(tex.dtype)[:, None]
    x0, y0 = xf.astype(np.int64) % w, yf.astype(np.int64) % h
    x1, y1 = (x0 + 1) % w, (y0 + 1) % h
    r0, r1 = y0 * w, y1 * w
    top = np.take(flat, r0 + x0, axis=0)
    top += (np.take(flat, r0 + x1, axis=0) - top) * fx
    bot = np.take(flat, r1 + x0, axis=0)
    bot += (np.take(flat, r1 + x1, axis=0) - bot) * fx
    top += (bot - top) * fy
    return top


def sky_blend(dirs: np.ndarray) -> np.ndarray:
    """Zenith weight of the sky dome toward directions (M, 3): sqrt(max(y, 0)) (horizon 0, zenith 1)."""
    return np.sqrt(np.clip(dirs[:, 1], 0.0, 1.0))[:, None].astype(np.float32)


def sky_radiance_rgb(spec: SetSpec, dirs: np.ndarray) -> np.ndarray:
    """Sky dome radiance (RGB) toward directions (M, 3): horizon -> zenith blend in sqrt(max(y, 0))."""
    t = sky_blend(dirs)
    return (spec.sky_horizon[None] * (1 - t) + spec.sky_zenith[None] * t).astype(np.float32)


def sky_ambient_weight() -> float:
    """Cosine-weighted mean of the zenith weight over the upper hemisphere: the dome's irradiance / π on a
    horizontal plane is horizon·(1 - w) + zenith·w (midpoint rule, 256 steps in cos θ)."""
    mu = np.linspace(0.0, 1.0, 257)[1:] - 0.5 / 256
    return float((np.sqrt(mu) * mu).sum() / mu.sum())


def sky_ambient_rgb(spec: SetSpec) -> np.ndarray:
    """Cosine-weighted mean sky radiance over the upper hemisphere (irradiance / π on a horizontal plane)."""
    w = sky_ambient_weight()
    return np.asarray(spec.sky_horizon, np.float64) * (1 - w) + np.asarray(spec.sky_zenith, np.float64) * w


def stratified_offsets(spp: int) -> np.ndarray:
    """Deterministic sub-pixel offsets (spp, 2) in [-0.5, 0.5)² (a k×k grid, k = ceil(sqrt(spp)))."""
    k = int(np.ceil(np.sqrt(spp)))
    g = (np.arange(k) + 0.5) / k - 0.5
    xx, yy = np.meshgrid(g, g)
    return np.stack([xx.ravel(), yy.ravel()], -1)[:spp]


@dataclass
class Hits:
    """The geometry of one sub-pixel sample set (the same for the hybrid and the full-spectral shading)."""

    dirs: np.ndarray  # (M, 3) float32
    kind: np.ndarray  # -1 background, 0 ground, 1 leaf, 2 film object
    index: np.ndarray  # leaf / object index
    uv: np.ndarray  # (M, 2)
    p: np.ndarray  # (M, 3)
    n: np.ndarray  # (M, 3) facing the viewer
    sun_cos: np.ndarray  # (M,) n·l * visibility (0 where shadowed)
    ambient: np.ndarray  # (M,) (1 + n_y)/2


@dataclass
class MirrorHits:
    """Film samples: view/sun geometry and what their mirror rays hit."""

    cos_v: np.ndarray  # (F,) incidence cosine of the view (= mirror) direction
    cos_d: np.ndarray  # (F,) incidence cosine of the sun on the half vector
    nh: np.ndarray  # (F,) n·h
    refl: np.ndarray  # (F, 3) mirror directions
    kind: np.ndarray  # (F,) what the mirror ray hits (-1 sky)
    index: np.ndarray
    uv: np.ndarray
    sun_cos: np.ndarray  # (F,) at the mirror hit
    ambient: np.ndarray  # (F,) at the mirror hit


class SetRenderer:
    """Builds rays, traces them (shared geometry), and shades samples in hybrid mode.

    ``timing`` accumulates seconds spent in the shared geometry (``geometry``: camera, shadow and mirror rays
    through Mitsuba, cut-outs) and in the mode's shading (``shading``), per render call.
    """

    def __init__(self, spec: SetSpec):
        self.spec = spec
        self.tracer = SetTracer(spec)
        self.tables: list[FilmTable] = [film_table(o.layers, o.substrate, grid=spec.grid,
                                                   angle_step_deg=spec.angle_step_deg) for o in spec.objects]
        for t in self.tables:
            t.R = t.R.astype(np.float32)
        self.sun_S = spec.sun_spectrum().astype(np.float32)
        # Dong §2.3.3: the RGB value of the spectral light, computed once in preprocessing
        self.sun_rgb = spectrum_to_rgb(self.sun_S.astype(np.float64), spec.grid).astype(np.float32)
        self.amb_rgb = sky_ambient_rgb(spec).astype(np.float32)
        names = self.tracer.names
        self.kind_of = np.array([0 if n == "ground" else 1 if n.startswith("leaf") else 2 for n in names])
        self.index_of = np.array([0 if n == "ground" else int(n[4:]) for n in names])
        # RGB materials (clipped albedo textures) and leaf alpha (cut-outs)
        self.ground_rgb = np.clip(spec.ground_texture[..., :3], 0, 1).astype(np.float32)
        self.leaf_rgb = [np.clip(lf.texture[..., :3], 0, 1).astype(np.float32) for lf in spec.leaves]
        self.leaf_alpha = [lf.texture[..., 3:4].astype(np.float32) if lf.texture.shape[-1] >= 4 else None
                           for lf in spec.leaves]
        self.timing = {"geometry": 0.0, "shading": 0.0}

    # -- geometry, shared by both modes
    def _classify(self, label):
        kind = np.where(label >= 0, self.kind_of[np.maximum(label, 0)], -1)
        index = np.where(label >= 0, self.index_of[np.maximum(label, 0)], 0)
        return kind, index

    def _leaf_keep(self, index: np.ndarray, uv: np.ndarray) -> np.ndarray:
        keep = np.ones(index.size, bool)
        for i, a in enumerate(self.leaf_alpha):
            m = index == i
            if not m.any():
                continue
            if a is None:  # no alpha: an elliptical leaf inscribed in the rectangle
                keep[m] = ((uv[m, 0] - 0.5) ** 2 + (uv[m, 1] - 0.5) ** 2) <= 0.25
            else:  # the texture's alpha is the shape (pattern petals, season leaves)
                keep[m] = sample_texture(a, uv[m])[:, 0] > 0.5
        return keep

    def _surface_hits(self, origins, dirs):
        """Closest hits skipping leaf cut-outs: kind, index, g-buffer."""
        g = self.tracer.intersect(origins, dirs)
        kind, index = self._classify(g["label"])
        for _ in range(4):
            lf = np.flatnonzero(kind == 1)
            if lf.size == 0:
                break
            keep = self._leaf_keep(index[lf], g["uv"][lf])
            if keep.all():
                break
            ids = lf[~keep]
            g2 = self.tracer.intersect(g["p"][ids] + dirs[ids] * 1e-4, dirs[ids])
            for key in g:
                g[key][ids] = g2[key]
            kind[ids], index[ids] = self._classify(g2["label"])
        return kind, index, g

    def _sun_visibility(self, kind, p, n):
        sun = self.spec.sun_dir.astype(np.float32)
        sun_cos = np.zeros(kind.shape[0], np.float32)
        nl = n @ sun
        lit = np.flatnonzero((kind >= 0) & (nl > 0))
        if lit.size:
            occ = self.tracer.occluded(p[lit] + n[lit] * 1e-4, sun)
            vis = lit[~occ]
            sun_cos[vis] = nl[vis]
        return sun_cos

    def camera_rays(self) -> np.ndarray:
        """Unit directions (spp, H·W, 3) of every sub-pixel sample (stratified offsets), float32."""
        cam = self.spec.camera
        H, W = cam.height, cam.width
        return np.stack([cam.ray_directions(jitter=np.broadcast_to(off, (H, W, 2))).reshape(-1, 3)
                         for off in stratified_offsets(self.spec.spp)]).astype(np.float32)

    def blocks(self, block_rays: int = 1 << 18):
        """Yield (pixel slice, directions (spp·n, 3) sample-major) over blocks of pixels, so that all samples of
        a block go through Mitsuba in one kernel launch per query."""
        t0 = time.perf_counter()
        dirs = self.camera_rays()
        self.timing["geometry"] += time.perf_counter() - t0
        spp, P = dirs.shape[:2]
        step = max(1, block_rays // spp)
        for a in range(0, P, step):
            b = min(P, a + step)
            yield slice(a, b), dirs[:, a:b].reshape(-1, 3)

    def trace(self, dirs: np.ndarray) -> Hits:
        """Shared geometry of camera rays (M, 3): visible surface (leaf cut-outs skipped), sun visibility."""
        t0 = time.perf_counter()
        org = np.broadcast_to(np.asarray(self.spec.camera.position, np.float32), dirs.shape)
        kind, index, g = self._surface_hits(org, dirs)
        sun_cos = self._sun_visibility(kind, g["p"], g["n"])
        ambient = np.where(kind >= 0, 0.5 * (1 + g["n"][:, 1]), 0.0).astype(np.float32)
        self.timing["geometry"] += time.perf_counter() - t0
        return Hits(dirs, kind, index, g["uv"], g["p"], g["n"], sun_cos, ambient)

    def mirror(self, h: Hits, m: np.ndarray) -> MirrorHits:
        """View/sun geometry of the film samples ``m`` and the hits of their mirror rays."""
        t0 = time.perf_counter()
        v = -h.dirs[m]
        n = h.n[m]
        cos_v = np.clip(np.einsum("ij,ij->i", n, v), 0.0, 1.0)
        refl = 2 * cos_v[:, None] * n - v
        l = self.spec.sun_dir.astype(np.float32)[None]
        hv = l + v
        hv /= np.maximum(np.linalg.norm(hv, axis=-1, keepdims=True), 1e-12)
        cos_d = np.clip(np.einsum("ij,ij->i", hv, np.broadcast_to(l, hv.shape)), 0.0, 1.0)
        nh = np.clip(np.einsum("ij,ij->i", n, hv), 0.0, 1.0)
        kind2, index2, g2 = self._surface_hits(h.p[m] + n * 1e-4, refl)
        sun2 = self._sun_visibility(np.where(kind2 == 2, -1, kind2), g2["p"], g2["n"])
        amb2 = np.where(kind2 >= 0, 0.5 * (1 + g2["n"][:, 1]), 0.0).astype(np.float32)
        self.timing["geometry"] += time.perf_counter() - t0
        return MirrorHits(cos_v, cos_d, nh, refl, kind2, index2, g2["uv"], sun2, amb2)

    # -- materials
    def albedo(self, kind, index, uv, ground, leaves) -> np.ndarray:
        """Albedo of ground/leaf samples from per-texel tables (RGB here, spectra in the full mode)."""
        def look(tex, uv_, repeat=1.0):
            return tex.lookup(uv_, repeat) if hasattr(tex, "lookup") else sample_texture(tex, uv_, repeat)

        out = None
        gr = kind == 0
        if gr.any():
            v = look(ground, uv[gr], self.spec.ground_repeat)
            out = np.zeros((kind.shape[0], v.shape[-1]), np.float32)
            out[gr] = v
        for i, tex in enumerate(leaves):
            k = (kind == 1) & (index == i)
            if k.any():
                v = look(tex, uv[k])
                if out is None:
                    out = np.zeros((kind.shape[0], v.shape[-1]), np.float32)
                out[k] = v
        if out is None:
            c = ground.grid.size if hasattr(ground, "lookup") else ground.shape[-1]
            out = np.zeros((kind.shape[0], c), np.float32)
        return out

    def lobe(self, ob: FilmObject, nh: np.ndarray, sun_cos: np.ndarray) -> np.ndarray:
        """Normalised Blinn-Phong sun lobe (e+8)/(8π) (n·h)^e cosθ V."""
        return ((ob.gloss + 8) / (8 * np.pi) * nh ** ob.gloss * sun_cos).astype(np.float32)

    # -- RGB radiance of RGB materials (what a camera ray or a mirror ray gathers)
    def rgb_radiance(self, albedo, sun_cos, ambient) -> np.ndarray:
        return albedo * (self.sun_rgb[None] / np.float32(np.pi) * sun_cos[:, None] + self.amb_rgb[None] * ambient[:, None])

    def gather_mirror_rgb(self, mh: MirrorHits) -> np.ndarray:
        """RGB radiance arriving along the mirror rays of film samples (set geometry or sky dome; a film seen in a
        film shows the sky behind it, both modes)."""
        out = sky_radiance_rgb(self.spec, mh.refl)
        surf = (mh.kind == 0) | (mh.kind == 1)
        if surf.any():
            a = self.albedo(mh.kind[surf], mh.index[surf], mh.uv[surf], self.ground_rgb, self.leaf_rgb)
            out[surf] = self.rgb_radiance(a, mh.sun_cos[surf], mh.ambient[surf])
        return out

    def shade_film_hybrid(self, h: Hits, fm: np.ndarray, mh: MirrorHits):
        """Spectral radiance (F, N) of film samples and their RGB highlight part (F, 3) (Fig. 2.3(b)): the RGB
        radiance the mirror ray gathers is upsampled to a spectrum, the sun's SPD is used as is."""
        spec = self.spec
        L_env = rgb_to_radiance(self.gather_mirror_rgb(mh), spec.grid, spec.upsampling).astype(np.float32)
        S, lobe = self.film_spectra(h, fm, mh, L_env)
        highlight = np.zeros((mh.cos_v.size, 3), np.float32)
        idx = h.index[fm]
        for i, ob in enumerate(spec.objects):
            highlight[idx == i] = np.asarray(ob.highlight_rgb, np.float32)
        return S, highlight * self.sun_rgb[None] * lobe[:, None]

    def film_spectra(self, h: Hits, fm: np.ndarray, mh: MirrorHits, L_env: np.ndarray,
                     highlight_spectra=None) -> tuple[np.ndarray, np.ndarray]:
        """Spectral radiance (F, N) of film samples: the tabulated film reflectance times the environment
        spectrum ``L_env`` the mirror ray brings, plus the sun's SPD through the glossy lobe (Eqs. 1.14-1.25
        tables, §2.2). ``highlight_spectra[i]`` (N,) is added to object i's sun reflectance (the full-spectral
        mode's upsampled highlight; the hybrid mode keeps the highlight in RGB). Also returns the lobe (F,)."""
        S = np.zeros((mh.cos_v.size, self.spec.grid.size), np.float32)
        lobe = np.zeros(mh.cos_v.size, np.float32)
        idx = h.index[fm]
        sun_cos = h.sun_cos[fm]
        for i, ob in enumerate(self.spec.objects):
            k = idx == i
            if not k.any():
                continue
            tab = self.tables[i]
            lobe[k] = self.lobe(ob, mh.nh[k], sun_cos[k])
            sun_refl = tab.reflectance(mh.cos_d[k])
            if highlight_spectra is not None:
                sun_refl = sun_refl + highlight_spectra[i][None]
            S[k] = tab.reflectance(mh.cos_v[k]) * L_env[k] + sun_refl * (self.sun_S[None] * lobe[k][:, None])
        return S, lobe

    # -- the hybrid render
    def render_hybrid(self) -> HybridImage:
        """Dong §2.3-2.4: RGB part for RGB materials, spectral part only on the film objects' samples."""
        spec = self.spec
        H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
        self.timing = {"geometry": 0.0, "shading": 0.0}
        t_start = time.perf_counter()
        spp = spec.spp
        rgb = np.zeros((H * W, 3), np.float32)
        S = np.zeros((H * W, N), np.float32)
        A = np.zeros(H * W, np.float32)
        has_s = np.zeros(H * W, bool)
        plate = spec.background.reshape(-1, 3).astype(np.float32)
        for sl, dirs in self.blocks():
            h = self.trace(dirs)
            fm = h.kind == 2
            mh = self.mirror(h, fm) if fm.any() else None
            n = sl.stop - sl.start
            out = np.zeros((dirs.shape[0], 3), np.float32)
            bg = h.kind < 0
            out[bg] = np.tile(plate[sl], (spp, 1))[bg]
            rm = (h.kind == 0) | (h.kind == 1)
            a = self.albedo(h.kind[rm], h.index[rm], h.uv[rm], self.ground_rgb, self.leaf_rgb)
            out[rm] = self.rgb_radiance(a, h.sun_cos[rm], h.ambient[rm])
            if mh is not None:
                s, r = self.shade_film_hybrid(h, fm, mh)
                out[fm] = r
                # scatter the film samples' spectra into their pixels (one sample per pixel per pass)
                ray = np.flatnonzero(fm)
                for j in range(spp):
                    k = (ray >= j * n) & (ray < (j + 1) * n)
                    S[sl.start + ray[k] - j * n] += s[k]
                    has_s[sl.start + ray[k] - j * n] = True
            rgb[sl] = out.reshape(spp, n, 3).sum(0)
            A[sl] = (~bg).reshape(spp, n).sum(0)
        w = np.float32(1.0 / spp)
        S[has_s] *= w  # the spectral part is sparse: only the film objects' pixels are touched
        out = HybridImage((rgb * w).reshape(H, W, 3), S.reshape(H, W, N), (A * w).reshape(H, W), spec.grid,
                          has_s.reshape(H, W))
        self.timing["shading"] = time.perf_counter() - t_start - self.timing["geometry"]
        return out


def spectral_coverage(hybrid: HybridImage) -> float:
    """Fraction of pixels with a non-zero spectral part."""
    if hybrid.mask is not None:
        return float(np.mean(hybrid.mask & np.any(hybrid.spectral != 0, axis=-1)))
    return float(np.mean(np.any(hybrid.spectral != 0, axis=-1)))


__all__ = ["Leaf", "FilmObject", "SetSpec", "SetRenderer", "spectral_coverage", "sun_spectrum_from_rgb", "spectrum_to_rgb_matrix",
           "rgb_to_reflectance"]
