"""Demo views for the Mie shading (Reimschuessel 2011, Ch. 4, Fig. 11): one sun, three cameras placed
around the cloud so that the same point-cloud solution is reused (the thesis' view independence):

- ``glory``: camera between the sun and the cloud, the cloud centre at the antisolar point (θ = 180°);
- ``fogbow``: the cloud centre ``fogbow_angle`` degrees from the antisolar point (θ = 180° - that);
- ``silver_lining``: camera behind the cloud, the sun ``silver_offset`` degrees from the cloud centre
  (θ near 0°, the forward peak).

Also the R_i picture of Fig. 8 (a slice of the point cloud through the centre, along the light).
"""
from __future__ import annotations

import numpy as np

from natscene.geometry import Camera

SHOTS = ("glory", "fogbow", "silver_lining")


def _rotate(v, axis, angle_rad):
    axis = axis / np.linalg.norm(axis)
    return (v * np.cos(angle_rad) + np.cross(axis, v) * np.sin(angle_rad)
            + axis * np.dot(axis, v) * (1 - np.cos(angle_rad)))


def demo_camera(shot: str, volume, sun_dir, distance: float = 2.2, fov: float = 32.0, resolution=(480, 360),
                fogbow_angle: float = 39.0, silver_offset: float = 6.0) -> Camera:
    """The camera of one demo shot, looking at the centre of the volume's bounding box."""
    c = (np.asarray(volume.bbox_min, float) + np.asarray(volume.bbox_max, float)) / 2
    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    side = np.cross(s, [0.0, 1.0, 0.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.array([1.0, 0.0, 0.0])
    if shot == "glory":
        to_cam = s
    elif shot == "fogbow":
        to_cam = _rotate(s, side, np.radians(fogbow_angle))   # away from the antisolar direction
    elif shot == "silver_lining":
        to_cam = -_rotate(s, side, np.radians(silver_offset))
    else:
        raise ValueError(f"unknown demo shot '{shot}' (one of {SHOTS})")
    pos = c + distance * to_cam
    up = np.array([0.0, 1.0, 0.0]) if abs(to_cam[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    w, h = resolution
    return Camera(tuple(pos), tuple(c), tuple(up), float(fov), int(w), int(h))


def scattering_angle_at_centre(camera: Camera, sun_dir) -> float:
    """Phase angle (deg) of sunlight scattered toward the camera at its look-at point."""
    to_cam = np.subtract(camera.position, camera.look_at)
    to_cam = to_cam / np.linalg.norm(to_cam)
    w = -np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    return float(np.degrees(np.arccos(np.clip(np.dot(w, to_cam), -1, 1))))


def ratio_slice(solution) -> np.ndarray:
    """Fig. 8: R_i on the lattice slice through the middle containing the light direction (rows: along
    the light, sun at the top; columns: across), NaN where there is no point. Returns (nc, na)."""
    p = solution.points
    nc, nb, na = p.shape
    b_mid = int(np.median(p.index[:, 1]))
    img = np.full((nc, na), np.nan, np.float32)
    sel = p.index[:, 1] == b_mid
    img[p.index[sel, 0], p.index[sel, 2]] = solution.ratio[sel]
    return img


def ratio_image(solution, scale: int = 4) -> np.ndarray:
    """Fig. 8 as a grey image (dark = isotropic, light = Mie), blue where there is no point."""
    r = ratio_slice(solution)
    rgb = np.where(np.isnan(r)[..., None], np.array([0.05, 0.08, 0.2], np.float32), np.nan_to_num(r)[..., None])
    return np.repeat(np.repeat(rgb, scale, 0), scale, 1).astype(np.float32)
