"""The cloud parameter is an extinction coefficient in 1/m (mu_t = extinction * rho), whatever the volume.

Independent facts checked here:
- Beer-Lambert: at the same extinction per metre, a copy of a cloud scaled x2 in size (seen by a camera scaled x2
  about the same origin, so every pixel's ray crosses the same part of it) has twice the optical depth along each
  ray: T_2 = T_1^2 (one ray per pixel: a pixel's mean over sub-rays would not square);
- a fit carries to another volume in physical terms: fitting each cloud to its own image rendered at a known
  extinction recovers that extinction per metre, although the volume builder gives the two clouds extinction
  scales a factor 2 apart (its unitless sigma_t would differ by 2);
- the optical depth the fit reports is the extinction times the column ∫ rho ds through the cloud.
"""
from __future__ import annotations

import numpy as np
import pytest

from natscene.fit.genetic import run_ga
from natscene.fit.keyframe import optical_depths
from natscene.fit.problem import FitProblem
from natscene.geometry import Camera, sun_direction
from natscene.scatter.compose import compose
from natscene.scatter.render import render
from natscene.scatter.tables import precompute
from natscene.volume.build import build_volume

SPEC = {"kind": "cumulus", "resolution": [24, 20, 24], "blobs": 10, "seed": 4, "altitude": 0.0}
SUN = sun_direction(130.0, 35.0)
TRUE = {"L_in": 5.0, "g": 0.8, "extinction": 0.03, "beta": 0.9999, "L_amb": 0.2}
NAMES = ("L_in", "g", "extinction", "beta", "L_amb")


def _cloud(scale: float):
    vol = build_volume({**SPEC, "size": 2000.0 * scale}, "units")[0]
    cam = Camera((200.0 * scale, 800.0 * scale, -3000.0 * scale), (0.0, 700.0 * scale, 0.0), (0.0, 1.0, 0.0), fov=36,
                 width=48, height=36)
    return vol, cam


def _params(values: dict) -> dict:
    return {"c_in": [1.0, 0.95, 0.9], "kappa_a": [0.0] * 3, **values}


def test_same_extinction_per_metre_doubles_the_optical_depth_of_a_cloud_twice_the_size():
    (v1, c1), (v2, c2) = _cloud(1.0), _cloud(2.0)
    assert v2.extinction_scale == pytest.approx(v1.extinction_scale / 2, rel=1e-6)   # the builder's normalisation
    sky = np.zeros(3, np.float32)
    settings = {"orders": 1, "transport": "dobashi", "supersample": 1}
    t1 = render(v1, c1, SUN, _params(TRUE), sky, settings, return_components=True)[1]["T"]
    t2 = render(v2, c2, SUN, _params(TRUE), sky, settings, return_components=True)[1]["T"]
    cloud = t1 < 0.99
    assert cloud.sum() > 100
    np.testing.assert_allclose(t2[cloud], t1[cloud] ** 2, rtol=2e-3, atol=2e-5)


@pytest.mark.parametrize("scale", [1.0, 2.0])
def test_a_fit_recovers_the_extinction_per_metre_on_either_size(scale):
    vol, cam = _cloud(scale)
    tb = precompute(vol, cam, SUN, extinctions=[0.0, 0.005, 0.01, 0.02, 0.04, 0.08], gs=[0.7, 0.8, 0.9], n_m=1,
                    transport="dobashi", with_error=False)
    sky = np.broadcast_to(np.array([0.2, 0.3, 0.55], np.float32), (cam.height, cam.width, 3)).copy()
    target = compose(tb, _params(TRUE), sky)[0]
    foot = tb.footprint > 0.5
    prob = FitProblem(tb, sky, target, foot, [1.0, 0.95, 0.9], metric="pixel_ssd", kappas=np.array([0.0]))
    ranges = {"L_in": (5.0, 5.0), "g": (0.8, 0.8), "extinction": (0.005, 0.08), "beta": (0.9999, 0.9999),
              "L_amb": (0.2, 0.2)}
    r = run_ga(prob, ranges, names=NAMES, seed=1, epsilon_o=0, n_suc=0, n_max=30)
    assert r.best.values["extinction"] == pytest.approx(TRUE["extinction"], rel=0.03)
    # the reported optical depth is the extinction times the column through the cloud (metres)
    depth = optical_depths(r.best.values["extinction"], tb.meta["column_m"])
    d = vol.density.sum(axis=0, dtype=np.float64) * float(vol.voxel_size[2])
    assert depth["horizontal"]["mean"] == pytest.approx(r.best.values["extinction"] * d[d > 0].mean(), rel=1e-3)
    # the column through the copy twice the size is twice as long (the same voxels, each twice as deep)
    assert float(vol.voxel_size[2]) == pytest.approx(2000.0 * scale / 24)
