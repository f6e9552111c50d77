"""
Forward renderer
================

Defines the forward renderer: the cloud model of Dobashi et al. (2012, Eqs. 3–5, 9) evaluated directly, without
tables, at any view, sun and resolution (the keyframe frames), with the same transport as the precompute:

-   :func:`render`: L_cg (H, W, 3) for one parameter set.

Common to every transport: the sun optical-depth volume for this sun (:mod:`natscene.scatter.medium`) and the
ray-marched S_sun, S_amb, T at the given extinction in 1/m (``params["extinction"]``, mu_t = e rho; the tracers
take the volume's unitless sigma_t = e / ``extinction_scale``) (:mod:`natscene.scatter.single`, at its hit
threshold of t_c and the footprint); the transport (:mod:`natscene.scatter.transport`, the settings'
``transport``) gives the cloud's own light (its ``render``: single and multiple scattering, and for ``all_orders``
the skylight of the frame's dome), then Eq. 4 adds the sky seen through the cloud, L_b = T L_sky, and Eq. 3 the
atmosphere.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError
from natscene.scatter.params import population
from natscene.scatter.transport.base import RenderOptions

__all__ = ["render"]


def render(volume, camera, sun_dir, params: dict, sky, settings: dict | None = None, *, batch_spp: int | None = None,
           return_components: bool = False, sky_settings=None, dome=None, skylight: bool = True, all_orders=None):
    """L_cg (H, W, 3) for one parameter set (scalars; c_in and kappa_a (3,)).

    ``sky``: (H, W, 3) linear L_sky at the camera's resolution (or a constant (3,) colour).
    ``settings``: the shot's render section (a validated ``shots.<name>.render``, or a part of one; None: the
    schema's defaults), through :func:`natscene.scatter.allorders.render_settings`: ``transport``, ``seed``, ``step_voxels``,
    ``supersample``, ``ground_albedo`` (all_orders), ``orders``, ``spp`` (dobashi) and the all-orders transport's
    collision budgets. ``batch_spp``: the dobashi transport's paths per pass (None: automatic).
    ``return_components``: also return a dict with L_s, L_m, L_b, T, t_c, footprint (all_orders: L_m holds
    every order >= 2 of the sun's light and L_sky_lit the skylight's). ``skylight=False``: the sun alone
    lights the cloud (all_orders; e.g. to compare with a sun-only reference). ``all_orders``: the all-orders
    transport's :class:`natscene.scatter.allorders.AllOrdersSettings`, used as they are; None: those of
    ``settings`` (:func:`natscene.scatter.allorders.frame_settings`).
    ``sky_settings``: the shot's sky (a validated ``shots.<name>.sky`` or its
    :class:`natscene.sky.daylight.Skylight`), whose dome lights the cloud (all_orders) unless ``dome`` is given.
    """
    from natscene.scatter.medium import make_medium
    from natscene.scatter.single import march_view
    from natscene.scatter.tables import geometry_images
    from natscene.scatter.transport import get

    from natscene.scatter.allorders import frame_settings, render_settings
    s = render_settings(settings)
    if all_orders is None:
        all_orders = frame_settings(s)
    model = get(s["transport"], "shots.<name>.render.transport")
    P, p = population(params)
    if P != 1:
        raise InputError(f"render: one parameter set expected, got a population of {P}")
    H, W = camera.height, camera.width
    sky = np.asarray(sky, np.float32)
    if sky.ndim == 1:
        sky = np.broadcast_to(sky.reshape(1, 1, -1), (H, W, 3))
    if sky.shape != (H, W, 3):
        raise InputError(f"render: sky image has shape {sky.shape}, the camera renders {W}x{H}")
    extinction = float(p["extinction"][0])
    if not extinction >= 0.0:
        raise InputError(f"render: extinction {extinction:g} /m is negative (a keyframe's or "
                         f"shots.<name>.keyframes' extinction)")
    sigma = extinction / float(volume.extinction_scale)          # the tracers' unitless sigma_t
    med = make_medium(volume, sun_dir)
    single = march_view(med, camera, [sigma], step_voxels=s["step_voxels"], supersample=s["supersample"])
    t_c, cos_t, foot = geometry_images(camera, volume, med.sun_dir, single["t_hit"])
    options = RenderOptions(seed=s["seed"], step_voxels=s["step_voxels"], supersample=s["supersample"],
                            orders=s["orders"], spp=s["spp"], batch_spp=batch_spp, sky_settings=sky_settings,
                            dome=dome, ground_albedo=s["ground_albedo"], skylight=skylight, all_orders=all_orders)
    cloud, comps = model.render(volume, med, camera, sigma, single, cos_t, p, sky, options)
    L_s, L_m = comps["L_s"], comps["L_m"]
    T = single["T"][0]
    L_b = T[..., None] * sky
    L_c = cloud + L_b
    e_a = np.exp(-p["kappa_a"][0].astype(np.float32) * t_c[..., None])
    L_cg = (L_c * e_a + (1 - e_a) * sky).astype(np.float32)
    if return_components:
        comps.update(L_s=L_s, L_m=L_m, L_b=L_b, T=T, t_c=t_c, footprint=foot)
        return L_cg, comps
    return L_cg
