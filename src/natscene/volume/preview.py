"""
Volume previews
===============

Defines the volume previews: the rendered look beside the optical depth projected along two axes:

-   :func:`preview_sheet`: the preview image (rendered look | tau front | tau top).
-   :func:`rendered_look`: the front view lit from the side, multiple scattering by scattering octaves.
-   :func:`optical_depth_projections`, :func:`side_by_side`: the optical depth along z and y, side by side.

- tau(x, y) = extinction_scale * sum_z rho * dz (that is, at sigma_t = 1) along z (front) and along y (top),
  stored in preview.exr and shown as grey-scale maps of 1 - exp(-tau / 20).
- The rendered look (:func:`rendered_look`): the front view lit by the sun from the side with multiple
  scattering approximated by Wrenninge's scattering octaves (sigma_t = 0.5: a mean optical depth of 30 along
  z), the sky above and behind. A preview, not the fitted renderer.
- :func:`lit_side_by_side`: the former quick look (single scattering by cumulative sums along the grid axes).

References
----------
-   Wrenninge, M., Kulla, C., & Lundqvist, V. (2013). Oz: the great and volumetric. SIGGRAPH 2013 Talks.
"""
from __future__ import annotations

import numpy as np

from natscene.phase import hg

__all__ = ["preview_sheet", "rendered_look", "optical_depth_projections", "side_by_side"]

SKY = np.array([0.18, 0.32, 0.62], np.float32)  # linear sRGB of a mid-blue sky


def optical_depth_projections(density: np.ndarray, voxel: float, extinction_scale: float):
    """(front [ny, nx] with row 0 at the top, top [nz, nx] seen from above) optical depths at sigma_t = 1."""
    front = density.sum(axis=0)[::-1] * voxel * extinction_scale
    top = density.sum(axis=1)[::-1] * voxel * extinction_scale
    return front.astype(np.float32), top.astype(np.float32)


def side_by_side(front: np.ndarray, top: np.ndarray, gap: int = 4) -> np.ndarray:
    """One single-channel image: front | gap | top, padded to the same height (NaN-free, pad = 0)."""
    h = max(front.shape[0], top.shape[0])
    out = np.zeros((h, front.shape[1] + gap + top.shape[1]), np.float32)
    out[h - front.shape[0]:, : front.shape[1]] = front
    out[h - top.shape[0]:, front.shape[1] + gap:] = top
    return out


def shade(tau: np.ndarray, sigma_show: float = 0.05) -> np.ndarray:
    """Linear RGB rendering of an optical-depth image for the PNG preview."""
    t = np.exp(-sigma_show * tau)[..., None]
    return ((1 - t) * np.float32(0.9) + t * SKY).astype(np.float32)


def lit_view(density: np.ndarray, voxel: float, extinction_scale: float, view_axis: int, light_axis: int,
             sigma_t: float = 0.05, ambient: float = 0.35) -> np.ndarray:
    """Linear RGB image of the grid seen along ``view_axis`` (0 = z, 1 = y of [z, y, x]) lit along
    ``light_axis`` from its high end, by single scattering with cumulative-sum transmittances."""
    mu = density * np.float32(voxel * extinction_scale * sigma_t)          # optical depth per voxel
    # transmittance from the light (entering at the high end of light_axis) to each voxel
    tau_l = np.flip(np.cumsum(np.flip(mu, light_axis), axis=light_axis), light_axis) - mu / 2
    tau_v = np.cumsum(mu, axis=view_axis) - mu / 2                         # from the viewer at index 0
    scatter = (mu * np.exp(-tau_l) * np.exp(-tau_v)).sum(axis=view_axis)
    total = mu.sum(axis=view_axis)
    t = np.exp(-total)
    img = (scatter * 1.6 + ambient * (1 - t))[..., None] * np.float32(0.95) + t[..., None] * SKY
    if view_axis == 0:
        img = img[::-1]                                                     # [y, x] with y up
    else:
        img = img[::-1]                                                     # [z, x] seen from above
    return img.astype(np.float32)


def lit_side_by_side(density: np.ndarray, voxel: float, extinction_scale: float, gap: int = 4) -> np.ndarray:
    """Front view (along z, light from above) | top view (along y, light from +x side), RGB."""
    front = lit_view(density, voxel, extinction_scale, view_axis=0, light_axis=1)
    top = lit_view(density, voxel, extinction_scale, view_axis=1, light_axis=2)
    h = max(front.shape[0], top.shape[0])
    out = np.zeros((h, front.shape[1] + gap + top.shape[1], 3), np.float32)
    out[...] = 1.0
    out[h - front.shape[0]:, : front.shape[1]] = front
    out[h - top.shape[0]:, front.shape[1] + gap:] = top
    return out


LOOK_SIGMA_T = 0.5                     # mean optical depth 30 along z: a thick cumulus
LOOK_SKY = np.array([0.16, 0.27, 0.55], np.float32)    # sky radiance (linear RGB), behind and above
LOOK_SUN = np.array([3.2, 3.05, 2.8], np.float32)      # sun irradiance (linear RGB)


def rendered_look(volume, sigma_t: float = LOOK_SIGMA_T, octaves: int = 8, a: float = 0.5, b: float = 0.7,
                  c: float = 0.5, g: float = 0.8, albedo: float = 0.999) -> np.ndarray:
    """Linear RGB [ny, nx, 3] of the cloud seen along +z (orthographic, y up), sun from the side (+x, level).

    Multiple scattering by Wrenninge's octave approximation ("Oz: the great and volumetric", SIGGRAPH 2013
    talk; Wrenninge, Kulla, Lundqvist): ``L = sum_i b^i L_ss(a^i sigma_t on the light path, HG(c^i g))`` -- each
    octave lets the sunlight reach deeper (extinction a^i) with a flatter phase (c^i g) and a smaller weight b^i,
    standing in for the light that diffuses through the cloud. Transmittances are exact cumulative sums along
    the grid axes (light along x, view along z); the sky lights the cloud from above through exp(-tau / 2)
    and shows behind it through the view transmittance. Deterministic, about a second at 194x122x194."""
    d = np.asarray(volume.density, np.float32)
    vox = float(volume.voxel_size[0])
    mu = d * np.float32(vox * volume.extinction_scale * sigma_t)          # optical depth per voxel
    tau_v = np.cumsum(mu, axis=0) - mu / 2                                 # from the viewer at z index 0
    tau_l = np.flip(np.cumsum(np.flip(mu, 2), axis=2), 2) - mu / 2        # from the sun at the +x side
    tau_t = np.flip(np.cumsum(np.flip(mu, 1), axis=1), 1) - mu / 2        # from the sky above (+y)
    w = (mu * np.float32(albedo)) * np.exp(-tau_v)                         # scattering seen by the camera
    sun = np.zeros(d.shape[1:], np.float32)
    for i in range(octaves):
        sun += np.float32(b ** i * hg(0.0, c ** i * g)) * (w * np.exp(-np.float32(a ** i) * tau_l)).sum(axis=0)
    amb = (w * np.exp(-0.5 * tau_t)).sum(axis=0)
    t = np.exp(-mu.sum(axis=0))
    img = sun[..., None] * LOOK_SUN + amb[..., None] * LOOK_SKY * np.float32(0.9) + t[..., None] * LOOK_SKY
    return img[::-1].astype(np.float32)                                    # row 0 at the top


def tau_map(tau: np.ndarray, scale: float = 20.0) -> np.ndarray:
    """Grey RGB of an optical-depth map: 1 - exp(-tau / scale) (0 = clear, 1 = opaque)."""
    v = 1 - np.exp(-np.asarray(tau, np.float32) / np.float32(scale))
    return np.repeat(v[..., None], 3, axis=-1).astype(np.float32)


def _resize_nearest(m: np.ndarray, h: int, w: int) -> np.ndarray:
    rows = np.clip((np.arange(h) * m.shape[0] / h).astype(int), 0, m.shape[0] - 1)
    cols = np.clip((np.arange(w) * m.shape[1] / w).astype(int), 0, m.shape[1] - 1)
    return m[rows][:, cols]


def preview_sheet(look: np.ndarray, front: np.ndarray, top: np.ndarray, gap: int = 4) -> np.ndarray:
    """One display-referred RGB image in [0, 1]: rendered look (tone-mapped) | tau front | tau top, the maps
    scaled to the look's height. A flat box (a deck, a field: the look over 2.5 times wider than tall) is
    stacked instead: the look over tau front over tau top, all at the look's width, so the top view, which
    shows the cloud cover, is not shrunk to a strip."""
    from natscene.io import to_srgb8
    look8 = to_srgb8(look, "auto").astype(np.float32) / 255.0
    h, w = look8.shape[:2]
    maps = [tau_map(t) for t in (front, top)]
    if w > 2.5 * h:
        parts = [look8]
        for m in maps:
            parts.append(np.ones((gap, w, 3), np.float32))
            parts.append(_resize_nearest(m, max(1, int(round(m.shape[0] * w / m.shape[1]))), w))
        return np.concatenate(parts, axis=0)
    parts = [look8]
    for m in maps:
        # tau maps are linear coverage, shown as is (display-referred)
        parts.append(np.ones((h, gap, 3), np.float32))
        parts.append(_resize_nearest(m, h, max(1, int(round(m.shape[1] * h / m.shape[0])))))
    return np.concatenate(parts, axis=1)
