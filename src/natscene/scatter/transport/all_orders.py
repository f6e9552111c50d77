"""
Transport ``all_orders``
========================

Defines the default transport: every scattering order of the sun's light and the skylight, in bands (the
remedies of Dobashi et al. 2012, §7; Bouthors et al. 2008):

-   :class:`AllOrders`: the transport model (precompute, composition, direct render).
-   :func:`skylight_dome`, :func:`frame_dome`: the sky dome of the precompute and of a frame.
-   :func:`sky_luminance_weights`, :func:`composed_halves`, :func:`node_noise`, :func:`target_figure`,
    :data:`NOISE_BETAS`: a node's composed noise and the figure its noise target is checked against.

Dobashi 2012 truncates multiple scattering at order 4 and adds a constant ambient term (§3); his §7 names the
remedies, clustering the high orders into sets (Bouthors et al. 2008) and the skylight as a light source. This
transport traces every order of the sun's light and of a sky dome's (:mod:`natscene.scatter.allorders`,
:mod:`natscene.scatter.photons`) into bands of orders whose albedo dependence is closed-form
(:mod:`natscene.scatter.bands`), so the GA composes any beta without tracing again:

    L_c  = c_in L_in [beta p(θ_q, g) S_sun + Σ_b c_b(beta) T_b^sun]
           + Σ_b c'_b(beta) [a ⊙ T_b^{sky,RGB} + G T_b^{ground}] + T L_sky,
    G    = albedo / π (L_in c_in sin(el_sun) + a ⊙ E_dome)

with the sky dome's R, G, B channels and a unit-radiance ground, c_b(beta) the bands' albedo weights, a the dome's
calibration to the photo (:func:`natscene.scatter.skylight.calibration`), E_dome its horizontal irradiance and G
the radiance of a Lambertian ground of ``ground_albedo``; interpolated bilinearly in the extinction and g between
the tables' nodes. The GA searches L_in, g, the extinction and beta; the skylight replaces L_amb. A frame's
direct render (:meth:`AllOrders.render`) knows its sun and sky as it traces, and puts its ground in the cloud's
shadow (:class:`natscene.scatter.skylight.GroundLight`): the ground's skylit part albedo / π E_dome joins the
R, G, B channels, and T^{ground} carries the ground's sunlit part, each ground point's light weighted by the sun's
transmittance through the cloud to it, composed with G_sun = albedo / π L_in c_in sin(el_sun).

References
----------
-   Bouthors, A., Neyret, F., Max, N., Bruneton, E., & Crassin, C. (2008). Interactive multiple anisotropic
    scattering in clouds. Proceedings of the 2008 Symposium on Interactive 3D Graphics and Games, 173–182.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import time

import numpy as np

from natscene.errors import InputError
from natscene.io import read_exr, write_exr
from natscene.scatter.bands import ORDER_BINS, SKY_HISTOGRAMS, band_weights, channel_weights, order_distribution
from natscene.scatter.nodes import brackets
from natscene.scatter.params import rgb_per_individual
from natscene.scatter.phase import INV_4PI, hg
from natscene.scatter.transport.base import Arrays, RenderOptions, Transport, noise_stats

try:  # a fused compiled kernel where numba is importable (it is a declared dependency); numpy otherwise
    import numba as _nb
except Exception:  # noqa: BLE001
    _nb = None

__all__ = ["AllOrders", "NOISE_BETAS", "composed_halves", "frame_dome", "node_noise", "sky_luminance_weights",
           "skylight_dome", "source_variances", "target_figure"]

SKY_CHANNELS = ("R", "G", "B", "ground")
_KERNEL = None
_CHUNK = 1024


def frame_dome(sun_dir, sky_settings):
    """The dome that lights a frame's cloud: the shot's Preetham sky for this sun (or a constant colour);
    ``sky_settings``: a validated ``shots.<name>.sky`` or its :class:`natscene.sky.daylight.Skylight`."""
    from natscene.scatter.skylight import Dome, daylight_dome
    from natscene.sky.daylight import skylight
    s = skylight(sky_settings)
    if s.model == "constant":
        c = np.asarray(s.color, np.float64)
        return Dome(np.broadcast_to(c, (8, 16, 3)).copy(), np.zeros(3))
    return daylight_dome(sun_dir, s)



NOISE_BETAS = (0.9, 0.99, 0.999)


def skylight_dome(sun_dir, sky):
    """The sky dome that lights the cloud for the precompute and its settings (``precompute.skylight``, validated,
    or its :class:`natscene.sky.daylight.Skylight`)."""
    from natscene.scatter.skylight import daylight_dome
    from natscene.sky.daylight import skylight
    s = skylight(sky, "precompute.skylight")
    if s.model != "preetham":
        raise InputError(f"config key 'precompute.skylight.model': unknown sky model {s.model!r} (preetham)")
    return daylight_dome(sun_dir, s)


def sky_luminance_weights(sun_dir, dome) -> np.ndarray:
    """Weights that compose the sky's four traced channels (the dome's R, G, B and a unit-radiance ground) in
    luminance for the noise figures: Rec. 709 luma of R, G, B, and of a ground of albedo 0.2 lit by the sun
    (irradiance 1 at ``sun_dir``) and the dome."""
    from natscene.color import LUMA_709
    from natscene.scatter.skylight import ground_radiance, irradiance
    s_dir = np.asarray(sun_dir, np.float64) / np.linalg.norm(sun_dir)
    ground = ground_radiance(np.full(3, 0.2), max(float(s_dir[1]), 0.0), irradiance(dome))
    return np.concatenate([LUMA_709, [float(ground @ LUMA_709)]])


def target_figure(noise: dict) -> tuple[float, float]:
    """The figure a node's noise target is checked against (``precompute.all_orders.noise_target``): of the
    per-pixel standard errors of :func:`node_noise`, the sun's and the sky's multiple scattering composed together,
    relative to the composed cloud pixel (single scattering included: the image the GA sees), the median and the
    p95 over the cloud pixels, each the worst of the betas. Relative to the multiple scattering alone, the thin
    nodes of a physical extinction grid (where it is a small part of the pixel) would take most of the photons
    for noise the image does not show."""
    e = [v for k, v in noise.items() if k.startswith("pixel.") and v.size]
    return tuple(max((float(np.percentile(v, q)) for v in e), default=0.0) for q in (50, 95))


def composed_halves(vi, sun_bands, sky_bands, sky_w, beta: float) -> dict:
    """The two halves of one node's composed multiple scattering at albedo ``beta`` (Σ_b c_b(β) T_b per half):
    ``sun`` (orders >= 2), ``sky`` (R + G + B, orders >= 1) and ``sun_and_sky`` (luminance, weights ``sky_w`` of
    the dome's R, G, B and the ground, :func:`sky_luminance_weights`)."""
    cs = band_weights(sun_bands, vi.sun_orders, beta)[0]
    ck = channel_weights(sky_bands, vi.sky_orders, beta)[0]                          # (4 channels, B)
    sun = [np.tensordot(cs, vi.sun_halves[h], 1) for h in range(2)]
    sky = [np.tensordot(ck[:3], vi.sky_halves[h][:3], 2) for h in range(2)]
    both = [sun[h] + np.tensordot(ck * np.asarray(sky_w)[:, None], vi.sky_halves[h], 2) for h in range(2)]
    return {"sun": sun, "sky": sky, "sun_and_sky": both}


def _pixel(half_a, half_b, beta: float, single_sun, foot):
    """The composed cloud pixel at albedo ``beta`` (single scattering ``beta * single_sun`` plus the mean of the
    two halves of the multiple scattering) and the footprint's pixels with light."""
    pixel = beta * single_sun + (half_a + half_b) / 2
    return pixel, foot & (pixel > 0)


def node_noise(vi, sun_bands, sky_bands, sky_w, foot, single_sun) -> dict:
    """Per-pixel relative standard error of one node's composed multiple scattering (two-halves estimate,
    :func:`natscene.scatter.allorders.standard_error`) over its cloud pixels, per ``<part>.beta<b>``: the sun's
    (orders >= 2), the sky's (R + G + B, orders >= 1), the two together (luminance, weights ``sky_w`` of the
    dome's R, G, B and the ground) and the two together over the composed pixel (``single_sun``: its order 1
    over beta)."""
    from natscene.scatter.allorders import standard_error
    out = {}
    for b in NOISE_BETAS:
        for part, (x, y) in composed_halves(vi, sun_bands, sky_bands, sky_w, b).items():
            m = (x + y) / 2
            se = standard_error(x, y)
            ok = foot & (m > 0)
            out[f"{part}.beta{b:g}"] = (se[ok] / m[ok]).astype(np.float32)
            if part == "sun_and_sky":          # the same error over the composed cloud pixel
                pixel, ok = _pixel(x, y, b, single_sun, foot)
                out[f"pixel.beta{b:g}"] = (se[ok] / pixel[ok]).astype(np.float32)
    return out


def source_variances(vi, sun_bands, sky_bands, sky_w, foot, single_sun) -> tuple:
    """The sun's and the sky's shares of one node's pixel variance: the mean over its cloud pixels of each
    source's squared two-halves standard error (:func:`natscene.scatter.allorders.standard_error`) relative to
    the composed pixel (as ``pixel`` of :func:`node_noise`), averaged over :data:`NOISE_BETAS`; what
    :func:`natscene.scatter.allorders.source_scales` divides a top-up by. Where the sky's order 1 comes from
    shadow rays (``vi.stats["sky_order1"]``), a third share: its variance, which more sky photons do not lower."""
    from dataclasses import replace

    from natscene.scatter.allorders import standard_error
    shadow = vi.stats.get("sky_order1") == "shadow_rays"
    photons = vi
    if shadow:                                        # the sky photons' bands alone (order 2 on)
        halves = vi.sky_halves.copy()
        halves[:, :, 0] = 0.0
        photons = replace(vi, sky_halves=halves)
    v = np.zeros(3)
    for b in NOISE_BETAS:
        h = composed_halves(photons, sun_bands, sky_bands, sky_w, b)
        full = composed_halves(vi, sun_bands, sky_bands, sky_w, b)["sun_and_sky"] if shadow else h["sun_and_sky"]
        parts = [h["sun"], [h["sun_and_sky"][i] - h["sun"][i] for i in range(2)]]
        if shadow:
            parts.append([full[i] - h["sun_and_sky"][i] for i in range(2)])
        pixel, ok = _pixel(*full, b, single_sun, foot)
        for n, (x, y) in enumerate(parts):
            v[n] += float(np.mean((standard_error(x, y)[ok] / pixel[ok]) ** 2)) if ok.any() else 0.0
    v /= len(NOISE_BETAS)
    return tuple(float(x) for x in (v if shadow else v[:2]))


def _multiple(volume, camera, sun_dir, sigmas, gs, settings, sky, seed, log, single):
    """Band images of the sun's and the sky's light over the (g, extinction) grid, their order distributions and
    noise (``sigmas``: the volume's unitless sigma_t of each node; ``single``: the precompute's
    :func:`natscene.scatter.single.march_view` of the grid)."""
    from natscene.scatter.allorders import START_MIN, Lighting, Scene, view_images
    from natscene.scatter.skylight import irradiance
    from natscene.sky.daylight import preetham_rgb, skylight
    sky = skylight(sky, "precompute.skylight")
    dome = skylight_dome(sun_dir, sky)
    # one set of the sky's shadow rays serves every node
    scene = Scene(volume, Lighting(np.asarray(sun_dir, np.float64), dome), settings, g_grid=gs, sigma_grid=sigmas,
                  shadow_seed=seed)
    H, W = camera.height, camera.width
    Ng, Ns = len(gs), len(sigmas)
    sb, kb = settings.sun_bands, settings.sky_bands
    sun_ms = np.zeros((len(sb), Ng, Ns, H, W), np.float32)
    sky_ms = np.zeros((4, len(kb), Ng, Ns, H, W), np.float32)
    sun_r = np.broadcast_to(order_distribution(sb, np.zeros(0)), (Ng, Ns, len(sb), ORDER_BINS, 2)).copy()
    sky_r = np.broadcast_to(order_distribution(kb, np.zeros((SKY_HISTOGRAMS, 0))),
                            (Ng, Ns, SKY_HISTOGRAMS, len(kb), ORDER_BINS, 2)).copy()
    noise = {f"{part}.beta{b:g}": [] for part in ("sun", "sky", "sun_and_sky", "pixel") for b in NOISE_BETAS}
    # the composed multiple scattering as the sun (irradiance 1) and the dome light the cloud, in luminance:
    # the dome's R, G, B and the ground (albedo 0.2 under the sun and the dome), and the pixel's single scattering
    from natscene.phase import hg
    s_dir = np.asarray(sun_dir, np.float64) / np.linalg.norm(sun_dir)
    sky_w = sky_luminance_weights(s_dir, dome)
    cos_q = camera.ray_directions() @ s_dir
    foot = single["footprint"] > 0
    counts = {"sun_photons": 0, "sun_collisions": 0, "sky_photons": 0, "sky_collisions": 0}
    truncated = 0.0
    scales, source_scales = [], []
    todo = [(i, j) for i in range(Ns) if sigmas[i] > 0 for j in range(Ng)]
    # per g: the photons that the node one extinction thinner needed where it met the target with its first pass
    # (a thin node meets it at a quarter of the budget); after a neighbour's top-up the need jumps between
    # neighbours and a node starts at its budget (docs/stages/precompute.md, "A noise target per node")
    # The thinnest extinction has no thinner neighbour: its nodes start at START_MIN and are topped up by what that
    # pass measures (the main job's thin nodes meet the target there; without a target view_images starts at 1)
    need = {}
    thinnest = todo[0][0] if todo else None
    t0 = time.perf_counter()
    for n, (i, j) in enumerate(todo):
        single_sun = hg(cos_q, gs[j]) * single["S_sun"][i]          # the pixel's order 1 over beta

        def figures(vi):
            return node_noise(vi, sb, kb, sky_w, foot, single_sun)

        vi = view_images(scene, camera, float(sigmas[i]), float(gs[j]), seed=seed * 100003 + i * 101 + j,
                         noise=lambda vi: target_figure(figures(vi)),
                         split=lambda vi: source_variances(vi, sb, kb, sky_w, foot, single_sun),
                         start=need.get(j, (START_MIN, START_MIN) if i == thinnest else None))
        if "need" in vi.stats and vi.stats["source_budget_scales"] == vi.stats["first_pass"]:
            need[j] = vi.stats["need"]
        else:
            need.pop(j, None)
        first = vi.stats.get("first_pass", [1.0, 1.0])
        sun_ms[:, j, i] = vi.sun
        sky_ms[:, :, j, i] = vi.sky
        sun_r[j, i], sky_r[j, i] = vi.sun_orders, vi.sky_orders
        for k in counts:
            counts[k] += int(vi.stats.get(k, 0))
        truncated = max(truncated, vi.stats.get("sun_truncated", 0.0))
        scales.append(float(vi.stats.get("budget_scale", 1.0)))
        source_scales.append([round(float(x), 3) for x in vi.stats.get("source_budget_scales", [1.0, 1.0])])
        for k, v in figures(vi).items():
            noise[k].append(v)
        el = time.perf_counter() - t0
        log(f"all orders extinction={sigmas[i] * volume.extinction_scale:.4g}/m g={gs[j]:g}: {vi.stats.get('sun_photons', 0)} sun + "
            f"{vi.stats.get('sky_photons', 0)} sky photons (budget x{scales[-1]:.2f}: sun x{source_scales[-1][0]:.2f}, sky x{source_scales[-1][-1]:.2f}; "
            f"first pass x{first[0]:.2f}, x{first[-1]:.2f}; {n + 1}/{len(todo)}, {el:.0f} s, "
            f"about {el / (n + 1) * (len(todo) - n - 1):.0f} s left)")
    dirs = camera.ray_directions()
    view_rgb = preetham_rgb(dirs.reshape(-1, 3), sun_dir, sky.turbidity, sky.zenith_luminance, sky.reference_elevation,
                            sky.min_view_elevation).reshape(-1, 3)
    s = np.asarray(sun_dir, np.float64)
    meta = {
        "sun_bands": [[a, e] for a, e in sb], "sky_bands": [[a, e] for a, e in kb],
        "skylight": {"model": "preetham", "turbidity": float(sky.turbidity),
                     "view_mean_rgb": view_rgb.mean(0).tolist(), "irradiance_rgb": irradiance(dome).tolist(),
                     "sun_elevation_sin": float(s[1] / np.linalg.norm(s))},
        "photons": counts, "truncated_light": float(truncated),
        # photons per node as a multiple of the collision budget's (noise_target tops the noisy nodes up),
        # per node, extinction > 0 in order, g within each extinction
        "budget_scale": [round(x, 3) for x in scales],
        # the same per source (sun, sky): the top-ups go where the pixel's variance is (source_variances)
        "source_budget_scales": source_scales,
        "settings": {"sun_collisions": int(settings.sun_collisions), "sky_collisions": int(settings.sky_collisions),
                     "sun_photons_max": int(settings.sun_photons_max), "sky_photons_max": int(settings.sky_photons_max),
                     "fine_voxels": int(settings.fine_voxels), "coarse_voxels": int(settings.coarse_voxels),
                     "guide_width": [float(x) for x in settings.guide_width], "max_order": int(settings.max_order),
                     "majorant_voxels": int(settings.majorant_voxels), "camera_lobe": float(settings.camera_lobe),
                     "noise_target": [float(x) for x in settings.noise_target],
                     "max_budget_scale": float(settings.max_budget_scale)},
        # per-pixel standard error of the composed multiple-scattering term divided by the term, over the
        # cloud pixels and every (g, extinction) node: the sun's (orders >= 2), the sky's (R+G+B, orders >= 1), the
        # two together (luminance, the sun's irradiance 1 and the dome as it lit the cloud); "pixel": the error of
        # the two together divided by the composed cloud pixel (single scattering included)
        "pixel_relative_standard_error": {k: noise_stats(v) for k, v in noise.items()},
    }
    return sun_ms, sky_ms, sun_r, sky_r, meta


def _kernel():
    """Fused all-orders composition, parallel over pixel chunks (compiled once, cached). Each chunk composes
    every individual in turn, so the table rows of the nodes the population shares are read from main
    memory once per chunk and from cache after that."""
    global _KERNEL
    if _KERNEL is None:
        @_nb.njit(parallel=True, cache=True, fastmath=True)
        def kernel(s_sun, s_T, sun_ms, sky_ms, cos_t, sky, sidx, ws, gidx, wsun, wsky, gpar, a_sun, c_in, a_sky, G,
                   out):
            P, N = out.shape[0], out.shape[1]
            Bs, Bk = sun_ms.shape[2], sky_ms.shape[3]
            nchunk = (N + _CHUNK - 1) // _CHUNK
            for ci in _nb.prange(nchunk):
                n0 = ci * _CHUNK
                n1 = min(n0 + _CHUNK, N)
                m = n1 - n0
                acc = np.empty(m, np.float32)
                acc_k = np.empty((4, m), np.float32)      # the sky bands' dome R, G, B and ground light
                for j in range(P):
                    s0, s1 = sidx[j, 0], sidx[j, 1]
                    w0, w1 = ws[j, 0], ws[j, 1]
                    g = gpar[j]
                    c_ph = np.float32((1.0 - g * g) * 0.07957747154594767) * a_sun[j]
                    opg = np.float32(1.0 + g * g)
                    tg = np.float32(2.0 * g)
                    for n in range(m):
                        q = n0 + n
                        d = opg - tg * cos_t[q]
                        acc[n] = c_ph / (d * np.sqrt(d)) * (w0 * s_sun[s0, q] + w1 * s_sun[s1, q])
                    acc_k[:] = 0
                    for u in range(2):
                        gi = gidx[j, u]
                        for v in range(2):
                            si = sidx[j, v]
                            for b in range(Bs):
                                w = wsun[j, u, v, b]
                                if w != 0:
                                    row = sun_ms[gi, si, b]
                                    for n in range(m):
                                        acc[n] += w * row[n0 + n]
                            for c in range(4):
                                for b in range(Bk):
                                    w = wsky[j, u, v, c, b]
                                    if w != 0:
                                        rc = sky_ms[gi, si, c, b]
                                        for n in range(m):
                                            acc_k[c, n] += w * rc[n0 + n]
                    for n in range(m):
                        q = n0 + n
                        t = w0 * s_T[s0, q] + w1 * s_T[s1, q]
                        gl = acc_k[3, n]
                        for c in range(3):
                            out[j, q, c] = (acc[n] * c_in[j, c] + a_sky[j, c] * acc_k[c, n] + G[j, c] * gl
                                            + t * sky[q, c])
        _KERNEL = kernel
    return _KERNEL




def weights(tables, p: dict, P: int):
    """Per individual: the (e, g) brackets and the band weights of the all-orders composition.

    Returns sidx, gidx (P, 2), ws (P, 2), wsun (P, 2, 2, B) = w_g w_s L_in c_b(beta), wsky (P, 2, 2, 4, B')
    = w_g w_s c'_cb(beta) for each of the sky's channels (:func:`natscene.scatter.bands.channel_weights`), a (P, 3)
    the dome's calibration, G (P, 3) the ground radiance (of ``p``'s ``ground_albedo``, which the composition
    needs: the fit gives it, :meth:`AllOrders.fit_fixed`)."""
    sig = np.asarray(tables.extinction, np.float64)
    gs = np.asarray(tables.g, np.float64)
    sb, kb = tables.sun_bands, tables.sky_bands
    si, fs = brackets(sig, p["extinction"])
    gi, fg = brackets(gs, p["g"])
    sidx = np.stack([si, np.minimum(si + 1, sig.size - 1)], 1)
    gidx = np.stack([gi, np.minimum(gi + 1, gs.size - 1)], 1)
    ws = np.stack([1.0 - fs, fs], 1).astype(np.float32)
    wsun = np.zeros((P, 2, 2, len(sb)), np.float32)
    wsky = np.zeros((P, 2, 2, 4, len(kb)), np.float32)          # per sky channel: its own order distribution
    sun_r, sky_r = np.asarray(tables.sun_orders), np.asarray(tables.sky_orders)
    for u, wg in enumerate((1.0 - fg, fg)):
        for v, wsv in enumerate((1.0 - fs, fs)):
            w = wg * wsv                                               # (P,)
            g_n, s_n = gidx[:, u], sidx[:, v]
            wsun[:, u, v] = (w * p["L_in"])[:, None] * band_weights(sb, sun_r[g_n, s_n], p["beta"])
            wsky[:, u, v] = w[:, None, None] * channel_weights(kb, sky_r[g_n, s_n], p["beta"])
    sl = tables.meta.get("skylight", {})
    a = rgb_per_individual(p, "sky_scale", P, 1.0)
    if "ground_albedo" not in p:
        raise InputError("compose: the all_orders transport needs the ground's albedo 'ground_albedo' in the "
                         "parameters (the fit composes with fit.ground_albedo: Transport.fit_fixed)")
    albedo = rgb_per_individual(p, "ground_albedo", P, None)
    e_dome = np.asarray(sl.get("irradiance_rgb", [0.0, 0.0, 0.0]), np.float64)
    sin_el = max(float(sl.get("sun_elevation_sin", 0.0)), 0.0)
    G = albedo / np.pi * (p["L_in"][:, None] * p["c_in"] * sin_el + a * e_dome[None])
    return sidx, gidx, ws, wsun, wsky, a, G.astype(np.float32)


def _compose(tables, p: dict, P: int, arrays, cos_t, sky, N: int, backend: str) -> np.ndarray:
    """L_c (P, N, 3) of the all-orders transport; ``arrays`` = (S_sun (Ns, N), T (Ns, N), sun (Ng, Ns, B, N),
    sky (Ng, Ns, 4, B', N))."""
    s_sun, s_T, sun_ms, sky_ms = arrays
    sidx, gidx, ws, wsun, wsky, a, G = weights(tables, p, P)
    a_sun = (p["L_in"] * p["beta"]).astype(np.float32)
    c_in = p["c_in"].astype(np.float32)
    out = np.empty((P, N, 3), np.float32)
    if _nb is not None and backend != "numpy":
        _kernel()(s_sun, s_T, sun_ms, sky_ms, np.asarray(cos_t, np.float32),
                                   np.ascontiguousarray(sky, np.float32), sidx, ws, gidx, wsun, wsky,
                                   p["g"].astype(np.float32), a_sun, c_in, a, G, out)
        return out
    for j in range(P):
        g = float(p["g"][j])
        denom = np.float32(1.0 + g * g) - np.float32(2.0 * g) * cos_t
        phase = np.float32((1.0 - g * g) * INV_4PI) / (denom * np.sqrt(denom))
        acc = a_sun[j] * phase * (ws[j, 0] * s_sun[sidx[j, 0]] + ws[j, 1] * s_sun[sidx[j, 1]])
        acc_c = np.zeros((3, N), np.float32)
        for u in range(2):
            for v in range(2):
                gi, si = gidx[j, u], sidx[j, v]
                if wsun[j, u, v].any():
                    acc += wsun[j, u, v] @ sun_ms[gi, si]
                if wsky[j, u, v].any():
                    k = np.einsum("cb,cbn->cn", wsky[j, u, v], sky_ms[gi, si])      # (4, N)
                    acc_c += a[j][:, None] * k[:3] + G[j][:, None] * k[3][None]
        t = ws[j, 0] * s_T[sidx[j, 0]] + ws[j, 1] * s_T[sidx[j, 1]]
        out[j] = (acc[:, None] * c_in[j][None] + acc_c.T + t[:, None] * sky).astype(np.float32)
    return out




def check_noise_target(settings) -> None:
    """``noise_target`` is (median, p95) in [0, 1] and ``max_budget_scale`` >= 1, else InputError naming the key."""
    t = tuple(settings.noise_target)
    if len(t) != 2 or not all(0.0 <= float(x) <= 1.0 for x in t):
        raise InputError(f"config key 'precompute.all_orders.noise_target': needs [median, p95] in [0, 1], got {list(t)}")
    if not float(settings.max_budget_scale) >= 1.0:
        raise InputError(f"config key 'precompute.all_orders.max_budget_scale': must be >= 1, "
                         f"got {settings.max_budget_scale}")


def _tag(x: float) -> str:
    return f"{float(x):g}"


def _names(sun_bands, sky_bands, gs, extinctions) -> list[str]:
    sig = [_tag(s) for s in extinctions]
    gt = [_tag(g) for g in gs]
    names = [f"sun.b{b}.g{g}.e{s}" for b in range(len(sun_bands)) for g in gt for s in sig]
    names += [f"sky.{c}.b{b}.g{g}.e{s}" for c in SKY_CHANNELS for b in range(len(sky_bands))
              for g in gt for s in sig]
    return names


class AllOrders(Transport):
    """Every order of the sun's light and the skylight (see the module docstring)."""

    name = "all_orders"
    fit_params = ("L_in", "g", "extinction", "beta")
    tables_file = "allorders.exr"

    def validate(self, settings) -> None:
        if settings is not None:
            check_noise_target(settings)

    def describe(self, section: dict) -> str:
        from natscene.scatter.allorders import settings_from_config
        st = settings_from_config(section)
        return f"{st.sun_collisions:.3g} + {st.sky_collisions:.3g} photon collisions per node"

    def preview_rows(self, tables, si: int, gis: list) -> list:
        """The sun's multiple scattering (every order >= 2) and the skylight (the dome's R, G, B, in colour), both
        at beta 0.99."""
        sun, sky = [], []
        for gi in gis:
            w = band_weights(tables.sun_bands, tables.sun_orders[gi, si], 0.99)[0]
            sun.append(("sun all orders", np.tensordot(w, tables.sun_ms[:, gi, si], 1)))
            w = channel_weights(tables.sky_bands, tables.sky_orders[gi, si], 0.99)[0, :3]       # (3, B)
            sky.append(("sky all orders", np.einsum("cb,cbhw->hwc", w, tables.sky_ms[:3, :, gi, si])))
        return [sun, sky]

    def values_per_node(self, section: dict) -> int:
        from natscene.scatter.bands import SKY_BANDS, SUN_BANDS
        return len(SUN_BANDS) + 4 * len(SKY_BANDS)      # the bands are not configurable

    def memory_model(self, rule: str) -> str:
        return f"{rule}_all_orders" if rule in ("precompute", "fit", "render_frame") else rule

    def precompute(self, volume, med, camera, sigmas, gs, single, *, settings=None, skylight=None, n_m=4,
                   spp=256, seed=0, batch_spp=None, with_error=True, log=None):
        from natscene.config import default_settings
        from natscene.scatter.allorders import AllOrdersSettings
        settings = settings if settings is not None else default_settings(AllOrdersSettings)
        sun_ms, sky_ms, sun_r, sky_r, meta = _multiple(volume, camera, med.sun_dir, sigmas, gs, settings, skylight,
                                                       seed, log or (lambda msg: None), single)
        fields = {"orders": [], "sun_bands": tuple(settings.sun_bands), "sky_bands": tuple(settings.sky_bands),
                  "sun_ms": sun_ms, "sky_ms": sky_ms, "sun_orders": sun_r, "sky_orders": sky_r}
        return fields, meta

    def save(self, directory, tables, attrs: dict) -> None:
        H, W = tables.t_c.shape
        data = np.concatenate([tables.sun_ms.reshape(-1, H, W), tables.sky_ms.reshape(-1, H, W)])
        scale = data.reshape(len(data), -1).max(1).astype(np.float64)
        scale[scale <= 0] = 1.0
        # each channel divided by its maximum: half floats then keep 4.9e-4 relative precision over 14 octaves
        write_exr(f"{directory}/{self.tables_file}", (data / scale[:, None, None]).transpose(1, 2, 0),
                  _names(tables.sun_bands, tables.sky_bands, tables.g, tables.extinction),
                  attrs={**attrs, "channel_scale": scale.tolist(),
                         # each band's order distribution (natscene.scatter.bands.order_distribution) per node
                         "sun_orders": np.round(tables.sun_orders, 6).tolist(),
                         "sky_orders": np.round(tables.sky_orders, 6).tolist()},
                  half=True, stage="precompute")

    def load(self, directory, meta: dict, extinctions, gs, orders, shape) -> dict:
        H, W = shape
        sb = tuple((int(a), None if e is None else int(e)) for a, e in meta["sun_bands"])
        kb = tuple((int(a), None if e is None else int(e)) for a, e in meta["sky_bands"])
        path = f"{directory}/{self.tables_file}"
        ao = read_exr(path)
        names = _names(sb, kb, gs, extinctions)
        scale = np.asarray(ao.attrs.get("channel_scale"), np.float64)
        if scale.size != len(names) or "sun_orders" not in ao.attrs or "sky_orders" not in ao.attrs:
            raise InputError(f"{path}: channel scales or the bands' order distributions missing; rerun the "
                             "precompute rule")
        sky_r = np.asarray(ao.attrs["sky_orders"], np.float64)
        if sky_r.ndim != 6 or sky_r.shape[2] != SKY_HISTOGRAMS:
            raise InputError(f"{path}: the sky's order distributions have shape {sky_r.shape}, not one per group of "
                             f"its channels (Ng, Ns, {SKY_HISTOGRAMS}, bands, bins, 2): written by an older "
                             "natscene; rerun the precompute rule")
        stack = np.moveaxis(ao.channel(*names).reshape(H, W, -1), -1, 0)
        data = stack.astype(np.float32) * scale[:, None, None].astype(np.float32)
        n_sun = len(sb) * len(gs) * len(extinctions)
        return {"sun_bands": sb, "sky_bands": kb,
                "sun_ms": np.ascontiguousarray(data[:n_sun].reshape(len(sb), len(gs), len(extinctions), H, W)),
                "sky_ms": np.ascontiguousarray(data[n_sun:].reshape(4, len(kb), len(gs), len(extinctions), H, W)),
                "sun_orders": np.asarray(ao.attrs["sun_orders"], np.float64),
                "sky_orders": sky_r}

    def compose(self, tables, p: dict, P: int, arrays: Arrays, sky: np.ndarray, backend: str) -> np.ndarray:
        return _compose(tables, p, P, (arrays.s_sun, arrays.T, arrays.sun_ms, arrays.sky_ms), arrays.cos_t,
                        sky, arrays.n, backend)

    def render(self, volume, med, camera, sigma: float, single: dict, cos_t, p: dict, sky,
               options: RenderOptions):
        H, W = camera.height, camera.width
        g, beta, L_in = float(p["g"][0]), float(p["beta"][0]), float(p["L_in"][0])
        c_in = p["c_in"][0].astype(np.float32)
        o = options
        seed, skylight, dome = o.seed, o.skylight, o.dome
        sky_settings, ground_albedo = o.sky_settings, o.ground_albedo
        comps = {}
        from natscene.scatter.allorders import Lighting, Scene, view_images
        from natscene.scatter.skylight import GroundLight, ground_radiance, irradiance
        st = o.all_orders
        albedo = np.broadcast_to(np.asarray(ground_albedo, np.float64), (3,))
        ground = None
        if skylight:
            dome = dome if dome is not None else frame_dome(med.sun_dir, sky_settings)
            # the ground in the cloud's shadow: its skylit part joins the dome's channels, its sunlit part (G_sun
            # below) is the ground channel, weighted by the sun's transmittance to the ground point
            ground = GroundLight(ground_radiance(albedo, 0.0, irradiance(dome)), sigma * volume.extinction_scale)
        else:
            dome = None
        # another seed, another run (the shadow rays' too); the medium is the frame's own
        scene = Scene(volume, Lighting(med.sun_dir, dome, ground), st, shadow_seed=seed, med=med)
        vi = view_images(scene, camera, sigma, g, seed=seed, halves=False)       # a frame needs no noise figure
        a_s = L_in * beta * hg(cos_t, g) * single["S_sun"][0]
        a_m = L_in * np.tensordot(band_weights(st.sun_bands, vi.sun_orders, beta)[0], vi.sun, 1)
        L_sky_lit = np.zeros((H, W, 3), np.float32)
        if dome is not None:
            ck = channel_weights(st.sky_bands, vi.sky_orders, beta)[0]          # (4, B)
            sky_bands = np.einsum("cb,cbhw->chw", ck, vi.sky)                   # (4, H, W)
            sin_el = max(float(med.sun_dir[1]), 0.0)
            G_sun = ground_radiance(albedo, L_in * c_in * sin_el, 0.0)
            L_sky_lit = (np.moveaxis(sky_bands[:3], 0, -1)
                         + sky_bands[3][..., None] * G_sun[None, None, :].astype(np.float32))
        L_s = a_s[..., None].astype(np.float32) * c_in
        L_m = a_m[..., None].astype(np.float32) * c_in
        comps.update(L_sky_lit=L_sky_lit.astype(np.float32), photons=vi.stats)
        cloud = L_s + L_m + L_sky_lit
        comps.update(L_s=L_s, L_m=L_m)
        return cloud, comps

    def fit_fixed(self, tables, sky, settings, log) -> dict:
        """The sky dome calibrated to the photo's L_sky and the ground's albedo (``fit.skylight``,
        ``fit.ground_albedo``); the sun alone (zeros) with ``fit.skylight: false``."""
        from natscene.scatter.skylight import calibration
        view_mean = tables.meta.get("skylight", {}).get("view_mean_rgb")
        if view_mean is None:
            raise InputError("the precompute's meta.yaml has no skylight.view_mean_rgb; rerun the precompute rule")
        fixed = {"sky_scale": calibration(np.asarray(sky, np.float64).reshape(-1, 3).mean(0), view_mean),
                 "ground_albedo": np.broadcast_to(np.asarray(settings.ground_albedo, np.float64), (3,))}
        if not settings.skylight:        # the sun alone lights the cloud
            fixed = {"sky_scale": np.zeros(3), "ground_albedo": np.zeros(3)}
        log(f"all-orders transport: the sky dome calibrated to the photo's L_sky by "
            f"{np.round(fixed['sky_scale'], 4).tolist()}, ground albedo {fixed['ground_albedo'].tolist()}")
        return fixed
