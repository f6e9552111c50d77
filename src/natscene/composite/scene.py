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
    """A textured leaf/petal: a rectangle with an elliptical cut-out, lambertian, two-sided."""

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
    """The Mitsuba scene of a set and ray queries returning numpy G-buffers."""

    def __init__(self, spec: SetSpec):
        from natscene.variant import select_variant
        self.variant = select_variant(spectral=False)
        import mitsuba as mi
        self.mi = mi
        T = mi.ScalarTransform4f
        d = {"type": "scene",
             "ground": {"type": "rectangle",
                        "to_world": T().rotate([1, 0, 0], -90.0).scale([spec.ground_size / 2, spec.ground_size / 2, 1])}}
        for i, lf in enumerate(spec.leaves):
            d[f"leaf{i:03d}"] = {"type": "rectangle", "to_world": _frame_matrix(lf.center, lf.size, lf.yaw, lf.tilt)}
        for i, ob in enumerate(spec.objects):
            d[f"film{i:03d}"] = {"type": "sphere", "center": list(map(float, ob.center)), "radius": float(ob.radius)}
        self.scene = mi.load_dict(d)
        self.names = [s.id() for s in self.scene.shapes()]
        self.ptrs = list(self.scene.shapes())

    def intersect(self, origins: np.ndarray, dirs: np.ndarray) -> dict:
        """Closest hits of rays (M, 3): ``hit`` (M,) bool, ``label`` (M,) shape name index or -1, ``p``, ``n``
        (geometric normal facing the ray origin), ``uv``."""
        mi, dr = self.mi, __import__("drjit")
        o = mi.Point3f(*[np.ascontiguousarray(origins[:, k], np.float32) for k in range(3)])
        v = mi.Vector3f(*[np.ascontiguousarray(dirs[:, k], np.float32) for k in range(3)])
        si = self.scene.ray_intersect(mi.Ray3f(o, v))
        label = np.full(origins.shape[0], -1, np.int64)
        for k, s in enumerate(self.ptrs):
            label[np.asarray(si.shape == mi.ShapePtr(s), bool)] = k
        valid = np.asarray(si.is_valid(), bool)
        label[~valid] = -1
        p = np.stack([np.asarray(si.p[k]) for k in range(3)], -1).astype(np.float64)
        n = np.stack([np.asarray(si.n[k]) for k in range(3)], -1).astype(np.float64)
        uv = np.stack([np.asarray(si.uv[k]) for k in range(2)], -1).astype(np.float64)
        flip = np.sum(n * dirs, -1) > 0
        n[flip] *= -1
        dr.eval()
        return {"hit": valid, "label": label, "p": p, "n": n, "uv": uv}

    def occluded(self, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
        mi = self.mi
        o = mi.Point3f(*[np.ascontiguousarray(origins[:, k], np.float32) for k in range(3)])
        dd = np.broadcast_to(direction, origins.shape)
        v = mi.Vector3f(*[np.ascontiguousarray(dd[:, k], np.float32) for k in range(3)])
        return np.asarray(self.scene.ray_test(mi.Ray3f(o, v)), bool)


# ------------------------------------------------------------------------------------ shading bits
def sample_texture(tex: np.ndarray, uv: np.ndarray, repeat: float = 1.0) -> np.ndarray:
    """Bilinear lookup with wrap-around, uv in [0,1]² (v up), (M, 2) -> (M, C)."""
    h, w = tex.shape[:2]
    x = (uv[:, 0] * repeat) % 1.0 * w - 0.5
    y = (1.0 - (uv[:, 1] * repeat) % 1.0) * h - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x0m, x1m, y0m, y1m = x0 % w, (x0 + 1) % w, y0 % h, (y0 + 1) % h
    return ((tex[y0m, x0m] * (1 - fx) + tex[y0m, x1m] * fx) * (1 - fy) +
            (tex[y1m, x0m] * (1 - fx) + tex[y1m, x1m] * fx) * fy)


def sky_radiance_rgb(spec: SetSpec, dirs: np.ndarray) -> np.ndarray:
    """Sky dome radiance (RGB) toward directions (M, 3): horizon -> zenith blend in sqrt(max(y, 0))."""
    t = np.sqrt(np.clip(dirs[:, 1], 0.0, 1.0))[:, None]
    return spec.sky_horizon[None] * (1 - t) + spec.sky_zenith[None] * t


def sky_ambient_rgb(spec: SetSpec) -> np.ndarray:
    """Cosine-weighted mean sky radiance over the upper hemisphere (irradiance / π on a horizontal plane)."""
    mu = np.linspace(0.0, 1.0, 257)[1:] - 0.5 / 256  # cos θ = y, weights cos θ d(cos θ)
    d = np.stack([np.sqrt(1 - mu ** 2), mu, np.zeros_like(mu)], -1)
    L = sky_radiance_rgb(spec, d)
    return (L * mu[:, None]).sum(0) / mu.sum()


def stratified_offsets(spp: int) -> np.ndarray:
    """Deterministic sub-pixel offsets (spp, 2) in [-0.5, 0.5)² (a k×k grid, k = ceil(sqrt(spp)))."""
    k = int(np.ceil(np.sqrt(spp)))
    g = (np.arange(k) + 0.5) / k - 0.5
    xx, yy = np.meshgrid(g, g)
    return np.stack([xx.ravel(), yy.ravel()], -1)[:spp]


@dataclass
class Hits:
    """Everything the shading of one sub-pixel sample set needs."""

    dirs: np.ndarray
    g: dict
    kind: np.ndarray  # -1 background, 0 ground, 1 leaf, 2 film object
    index: np.ndarray  # leaf / object index
    albedo: np.ndarray  # (M, 3) RGB albedo for ground/leaves
    sun_cos: np.ndarray  # (M,) n·l * visibility (0 where shadowed)
    ambient: np.ndarray  # (M,) (1 + n_y)/2
    plate: np.ndarray  # (M, 3) background plate


class SetRenderer:
    """Builds rays, traces them, and shades samples in hybrid or full-spectral mode."""

    def __init__(self, spec: SetSpec):
        self.spec = spec
        self.tracer = SetTracer(spec)
        self.tables: list[FilmTable] = [film_table(o.layers, o.substrate, grid=spec.grid,
                                                   angle_step_deg=spec.angle_step_deg) for o in spec.objects]
        self.sun_S = spec.sun_spectrum()
        self.sun_rgb = spectrum_to_rgb(self.sun_S, spec.grid).astype(np.float64)  # §2.3.3 precomputed RGB
        self.amb_rgb = sky_ambient_rgb(spec)
        names = self.tracer.names
        self.kind_of = np.array([0 if n == "ground" else 1 if n.startswith("leaf") else 2 for n in names])
        self.index_of = np.array([0 if n == "ground" else int(n[4:]) for n in names])

    # -- geometry, shared by both modes
    def trace(self, offset: np.ndarray) -> Hits:
        spec, cam = self.spec, self.spec.camera
        H, W = cam.height, cam.width
        dirs = cam.ray_directions(jitter=np.broadcast_to(offset, (H, W, 2))).reshape(-1, 3)
        org = np.broadcast_to(np.asarray(cam.position, np.float64), dirs.shape)
        g = self.tracer.intersect(org, dirs)
        kind = np.where(g["label"] >= 0, self.kind_of[np.maximum(g["label"], 0)], -1)
        index = np.where(g["label"] >= 0, self.index_of[np.maximum(g["label"], 0)], 0)
        # leaves: elliptical cut-out (and the texture's alpha if any); a cut-out sample continues
        for _ in range(4):
            lf = kind == 1
            if not lf.any():
                break
            uv = g["uv"][lf]
            keep = ((uv[:, 0] - 0.5) ** 2 + (uv[:, 1] - 0.5) ** 2 * 1.0) <= 0.25
            keep &= self._leaf_alpha(index[lf], uv) > 0.5
            if keep.all():
                break
            ids = np.flatnonzero(lf)[~keep]
            g2 = self.tracer.intersect(g["p"][ids] + dirs[ids] * 1e-4, dirs[ids])
            for key in g:
                g[key][ids] = g2[key]
            kind[ids] = np.where(g2["label"] >= 0, self.kind_of[np.maximum(g2["label"], 0)], -1)
            index[ids] = np.where(g2["label"] >= 0, self.index_of[np.maximum(g2["label"], 0)], 0)
        M = dirs.shape[0]
        albedo = np.zeros((M, 3))
        gr = kind == 0
        albedo[gr] = sample_texture(spec.ground_texture[..., :3], g["uv"][gr], spec.ground_repeat)
        for i, lf in enumerate(spec.leaves):
            m = (kind == 1) & (index == i)
            if m.any():
                albedo[m] = sample_texture(lf.texture[..., :3], g["uv"][m])
        albedo = np.clip(albedo, 0.0, 1.0)
        sun_cos = np.zeros(M)
        surf = kind >= 0
        if surf.any():
            nl = np.clip(g["n"][surf] @ spec.sun_dir, 0.0, None)
            lit = nl > 0
            idx = np.flatnonzero(surf)[lit]
            occ = self.tracer.occluded(g["p"][idx] + g["n"][idx] * 1e-4, spec.sun_dir)
            nl_full = np.zeros(idx.size)
            nl_full[~occ] = nl[lit][~occ]
            sun_cos[idx] = nl_full
        ambient = np.where(surf, 0.5 * (1 + g["n"][:, 1]), 0.0)
        # background plate in screen space at this sample's pixel
        plate = spec.background.reshape(-1, 3).astype(np.float64)
        return Hits(dirs, g, kind, index, albedo, sun_cos, ambient, plate)

    def _leaf_alpha(self, index: np.ndarray, uv: np.ndarray) -> np.ndarray:
        out = np.ones(index.size)
        for i, lf in enumerate(self.spec.leaves):
            if lf.texture.shape[-1] >= 4:
                m = index == i
                if m.any():
                    out[m] = sample_texture(lf.texture[..., 3:4], uv[m])[:, 0]
        return out

    # -- RGB radiance of RGB materials (used directly, and as what a mirror ray "gathers")
    def rgb_radiance(self, h: Hits, mask: np.ndarray) -> np.ndarray:
        a = h.albedo[mask]
        return (a / np.pi * self.sun_rgb[None] * h.sun_cos[mask, None] + a * self.amb_rgb[None] * h.ambient[mask, None])

    def _film_geometry(self, h: Hits, m: np.ndarray):
        v = -h.dirs[m]
        n = h.g["n"][m]
        cos_v = np.clip(np.sum(n * v, -1), 0.0, 1.0)
        refl = 2 * cos_v[:, None] * n - v
        l = self.spec.sun_dir[None]
        hv = l + v
        hv /= np.maximum(np.linalg.norm(hv, axis=-1, keepdims=True), 1e-12)
        cos_d = np.clip(np.sum(hv * l, -1), 0.0, 1.0)
        nh = np.clip(np.sum(n * hv, -1), 0.0, 1.0)
        return cos_v, refl, cos_d, nh

    def gather_mirror_rgb(self, h: Hits, m: np.ndarray, refl: np.ndarray) -> np.ndarray:
        """RGB radiance arriving along the mirror rays of film samples (set geometry or sky dome)."""
        p = h.g["p"][m] + h.g["n"][m] * 1e-4
        g2 = self.tracer.intersect(p, refl)
        kind2 = np.where(g2["label"] >= 0, self.kind_of[np.maximum(g2["label"], 0)], -1)
        index2 = np.where(g2["label"] >= 0, self.index_of[np.maximum(g2["label"], 0)], 0)
        out = sky_radiance_rgb(self.spec, refl)
        surf = (kind2 == 0) | (kind2 == 1)
        if surf.any():
            alb = np.zeros((surf.sum(), 3))
            gr = kind2[surf] == 0
            uv = g2["uv"][surf]
            alb[gr] = sample_texture(self.spec.ground_texture[..., :3], uv[gr], self.spec.ground_repeat)
            for i, lf in enumerate(self.spec.leaves):
                mm = (kind2[surf] == 1) & (index2[surf] == i)
                if mm.any():
                    alb[mm] = sample_texture(lf.texture[..., :3], uv[mm])
            alb = np.clip(alb, 0, 1)
            nrm = g2["n"][surf]
            nl = np.clip(nrm @ self.spec.sun_dir, 0, None)
            occ = self.tracer.occluded(g2["p"][surf] + nrm * 1e-4, self.spec.sun_dir)
            nl[occ] = 0
            out[surf] = alb / np.pi * self.sun_rgb[None] * nl[:, None] + alb * self.amb_rgb[None] * (0.5 * (1 + nrm[:, 1]))[:, None]
        film = kind2 == 2  # film seen in a film: its colour as RGB highlight-free approximation (sky)
        out[film] = sky_radiance_rgb(self.spec, refl[film])
        return out

    def shade_film_spectral(self, h: Hits, m: np.ndarray, mirror_rgb: np.ndarray):
        """Spectral radiance (M_f, N) of film samples and their RGB highlight part (M_f, 3)."""
        spec = self.spec
        cos_v, refl, cos_d, nh = self._film_geometry(h, m)
        S = np.zeros((m.sum(), spec.grid.size))
        rgb = np.zeros((m.sum(), 3))
        idx = h.index[m]
        sun_cos = h.sun_cos[m]
        L_env = rgb_to_radiance(mirror_rgb, spec.grid, spec.upsampling)  # RGB -> spectrum (Fig. 2.3(b))
        for i, ob in enumerate(spec.objects):
            k = idx == i
            if not k.any():
                continue
            tab = self.tables[i]
            lobe = (ob.gloss + 8) / (8 * np.pi) * nh[k] ** ob.gloss * sun_cos[k]
            S[k] = tab.reflectance(cos_v[k]) * L_env[k] + tab.reflectance(cos_d[k]) * (self.sun_S[None] * lobe[:, None])
            rgb[k] = np.asarray(ob.highlight_rgb)[None] * self.sun_rgb[None] * lobe[:, None]
        return S, rgb

    # -- the hybrid render
    def render_hybrid(self) -> HybridImage:
        spec = self.spec
        H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
        rgb = np.zeros((H * W, 3))
        S = np.zeros((H * W, N), np.float32)
        A = np.zeros(H * W)
        offs = stratified_offsets(spec.spp)
        for off in offs:
            h = self.trace(off)
            bg = h.kind < 0
            rgb[bg] += h.plate[bg]
            rm = (h.kind == 0) | (h.kind == 1)
            rgb[rm] += self.rgb_radiance(h, rm)
            fm = h.kind == 2
            if fm.any():
                _, refl, _, _ = self._film_geometry(h, fm)
                s, r = self.shade_film_spectral(h, fm, self.gather_mirror_rgb(h, fm, refl))
                S[fm] += s.astype(np.float32)
                rgb[fm] += r
            A += ~bg
        n = len(offs)
        return HybridImage((rgb / n).reshape(H, W, 3).astype(np.float32), (S / n).reshape(H, W, N),
                           (A / n).reshape(H, W).astype(np.float32), spec.grid)


def spectral_coverage(hybrid: HybridImage) -> float:
    """Fraction of pixels with a non-zero spectral part."""
    return float(np.mean(np.any(hybrid.spectral != 0, axis=-1)))


__all__ = ["Leaf", "FilmObject", "SetSpec", "SetRenderer", "spectral_coverage", "sun_spectrum_from_rgb", "spectrum_to_rgb_matrix",
           "rgb_to_reflectance"]
