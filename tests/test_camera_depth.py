"""The visibility weight's camera depth in a volume that fills its box (natscene.scatter.inscatter.CameraDepth).

Known independently of the code under test: in a slab of constant density 1 that fills its box, the optical depth
from a point toward the camera is the distance to the box's face along the direction to the camera (numpy
here, the slab test), and the cache's denominator per voxel, ∫ rho w dV / V with w = exp(-sig_k depth), is the mean of that
exponential over the voxel (a 16 x 16 x 16 midpoint rule here).
"""
import numpy as np
import pytest

import natscene  # noqa: F401
import mitsuba as mi

from natscene.scatter.inscatter import (EXACT_STEEPNESS, CameraDepth, blended_depth, voxel_camera_depth,
                                        weighted_voxel_integrals)
from natscene.scatter.medium import make_medium
from natscene.scatter.reference_scene import slab_volume

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


def test_depth_is_the_distance_to_the_face_where_the_weight_is_smooth():
    """At sig_k 24 (1.9 optical depths across a voxel toward the camera) the depth at random points of the slab
    whose ray to the camera leaves through its top face, the half voxel under it included, is the distance to the
    face within 0.1 %; the
    voxel-centred depth interpolated alone reads the top half voxel too deep (clamped to the top centre's)."""
    med, cam = _slab(24.0)
    assert med.face_dense
    cd = CameraDepth(med, voxel_camera_depth(med, cam), cam)
    rng = np.random.default_rng(0)
    x = np.column_stack([rng.uniform(-0.75, 0.0, 20000), rng.uniform(0.0, 1.0, 20000), rng.uniform(-0.5, 0.5, 20000)])
    p = mi.Point3f(*[x[:, i].astype(np.float32) for i in range(3)])
    uvw = mi.Point3f(*[((x[:, i] - med.bbox_min[i]) / (med.bbox_max[i] - med.bbox_min[i])).astype(np.float32)
                       for i in range(3)])
    ref = _to_face(x, cam, med.bbox_min, med.bbox_max)
    got = np.asarray(cd(p, uvw, 24.0), np.float64)
    top = x[:, 1] > 1 - 0.5 / N
    np.testing.assert_allclose(got, ref, rtol=1e-3, atol=1e-5)
    trilinear = np.asarray(cd.parts(p, uvw)[0], np.float64)
    assert np.median(trilinear[top] - ref[top]) > 0.3 * (0.5 / N) / MU


def test_blend_takes_the_voxel_centred_depth_where_the_weight_is_steep():
    """The blend: the exact depth up to EXACT_STEEPNESS[0] across a voxel, the voxel-centred one from [1] on."""
    d, e = np.array([1.0, 1.0, 1.0, 1.0]), np.array([0.5, 0.5, 0.5, 0.5])
    lo, hi = EXACT_STEEPNESS
    s = np.array([0.5 * lo, lo, (lo + hi) / 2, 2 * hi])
    np.testing.assert_allclose(blended_depth(d, e, s, 1.0), [0.5, 0.5, 0.75, 1.0])
    assert blended_depth(d, None, None, 1.0) is d


@pytest.mark.parametrize("scale", [8.0, 24.0])
def test_denominator_is_the_mean_weight_of_every_voxel(scale):
    """∫ rho w dV / V per voxel against a 16^3 midpoint rule of exp(-sig_k distance to the face): within 0.3 % in
    every voxel the camera sees through a weight above 1e-6 (the top voxels' half under the face included)."""
    med, cam = _slab(scale)
    depth = voxel_camera_depth(med, cam)
    got = weighted_voxel_integrals(med, depth, cam, scale)
    h = (med.bbox_max - med.bbox_min) / np.array([2 * N, N, 2 * N])
    sub = (np.arange(16) + 0.5) / 16
    off = np.stack(np.meshgrid(sub, sub, sub, indexing="ij"), -1).reshape(-1, 3)
    bad = []
    for iy in range(N):
        for ix, iz in ((10, 16), (12, 14)):
            x = med.bbox_min + (np.array([ix, iy, iz]) + off) * h
            ref = float(np.exp(-scale * _to_face(x, cam, med.bbox_min, med.bbox_max)).mean())
            if ref > 1e-6 and abs(got[iz, iy, ix] / ref - 1) > 3e-3:
                bad.append((iy, ix, iz, round(float(got[iz, iy, ix] / ref), 4)))
    assert not bad, bad


def test_steepness_sees_a_face_at_a_grazing_angle():
    """Seen from 89 degrees, the depth to the top face changes by 1 / cos(zenith) of a voxel across the top voxels
    (the distance to the face at their top and bottom, numpy), while near the side toward the camera their
    neighbours' rays leave through that side at much the same depth as theirs through the top: the lookup's change
    across a voxel is at least the exact depth's wherever that passes EXACT_STEEPNESS[1], so that those voxels take
    the voxel-centred depth their denominator can integrate (the exact one read 10^18 times too bright there)."""
    mu, sig_k = np.cos(np.radians(89.17)), 10.0
    med = make_medium(slab_volume(tau=sig_k, n=(48, 16, 48), width=12.0))
    cam = np.array([0.0, 1.0, 0.0]) + 400.0 * np.array([np.sqrt(1 - mu * mu), mu, 0.0])
    cd = CameraDepth(med, voxel_camera_depth(med, cam), cam)
    h = (med.bbox_max - med.bbox_min) / np.array([48, 16, 48])
    ix, iz = np.meshgrid(np.arange(48), np.arange(48), indexing="ij")
    c = med.bbox_min + (np.column_stack([ix.ravel(), np.full(ix.size, 15), iz.ravel()]) + 0.5) * h
    true = sig_k * np.abs(_to_face(c + [0, h[1] / 2 - 1e-9, 0], cam, med.bbox_min, med.bbox_max)
                          - _to_face(c - [0, h[1] / 2, 0], cam, med.bbox_min, med.bbox_max))
    uvw = (c - med.bbox_min) / (med.bbox_max - med.bbox_min)
    steep = sig_k * np.asarray(cd.parts(mi.Point3f(*[c[:, i].astype(np.float32) for i in range(3)]),
                                        mi.Point3f(*[uvw[:, i].astype(np.float32) for i in range(3)]))[2], np.float64)
    hi = EXACT_STEEPNESS[1]
    assert (true > hi).sum() > 1000
    miss = (true > hi) & (steep < hi)
    assert not miss.any(), (int(miss.sum()), c[miss][:3], true[miss][:3], steep[miss][:3])
