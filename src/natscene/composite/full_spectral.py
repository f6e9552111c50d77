"""Full-spectral reference mode (Dong 2007 §2.5: the comparison with Sun et al.'s full-spectrum framework
[SFDC01], "which emphasizes real spectra as input, computes full spectra light-object interactions and
generates spectral images convertible to RGB"): the same set and the same rays as the hybrid renderer, but
every material, light and pixel is a spectrum on the wavelength grid (default 81 bands) and every
light-material interaction is a per-band product, on every pixel and every bounce.

Preprocessing (once per render, timed with it): the RGB inputs become spectral inputs the way a spectral
renderer's material database holds them, with the same published upsampling as the hybrid
(:mod:`natscene.spectral.upsampling`): each texel of the ground and leaf textures becomes a reflectance
spectrum (``rgb_to_reflectance``), each pixel of the background plate and the sky dome's zenith/horizon a
radiance spectrum (``rgb_to_radiance``); the sun is its SPD. Rendering: textures are looked up as spectra
(bilinear over 81 bands), shaded as ρ(λ)·(E_sun(λ) cosθ V / π + L_amb(λ) (1 + n_y)/2), film objects as
R(θ_v, λ) L_env(λ) + R(θ_d, λ) E_sun(λ) lobe + highlight(λ) E_sun(λ) lobe with L_env the *spectral* radiance
the mirror ray gathers; the pixel spectra are integrated to XYZ -> linear sRGB once at the end (§2.4).

With the Mallett-Yuksel upsampling (linear, exact round trip under D65) the two modes agree exactly under a
D65 sun and a neutral sky; under coloured light they differ on RGB materials, because a product of two
upsampled spectra does not integrate to the product of the two RGB triples (Dong's hybrid, which shades RGB
materials in RGB, has the same property).
"""
from __future__ import annotations

import time

import numpy as np

from natscene.composite.scene import SetRenderer, sky_ambient_weight, sky_blend
from natscene.spectral.grid import spectrum_to_rgb_matrix
from natscene.spectral.upsampling import rgb_to_radiance, rgb_to_reflectance


class UpsampleOnLookup:
    """A texture with more texels than the render has samples: converting every texel up front would cost more
    than converting each looked-up value, so the spectral renderer does the latter (bilinear RGB lookup, then
    the upsampling; identical for the linear Mallett-Yuksel method, a close variant for Smits 1999)."""

    def __init__(self, rgb: np.ndarray, grid, method: str):
        self.rgb, self.grid, self.method = rgb, grid, method

    def lookup(self, uv: np.ndarray, repeat: float = 1.0) -> np.ndarray:
        from natscene.composite.scene import sample_texture
        return rgb_to_reflectance(sample_texture(self.rgb, uv, repeat), self.grid, self.method).astype(np.float32)


def spectral_texture(rgb: np.ndarray, grid, method: str, n_samples: int):
    """Per-texel reflectance spectra (h, w, N) when the texture has at most ``n_samples`` texels, else
    :class:`UpsampleOnLookup` (whichever is cheaper: the fair choice for the reference renderer)."""
    if rgb.shape[0] * rgb.shape[1] <= n_samples:
        return rgb_to_reflectance(rgb, grid, method).astype(np.float32)
    return UpsampleOnLookup(rgb, grid, method)


class SpectralInputs:
    """Spectra of the set's RGB inputs (the spectral renderer's preprocessing): per-texel reflectance spectra of
    the textures (or upsampling on lookup for textures larger than the render, see :func:`spectral_texture`),
    per-pixel radiance spectra of the plate, sky and highlight spectra."""

    def __init__(self, r: SetRenderer):
        spec = r.spec
        g, up = spec.grid, spec.upsampling
        n = spec.camera.width * spec.camera.height * spec.spp
        self.ground = spectral_texture(r.ground_rgb, g, up, n)
        self.leaves = [spectral_texture(t, g, up, n) for t in r.leaf_rgb]
        self.plate = rgb_to_radiance(spec.background.reshape(-1, 3), g, up).astype(np.float32)
        self.zenith = rgb_to_radiance(np.asarray(spec.sky_zenith, np.float64), g, up).astype(np.float32)
        self.horizon = rgb_to_radiance(np.asarray(spec.sky_horizon, np.float64), g, up).astype(np.float32)
        w = sky_ambient_weight()
        self.ambient = (self.horizon * (1 - w) + self.zenith * w).astype(np.float32)
        self.highlight = [rgb_to_reflectance(np.asarray(o.highlight_rgb, np.float64), g, up).astype(np.float32)
                          for o in spec.objects]


def _radiance(rho, sun_S, amb_S, sun_cos, ambient):
    return rho * (sun_S[None] / np.float32(np.pi) * sun_cos[:, None] + amb_S[None] * ambient[:, None])


def render_full_spectral(renderer: SetRenderer) -> tuple[np.ndarray, np.ndarray]:
    """Spectral radiance image (H, W, N) and its linear sRGB (H, W, 3). ``renderer.timing`` gets
    ``preprocess`` (input spectra), ``geometry`` (shared ray casting) and ``shading`` seconds."""
    r, spec = renderer, renderer.spec
    H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
    r.timing = {"geometry": 0.0, "shading": 0.0}
    t_start = time.perf_counter()
    inp = SpectralInputs(r)
    r.timing["preprocess"] = time.perf_counter() - t_start
    sun_S = r.sun_S
    S = np.zeros((H * W, N), np.float32)
    spp = spec.spp
    for sl, dirs in r.blocks(block_rays=max(spp, (1 << 24) // (4 * N))):  # (rays x N) float32 <= 16 MB
        h = r.trace(dirs)
        fm = h.kind == 2
        mh = r.mirror(h, fm) if fm.any() else None
        n = sl.stop - sl.start
        out = np.zeros((dirs.shape[0], N), np.float32)
        bg = h.kind < 0
        out[bg] = np.tile(inp.plate[sl], (spp, 1))[bg]
        rm = (h.kind == 0) | (h.kind == 1)
        rho = r.albedo(h.kind[rm], h.index[rm], h.uv[rm], inp.ground, inp.leaves)
        out[rm] = _radiance(rho, sun_S, inp.ambient, h.sun_cos[rm], h.ambient[rm])
        if mh is not None:
            # spectral radiance gathered by the mirror rays: the sky dome's spectra or a spectral surface
            t = sky_blend(mh.refl)
            L_env = inp.horizon[None] * (1 - t) + inp.zenith[None] * t
            surf = (mh.kind == 0) | (mh.kind == 1)
            if surf.any():
                rho2 = r.albedo(mh.kind[surf], mh.index[surf], mh.uv[surf], inp.ground, inp.leaves)
                L_env[surf] = _radiance(rho2, sun_S, inp.ambient, mh.sun_cos[surf], mh.ambient[surf])
            out[fm] = r.film_spectra(h, fm, mh, L_env, highlight_spectra=inp.highlight)[0]
        S[sl] = out.reshape(spp, n, N).sum(0)
    S *= np.float32(1.0 / spp)
    rgb = (S @ spectrum_to_rgb_matrix(spec.grid).astype(np.float32)).reshape(H, W, 3)
    r.timing["shading"] = time.perf_counter() - t_start - r.timing["geometry"] - r.timing["preprocess"]
    return S.reshape(H, W, N), rgb
