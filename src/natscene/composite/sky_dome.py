"""
Sky dome of the set
===================

Defines the sky dome that lights the set: the frame's sky radiance toward any direction, and the irradiance it
gives a surface of any orientation:

-   :class:`SkyDome`: the sky radiance above the horizon, the ground's bounce below it, and the SH9 irradiance of
    both.
-   :func:`shot_sky`, :func:`gradient_sky`: the radiance function of a shot's sky or of a gradient.
-   :func:`sh9`, :func:`sphere_quadrature`: the nine spherical harmonics and the quadrature over the sphere.
-   :func:`lookup_table`: a bilinear lookup of a latitude-longitude table.

Radiance. With a shot, the sky is the one behind the clouds of the frame
(:func:`natscene.sky.daylight.shot_sky_radiance`: Preetham et al. 1999 following the frame's sun, or the shot's
constant colour), so the set, the haze over
the ground and the plate agree; without one, a zenith-to-horizon blend in sqrt(max(y, 0)). Below the
horizon a set on an infinite ground sees the ground: its radiance is the ground's mean albedo ρ̄ times its
irradiance over π, L_g = ρ̄/π · (E_sun·sin(elevation) + E_sky(up)) (one bounce).

Irradiance (Ramamoorthi & Hanrahan 2001, "An efficient representation for irradiance environment maps"):
the radiance is projected on the nine real spherical harmonics of order ≤ 2, L_lm = ∫ L(ω) Y_lm(ω) dω
(a 64×128 latitude-longitude quadrature), and E(n) = Σ Â_l L_lm Y_lm(n) with Â₀ = π, Â₁ = 2π/3, Â₂ = π/4.

References
----------
-   Preetham, A. J., Shirley, P., & Smits, B. (1999). A practical analytic model for daylight. SIGGRAPH '99,
    91–100.
-   Ramamoorthi, R., & Hanrahan, P. (2001). An efficient representation for irradiance environment maps.
    SIGGRAPH '01, 497–500.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

__all__ = ["sh9", "sphere_quadrature", "gradient_sky", "shot_sky", "SkyDome", "lookup_table"]

_A_HAT = np.array([np.pi] + [2 * np.pi / 3] * 3 + [np.pi / 4] * 5)


def sh9(dirs: np.ndarray) -> np.ndarray:
    """The nine real spherical harmonics (order <= 2) at unit directions (M, 3) -> (M, 9), in their dtype."""
    x, y, z = dirs[:, 0], dirs[:, 1], dirs[:, 2]
    c = [dirs.dtype.type(v) for v in (0.282095, 0.488603, 1.092548, 0.315392, 0.546274, 3.0, 1.0)]
    return np.stack([np.full_like(x, c[0]), c[1] * y, c[1] * z, c[1] * x, c[2] * x * y, c[2] * y * z,
                     c[3] * (c[5] * z * z - c[6]), c[2] * x * z, c[4] * (x * x - y * y)], -1)


def sphere_quadrature(n_theta: int = 64, n_phi: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Directions (K, 3) and solid-angle weights (K,) of a midpoint latitude-longitude grid (y up)."""
    th = (np.arange(n_theta) + 0.5) * np.pi / n_theta
    ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    T, P = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(T) * np.sin(P), np.cos(T), np.sin(T) * np.cos(P)], -1).reshape(-1, 3)
    w = (np.sin(T) * (np.pi / n_theta) * (2 * np.pi / n_phi)).reshape(-1)
    return d, w


def gradient_sky(zenith, horizon) -> Callable[[np.ndarray], np.ndarray]:
    """Radiance function of a zenith-to-horizon blend in sqrt(max(y, 0)) (the horizon colour below it)."""
    z, h = np.asarray(zenith, np.float32), np.asarray(horizon, np.float32)

    def radiance(dirs):
        t = np.sqrt(np.clip(np.asarray(dirs)[:, 1], 0.0, 1.0)).astype(np.float32)[:, None]
        return h[None] * (1 - t) + z[None] * t
    return radiance


def shot_sky(settings: dict | None, sun_dir) -> Callable[[np.ndarray], np.ndarray]:
    """Radiance function of a shot's sky (a validated ``shots.<name>.sky``) for the frame's sun: the sky the
    frame's clouds were rendered in front of (:func:`natscene.sky.daylight.shot_sky_radiance`)."""
    from natscene.sky.daylight import shot_sky_radiance, skylight
    sky = skylight(settings)
    if sky.model not in ("preetham", "constant"):
        raise ValueError(f"unknown sky model {sky.model!r}")
    s = np.asarray(sun_dir, np.float64)
    return lambda dirs: shot_sky_radiance(sky, np.asarray(dirs, np.float64), s)


class SkyDome:
    """Sky radiance above the horizon, the ground's bounce below it, and the SH9 irradiance of both.

    ``radiance`` looks the sky up in a latitude-longitude table of ``table`` (rows, columns) built once
    (bilinear; 0.5° steps by default, finer than the sky models' features), so that per-sample haze and mirror
    rays cost a table lookup instead of the model's exponentials."""

    def __init__(self, sky: Callable[[np.ndarray], np.ndarray], sun_dir, sun_rgb, ground_albedo,
                 quadrature=(64, 128), table=(361, 720)):
        self.sky = sky
        nr, nc = table
        el = np.linspace(-np.pi / 2, np.pi / 2, nr)
        az = np.linspace(-np.pi, np.pi, nc)
        E, A = np.meshgrid(el, az, indexing="ij")
        dt = np.stack([np.cos(E) * np.sin(A), np.sin(E), np.cos(E) * np.cos(A)], -1).reshape(-1, 3)
        self._table = np.asarray(sky(dt), np.float32).reshape(nr, nc, 3)
        d, w = sphere_quadrature(*quadrature)
        Y = sh9(d)
        up = d[:, 1] > 0
        L = np.zeros((d.shape[0], 3))
        L[up] = np.asarray(sky(d[up]), np.float64)
        coef_sky = (Y * w[:, None]).T @ L  # (9, 3)
        self.zenith_irradiance = self._eval(coef_sky, np.array([[0.0, 1.0, 0.0]]))[0]
        s = np.asarray(sun_dir, np.float64)
        sun_h = np.asarray(sun_rgb, np.float64) * max(float(s[1]) / np.linalg.norm(s), 0.0)
        self.ground_radiance = np.asarray(ground_albedo, np.float64) / np.pi * (sun_h + self.zenith_irradiance)
        Lg = np.zeros_like(L)
        Lg[~up] = self.ground_radiance
        self.coef = coef_sky + (Y * w[:, None]).T @ Lg

    @staticmethod
    def _eval(coef, normals):
        return (sh9(np.asarray(normals, np.float64)) * _A_HAT[None]) @ coef

    def irradiance(self, normals: np.ndarray) -> np.ndarray:
        """Irradiance (M, 3) of surfaces with unit ``normals`` (M, 3) from sky and ground (no sun), clipped >= 0."""
        n = np.asarray(normals, np.float32)
        return np.maximum(sh9(n) @ (_A_HAT[:, None] * self.coef).astype(np.float32), 0.0)

    def radiance(self, dirs: np.ndarray) -> np.ndarray:
        """Sky radiance toward unit ``dirs`` (M, 3) (the model's horizon colour continues below it), from the
        table."""
        return lookup_table(self._table, dirs)


def lookup_table(table: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Bilinear lookup (M, C) of a latitude-longitude table (rows: elevation -90..90°, columns: azimuth
    -180..180° from +z toward +x) toward unit ``dirs`` (M, 3)."""
    d = np.asarray(dirs, np.float32)
    nr, nc = table.shape[:2]
    y = (np.arcsin(np.clip(d[:, 1], -1, 1)) / np.float32(np.pi) + np.float32(0.5)) * (nr - 1)
    x = (np.arctan2(d[:, 0], d[:, 2]) / np.float32(2 * np.pi) + np.float32(0.5)) * (nc - 1)
    y0 = np.clip(np.floor(y).astype(np.int64), 0, nr - 2)
    x0 = np.clip(np.floor(x).astype(np.int64), 0, nc - 2)
    fy = (y - y0)[:, None]
    fx = (x - x0)[:, None]
    top = table[y0, x0] * (1 - fx) + table[y0, x0 + 1] * fx
    bot = table[y0 + 1, x0] * (1 - fx) + table[y0 + 1, x0 + 1] * fx
    return (top * (1 - fy) + bot * fy).astype(np.float32)
