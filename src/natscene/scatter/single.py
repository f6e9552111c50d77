"""
Single scattering by ray marching
=================================

Defines the ray-marched single scattering, ambient term and view transmittance (Dobashi et al. 2012, §4.3,
Eqs. 5 and 9):

-   :func:`march_view`: S_sun, S_amb, T for every view ray and every sigma_t of a grid, the distance to the cloud
    and the footprint.
-   :func:`one_minus_exp`: 1 - exp(-x), accurate in float32 for small x.

For every view ray and every sigma_t of a grid, in ONE march (mu_t = sigma_t · k · rho, k the volume's
``extinction_scale``; O(t) = ∫_0^t rho; D(x) the sun optical depth of :mod:`natscene.scatter.medium`):

- S_sun(q, sigma_t) = ∫ sigma_t k rho(x) tau(x_l, x) tau(x_v, x) dt, with tau(x_l, x) = exp(-sigma_t k D(x)),
- S_amb(q, sigma_t) = ∫ rho(x) tau(x_v, x) dt / L, L the longest side of the volume's box (the ambient term is
  dimensionless: Dobashi's L_amb keeps its meaning for a cloud of any size in metres),
- T(q, sigma_t) = tau(x_v, x_b) = exp(-sigma_t k O(T)) (Eq. 9),

integrated segment by segment exactly for a density that is constant over a step (midpoint value) and a sun
optical depth linear between the step's ends (:func:`sun_segment`): a segment of length h and density rho_i
contributes T_prev ∫_0^1 a e^(-a s) tau_sun(s) ds to S_sun and T_prev (1 - e^-a) / (sigma_t k) to S_amb,
a = sigma_t k rho_i h (limit rho_i h at sigma_t = 0). Constant media are therefore integrated without
discretisation error. The sun's transmittance taken at the step's midpoint instead (T_prev (1 - e^-a) tau_sun)
is exact only where it is constant along the step, not in a thick cloud's lit skin (docs/stages/precompute.md,
"Single scattering and transmittance"). Also returned: the distance to the cloud
(first sample with rho >= ``rho_threshold``) and the footprint (the ray meets such a sample).

A step in an empty cell of the volume's majorant grid adds nothing (rho = 0 there, and a = 0), so the march
passes over the steps within the cell's safe jump (:meth:`natscene.scatter.majorant.MajorantGrid.empty_jump`):
the same sample points, the same images. The step it lands on is within the jump, empty too, so the sun depth
carried to its start (that of the step before the jump) meets a = 0 and is never used; its end is read afresh.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

from natscene.scatter.medium import Medium, ray_box_dr
from natscene.scatter.rays import camera_rays, pixel_means

__all__ = ["march_view", "one_minus_exp", "sun_segment"]


def one_minus_exp(x):
    """1 - exp(-x) accurate in float32 also for small x (series below 1e-2)."""
    return dr.select(x < 1e-2, x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0))), 1.0 - dr.exp(-x))


def sun_segment(a, x_in, x_out):
    """∫_0^1 a exp(-a s) exp(-(x_in + (x_out - x_in) s)) ds: a view segment of optical thickness ``a`` (its
    density constant) whose sun optical depth runs linearly from ``x_in`` to ``x_out``, in closed form,
    (e^-x_in - e^-(x_out + a)) a / (a + x_out - x_in), its limit a e^-x_in at a + x_out - x_in = 0 (series
    below 1e-3)."""
    x = a + x_out - x_in
    small = dr.abs(x) < 1e-3
    exact = (dr.exp(-x_in) - dr.exp(-(x_out + a))) * a / dr.select(small, 1.0, x)
    return dr.select(small, a * dr.exp(-x_in) * (1.0 - 0.5 * x), exact)


@dr.syntax
def _march(med: Medium, o, d, sigmas, step, rho_threshold, with_sun: bool, grid=None):
    k = med.scale
    t0, t1 = ray_box_dr(o, d, med.bbox_min, med.bbox_max)
    length = dr.maximum(t1 - t0, 0.0)
    n = dr.select(length > 0, dr.maximum(dr.ceil(length / step), 1.0), 0.0)
    h = dr.select(n > 0, length / dr.maximum(n, 1.0), 0.0)
    depth = mi.Float(0.0)
    t_hit = mi.Float(-1.0)
    s_sun = [dr.zeros(mi.Float, dr.width(o)) for _ in sigmas]
    s_amb = [dr.zeros(mi.Float, dr.width(o)) for _ in sigmas]
    d_in = mi.Float(0.0)                  # the sun depth where the segment begins
    eps = 1e-3 * h                        # the ends just inside the box: on a face, the sun ray's box test is 0 * inf
    if with_sun:
        d_in = med.sun_depth(o + d * (t0 + eps))
    i = mi.Float(0.0)
    while i < n:
        t = t0 + (i + 0.5) * h
        p = o + d * t
        r = med.rho(p)
        if with_sun:
            d_out = med.sun_depth(o + d * dr.minimum(t0 + (i + 1.0) * h, t1 - eps))
        else:
            d_out = mi.Float(0.0)
        for j in range(len(sigmas)):
            sig = sigmas[j]
            if sig > 0:
                tv = dr.exp(-sig * k * depth)
                a = sig * k * r * h
                one_minus_a = one_minus_exp(a)
                s_sun[j] += tv * sun_segment(a, sig * k * d_in, sig * k * d_out)
                s_amb[j] += tv * one_minus_a / (sig * k)
            else:
                s_amb[j] += r * h
        t_hit = dr.select((t_hit < 0) & (r >= rho_threshold), t0 + i * h, t_hit)
        depth += r * h
        d_in = d_out
        if grid is not None:  # in an empty cell every step within its safe jump adds nothing
            i += grid.empty_steps(p, h)
        else:
            i += 1.0
    return depth, t_hit, s_sun, s_amb


def march_view(med: Medium, camera, sigmas, step_voxels: float = 0.5, supersample: int = 4,
               rho_threshold: float = 0.01, skip_empty: bool = True) -> dict:
    """S_sun, S_amb, T (Ns, H, W), the distance to the cloud t_hit (H, W; NaN: no cloud) and the footprint.

    ``supersample``: stratified sub-pixel rays per pixel (a square); the pixel value is their mean (box
    filter). ``t_hit`` is taken at the pixel centre ray's resolution (mean of the sub-rays that hit).
    ``skip_empty``: pass over the empty cells of the volume's majorant grid (the same images; False: every step).
    """
    from natscene.scatter.majorant import majorant_grid
    sigmas = [float(s) for s in sigmas]
    v = med.volume
    grid = majorant_grid(v.density, v.bbox_min, v.bbox_max) if skip_empty else None
    W, H = camera.width, camera.height
    o, d, _ = camera_rays(camera, supersample, stratified=supersample > 1)
    depth, t_hit, s_sun, s_amb = _march(med, o, d, sigmas, med.voxel * step_voxels, float(rho_threshold),
                                        med.sun_depth_tex is not None, grid)
    ns = len(sigmas)
    hit = t_hit >= 0
    means = pixel_means([dr.exp(-s * med.scale * depth) for s in sigmas] + list(s_sun) + list(s_amb)
                        + [mi.Float(hit), dr.select(hit, t_hit, 0.0)], supersample, W, H)
    T, S_sun = means[:ns], means[ns:2 * ns]
    S_amb = means[2 * ns:3 * ns] / float(np.max(med.bbox_max - med.bbox_min))
    n_hit, t_sum = means[3 * ns], means[3 * ns + 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        t_c = np.where(n_hit > 0, t_sum / np.maximum(n_hit, 1e-12), np.nan).astype(np.float32)
    return {"S_sun": S_sun, "S_amb": S_amb, "T": T,
            "t_hit": t_c, "footprint": (n_hit > 0).astype(np.float32)}
