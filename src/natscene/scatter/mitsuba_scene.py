"""
Mitsuba reference scene
=======================

Defines an independent Mitsuba 3 ``volpath`` scene of the same cloud, camera and sun (the reference of the tests):

-   :func:`scene_dict`: the ``mi.load_dict`` description of the scene.
-   :func:`render_reference`: the ``volpath`` image with scattering orders 1..n.
-   :func:`render_transmittance`: the ``volpath`` view transmittance T.

The volume becomes a ``heterogeneous`` medium (``gridvolume`` from an in-memory ``mi.TensorXf``, unit cube
mapped to the bbox, ``scale`` = sigma_t · extinction_scale, constant albedo beta, ``hg`` phase) inside a
``cube`` with a ``null`` BSDF; the sun is a ``directional`` emitter of irradiance L_in · c_in propagating
along -sun_dir; the camera a ``perspective`` sensor (vertical fov) with a ``box``-filtered ``hdrfilm``.
``volpath``'s ``max_depth = n + 1`` keeps scattering orders 1..n (DESIGN §3, Mitsuba facts).
Optionally a ``constant`` environment (radiance 1) with ``max_depth = 1`` renders the view transmittance T.

References
----------
-   Jakob, W., et al. (2022). Mitsuba 3 renderer. https://mitsuba-renderer.org
"""
from __future__ import annotations

import numpy as np

import natscene.variant  # noqa: F401
import mitsuba as mi

from natscene.scatter.medium import _mi

# ``mi`` (the mitsuba module) is listed because tools/thick_references.py imports it from here.
__all__ = ["scene_dict", "render_reference", "render_transmittance", "mi"]


def scene_dict(volume, camera, sun_dir, sigma_t: float, g: float, beta: float, irradiance=(1.0, 1.0, 1.0),
               max_depth: int = 5, spp: int = 256, background: float | None = None) -> dict:
    """``mi.load_dict`` description of the reference scene."""
    _mi()
    lo = np.asarray(volume.bbox_min, np.float64)
    hi = np.asarray(volume.bbox_max, np.float64)
    ext = hi - lo
    centre = (lo + hi) / 2
    T = mi.ScalarTransform4f
    density = mi.TensorXf(np.ascontiguousarray(np.asarray(volume.density, np.float32)[..., None]))
    medium = {
        "type": "heterogeneous",
        "sigma_t": {"type": "gridvolume", "data": density,
                    "to_world": T().translate(mi.ScalarVector3f(*lo)) @ T().scale(mi.ScalarVector3f(*ext))},
        "scale": float(sigma_t) * float(volume.extinction_scale),
        "albedo": float(beta),
        "phase": {"type": "hg", "g": float(g)},
    }
    sd = np.asarray(sun_dir, np.float64)
    sd = sd / np.linalg.norm(sd)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    far = float(np.linalg.norm(corners - np.asarray(camera.position, np.float64), axis=1).max())
    d = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": int(max_depth), "rr_depth": 10_000},
        "sensor": {
            "type": "perspective", "fov": float(camera.fov), "fov_axis": "y",
            "far_clip": max(1e4, 1.01 * far),       # Mitsuba's default far clip is 10 km: a cloud 25 km away
            "to_world": T().look_at(origin=list(map(float, camera.position)), target=list(map(float, camera.look_at)),
                                    up=list(map(float, camera.up))),
            "film": {"type": "hdrfilm", "width": camera.width, "height": camera.height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": int(spp)},
        },
        "cloud": {
            "type": "cube",
            "to_world": T().translate(mi.ScalarVector3f(*centre)) @ T().scale(mi.ScalarVector3f(*(ext / 2))),
            "bsdf": {"type": "null"},
            "interior": medium,
        },
    }
    if background is not None:
        d["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": [float(background)] * 3}}
    else:
        d["sun"] = {"type": "directional", "direction": list(map(float, -sd)),
                    "irradiance": {"type": "rgb", "value": list(map(float, irradiance))}}
    return d


def render_reference(volume, camera, sun_dir, sigma_t: float, g: float, beta: float, orders: int = 4,
                     spp: int = 256, seed: int = 0, irradiance=(1.0, 1.0, 1.0)) -> np.ndarray:
    """volpath image (H, W, 3) with scattering orders 1..``orders`` (orders = 0: nothing is lit)."""
    scene = mi.load_dict(scene_dict(volume, camera, sun_dir, sigma_t, g, beta, irradiance, orders + 1, spp))
    return np.asarray(mi.render(scene, seed=seed), np.float32)[..., :3]


def render_transmittance(volume, camera, sigma_t: float, spp: int = 64, seed: int = 0) -> np.ndarray:
    """volpath transmittance T (H, W): constant environment of radiance 1, max_depth 1, no sun."""
    scene = mi.load_dict(scene_dict(volume, camera, np.array([0.0, 1.0, 0.0]), sigma_t, 0.0, 1.0, max_depth=1,
                                    spp=spp, background=1.0))
    return np.asarray(mi.render(scene, seed=seed), np.float32)[..., 0]
