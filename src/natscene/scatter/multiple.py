"""
Per-order path tracing
======================

Defines the multiple scattering of the ``dobashi`` transport by Monte Carlo path tracing, one tally per order
(Dobashi et al. 2012, §4.3, Eqs. 6–8):

-   :func:`trace_orders`: the per-order estimates E^(k)(q, g, sigma) for k = 1..n_max, every g from the same paths.

Paths start at the camera (uniform sub-pixel jitter, box filter) and are built by delta tracking through
mu_t = sigma_t k rho (k = extinction_scale, one global majorant sigma_t k max rho). Free flights sampled
with pdf mu_t tau cancel the factors tau(x_{i-1}, x_i) sigma_t rho(x_i) / P of Eq. 7, so the estimate of
E_m^(k)(q, g, sigma_t) (Eq. 7, without beta^k) for a path reaching its k-th vertex x_k is

    W_g · p(θ_k, g) · tau(x_k, x_l),  W_g = Π_{i<k} p(θ_i, g) / q(θ_i),

with next-event estimation to the sun at every vertex (tau(x_k, x_l) = exp(-sigma_t k D(x_k)) from the sun
optical-depth volume) and θ_k the angle between the sun's propagation direction and the path direction
back toward the previous vertex. Every g of the grid is tallied from the SAME paths: directions are drawn
from the mixture q = (1/N_g) Σ_j p(·, g_j) of the grid's HG lobes (one-sample MIS, so p(·, g)/q <= N_g, no
weight blows up) and each g keeps its own running product W_g. With a single g the proposal is HG(g) and
W_g = 1 (the forward renderer). Orders 1..n_max are tallied; the tables keep k >= 2 (order 1 is Eq. 5's
ray-marched S_sun, the MC order 1 serves as a cross-check). Sum of squares per pixel gives standard errors.

Options, all unbiased (tests compare them with plain sampling): ``pixels`` traces only the listed pixels
(the precompute passes those whose view rays meet density: the others are exactly 0); ``split`` continues
every camera path from its first vertex as ``split`` secondary paths of weight 1/split (the standard error
is then taken over camera paths); ``guide`` draws that fraction of the directions from an HG(``g_guide``)
lobe around the direction toward the sun, weights with the whole mixture pdf. ``split`` and ``guide`` are off
by default.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import math

import numpy as np

import natscene.variant  # noqa: F401
import drjit as dr
import mitsuba as mi

from natscene.scatter.medium import Medium, ray_box_dr
from natscene.scatter.phase import hg_dr, hg_sample_cos_dr
from natscene.scatter.rays import camera_rays

__all__ = ["trace_orders"]


@dr.syntax
def _free_flight(med: Medium, p, w, sig_k: float, mu_bar: float, rng, active):
    """Delta tracking from p along w inside the volume box: (distance, collided)."""
    t0, t1 = ray_box_dr(p, w, med.bbox_min, med.bbox_max)
    t = mi.Float(t0)
    hit = mi.Bool(False)
    running = mi.Bool(active & (t1 > t0))
    while dr.hint(running, include=[rng]):
        t = t - dr.log(1.0 - rng.next_float32()) / mu_bar
        escaped = t >= t1
        r = med.rho(p + w * t)
        accept = (~escaped) & (rng.next_float32() * mu_bar < sig_k * r)
        hit |= accept
        running &= (~escaped) & (~accept)
    return t, hit


def _trace_batch(med: Medium, camera, sigma: float, gs, n_max: int, spp: int, seed: int, with_sq: bool,
                 pixels=None, split: int = 1, guide: float = 0.0, g_guide: float = 0.9):
    W, H = camera.width, camera.height
    npix = W * H if pixels is None else len(pixels)
    n = npix * spp
    seq = mi.UInt64(seed * 2654435761 % 2**63 + 1)
    rng = mi.PCG32(size=n, initstate=dr.arange(mi.UInt64, n), initseq=seq)
    p, w, _ = camera_rays(camera, spp, rng=rng, pixels=pixels)
    sig_k = float(sigma) * med.scale
    mu_bar = sig_k * med.rho_max
    sun = mi.Vector3f(*[float(c) for c in med.sun_dir])
    gs = [float(g) for g in gs]
    ng = len(gs)
    g_arr = mi.Float(gs)
    weights = [mi.Float(1.0) for _ in gs]
    alive = dr.full(mi.Bool, True, n)
    m = 1  # secondary paths per camera path (after the split)
    sums, sqs = [], []
    for k in range(1, n_max + 1):
        t, hit = _free_flight(med, p, w, sig_k, mu_bar, rng, alive)
        alive &= hit
        p = dr.select(alive, p + w * t, p)
        dr.eval(p, alive)
        tau_sun = dr.select(alive, dr.exp(-sig_k * med.sun_depth(p)), 0.0)
        cos_sun = dr.dot(sun, w)
        cs = [weights[j] * hg_dr(cos_sun, gs[j]) * tau_sun for j in range(ng)]
        if m > 1:
            # one estimate per camera path: the mean over its secondary paths (they share x_1, so the
            # standard error must be taken over camera paths, not over secondary paths)
            cs = [dr.block_sum(c, m) * (1.0 / m) for c in cs]
        dr.eval(*cs)
        red = [dr.block_sum(c, spp) for c in cs]
        if with_sq:
            red += [dr.block_sum(c * c, spp) for c in cs]
        dr.eval(*red)
        sums.append([np.asarray(r, np.float64) for r in red[:ng]])
        sqs.append([np.asarray(r, np.float64) for r in red[ng:]])
        if k == n_max:
            break
        if k == 1 and split > 1:
            # splitting at the first vertex: every camera path continues as ``split`` independent
            # secondary paths of weight 1/split each (applied above), sharing x_1
            m = int(split)
            src = dr.arange(mi.UInt32, n * m) // m
            p = dr.gather(mi.Point3f, p, src)
            w = dr.gather(mi.Vector3f, w, src)
            alive = dr.gather(mi.Bool, alive, src)
            rng = mi.PCG32(size=n * m, initstate=dr.arange(mi.UInt64, n * m) + mi.UInt64(n), initseq=seq + 1)
        # next direction: with probability ``guide`` from an HG(g_guide) lobe around the direction toward
        # the sun (the order-k+1 integrand peaks there: a path heading sunward reaches lit cloud), else
        # from the mixture of the grid's HG lobes around the propagation direction; weights use the
        # full mixture pdf (one-sample MIS: p(., g) / q <= N_g / (1 - guide), no weight blows up)
        if ng > 1:
            j_sel = mi.UInt32(dr.minimum(rng.next_float32() * ng, ng - 1))
            g_sel = dr.gather(mi.Float, g_arr, j_sel)
        else:
            g_sel = mi.Float(gs[0])
        if guide > 0:
            to_sun = rng.next_float32() < guide
            axis = dr.select(to_sun, sun, w)
            g_sel = dr.select(to_sun, g_guide, g_sel)
        else:
            axis = w
        cos_t = hg_sample_cos_dr(rng.next_float32(), g_sel)
        phi = 2.0 * math.pi * rng.next_float32()
        sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
        local = mi.Vector3f(sin_t * dr.cos(phi), sin_t * dr.sin(phi), cos_t)
        w_new = dr.normalize(mi.Frame3f(axis).to_world(local))
        cos_p = dr.clip(dr.dot(w, w_new), -1.0, 1.0)
        if ng > 1 or guide > 0:
            q = hg_dr(cos_p, gs[0])
            for j in range(1, ng):
                q += hg_dr(cos_p, gs[j])
            q = q / ng
            if guide > 0:
                q = (1.0 - guide) * q + guide * hg_dr(dr.dot(sun, w_new), g_guide)
            weights = [weights[j] * hg_dr(cos_p, gs[j]) / q for j in range(ng)]
        w = dr.select(alive, w_new, w)
        dr.eval(p, w, alive, rng, *weights)
    return sums, sqs


def trace_orders(med: Medium, camera, sigma: float, gs, n_max: int = 4, spp: int = 64, seed: int = 0,
                 batch_spp: int | None = None, with_error: bool = False, progress=None, pixels=None,
                 split: int = 1, guide: float = 0.0, g_guide: float = 0.9):
    """Per-order estimates (n_max, N_g, H, W) of E^(k)(q, g, sigma) for k = 1..n_max (float32).

    ``batch_spp`` samples per pixel per Dr.Jit pass (memory); ``with_error`` also returns the standard
    error of each estimate (same shape). ``progress(done_spp, total_spp)`` is called after each pass.
    ``pixels``: flat indices of the only pixels to trace (the others are 0: e.g. those whose view rays meet
    no density, which contribute nothing). ``split``: secondary paths per camera path from the first
    vertex on (splitting; 1 = none).
    """
    W, H = camera.width, camera.height
    ng = len(gs)
    if med.sun_depth_tex is None:
        raise ValueError("trace_orders needs a medium built with a sun direction")
    split = max(1, int(split))
    if pixels is not None:
        pixels = np.asarray(pixels, np.int64).reshape(-1)
    if sigma <= 0 or n_max < 1 or (pixels is not None and pixels.size == 0):
        z = np.zeros((max(n_max, 0), ng, H, W), np.float32)
        return (z, z.copy()) if with_error else z
    npix = W * H if pixels is None else pixels.size
    if batch_spp is None:
        batch_spp = max(1, min(spp, int(2_000_000 // (npix * split)) or 1))
    total = np.zeros((n_max, ng, npix))
    total_sq = np.zeros((n_max, ng, npix))
    done, b = 0, 0
    while done < spp:
        m = min(batch_spp, spp - done)
        sums, sqs = _trace_batch(med, camera, sigma, gs, n_max, m, seed * 100003 + b, with_error, pixels, split,
                                 guide, g_guide)
        total += np.asarray(sums)
        if with_error:
            total_sq += np.asarray(sqs)
        done += m
        b += 1
        if progress:
            progress(done, spp)

    def image(x):
        if pixels is None:
            return x.reshape(n_max, ng, H, W)
        full = np.zeros((n_max, ng, H * W))
        full[..., pixels] = x
        return full.reshape(n_max, ng, H, W)

    mean = total / spp
    if not with_error:
        return image(mean).astype(np.float32)
    var = np.maximum(total_sq / spp - mean ** 2, 0.0)
    se = np.sqrt(var / max(spp - 1, 1))
    return image(mean).astype(np.float32), image(se).astype(np.float32)
