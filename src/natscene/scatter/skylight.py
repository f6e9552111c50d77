"""
Sky dome
========

Defines the sky dome that lights the cloud (the skylight Dobashi et al. 2012, §3 leaves out and §7 names as a
limit):

-   :class:`Dome`, :func:`cell_directions`: the dome's radiance table and its cells' directions.
-   :func:`daylight_dome`: the Preetham sky of a sun direction; :func:`uniform_dome`: a uniform dome.
-   :func:`irradiance`, :func:`ground_radiance`: the horizontal irradiance and the ground's radiance.
-   :class:`GroundLight`: a frame's ground in the cloud's shadow.
-   :func:`calibration`: the per-channel factors that give the dome the photo's mean sky radiance.

The dome is a table of radiance over the upper hemisphere (cells uniform in cos(zenith) and azimuth, so all
cells have the same solid angle 2π / (n_theta n_phi)) in linear RGB, plus a uniform lower hemisphere
standing for the ground. The precompute lights the cloud with four separate "channels" so that the fit
can scale them afterwards: the dome's R, G and B radiance distributions and a unit-radiance ground
(§7: "estimate the intensity distribution of the sky from a photograph before using GAs").

Model: the Preetham et al. (1999) daylight sky of the view's sun (:mod:`natscene.sky.daylight`). It is
chosen over extrapolating the photo's L_sky to a hemisphere because a photo shows a few tens of degrees
of sky around the clouds while the cloud is lit by the whole dome, most of it (the zenith, the sun's
aureole, the horizon) outside the frame; the analytic dome follows the sun and its turbidity. The photo
fixes its level and colour: each channel is scaled so that the dome, seen through the view's camera, has
the photo's mean L_sky (:func:`calibration`). The ground radiance is albedo / π times the horizontal
irradiance of the sun and the sky (a Lambertian ground in the open). A shot's frame knows its sun and sky
when it traces, so its ground lies in the cloud's shadow (:class:`GroundLight`): the ground channel carries the
ground's sunlit part, weighted by the sun's transmittance through the cloud from the ground point
(:meth:`natscene.scatter.medium.Medium.ground_sun_depth`), and the ground's skylit part joins the R, G, B channels.
The precompute keeps the open ground: the fit sets the sun's and the sky's levels after it.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Preetham, A. J., Shirley, P., & Smits, B. (1999). A practical analytic model for daylight. Proceedings of
    ACM SIGGRAPH 1999, 91–100.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Dome", "GroundLight", "cell_directions", "daylight_dome", "uniform_dome", "irradiance",
           "ground_radiance", "calibration"]


@dataclass
class Dome:
    """Radiance of the sky dome: ``rgb`` (n_theta, n_phi, 3) over the upper hemisphere (row 0 at the zenith,
    cells uniform in cos(zenith) and azimuth from +z toward +x), ``ground`` (3,) for the lower hemisphere."""

    rgb: np.ndarray
    ground: np.ndarray

    @property
    def cell_solid_angle(self) -> float:
        n_t, n_p = self.rgb.shape[:2]
        return 2.0 * np.pi / (n_t * n_p)


@dataclass
class GroundLight:
    """A frame's ground in the cloud's shadow: ``sky`` (3,) the ground's radiance under the sky alone
    (:func:`ground_radiance` of the sky's irradiance), ``extinction`` the cloud's mu_t per unit density
    (sigma_t x extinction_scale, 1/m). The ground channel then carries exp(-extinction D(x_g)) per unit sunlit
    ground radiance, x_g the ground point the light leaves (:meth:`natscene.scatter.medium.Medium.ground_sun_depth`),
    and the R, G, B channels the ground's ``sky`` radiance: the ground under the cloud is lit by the sky only. The
    sky's own light on the ground is not shadowed (the cloud hides a part of the dome from the ground under it)."""

    sky: np.ndarray
    extinction: float


def cell_directions(n_theta: int, n_phi: int) -> np.ndarray:
    """Unit directions (n_theta, n_phi, 3) of the dome's cell centres (y up)."""
    mu = 1.0 - (np.arange(n_theta) + 0.5) / n_theta          # cos(zenith), 1 at the zenith
    phi = 2.0 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    s = np.sqrt(1.0 - mu ** 2)
    return np.stack([s[:, None] * np.sin(phi)[None], np.broadcast_to(mu[:, None], (n_theta, n_phi)),
                     s[:, None] * np.cos(phi)[None]], axis=-1)


def daylight_dome(sun_dir, sky, ground=(0.0, 0.0, 0.0), n_theta: int = 32, n_phi: int = 64) -> Dome:
    """The Preetham sky of ``sun_dir`` on a dome table, with the turbidity and the scale (zenith_luminance,
    reference_elevation) of ``sky``: a :class:`natscene.sky.daylight.Skylight` or a validated sky block
    (:func:`natscene.sky.daylight.skylight`); the dome keeps the model's colour down to 0.5 deg of elevation."""
    from natscene.sky.daylight import preetham_rgb, skylight
    s = skylight(sky)
    d = cell_directions(n_theta, n_phi)
    rgb = preetham_rgb(d.reshape(-1, 3), sun_dir, s.turbidity, s.zenith_luminance, s.reference_elevation,
                       min_view_elevation=0.5).reshape(n_theta, n_phi, 3)
    return Dome(rgb.astype(np.float64), np.asarray(ground, np.float64).reshape(3))


def uniform_dome(radiance: float = 1.0, n_theta: int = 8, n_phi: int = 16) -> Dome:
    """Radiance ``radiance`` from every direction (the white furnace)."""
    return Dome(np.full((n_theta, n_phi, 3), float(radiance)), np.full(3, float(radiance)))


def irradiance(dome: Dome) -> np.ndarray:
    """Horizontal irradiance (3,) of the upper hemisphere, ∫ L cos(zenith) dω."""
    mu = cell_directions(*dome.rgb.shape[:2])[..., 1]
    return (dome.rgb * mu[..., None]).sum((0, 1)) * dome.cell_solid_angle


def ground_radiance(albedo, sun_irradiance, sky_irradiance) -> np.ndarray:
    """Radiance (3,) of a Lambertian ground of ``albedo`` under the sun's and the sky's horizontal irradiance."""
    return np.asarray(albedo, np.float64) / np.pi * (np.asarray(sun_irradiance, np.float64)
                                                    + np.asarray(sky_irradiance, np.float64))


def calibration(photo_sky_mean, dome_view_mean) -> np.ndarray:
    """Per-channel factors (3,) that give the dome the photo's mean sky radiance in the view.

    ``photo_sky_mean``: mean linear RGB of the photo's L_sky; ``dome_view_mean``: mean of the dome's radiance
    over the same view's pixel directions (recorded by the precompute)."""
    p = np.asarray(photo_sky_mean, np.float64).reshape(3)
    d = np.asarray(dome_view_mean, np.float64).reshape(3)
    return np.where(d > 0, p / np.maximum(d, 1e-30), 0.0)
