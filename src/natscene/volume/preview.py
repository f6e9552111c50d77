"""Volume previews: optical depth projected along two axes (front: along z; top: along y).

tau(x, y) = extinction_scale * sum_z rho * dz (that is, at sigma_t = 1), stored in preview.exr.
The PNG is a quick self-shadowed look at the same two views (:func:`lit_view`): single scattering of a
light from above-front with its transmittance by cumulative sums along the grid axes, an ambient term, and
the blue sky behind through the view transmittance. It is a preview, not the cloud renderer.
"""
from __future__ import annotations

import numpy as np

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
