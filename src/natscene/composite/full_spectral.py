"""
Full-spectral reference mode
============================

Defines the full-spectral reference mode (Dong 2007 §2.5: the comparison with Sun et al.'s full-spectrum framework
[SFDC01], "which emphasizes real spectra as input, computes full spectra light-object interactions and
generates spectral images convertible to RGB"): the same set and the same rays as the hybrid renderer, but
every material, light and pixel is a spectrum on the wavelength grid (default 81 bands) and every
light-material interaction is a per-band product, on every sample and every bounce.

-   :func:`render_full_spectral`: the set rendered with every colour a spectrum.
-   :class:`SpectralInputs`: the spectra of the set's RGB inputs (the spectral renderer's preprocessing).

Preprocessing and rendering (the preprocessing timed with the render): every RGB input becomes spectra with the
hybrid's published upsampling (:mod:`natscene.spectral.upsampling`), each by the cheaper of two equivalent
routes (:class:`SpectralInputs`): once per entry (the background plate per pixel, the surfaces' colours, Dong's
highlight, κ_a as a per-band extinction, the sky dome's irradiance on the flat ground) or per lookup (texture
values filtered in RGB, the sky's radiance and the sky dome's irradiance on the meshes: upsampled per sample;
identical for the linear Mallett-Yuksel method). The sun is
its SPD. Every sample is shaded on the grid as ρ(λ)/π·(E_sun(λ)·cos·V + E_sky(n, λ)) (+ translucency), hazed
by e^{−κ(λ)t} toward L_sky(λ), films as R(θ_v, λ)·L_env(λ) + (R(θ_d, λ) + highlight(λ))·E_sun(λ)·lobe with
L_env the *spectral* radiance the mirror ray gathers; the pixel spectra are integrated to XYZ -> linear sRGB
once at the end (§2.4).

With the Mallett-Yuksel upsampling (linear, exact round trip under D65) the two modes agree under a D65 sun
and a neutral sky; under coloured light they differ on RGB materials, because a product of two upsampled
spectra does not integrate to the product of the two RGB triples (Dong's hybrid, which shades RGB materials
in RGB, has the same property).

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
-   Mallett, I., & Yuksel, C. (2019). Spectral primary decomposition for rendering with sRGB reflectance.
    Eurographics Symposium on Rendering 2019.
-   Sun, Y., Fracchia, F. D., Drew, M. S., & Calvert, T. W. (2001). A spectrally based framework for realistic
    image synthesis. The Visual Computer, 17(7), 429–444.
"""
from __future__ import annotations

import time

import numpy as np

from natscene.composite.renderer import SetRenderer
from natscene.composite.set_geometry import KIND_FILM, KIND_GROUND, KIND_SKY, KIND_SURFACE, Hits, MirrorHits
from natscene.spectral.grid import spectrum_to_rgb_matrix
from natscene.spectral.upsampling import rgb_to_radiance, rgb_to_reflectance

__all__ = ["SpectralInputs", "render_full_spectral"]


class SpectralInputs:
    """Spectra of the set's RGB inputs (the spectral renderer's preprocessing). Each input takes the cheaper of
    two equivalent routes (identical results for the linear Mallett-Yuksel method; the fair choice for the
    reference): spectra per entry once when the input has fewer entries than the render has lookups (the plate
    per pixel, the surfaces' colours, Dong's highlight, κ_a), else the RGB value upsampled per lookup (the
    textures, whose filtered lookups are upsampled; the sky table and the sky dome's irradiance, evaluated per
    sample in RGB and upsampled)."""

    def __init__(self, r: SetRenderer):
        spec = r.spec
        g, up = spec.grid, spec.upsampling
        self.grid, self.method = g, up
        self.plate = rgb_to_radiance(spec.plate.reshape(-1, 3), g, up).astype(np.float32)
        self.surface = rgb_to_reflectance(np.asarray(r.surface_color, np.float64).reshape(-1, 3), g, up) \
            .astype(np.float32).reshape(-1, g.size)
        self.highlight = [rgb_to_reflectance(np.asarray(f.highlight_rgb, np.float64), g, up).astype(np.float32)
                          for f in spec.films]
        at = spec.atmosphere
        self.kappa = None if at is None else rgb_to_reflectance(np.asarray(at.kappa, np.float64), g, up)
        self._dome = r.dome

    def irradiance(self, normals: np.ndarray) -> np.ndarray:
        """Spectral sky-dome irradiance (M, N): the dome's irradiance toward each normal, upsampled."""
        return rgb_to_radiance(self._dome.irradiance(normals), self.grid, self.method).astype(np.float32)

    def sky(self, dirs: np.ndarray) -> np.ndarray:
        """Spectral sky radiance (M, N) toward ``dirs``, upsampled from the sky table's RGB."""
        return rgb_to_radiance(self._dome.radiance(dirs), self.grid, self.method).astype(np.float32)


def _albedo(r: SetRenderer, inp: SpectralInputs, h: Hits, sel: np.ndarray, coarse: bool) -> np.ndarray:
    """Reflectance spectra (len(sel), N) of ground/surface samples: filtered RGB lookups upsampled, the
    untextured surfaces' own spectra."""
    rho = rgb_to_reflectance(r.albedo_rgb(h, sel, coarse), inp.grid, inp.method).astype(np.float32)
    kind, index = h.kind[sel], h.index[sel]
    for i, s in enumerate(r.spec.surfaces):
        if s.texture is None:
            k = (kind == KIND_SURFACE) & (index == i)
            rho[k] = inp.surface[i]
    return rho


def _radiance(r: SetRenderer, inp: SpectralInputs, h: Hits, sel: np.ndarray, coarse: bool = False) -> np.ndarray:
    """Spectral radiance (len(sel), N) of ground/surface samples, aerial perspective included."""
    rho = _albedo(r, inp, h, sel, coarse)
    surf = (h.kind[sel] == KIND_SURFACE)
    n = h.n[sel]
    E = r.sun_S[None] * h.sun_front[sel, None] + r.sky_irradiance(h, sel, inp.irradiance)
    tr = np.where(surf, r.translucency[np.where(surf, h.index[sel], -1)], 0.0)
    back = np.flatnonzero(tr > 0)
    if back.size:
        E[back] += tr[back, None] * (r.sun_S[None] * h.sun_back[sel[back], None] + inp.irradiance(-n[back]))
    L = rho / np.float32(np.pi) * E
    if inp.kappa is not None:
        at = r.spec.atmosphere
        far = r.hazy(h, sel)
        if far.any():
            f = sel[far]
            T = np.exp(-inp.kappa[None] * (h.t[f] / at.reference_distance)[:, None]).astype(np.float32)
            L[far] = L[far] * T + (1 - T) * inp.sky(h.dirs[f])
    return L


def render_full_spectral(renderer: SetRenderer) -> tuple[np.ndarray, np.ndarray]:
    """Spectral radiance image (H, W, N) and its linear sRGB (H, W, 3). ``renderer.timing`` gets
    ``preprocess`` (input spectra), ``geometry`` (shared ray casting) and ``shading`` seconds."""
    r, spec = renderer, renderer.spec
    H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
    r.timing = {"geometry": 0.0, "shading": 0.0}
    t_start = time.perf_counter()
    inp = SpectralInputs(r)
    r.timing["preprocess"] = time.perf_counter() - t_start
    S = np.zeros((H * W, N), np.float32)
    spp = spec.spp
    origin = np.asarray(spec.camera.position, np.float64)
    for sl, dirs, ddx, ddy in r.blocks(block_rays=max(spp, (1 << 24) // (4 * N))):  # (rays x N) float32 <= 16 MB
        h = r.trace(origin, dirs, ddx, ddy, pixels=sl.stop - sl.start)
        n = sl.stop - sl.start
        out = np.zeros((h.kind.size, N), np.float32)
        bg = h.kind == KIND_SKY
        bg_i = np.flatnonzero(bg)
        out[bg_i] = inp.plate[sl.start + bg_i % n]
        rm = np.flatnonzero((h.kind == KIND_GROUND) | (h.kind == KIND_SURFACE))
        out[rm] = _radiance(r, inp, h, rm)
        fm = np.flatnonzero(h.kind == KIND_FILM)
        if fm.size:
            mh: MirrorHits = r.mirror(h, fm)
            m = mh.hits
            L_env = inp.sky(m.dirs)
            surf = np.flatnonzero((m.kind == KIND_GROUND) | (m.kind == KIND_SURFACE))
            if surf.size:
                L_env[surf] = _radiance(r, inp, m, surf, coarse=True)
            s = r.film_spectra(h, fm, mh, L_env, highlight_spectra=inp.highlight)[0]
            if inp.kappa is not None:
                tc = h.t[fm] / spec.atmosphere.reference_distance
                T = np.exp(-inp.kappa[None] * tc[:, None]).astype(np.float32)
                s = s * T + (1 - T) * inp.sky(h.dirs[fm])
            out[fm] = s
        S[sl] = out.reshape(spp, n, N).sum(0)
    S *= np.float32(1.0 / spp)
    rgb = (S @ spectrum_to_rgb_matrix(spec.grid).astype(np.float32)).reshape(H, W, 3)
    r.timing["shading"] = time.perf_counter() - t_start - r.timing["geometry"] - r.timing["preprocess"]
    return S.reshape(H, W, N), rgb
