"""The voxels a camera's frame sees (natscene.geometry.frame_voxels) against the camera's own rays, marched."""
from dataclasses import replace

import numpy as np
import pytest

from natscene.geometry import Camera, frame_voxels, ray_box

LO, HI, SHAPE = np.array([-4.0, 0.0, -3.0]), np.array([4.0, 2.0, 3.0]), (12, 10, 16)     # (nz, ny, nx)


def _hit_voxels(camera: Camera, supersample: int = 4, steps: int = 1500) -> np.ndarray:
    """bool (nz, ny, nx): the voxels that rays through a ``supersample``-times finer grid of the frame (its edges
    included) pass through, by points every 1/``steps`` of each ray's chord through the box."""
    fine = replace(camera, width=camera.width * supersample + 1, height=camera.height * supersample + 1)
    # pixel centres of the finer camera span the frame less half a fine pixel: widen its field by that much
    tan = np.tan(np.radians(camera.fov) / 2) * fine.height / (fine.height - 1)
    fine = replace(fine, fov=float(np.degrees(2 * np.arctan(tan))))
    d = fine.ray_directions().reshape(-1, 3)
    o = np.broadcast_to(np.asarray(camera.position, np.float64), d.shape)
    t0, t1 = ray_box(o, d, LO, HI)
    keep = t1 > t0
    d, t0, t1 = d[keep], t0[keep], t1[keep]
    out = np.zeros(SHAPE, bool)
    size = (HI - LO) / np.array(SHAPE[::-1])
    for f in np.linspace(0.0, 1.0, steps):
        p = camera.position + d * (t0 + f * (t1 - t0))[:, None]
        i = np.clip(((p - LO) / size).astype(int), 0, np.array(SHAPE[::-1]) - 1)
        out[i[:, 2], i[:, 1], i[:, 0]] = True
    return out


@pytest.mark.parametrize("camera", [
    Camera((0.5, 1.0, -20.0), (0.0, 1.0, 0.0), (0.0, 1.0, 0.0), 8.0, 64, 48),          # inside the box's sides
    Camera((30.0, -12.0, 5.0), (0.0, 1.0, 0.0), (0.0, 1.0, 0.0), 5.0, 40, 40),          # from below, oblique
    Camera((2.0, 1.0, 1.0), (-3.0, 1.5, 0.0), (0.0, 1.0, 0.0), 40.0, 32, 24),           # inside the box
])
def test_frame_voxels_hold_every_voxel_the_cameras_rays_cross(camera):
    """Every voxel that one of the camera's rays crosses is in the frame (conservative), and the frame holds
    nothing more than a voxel away from those (away from the camera, within 3 voxel diagonals of which a voxel's
    bounding sphere spans a wide angle); ``pad`` voxels more hold the crossed voxels dilated by ``pad``."""
    from scipy.ndimage import binary_dilation
    hit = _hit_voxels(camera)
    got = frame_voxels(camera, LO, HI, SHAPE)
    assert hit.any() and not hit.all()
    assert not np.any(hit & ~got), np.argwhere(hit & ~got)[:5]
    size = (HI - LO) / np.array(SHAPE[::-1])
    zz, yy, xx = np.meshgrid(*[np.arange(n) + 0.5 for n in SHAPE], indexing="ij")
    centres = LO + np.stack([xx, yy, zz], -1) * size
    far = np.linalg.norm(centres - camera.position, axis=-1) > 3 * np.linalg.norm(size)
    loose = got & far & ~binary_dilation(hit, np.ones((3, 3, 3), bool))
    assert not loose.any(), np.argwhere(loose)[:5]
    grown = frame_voxels(camera, LO, HI, SHAPE, pad=2)
    assert np.all(grown >= got) and not np.any(binary_dilation(hit, np.ones((5, 5, 5), bool)) & ~grown)
