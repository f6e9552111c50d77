"""Volume previews: optical depth projected along two axes (front: along z; top: along y).

tau(x, y) = extinction_scale * sum_z rho * dz (that is, at sigma_t = 1). The PNG shows the cloud as it
would look lit by a flat white light with transmittance exp(-sigma_t * tau) at sigma_t = ``sigma_show``:
``colour = (1 - exp(-sigma_show * tau)) * white + exp(-sigma_show * tau) * sky_blue``.
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
