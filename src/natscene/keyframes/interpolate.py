"""
Interpolation between keyframes
===============================

Defines the interpolation between keyframes (Dobashi et al. 2012, §5.2, §6: "the parameters are then
interpolated to render the clouds between the key frames"; Fig. 13: "the parameters for the in-between images are
linearly interpolated"):

-   :func:`lerp`, :func:`slerp`, :func:`catmull_rom`: linear, spherical linear and Catmull-Rom interpolation.
-   :func:`ease` (:data:`EASINGS`), :func:`segment_t`: the eased position of a frame in its segment.
-   :func:`direction_to_sun_angles`: the sun's azimuth and elevation of a direction.

- scalars (L_in, g, extinction, beta, L_amb) and colours (c_in, kappa_a per channel): linear, as in the paper;
- the sun direction: spherical linear interpolation (slerp) of the unit vectors toward the sun, so it stays
  unit length and sweeps the great circle between the two keyframes at constant angular speed;
- the camera position / look-at point / field of view: linear (default) or a non-uniform Catmull-Rom spline
  through the keyframes (knots = the keyframes' frame indices; Catmull & Rom 1974 in the Barry-Goldman
  pyramidal form), which passes through every keyframe with a continuous velocity;
- easing of the segment parameter t in [0, 1]: ``linear`` (none, the paper), ``smoothstep`` (3t^2 - 2t^3)
  or ``sine`` ((1 - cos(pi t)) / 2): both ease in and out, so the motion stops at each keyframe.

References
----------
-   Barry, P. J., & Goldman, R. N. (1988). A recursive evaluation algorithm for a class of Catmull-Rom splines.
    SIGGRAPH '88, 199–204.
-   Catmull, E., & Rom, R. (1974). A class of local interpolating splines. In Computer Aided Geometric Design,
    317–326. Academic Press.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

__all__ = ["EASINGS", "ease", "segment_t", "lerp", "slerp", "direction_to_sun_angles", "catmull_rom"]

EASINGS = ("linear", "smoothstep", "sine")


def ease(t, kind: str = "linear"):
    """The eased segment parameter: maps [0, 1] onto [0, 1] monotonically, ease(0) = 0, ease(1) = 1."""
    t = np.clip(np.asarray(t, np.float64), 0.0, 1.0)
    if kind == "linear":
        return t
    if kind == "smoothstep":
        return t * t * (3.0 - 2.0 * t)
    if kind == "sine":
        return 0.5 - 0.5 * np.cos(np.pi * t)
    raise ValueError(f"unknown easing {kind!r}; one of {EASINGS}")


def segment_t(frame: float, at0: float, at1: float) -> float:
    """Position of ``frame`` in the segment [at0, at1] as t in [0, 1] (clamped; 0 for a zero-length segment)."""
    if at1 == at0:
        return 0.0
    return float(np.clip((frame - at0) / (at1 - at0), 0.0, 1.0))


def lerp(a, b, t):
    """(1 - t) a + t b, element-wise (scalars, colours, positions). Exact at t = 0 and t = 1."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    if t == 0:
        return a.copy()
    if t == 1:
        return b.copy()
    return (1.0 - t) * a + t * b


def slerp(u, v, t):
    """Spherical linear interpolation of two directions (normalised first); ``t`` scalar or array.

    Returns unit vectors on the shorter great-circle arc, at angle t * angle(u, v) from u. Antipodal
    directions have no unique arc: ValueError.
    """
    u = np.asarray(u, np.float64)
    v = np.asarray(v, np.float64)
    u = u / np.linalg.norm(u)
    v = v / np.linalg.norm(v)
    t = np.asarray(t, np.float64)
    cos_o = float(np.clip(np.dot(u, v), -1.0, 1.0))
    omega = np.arccos(cos_o)
    if cos_o < -1 + 1e-9:
        raise ValueError("slerp: opposite directions have no unique great circle between them")
    if omega < 1e-9:
        out = np.broadcast_to(u, t.shape + (3,)).copy()
    else:
        s = np.sin(omega)
        w0 = np.sin((1.0 - t) * omega) / s
        w1 = np.sin(t * omega) / s
        out = w0[..., None] * u + w1[..., None] * v
        out = out / np.linalg.norm(out, axis=-1, keepdims=True)
    # exact endpoints
    out = np.where(np.asarray(t)[..., None] == 0, u, out)
    out = np.where(np.asarray(t)[..., None] == 1, v, out)
    return out


def direction_to_sun_angles(d) -> tuple[float, float]:
    """(azimuth, elevation) in degrees of a unit vector toward the sun (inverse of geometry.sun_direction)."""
    d = np.asarray(d, np.float64)
    d = d / np.linalg.norm(d)
    el = np.degrees(np.arcsin(np.clip(d[1], -1.0, 1.0)))
    az = np.degrees(np.arctan2(d[0], d[2])) % 360.0
    return float(az), float(el)


def catmull_rom(points, knots, x):
    """Non-uniform Catmull-Rom spline through ``points`` (n, d) at parameter values ``knots`` (n, increasing),
    evaluated at ``x`` (within [knots[0], knots[-1]]).

    Barry & Goldman's pyramidal formulation on the segment [knots[i], knots[i+1]] containing x, with the
    missing end neighbours reflected (P_{-1} = 2 P_0 - P_1, knot t_{-1} = 2 t_0 - t_1). Interpolating:
    x = knots[i] gives points[i] exactly. Two points: the straight line.
    """
    P = np.asarray(points, np.float64)
    k = np.asarray(knots, np.float64)
    n = len(P)
    if n != len(k):
        raise ValueError("catmull_rom: as many knots as points are needed")
    if n == 1:
        return P[0].copy()
    if np.any(np.diff(k) <= 0):
        raise ValueError("catmull_rom: knots must increase strictly")
    x = float(np.clip(x, k[0], k[-1]))
    hit = np.nonzero(k == x)[0]
    if hit.size:
        return P[hit[0]].copy()
    i = int(np.searchsorted(k, x) - 1)
    P_ext = np.concatenate([[2 * P[0] - P[1]], P, [2 * P[-1] - P[-2]]])
    k_ext = np.concatenate([[2 * k[0] - k[1]], k, [2 * k[-1] - k[-2]]])
    p0, p1, p2, p3 = P_ext[i:i + 4]
    t0, t1, t2, t3 = k_ext[i:i + 4]
    a1 = (t1 - x) / (t1 - t0) * p0 + (x - t0) / (t1 - t0) * p1
    a2 = (t2 - x) / (t2 - t1) * p1 + (x - t1) / (t2 - t1) * p2
    a3 = (t3 - x) / (t3 - t2) * p2 + (x - t2) / (t3 - t2) * p3
    b1 = (t2 - x) / (t2 - t0) * a1 + (x - t0) / (t2 - t0) * a2
    b2 = (t3 - x) / (t3 - t1) * a2 + (x - t1) / (t3 - t1) * a3
    return (t2 - x) / (t2 - t1) * b1 + (x - t1) / (t2 - t1) * b2
