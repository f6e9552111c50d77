"""
Texture footprints from ray differentials
=========================================

Defines texture footprints from ray differentials (Igehy 1999, "Tracing ray differentials"; the form of PBRT's
``SurfaceInteraction::ComputeDifferentials``), as Dr.Jit expressions (Array3f64 / Float64 in, unevaluated):

-   :func:`texture_derivative`: the (u, v) derivative across one sample spacing toward a neighbour ray.
-   :func:`tangent_plane_offsets`: a neighbour ray's offset on the tangent plane.
-   :func:`uv_derivatives`: the (u, v) derivatives of a position offset on a surface.

A camera sample has two neighbour rays, one sample spacing to the right and one down. Where the main ray hits
a surface at p with normal n, the neighbours are intersected with the tangent plane,
p' = o + d'·((p − o)·n / (d'·n)), giving ∂p/∂x = p'_x − p and ∂p/∂y = p'_y − p. With the surface's
parametrisation ∂p/∂u, ∂p/∂v, the texture-space derivatives are the least-squares solution of
∂p/∂x = ∂p/∂u·∂u/∂x + ∂p/∂v·∂v/∂x (normal equations, 2×2), likewise for y.

References
----------
-   Igehy, H. (1999). Tracing ray differentials. SIGGRAPH '99, 179–186.
-   Pharr, M., Jakob, W., & Humphreys, G. (2016). Physically Based Rendering: From Theory to Implementation
    (3rd ed.). Morgan Kaufmann.
"""
from __future__ import annotations

from natscene.composite.vectors import dot

__all__ = ["tangent_plane_offsets", "uv_derivatives", "texture_derivative"]


def tangent_plane_offsets(o, p, n, d_offset):
    """∂p for a neighbour ray (origin ``o``, direction ``d_offset``) against the tangent plane (p, n); zero
    where the neighbour runs parallel to the plane."""
    import drjit as dr
    num = dot(p - o, n)
    den = dot(d_offset, n)
    ok = dr.abs(den) > 1e-12
    t = dr.select(ok, num / dr.select(ok, den, 1.0), 0.0)
    return dr.select(ok, o + d_offset * t - p, 0.0)


def uv_derivatives(dp, dp_du, dp_dv):
    """(∂u, ∂v) (Array2f64) of a position offset ``dp`` on a surface with tangents ∂p/∂u, ∂p/∂v (zero where
    the tangents are degenerate)."""
    import drjit as dr
    import mitsuba as mi
    a, b, c = dot(dp_du, dp_du), dot(dp_du, dp_dv), dot(dp_dv, dp_dv)
    r0, r1 = dot(dp_du, dp), dot(dp_dv, dp)
    det = a * c - b * b
    ok = dr.abs(det) > 1e-30 * dr.maximum(a * c, 1e-300)
    inv = dr.select(ok, 1.0 / dr.select(ok, det, 1.0), 0.0)
    return mi.Array2f64((c * r0 - b * r1) * inv, (a * r1 - b * r0) * inv)


def texture_derivative(o, p, n, d_offset, dp_du, dp_dv):
    """∂uv (Array2f64) across one sample spacing toward the neighbour direction ``d_offset`` for hits (p, n)
    of rays from ``o``."""
    return uv_derivatives(tangent_plane_offsets(o, p, n, d_offset), dp_du, dp_dv)
