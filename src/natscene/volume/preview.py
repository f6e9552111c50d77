"""Volume previews: the rendered look beside the optical depth projected along two axes.

- tau(x, y) = extinction_scale * sum_z rho * dz (that is, at sigma_t = 1) along z (front) and along y (top),
  stored in preview.exr and shown as grey-scale maps of 1 - exp(-tau / 20).
- The rendered look (:func:`rendered_look`): Mitsuba 3 ``volpath`` with multiple scattering (max depth
  ``depth``), the scene of :func:`natscene.scatter.mitsuba_scene.scene_dict` (heterogeneous medium, HG phase
  g = 0.85, albedo 0.999, sigma_t = 0.5: a mean optical depth of 30 along z) lit by the sun from the side
  (azimuth 90 degrees from the view direction, elevation 25 degrees) and a uniform blue sky, seen from the front
  (-z) at 3 box widths. A preview at a small size and few samples, not the fitted renderer.
- :func:`lit_side_by_side`: the former quick look (single scattering by cumulative sums along the grid axes).
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


LOOK_SIGMA_T = 0.08
LOOK_SUN = (1.0, 0.47, 0.0)           # toward the sun: from the +x side, ~25 degrees up
LOOK_SKY = (0.13, 0.22, 0.45)          # uniform sky radiance (linear RGB)


def look_camera(volume, width: int = 256):
    """A perspective camera on -z looking at the box centre from 3 box widths, framing the box's x-y face."""
    from natscene.geometry import Camera
    lo, hi = np.asarray(volume.bbox_min, float), np.asarray(volume.bbox_max, float)
    c = (lo + hi) / 2
    ext = hi - lo
    dist = 3.0 * max(ext[0], ext[1]) + ext[2] / 2
    aspect = ext[0] / ext[1]
    height = max(8, int(round(width / max(aspect, 0.25))))
    fov = float(np.degrees(2 * np.arctan(0.56 * max(ext[1], ext[0] / (width / height)) / (dist - ext[2] / 2))))
    return Camera((c[0], c[1], c[2] - dist), tuple(c), (0.0, 1.0, 0.0), fov, int(width), int(min(height, 2 * width)))


def rendered_look(volume, width: int = 256, spp: int = 32, depth: int = 48, seed: int = 0,
                  threads: int | None = None) -> np.ndarray:
    """Linear RGB (H, W, 3): the cloud rendered with multiple scattering, sun from the side, blue sky."""
    from natscene.variant import select_variant
    select_variant(threads=threads)
    import mitsuba as mi

    from natscene.scatter.mitsuba_scene import scene_dict
    cam = look_camera(volume, width)
    d = scene_dict(volume, cam, np.asarray(LOOK_SUN), LOOK_SIGMA_T, 0.85, 0.999, irradiance=(3.0, 2.9, 2.7),
                   max_depth=depth, spp=spp)
    d["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": list(LOOK_SKY)}}
    img = np.asarray(mi.render(mi.load_dict(d), seed=seed), np.float32)[..., :3]
    return img


def tau_map(tau: np.ndarray, scale: float = 20.0) -> np.ndarray:
    """Grey RGB of an optical-depth map: 1 - exp(-tau / scale) (0 = clear, 1 = opaque)."""
    v = 1 - np.exp(-np.asarray(tau, np.float32) / np.float32(scale))
    return np.repeat(v[..., None], 3, axis=-1).astype(np.float32)


def preview_sheet(look: np.ndarray, front: np.ndarray, top: np.ndarray, gap: int = 4) -> np.ndarray:
    """One display-referred RGB image in [0, 1]: rendered look (tone-mapped) | tau front | tau top, the maps
    scaled to the look's height."""
    from natscene.io import to_srgb8
    look8 = to_srgb8(look, "auto").astype(np.float32) / 255.0
    h = look8.shape[0]
    parts = [look8]
    for t in (front, top):
        m = tau_map(t)
        k = h / m.shape[0]
        rows = np.clip((np.arange(h) / k).astype(int), 0, m.shape[0] - 1)
        w = max(1, int(round(m.shape[1] * k)))
        cols = np.clip((np.arange(w) / k).astype(int), 0, m.shape[1] - 1)
        m = m[rows][:, cols]
        # tau maps are linear coverage, shown as is (display-referred)
        parts.append(np.ones((h, gap, 3), np.float32))
        parts.append(m)
    return np.concatenate(parts, axis=1)
