"""The skylight's first order toward the camera by paths from the camera (an experiment for issue 39).

The sky's order-1 band of a precompute node is the image

    I_1(pixel) = ∫ T_cam(s) mu_t(x_s) ∫ p(w_in · w_cam, g) L_dome(-w_in) T(x_s, -w_in) dw_in ds

(the albedo left to the band's closed-form weight, as every band). The photons of the sky source reach it only when
a dome direction behind the cloud happens to be sampled; at g 0.9 the phase function's peak is about ±5° wide and
the pixel's variance is mostly this band (docs/stages/precompute.md, "Effort per source"). Here each sample of a
pixel follows its camera ray by delta tracking (majorant grid, :func:`natscene.scatter.majorant.flight_event`) to
a real collision x (density T_cam mu_t ds: the outer integral), draws the incoming direction from a mixture of the
HG lobes of every g node around the direction to the camera, and follows a shadow ray toward the source by delta
tracking (escape probability T): one path serves every g node with the weight p(g_j) / q. The radiance of the
dome and the unit ground come from :class:`natscene.scatter.photons.SkySource` (its four channels).
"""
from __future__ import annotations

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

from natscene.scatter.majorant import flight_event
from natscene.scatter.medium import ray_box_dr
from natscene.scatter.phase import hg_dr, hg_sample_cos_dr
from natscene.scatter.rays import camera_rays

__all__ = ["sky_order1"]


@dr.syntax
def _paths(med, grid, o, d, sig_k, gs, rng, tries: int = 1):
    """Per lane: lit (the shadow ray escaped), the direction toward the source, cos(w_in, w_cam). ``tries`` > 1: a
    camera ray that leaves the box without a collision starts again, up to ``tries`` times (a collision forced by
    rejection: its density is T_cam mu_t / (1 - T), the caller weights it by 1 - T)."""
    n = dr.width(d)
    left = mi.UInt32(tries - 1)
    p, w = mi.Point3f(o), mi.Vector3f(d)
    to_cam = -mi.Vector3f(d)
    t_in, t_out = ray_box_dr(p, w, med.bbox_min, med.bbox_max)
    t, t1 = mi.Float(t_in), mi.Float(t_out)
    flying = t_out > t_in
    restart = mi.Bool(flying)
    tau = -dr.log(1.0 - rng.next_float32())
    shadow = mi.Bool(False)
    lit = mi.Bool(False)
    cos_t = mi.Float(0.0)
    ix, iy, iz = mi.Int32(0), mi.Int32(0), mi.Int32(0)
    tmx, tmy, tmz = mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)
    ng = len(gs)
    while dr.hint(flying, include=[rng]):
        t, tau, cells, x, ratio, inside, accept, escaped = flight_event(
            med, grid, p, w, sig_k, rng, flying, restart, t, t1, tau, (ix, iy, iz, tmx, tmy, tmz), 0.0)
        ix, iy, iz, tmx, tmy, tmz = cells
        restart = mi.Bool(False)
        # the camera ray's real collision: scatter toward the source and fly the shadow ray
        turn = accept & ~shadow
        u = rng.next_float32() * ng
        g_m = mi.Float(gs[0])
        for m in range(1, ng):
            g_m = dr.select(u >= m, gs[m], g_m)
        cos_s = hg_sample_cos_dr(rng.next_float32(), g_m)
        phi = 2.0 * dr.pi * rng.next_float32()
        sin_s = dr.safe_sqrt(1.0 - cos_s * cos_s)
        w_in = dr.normalize(mi.Frame3f(to_cam).to_world(mi.Vector3f(sin_s * dr.cos(phi), sin_s * dr.sin(phi), cos_s)))
        cos_t = dr.select(turn, cos_s, cos_t)
        p = dr.select(turn, x, p)
        w = dr.select(turn, -w_in, w)
        a, b = ray_box_dr(x, -w_in, med.bbox_min, med.bbox_max)
        t = dr.select(turn, 0.0, t)
        t1 = dr.select(turn, b, t1)
        tau = dr.select(turn, -dr.log(1.0 - rng.next_float32()), tau)
        lit = lit | (shadow & escaped)
        again = ~shadow & escaped & (left > 0)
        left = dr.select(again, left - 1, left)
        t = dr.select(again, t_in, t)
        tau = dr.select(again, -dr.log(1.0 - rng.next_float32()), tau)
        done = (shadow & (accept | escaped)) | (~shadow & escaped & ~again)
        shadow = shadow | turn
        restart = turn | again
        flying = flying & ~done
    return lit, mi.Vector3f(w), cos_t


def sky_order1(med, grid, camera, sig_k: float, gs, sky, spp: int, seed: int = 0, batch: int = 1 << 21,
               opacity=None, tries: int = 64):
    """(4 channels, len(gs), H, W) float32: the sky's order-1 band images at mu_t = ``sig_k`` rho for each g of
    ``gs`` (``sky``: a :class:`natscene.scatter.photons.SkySource`), ``spp`` paths per pixel. ``opacity``: the
    pixels' 1 - T (H, W; :func:`natscene.scatter.single.march_view` at the pixels' centres): with it the camera
    rays go through the pixels' centres, each collision is forced by up to ``tries`` restarts and weighted by the
    pixel's opacity."""
    H, W = camera.height, camera.width
    gs = [float(g) for g in gs]
    out = np.zeros((4, len(gs), H * W), np.float64)
    rows = max(1, batch // (W * spp))
    for r0 in range(0, H, rows):
        pix = np.arange(r0 * W, min(H, r0 + rows) * W)
        rng = mi.PCG32(size=len(pix) * spp, initstate=dr.arange(mi.UInt64, len(pix) * spp) + r0 * W * spp,
                       initseq=mi.UInt64(int(seed) * 7919 + 3))
        forced = opacity is not None
        o, d, pidx = camera_rays(camera, spp, rng=None if forced else rng, pixels=pix)
        lit, om, cos_t = _paths(med, grid, o, d, float(sig_k), gs, rng, tries if forced else 1)
        _, rad = sky._pdf_radiance(om)
        q = sum(hg_dr(cos_t, g) for g in gs) / len(gs)
        a = (dr.gather(mi.Float, mi.Float(np.asarray(opacity, np.float32).ravel()), pidx) if forced
             else mi.Float(1.0))
        for j, g in enumerate(gs):
            wj = dr.select(lit, a * hg_dr(cos_t, g) / q, 0.0)
            for c in range(4):
                v = dr.block_sum(wj * rad[c], spp) / spp
                out[c, j, pix] = np.asarray(v, np.float64)
    return out.reshape(4, len(gs), H, W).astype(np.float32)
