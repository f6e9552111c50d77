"""The visibility weight's camera depth in a volume that fills its box (natscene.scatter.inscatter.CameraDepth).

Known independently of the code under test: in a slab of constant density 1 that fills its box, the optical depth
from a point toward the camera is the distance to the box's face along the direction to the camera (numpy
here, the slab test), and the cache's denominator per voxel, ∫ rho w dV / V with w = exp(-sig_k depth), is the mean of that
exponential over the voxel (a midpoint rule here).
"""
import numpy as np
import pytest

import natscene  # noqa: F401
import mitsuba as mi

from natscene.scatter.inscatter import CameraDepth, voxel_camera_depth, weighted_voxel_integrals
from natscene.scatter.medium import make_medium
from natscene.scatter.reference_scene import slab_camera, slab_volume

N = 16
MU = 0.8                                                  # cosine of the camera's zenith angle


def _slab(scale: float):
    vol = slab_volume(tau=scale, n=(2 * N, N, 2 * N), width=2.0)          # cubic voxels, 1/16 a side
    med = make_medium(vol)
    cam = np.array([0.0, 0.5, 0.0]) + 400.0 * np.array([np.sqrt(1 - MU * MU), MU, 0.0])
    return med, cam


def _to_face(x: np.ndarray, cam: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Distance from the points x (rows, inside the box [lo, hi]) toward the camera to the box's face."""
    d = cam - x
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    with np.errstate(divide="ignore"):
        t = np.where(d > 0, (hi - x) / d, np.where(d < 0, (lo - x) / d, np.inf))
    return t.min(axis=1)


def test_depth_is_the_distance_to_the_face():
    """At sig_k 24 (1.9 optical depths across a voxel toward the camera) the depth at random points of the slab
    whose ray to the camera leaves through its top face, the half voxel under it included, is the distance to the
    face within 0.1 %; the voxel-centred depth interpolated alone reads the top half voxel too deep (clamped to the
    top centre's)."""
    med, cam = _slab(24.0)
    assert med.face_dense
    cd = CameraDepth(med, voxel_camera_depth(med, cam), cam)
    rng = np.random.default_rng(0)
    x = np.column_stack([rng.uniform(-0.75, 0.0, 20000), rng.uniform(0.0, 1.0, 20000), rng.uniform(-0.5, 0.5, 20000)])
    p = mi.Point3f(*[x[:, i].astype(np.float32) for i in range(3)])
    uvw = mi.Point3f(*[((x[:, i] - med.bbox_min[i]) / (med.bbox_max[i] - med.bbox_min[i])).astype(np.float32)
                       for i in range(3)])
    ref = _to_face(x, cam, med.bbox_min, med.bbox_max)
    got = np.asarray(cd(p, uvw), np.float64)
    top = x[:, 1] > 1 - 0.5 / N
    np.testing.assert_allclose(got, ref, rtol=1e-3, atol=1e-5)
    trilinear = np.asarray(cd.trilinear(uvw), np.float64)
    assert np.median(trilinear[top] - ref[top]) > 0.3 * (0.5 / N) / MU


def _grazing_slab():
    """A slab of 10 optical depths in 16 layers, 12 thicknesses wide, seen from 89.17 degrees, the camera aimed at
    its top face's middle: the depth falls by 45 optical depths across a top voxel, and near the side toward the
    camera the rays of the voxels below leave through that side at much the same depth as the top voxel's through
    the top."""
    mu = np.cos(np.radians(89.17))
    med = make_medium(slab_volume(tau=10.0, n=(48, 16, 48), width=12.0))
    return med, np.asarray(slab_camera(mu, height=1.0).position, np.float64)


@pytest.mark.parametrize("case", ["sig_k 8", "sig_k 24", "grazing"])
def test_denominator_is_the_mean_weight_of_every_voxel(case):
    """∫ rho w dV / V per voxel against a midpoint rule of exp(-sig_k distance to the face) (16^3 points, 8 x 512 x 8
    at the grazing view): within 0.3 % in every voxel of two columns (three at the grazing view, two of them by the
    side toward the camera) that the camera sees through a weight above 1e-6, the top voxels' half under the face
    included. At the grazing view the 4 x 4 x 4 nodes alone read the top voxels 10^-13 to 10^7 times the mean, or
    0 where the voxel centre's depth hid the face."""
    if case == "grazing":
        med, cam = _grazing_slab()
        scale, n, columns, sub_y = 10.0, (48, 16, 48), ((38, 24), (39, 24), (20, 24)), 512
    else:
        scale = float(case.split()[1])
        med, cam = _slab(scale)
        n, columns, sub_y = (2 * N, N, 2 * N), ((10, 16), (12, 14)), 16
    depth = voxel_camera_depth(med, cam)
    got = weighted_voxel_integrals(med, depth, cam, scale)
    h = (med.bbox_max - med.bbox_min) / np.array(n)
    sx = (np.arange(16 if sub_y == 16 else 8) + 0.5) / (16 if sub_y == 16 else 8)
    sy = (np.arange(sub_y) + 0.5) / sub_y
    off = np.stack(np.meshgrid(sx, sy, sx, indexing="ij"), -1).reshape(-1, 3)
    bad, seen = [], 0
    for iy in range(n[1]):
        for ix, iz in columns:
            x = med.bbox_min + (np.array([ix, iy, iz]) + off) * h
            ref = float(np.exp(-scale * _to_face(x, cam, med.bbox_min, med.bbox_max)).mean())
            if ref > 1e-6:
                seen += 1
                if abs(got[iz, iy, ix] / ref - 1) > 3e-3:
                    bad.append((iy, ix, iz, float(got[iz, iy, ix] / ref)))
    assert seen >= len(columns)
    assert not bad, bad
