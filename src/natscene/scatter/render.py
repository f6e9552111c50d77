"""The forward renderer: Dobashi's cloud model (Eqs. 3–9) evaluated directly, without tables, at any view,
sun and resolution (the keyframe frames).

The same components as the precompute, for one parameter set: the sun optical-depth volume for this sun
(:mod:`natscene.scatter.medium`), the ray-marched S_sun, S_amb, T at the given sigma_t
(:mod:`natscene.scatter.single`), and orders 2..``orders`` of multiple scattering by path tracing with
directions importance-sampled from HG(g) itself (:mod:`natscene.scatter.multiple` with one g), then Eqs. 4
and 3 exactly as :func:`natscene.scatter.compose.compose`.
"""
from __future__ import annotations

import numpy as np

from natscene.io import InputError
from natscene.scatter.compose import population
from natscene.scatter.phase import hg


def render(volume, camera, sun_dir, params: dict, sky, orders: int = 4, spp: int = 64, seed: int = 0,
           step_voxels: float = 0.5, supersample: int = 4, rho_threshold: float = 0.01,
           batch_spp: int | None = None, return_components: bool = False):
    """L_cg (H, W, 3) for one parameter set (scalars; c_in and kappa_a (3,)).

    ``sky``: (H, W, 3) linear L_sky at the camera's resolution (or a constant (3,) colour).
    ``return_components``: also return a dict with L_s, L_m, L_b, T, t_c, footprint.
    """
    from natscene.scatter.medium import make_medium
    from natscene.scatter.multiple import trace_orders
    from natscene.scatter.single import march_view
    from natscene.scatter.tables import geometry_images

    P, p = population(params)
    if P != 1:
        raise InputError(f"render: one parameter set expected, got a population of {P}")
    H, W = camera.height, camera.width
    sky = np.asarray(sky, np.float32)
    if sky.ndim == 1:
        sky = np.broadcast_to(sky.reshape(1, 1, -1), (H, W, 3))
    if sky.shape != (H, W, 3):
        raise InputError(f"render: sky image has shape {sky.shape}, the camera renders {W}x{H}")
    if orders < 1:
        raise InputError(f"render: orders must be >= 1, got {orders}")
    sigma, g, beta = float(p["sigma_t"][0]), float(p["g"][0]), float(p["beta"][0])
    med = make_medium(volume, sun_dir)
    single = march_view(med, camera, [sigma], step_voxels=step_voxels, supersample=supersample,
                        rho_threshold=rho_threshold)
    t_c, cos_t, foot = geometry_images(camera, volume, med.sun_dir, single["t_hit"])
    c_in = p["c_in"][0].astype(np.float32)
    L_in, L_amb = float(p["L_in"][0]), float(p["L_amb"][0])
    a_s = L_in * beta * hg(cos_t, g) * single["S_sun"][0] + L_amb * single["S_amb"][0]
    a_m = np.zeros((H, W))
    if orders >= 2 and sigma > 0:
        e = trace_orders(med, camera, sigma, [g], n_max=orders, spp=spp, seed=seed, batch_spp=batch_spp)
        for k in range(2, orders + 1):
            a_m += beta ** k * e[k - 1, 0]
        a_m *= L_in
    T = single["T"][0]
    L_s = a_s[..., None].astype(np.float32) * c_in
    L_m = a_m[..., None].astype(np.float32) * c_in
    L_b = T[..., None] * sky
    L_c = L_s + L_m + L_b
    e_a = np.exp(-p["kappa_a"][0].astype(np.float32) * t_c[..., None])
    L_cg = (L_c * e_a + (1 - e_a) * sky).astype(np.float32)
    if return_components:
        return L_cg, {"L_s": L_s, "L_m": L_m, "L_b": L_b, "T": T, "t_c": t_c, "footprint": foot}
    return L_cg
