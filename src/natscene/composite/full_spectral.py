"""Full-spectral reference mode (Dong 2007 §2.5: the comparison with Sun et al.'s full-spectrum framework
[SFDC01]): the same set, the same rays, but every colour computation is done on spectra for every sample.

RGB inputs (textures, the background plate, the sky dome) are upsampled once per sample with the same
published method as the hybrid renderer (:mod:`natscene.spectral.upsampling`): reflectances with
``rgb_to_reflectance``, radiances with ``rgb_to_radiance``; lights are spectra (the sun's SPD, the sky dome
upsampled); each sample's radiance spectrum is integrated to XYZ -> linear sRGB only at the end.
"""
from __future__ import annotations

import numpy as np

from natscene.composite.scene import SetRenderer, sky_ambient_rgb, stratified_offsets
from natscene.spectral.grid import spectrum_to_rgb
from natscene.spectral.upsampling import rgb_to_radiance, rgb_to_reflectance


def render_full_spectral(renderer: SetRenderer) -> tuple[np.ndarray, np.ndarray]:
    """Spectral radiance image (H, W, N) and its linear sRGB (H, W, 3)."""
    spec = renderer.spec
    H, W, N = spec.camera.height, spec.camera.width, spec.grid.size
    up = spec.upsampling
    S = np.zeros((H * W, N), np.float32)
    sun_S = renderer.sun_S
    amb_S = rgb_to_radiance(sky_ambient_rgb(spec), spec.grid, up)
    offs = stratified_offsets(spec.spp)
    for off in offs:
        h = renderer.trace(off)
        bg = h.kind < 0
        S[bg] += rgb_to_radiance(h.plate[bg], spec.grid, up).astype(np.float32)
        rm = (h.kind == 0) | (h.kind == 1)
        if rm.any():
            rho = rgb_to_reflectance(h.albedo[rm], spec.grid, up)
            S[rm] += (rho * (sun_S[None] / np.pi * h.sun_cos[rm, None] + amb_S[None] * h.ambient[rm, None])).astype(np.float32)
        fm = h.kind == 2
        if fm.any():
            _, refl, _, nh = renderer._film_geometry(h, fm)
            s, _ = renderer.shade_film_spectral(h, fm, renderer.gather_mirror_rgb(h, fm, refl))
            # the RGB highlight, as a spectrum: upsampled highlight reflectance x sun SPD x lobe
            idx = h.index[fm]
            for i, ob in enumerate(spec.objects):
                k = idx == i
                if k.any():
                    lobe = (ob.gloss + 8) / (8 * np.pi) * nh[k] ** ob.gloss * h.sun_cos[fm][k]
                    s[k] += rgb_to_reflectance(np.asarray(ob.highlight_rgb, np.float64), spec.grid, up)[None] * sun_S[None] * lobe[:, None]
            S[fm] += s.astype(np.float32)
    S /= len(offs)
    S = S.reshape(H, W, N)
    return S, spectrum_to_rgb(S, spec.grid).astype(np.float32)
