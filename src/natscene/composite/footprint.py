"""Texture footprints from ray differentials (Igehy 1999, "Tracing ray differentials"; the form of PBRT's
``SurfaceInteraction::ComputeDifferentials``).

A camera sample has two neighbour rays, one sample spacing to the right and one down. Where the main ray hits
a surface at p with normal n, the neighbours are intersected with the tangent plane,
p' = o + d'·((p − o)·n / (d'·n)), giving ∂p/∂x = p'_x − p and ∂p/∂y = p'_y − p. With the surface's
parametrisation ∂p/∂u, ∂p/∂v, the texture-space derivatives are the least-squares solution of
∂p/∂x = ∂p/∂u·∂u/∂x + ∂p/∂v·∂v/∂x (normal equations, 2×2), likewise for y.
"""
from __future__ import annotations

import numpy as np


def tangent_plane_offsets(origin: np.ndarray, p: np.ndarray, n: np.ndarray, d_offset: np.ndarray) -> np.ndarray:
    """∂p for a neighbour ray (origin, direction ``d_offset``) against the tangent plane (p, n), (M, 3)."""
    o = np.asarray(origin, np.float64)
    num = np.einsum("ij,ij->i", p - o, n)
    den = np.einsum("ij,ij->i", d_offset, n)
    ok = np.abs(den) > 1e-12
    t = np.where(ok, num / np.where(ok, den, 1.0), 0.0)
    dp = o + d_offset * t[:, None] - p
    dp[~ok] = 0.0
    return dp


def uv_derivatives(dp: np.ndarray, dp_du: np.ndarray, dp_dv: np.ndarray) -> np.ndarray:
    """(∂u, ∂v) (M, 2) of a position offset ``dp`` (M, 3) on a surface with tangents ∂p/∂u, ∂p/∂v (M, 3)."""
    a = np.einsum("ij,ij->i", dp_du, dp_du)
    b = np.einsum("ij,ij->i", dp_du, dp_dv)
    c = np.einsum("ij,ij->i", dp_dv, dp_dv)
    r0 = np.einsum("ij,ij->i", dp_du, dp)
    r1 = np.einsum("ij,ij->i", dp_dv, dp)
    det = a * c - b * b
    ok = np.abs(det) > 1e-30 * np.maximum(a * c, 1e-300)
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    return np.stack([(c * r0 - b * r1) * inv, (a * r1 - b * r0) * inv], -1)


def texture_derivatives(origin, p, n, dx_dir, dy_dir, dp_du, dp_dv) -> tuple[np.ndarray, np.ndarray]:
    """(∂uv/∂x, ∂uv/∂y), each (M, 2), for hits (p, n) of rays from ``origin`` whose neighbours have directions
    ``dx_dir``, ``dy_dir`` (M, 3)."""
    p = np.asarray(p, np.float64)
    n = np.asarray(n, np.float64)
    dpx = tangent_plane_offsets(origin, p, n, np.asarray(dx_dir, np.float64))
    dpy = tangent_plane_offsets(origin, p, n, np.asarray(dy_dir, np.float64))
    du = np.asarray(dp_du, np.float64)
    dv = np.asarray(dp_dv, np.float64)
    return uv_derivatives(dpx, du, dv), uv_derivatives(dpy, du, dv)
