"""
Daylight sky
============

Defines the analytic daylight sky of Preetham, Shirley & Smits (1999) and a shot's sky:

-   :func:`zenith_Yxy`: the zenith luminance and chromaticity for a sun zenith angle.
-   :func:`preetham_Yxy`: the absolute sky (Y, x, y) toward view directions.
-   :func:`preetham_rgb`: the scaled sky in linear sRGB (:func:`sky_scale`: the scale).
-   :func:`skylight`: a sky block of the config as a :class:`Skylight`.
-   :func:`shot_sky_radiance`: a shot's sky (this model or a constant colour) toward any directions.

The Perez et al. (1993) all-weather distribution

    F(theta, gamma) = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma)

for each of Y, x, y, with the turbidity-dependent coefficients A..E, the zenith luminance
Y_z = (4.0453 T - 4.9710) tan chi - 0.2155 T + 2.4192, chi = (4/9 - T/120)(pi - 2 theta_s), and the
zenith chromaticities x_z, y_z (cubic in theta_s, quadratic in T) of the paper's appendix; then
Y(theta, gamma) = Y_z F(theta, gamma) / F(0, theta_s) (same for x, y), Yxy -> XYZ -> linear sRGB.
theta is the zenith angle of the view direction, gamma its angle to the sun, theta_s the sun's zenith angle.

Scale: one constant, so that the zenith luminance at ``reference_elevation`` of the sun equals
``zenith_luminance`` (photo-relative linear units, like the fitted L_sky); the sky therefore darkens and
reddens by itself as the sun sets. The model is defined for the sun at or above the horizon and view
directions above it: sun elevations are clamped to >= 0 and view elevations to >= ``min_view_elevation``
(the horizon's colour continues below it).

:func:`shot_sky_radiance` is a shot's sky (config ``shots.<name>.sky``: this model, or a constant colour) toward
any directions: the one place that reads those settings, used for the sky behind shot frames
(:func:`natscene.keyframes.sky.sky_image`) and the sky that lights a composite's set
(:func:`natscene.composite.sky_dome.shot_sky`). The sky dome that lights the clouds in the transport
(:mod:`natscene.scatter.skylight`) uses :func:`preetham_rgb` too.

References
----------
-   Perez, R., Seals, R., & Michalsky, J. (1993). All-weather model for sky luminance distribution—preliminary
    configuration and validation. Solar Energy, 50(3), 235–245.
-   Preetham, A. J., Shirley, P., & Smits, B. (1999). A practical analytic model for daylight. Proceedings of
    ACM SIGGRAPH 1999, 91–100.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from natscene.color import xyz_to_linear_srgb

__all__ = ["zenith_Yxy", "preetham_Yxy", "sky_scale", "preetham_rgb", "Skylight", "skylight", "shot_sky_radiance"]

# Perez coefficients as linear functions of turbidity: rows A..E, columns (slope, intercept) (Preetham App. A.2)
_COEF_Y = np.array([[0.1787, -1.4630], [-0.3554, 0.4275], [-0.0227, 5.3251], [0.1206, -2.5771],
                    [-0.0670, 0.3703]])
_COEF_x = np.array([[-0.0193, -0.2592], [-0.0665, 0.0008], [-0.0004, 0.2125], [-0.0641, -0.8989],
                    [-0.0033, 0.0452]])
_COEF_y = np.array([[-0.0167, -0.2608], [-0.0950, 0.0092], [-0.0079, 0.2102], [-0.0441, -1.6537],
                    [-0.0109, 0.0529]])
# zenith chromaticity: [T^2, T, 1] x [theta^3, theta^2, theta, 1] (Preetham App. A.2)
_ZEN_x = np.array([[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394],
                   [0.11693, -0.21196, 0.06052, 0.25886]])
_ZEN_y = np.array([[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516],
                   [0.15346, -0.26756, 0.06670, 0.26688]])


def _perez(theta, gamma, coef):
    A, B, C, D, E = coef
    return (1.0 + A * np.exp(B / np.cos(theta))) * (1.0 + C * np.exp(D * gamma) + E * np.cos(gamma) ** 2)


def zenith_Yxy(theta_s: float, turbidity: float) -> tuple[float, float, float]:
    """Preetham's zenith luminance (kcd/m^2) and chromaticity for sun zenith angle theta_s (radians)."""
    T = float(turbidity)
    chi = (4.0 / 9.0 - T / 120.0) * (np.pi - 2.0 * theta_s)
    Yz = (4.0453 * T - 4.9710) * np.tan(chi) - 0.2155 * T + 2.4192
    tv = np.array([T * T, T, 1.0])
    th = np.array([theta_s ** 3, theta_s ** 2, theta_s, 1.0])
    return float(Yz), float(tv @ _ZEN_x @ th), float(tv @ _ZEN_y @ th)


def _coefs(turbidity):
    T = float(turbidity)
    return [c[:, 0] * T + c[:, 1] for c in (_COEF_Y, _COEF_x, _COEF_y)]


def preetham_Yxy(dirs, sun_dir, turbidity: float, min_view_elevation: float):
    """Absolute Preetham sky (Y in kcd/m^2, x, y) for unit view directions ``dirs`` (..., 3), y up."""
    if not 1.7 <= turbidity <= 10.0:
        raise ValueError(f"turbidity {turbidity} outside the model's range [1.7, 10]")
    d = np.asarray(dirs, np.float64)
    s = np.asarray(sun_dir, np.float64)
    s = s / np.linalg.norm(s)
    if s[1] < 0:  # clamp the sun to the horizon
        s = np.array([s[0], 0.0, s[2]])
        s = s / np.linalg.norm(s) if np.linalg.norm(s) > 0 else np.array([0.0, 0.0, 1.0])
    theta_s = float(np.arccos(np.clip(s[1], -1.0, 1.0)))
    ymin = np.sin(np.radians(min_view_elevation))
    dy = np.maximum(d[..., 1], ymin)
    dh = d[..., [0, 2]] * np.sqrt((1 - dy ** 2) / np.maximum((d[..., [0, 2]] ** 2).sum(-1), 1e-20))[..., None]
    dd = np.stack([dh[..., 0], dy, dh[..., 1]], axis=-1)
    theta = np.arccos(np.clip(dy, -1.0, 1.0))
    gamma = np.arccos(np.clip(dd @ s, -1.0, 1.0))
    cY, cx, cy = _coefs(turbidity)
    Yz, xz, yz = zenith_Yxy(theta_s, turbidity)
    Y = Yz * _perez(theta, gamma, cY) / _perez(0.0, theta_s, cY)
    x = xz * _perez(theta, gamma, cx) / _perez(0.0, theta_s, cx)
    y = yz * _perez(theta, gamma, cy) / _perez(0.0, theta_s, cy)
    return Y, x, y


def sky_scale(turbidity: float, zenith_luminance: float, reference_elevation: float) -> float:
    """Constant that maps Preetham's zenith luminance at the reference sun elevation to ``zenith_luminance``."""
    Yz, _, _ = zenith_Yxy(np.radians(90.0 - reference_elevation), turbidity)
    return float(zenith_luminance) / Yz


def preetham_rgb(dirs, sun_dir, turbidity: float, zenith_luminance: float, reference_elevation: float,
                 min_view_elevation: float) -> np.ndarray:
    """Linear sRGB sky radiance (..., 3), float32, scaled by :func:`sky_scale`; negative values clipped (the
    settings of a sky block: :class:`Skylight`)."""
    Y, x, y = preetham_Yxy(dirs, sun_dir, turbidity, min_view_elevation)
    Y = Y * sky_scale(turbidity, zenith_luminance, reference_elevation)
    X = x / y * Y
    Z = (1.0 - x - y) / y * Y
    rgb = xyz_to_linear_srgb(np.stack([X, Y, Z], axis=-1))
    return np.clip(rgb, 0.0, None).astype(np.float32)


@dataclass(frozen=True)
class Skylight:
    """The settings of a sky block of the config, completed (:func:`skylight`): ``shots.<name>.sky`` (the sky
    behind a shot's frames, the dome that lights their clouds and a composite's set) and ``precompute.skylight``
    (the dome that lights the cloud in the precompute, which configures ``model`` and ``turbidity``). No field has
    a default here: they are the shots' sky schema's, ``workflow/schemas/shots.schema.yaml``
    (``tests/test_settings.py`` keeps ``precompute.skylight``'s equal to them)."""

    model: str                   # preetham or constant
    turbidity: float
    zenith_luminance: float
    reference_elevation: float
    min_view_elevation: float
    color: tuple                 # linear RGB of the constant model

    SCHEMA = (("shots.schema.yaml", ("additionalProperties", "sky")),)


def skylight(settings: dict | Skylight | None, key: str = "shots.<name>.sky") -> Skylight:
    """The one place that reads a sky block: a validated ``shots.<name>.sky`` or ``precompute.skylight`` (or a
    part of one, or None) as a :class:`Skylight`, each key it lacks the schema's default
    (:func:`natscene.config.settings_from_section`); a :class:`Skylight` is returned as it is."""
    if isinstance(settings, Skylight):
        return settings
    from natscene.config import settings_from_section
    return settings_from_section(Skylight, settings, key)


def shot_sky_radiance(settings: dict | Skylight, dirs, sun_dir) -> np.ndarray:
    """Linear sRGB radiance (..., 3), float32, of a shot's sky toward unit ``dirs`` (..., 3) for the sun toward
    ``sun_dir``; ``settings``: a validated ``shots.<name>.sky`` or its :class:`Skylight` (``model: preetham``:
    :func:`preetham_rgb` with its turbidity, zenith_luminance, reference_elevation, min_view_elevation;
    ``model: constant``: ``color``)."""
    s = skylight(settings)
    if s.model == "preetham":
        return preetham_rgb(dirs, sun_dir, s.turbidity, s.zenith_luminance, s.reference_elevation,
                            s.min_view_elevation)
    if s.model == "constant":
        c = np.asarray(s.color, np.float32)
        return np.broadcast_to(c, np.shape(dirs)[:-1] + (3,)).copy()
    raise ValueError(f"unknown sky model {s.model!r}")


