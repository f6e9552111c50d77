"""The precomputed intermediate images for one volume, camera and sun (Dobashi 2012 §4.3), for either
transport model (``precompute.transport``).

For a grid of the extinction coefficient e in 1/m (mu_t(x) = e rho(x), rho the volume's density; default 0 and
0.002 ... 0.3 /m, two decades from haze to a storm cloud's core, about log-spaced) and a g grid (default 0, 0.1,
..., 0.9: HG with g -> 1 is a delta lobe, 0.9 is the documented maximum), the tables hold, per pixel q:

- ``s_sun``, ``s_amb`` (Ns, H, W): the two integrals of Eq. 5 (:mod:`natscene.scatter.single`);
- ``transmittance`` (Ns, H, W): tau(x_v, x_b, e) of Eq. 9;
- ``t_c`` (H, W): distance from the camera to the cloud (first sample with rho >= ``rho_threshold``)
  divided by the camera-to-volume distance (camera to bbox centre); 0 where no cloud;
- ``cos_theta`` (H, W): cosine of θ_q, the angle between the sun's propagation direction and the
  direction toward the camera (= dot(sun_dir, view_dir));
- ``footprint`` (H, W): 1 where the view ray meets the cloud;

and the multiple scattering of the chosen transport:

- ``transport: all_orders`` (the default, :mod:`natscene.scatter.allorders`): ``sun_ms`` (B, Ng, Ns, H, W),
  every order >= 2 of the sun's light grouped into bands of orders, and ``sky_ms`` (4, B', Ng, Ns, H, W),
  every order >= 1 of the skylight for the dome's R, G, B distributions and a unit-radiance ground, both
  without the albedo, with the bands' geometric ratios (``sun_ratios``, ``sky_ratios``: (Ng, Ns, B)) that
  make beta compose in closed form (:mod:`natscene.scatter.bands`);
- ``transport: dobashi`` (the paper): ``multiple`` (K, Ng, Ns, H, W), E_m^(k)(q, g, e) of Eq. 7 for k in
  ``orders`` = 2..n_m (:mod:`natscene.scatter.multiple`), plus the ambient term through ``s_amb``.

The tracers take the volume's unitless sigma_t = e / ``extinction_scale`` (mu_t = sigma_t k rho).

On disk (``results/precompute/{volume}/{view}/``): ``single.exr`` (channels ``sun.e<e>``, ``amb.e<e>``),
``transmittance.exr`` (``T.e<e>``), ``geometry.exr`` (``t_c``, ``cos_theta``, ``footprint``), then
``allorders.exr`` (``sun.b<i>.g<g>.e<e>``, ``sky.<R|G|B|ground>.b<i>.g<g>.e<e>``; half floats, each channel
divided by its maximum, the maxima in the header) or ``multiple.exr`` (``k<k>.g<g>.e<e>``, float32), and
``meta.yaml`` (grids, bands and ratios, the sky dome, sample counts, noise). No wall-clock time is written
into any of them (timings go to the log): a rerun gives the same bytes.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from natscene.errors import InputError
from natscene.io import read_exr, read_yaml, write_exr, write_yaml

TRANSPORTS = ("all_orders", "dobashi")
SKY_CHANNELS = ("R", "G", "B", "ground")

DEFAULT_EXTINCTIONS = (0.0, 0.002, 0.005, 0.01, 0.02, 0.04, 0.08, 0.15, 0.3)   # 1/m
# 1/m: the physical range of a configured node or fitted extinction (0 is allowed as a node); checked on the config
# (natscene.config_checks), not here: a volume in other units (the tests' unit boxes) takes any extinction >= 0
EXTINCTION_RANGE = (1e-4, 1.0)
DEFAULT_GS = tuple(np.round(np.arange(10) * 0.1, 6))


@dataclass
class Tables:
    extinction: np.ndarray       # (Ns,) 1/m
    g: np.ndarray                # (Ng,)
    orders: list                 # e.g. [2, 3, 4]
    s_sun: np.ndarray            # (Ns, H, W)
    s_amb: np.ndarray            # (Ns, H, W)
    transmittance: np.ndarray    # (Ns, H, W)
    multiple: np.ndarray         # (K, Ng, Ns, H, W)
    t_c: np.ndarray              # (H, W)
    cos_theta: np.ndarray        # (H, W)
    footprint: np.ndarray        # (H, W)
    meta: dict = field(default_factory=dict)
    transport: str = "dobashi"
    sun_bands: tuple = ()
    sky_bands: tuple = ()
    sun_ms: np.ndarray | None = None       # (B, Ng, Ns, H, W)
    sky_ms: np.ndarray | None = None       # (4, B', Ng, Ns, H, W)
    sun_ratios: np.ndarray | None = None   # (Ng, Ns, B)
    sky_ratios: np.ndarray | None = None   # (Ng, Ns, B')

    @property
    def shape(self) -> tuple[int, int]:
        return self.t_c.shape

    def nbytes(self) -> int:
        arrays = (self.s_sun, self.s_amb, self.transmittance, self.multiple, self.t_c, self.cos_theta,
                  self.footprint, self.sun_ms, self.sky_ms)
        return int(sum(a.nbytes for a in arrays if a is not None))


def _tag(x: float) -> str:
    return f"{float(x):g}"


def check_grid(values, name: str, lo: float, hi: float, hi_open: bool = False) -> np.ndarray:
    """A strictly increasing grid inside [lo, hi] (or [lo, hi)), else InputError naming the config key."""
    v = np.asarray(values, np.float64)
    if v.ndim != 1 or v.size < 1:
        raise InputError(f"config key 'precompute.{name}': needs a non-empty list of numbers")
    if np.any(np.diff(v) <= 0):
        raise InputError(f"config key 'precompute.{name}': values must be strictly increasing, got {v.tolist()}")
    if v[0] < lo or v[-1] > hi or (hi_open and v[-1] >= hi):
        rng = f"[{lo}, {hi})" if hi_open else f"[{lo}, {hi}]"
        raise InputError(f"config key 'precompute.{name}': values must lie in {rng}, got {v.tolist()}")
    return v


def cloud_columns(volume) -> dict:
    """The volume's columns ∫ rho ds in metres along z (``horizontal``) and y (``vertical``): mean, p95, max over
    the rays that hit the cloud (:func:`natscene.volume.grid.column_statistics`)."""
    from natscene.volume.grid import column_statistics
    d = np.asarray(volume.density)
    vs = np.asarray(volume.voxel_size, np.float64)
    return {"horizontal": column_statistics(d, float(vs[2]), axis=0),
            "vertical": column_statistics(d, float(vs[1]), axis=1)}


def reference_distance(camera, volume) -> float:
    """Camera-to-volume distance used to normalise t_c: camera position to the bbox centre."""
    c = (np.asarray(volume.bbox_min, np.float64) + np.asarray(volume.bbox_max, np.float64)) / 2
    return float(np.linalg.norm(c - np.asarray(camera.position, np.float64)))


def geometry_images(camera, volume, sun_dir, t_hit: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t_c, cos_theta, footprint) from the march's distance to the cloud (NaN: no cloud)."""
    foot = np.isfinite(t_hit)
    t_c = np.where(foot, t_hit, 0.0) / reference_distance(camera, volume)
    s = np.asarray(sun_dir, np.float64)
    cos_t = camera.ray_directions() @ (s / np.linalg.norm(s))
    return t_c.astype(np.float32), cos_t.astype(np.float32), foot.astype(np.float32)


def check_noise_target(settings) -> None:
    """``noise_target`` is (median, p95) in [0, 1] and ``max_budget_scale`` >= 1, else InputError naming the key."""
    t = tuple(settings.noise_target)
    if len(t) != 2 or not all(0.0 <= float(x) <= 1.0 for x in t):
        raise InputError(f"config key 'precompute.all_orders.noise_target': needs [median, p95] in [0, 1], got {list(t)}")
    if not float(settings.max_budget_scale) >= 1.0:
        raise InputError(f"config key 'precompute.all_orders.max_budget_scale': must be >= 1, "
                         f"got {settings.max_budget_scale}")


def _stats(values: list) -> dict | None:
    v = np.concatenate(values) if values else np.zeros(0)
    return {"median": float(np.median(v)), "p95": float(np.percentile(v, 95))} if v.size else None


def _dobashi_multiple(med, camera, sigmas, gs, single, n_m, spp, seed, batch_spp, with_error, log):
    # sigmas: the volume's unitless sigma_t of each node (e / extinction_scale)
    """E_m^(k) (K, Ng, Ns, H, W) by per-order path tracing (Eq. 7) and its noise figures."""
    from natscene.scatter.multiple import trace_orders
    from natscene.scatter.phase import hg
    from scipy.ndimage import binary_dilation
    orders = list(range(2, n_m + 1))
    H, W = camera.height, camera.width
    multiple = np.zeros((len(orders), len(gs), len(sigmas), H, W), np.float32)
    single_cos = camera.ray_directions() @ (med.sun_dir / np.linalg.norm(med.sun_dir))
    foot = single["footprint"] > 0
    # only pixels whose view rays meet any density can score (T < 1 at the largest extinction), dilated by
    # one pixel for jittered rays at the silhouette; the others are exactly 0 and are not traced
    traced = np.flatnonzero(binary_dilation(single["T"][-1] < 1, iterations=1)) if sigmas[-1] > 0 else None
    rel_se = {k: [] for k in orders}
    weighted = {k: [] for k in orders}
    weighted_sum = []
    for i, s in enumerate(sigmas):
        if s <= 0 or not orders:
            continue
        ts = time.perf_counter()
        out = trace_orders(med, camera, float(s), gs, n_max=n_m, spp=spp, seed=seed * 1000 + i,
                           batch_spp=batch_spp, with_error=with_error, pixels=traced)
        est, se = out if with_error else (out, None)
        multiple[:, :, i] = est[1:]
        if with_error:
            for ki, k in enumerate(orders):
                e, u = est[k - 1][:, foot], se[k - 1][:, foot]
                ok = e > 0
                rel_se[k].append((u[ok] / e[ok]).astype(np.float32))
            # the same noise relative to the pixel's composed cloud radiance at beta = 1, L_amb = 0:
            # L = p(theta_q, g) S_sun + sum_k E^(k) (what the noise does to the image the GA sees)
            L = hg(single_cos[foot][None], gs[:, None]) * single["S_sun"][i][foot][None] + est[1:][:, :, foot].sum(0)
            okL = L > 0
            for ki, k in enumerate(orders):
                weighted[k].append((se[k - 1][:, foot][okL] / L[okL]).astype(np.float32))
            tot = np.sqrt((se[1:][:, :, foot] ** 2).sum(0))
            weighted_sum.append((tot[okL] / L[okL]).astype(np.float32))
        log(f"multiple scattering extinction={s * med.scale:g}/m: orders {orders[0]}..{n_m}, {len(gs)} g, {spp} spp "
            f"in {time.perf_counter() - ts:.1f} s")
    meta = {"orders": orders, "n_m": int(n_m), "spp": int(spp)}
    if with_error and orders:
        meta["relative_standard_error"] = {f"k{k}": _stats(v) for k, v in rel_se.items()}
        # standard error of E^(k) divided by the pixel's composed radiance (beta = 1, no ambient), and of
        # sum_k E^(k) (orders' errors combined in quadrature), over cloud pixels, all extinctions > 0 and g
        meta["pixel_relative_standard_error"] = {**{f"k{k}": _stats(v) for k, v in weighted.items()},
                                                 "sum": _stats(weighted_sum)}
        meta["traced_pixels"] = int(H * W if traced is None else traced.size)
    return orders, multiple, meta


NOISE_BETAS = (0.9, 0.99, 0.999)


def skylight_dome(sun_dir, sky: dict | None):
    """The sky dome that lights the cloud for the precompute and its settings (``precompute.skylight``)."""
    from natscene.scatter.skylight import daylight_dome
    sky = dict(sky or {})
    model = sky.get("model", "preetham")
    if model != "preetham":
        raise InputError(f"config key 'precompute.skylight.model': unknown sky model {model!r} (preetham)")
    return daylight_dome(sun_dir, float(sky.get("turbidity", 3.0)))


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
    per-pixel relative standard errors of :func:`_node_noise`, the sun and sky composed together, the median and
    the p95 over the cloud pixels, each the worst of the betas."""
    e = [v for k, v in noise.items() if k.startswith("sun_and_sky.") and v.size]
    return tuple(max((float(np.percentile(v, q)) for v in e), default=0.0) for q in (50, 95))


def composed_halves(vi, sun_bands, sky_bands, sky_w, beta: float) -> dict:
    """The two halves of one node's composed multiple scattering at albedo ``beta`` (Σ_b c_b(β) T_b per half):
    ``sun`` (orders >= 2), ``sky`` (R + G + B, orders >= 1) and ``sun_and_sky`` (luminance, weights ``sky_w`` of
    the dome's R, G, B and the ground, :func:`sky_luminance_weights`)."""
    from natscene.scatter.bands import band_weights
    cs = band_weights(sun_bands, vi.sun_ratios, beta)[0]
    ck = band_weights(sky_bands, vi.sky_ratios, beta)[0]
    sun = [np.tensordot(cs, vi.sun_halves[h], 1) for h in range(2)]
    sky = [np.tensordot(ck, vi.sky_halves[h][:3].sum(0), 1) for h in range(2)]
    both = [sun[h] + np.tensordot(ck, np.tensordot(sky_w, vi.sky_halves[h], 1), 1) for h in range(2)]
    return {"sun": sun, "sky": sky, "sun_and_sky": both}


def _node_noise(vi, sun_bands, sky_bands, sky_w, foot, single_sun) -> dict:
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
                pixel = b * single_sun + m
                ok = foot & (pixel > 0)
                out[f"pixel.beta{b:g}"] = (se[ok] / pixel[ok]).astype(np.float32)
    return out


def _all_orders_multiple(volume, camera, sun_dir, sigmas, gs, settings, sky, seed, log, single):
    """Band images of the sun's and the sky's light over the (g, extinction) grid, their ratios and noise
    (``sigmas``: the volume's unitless sigma_t of each node; ``single``: the precompute's
    :func:`natscene.scatter.single.march_view` of the grid)."""
    from natscene.scatter.allorders import Lighting, Scene, view_images
    from natscene.scatter.skylight import irradiance
    from natscene.sky.daylight import preetham_rgb
    dome = skylight_dome(sun_dir, sky)
    scene = Scene(volume, Lighting(np.asarray(sun_dir, np.float64), dome), settings)
    H, W = camera.height, camera.width
    Ng, Ns = len(gs), len(sigmas)
    sb, kb = settings.sun_bands, settings.sky_bands
    sun_ms = np.zeros((len(sb), Ng, Ns, H, W), np.float32)
    sky_ms = np.zeros((4, len(kb), Ng, Ns, H, W), np.float32)
    sun_r = np.ones((Ng, Ns, len(sb)))
    sky_r = np.ones((Ng, Ns, len(kb)))
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
    scales = []
    todo = [(i, j) for i in range(Ns) if sigmas[i] > 0 for j in range(Ng)]
    t0 = time.perf_counter()
    for n, (i, j) in enumerate(todo):
        single_sun = hg(cos_q, gs[j]) * single["S_sun"][i]          # the pixel's order 1 over beta

        def node_noise(vi):
            return _node_noise(vi, sb, kb, sky_w, foot, single_sun)

        vi = view_images(scene, camera, float(sigmas[i]), float(gs[j]), seed=seed * 100003 + i * 101 + j,
                         noise=lambda vi: target_figure(node_noise(vi)))
        sun_ms[:, j, i] = vi.sun
        sky_ms[:, :, j, i] = vi.sky
        sun_r[j, i], sky_r[j, i] = vi.sun_ratios, vi.sky_ratios
        for k in counts:
            counts[k] += int(vi.stats.get(k, 0))
        truncated = max(truncated, vi.stats.get("sun_truncated", 0.0))
        scales.append(float(vi.stats.get("budget_scale", 1.0)))
        for k, v in node_noise(vi).items():
            noise[k].append(v)
        el = time.perf_counter() - t0
        log(f"all orders extinction={sigmas[i] * volume.extinction_scale:.4g}/m g={gs[j]:g}: {vi.stats.get('sun_photons', 0)} sun + "
            f"{vi.stats.get('sky_photons', 0)} sky photons (budget x{scales[-1]:.2f}; {n + 1}/{len(todo)}, {el:.0f} s, "
            f"about {el / (n + 1) * (len(todo) - n - 1):.0f} s left)")
    dirs = camera.ray_directions()
    view_rgb = preetham_rgb(dirs.reshape(-1, 3), sun_dir, float((sky or {}).get("turbidity", 3.0))).reshape(-1, 3)
    s = np.asarray(sun_dir, np.float64)
    meta = {
        "sun_bands": [[a, e] for a, e in sb], "sky_bands": [[a, e] for a, e in kb],
        "sun_ratios": np.round(sun_r, 6).tolist(), "sky_ratios": np.round(sky_r, 6).tolist(),
        "skylight": {"model": "preetham", "turbidity": float((sky or {}).get("turbidity", 3.0)),
                     "view_mean_rgb": view_rgb.mean(0).tolist(), "irradiance_rgb": irradiance(dome).tolist(),
                     "sun_elevation_sin": float(s[1] / np.linalg.norm(s))},
        "photons": counts, "truncated_light": float(truncated),
        # photons per node as a multiple of the collision budget's (noise_target tops the noisy nodes up),
        # per node, extinction > 0 in order, g within each extinction
        "budget_scale": [round(x, 3) for x in scales],
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
        "pixel_relative_standard_error": {k: _stats(v) for k, v in noise.items()},
    }
    return sun_ms, sky_ms, sun_r, sky_r, meta


def precompute(volume, camera, sun_dir, extinctions=DEFAULT_EXTINCTIONS, gs=DEFAULT_GS, n_m: int = 4, spp: int = 256,
               seed: int = 0, step_voxels: float = 0.5, supersample: int = 4, rho_threshold: float = 0.01,
               batch_spp: int | None = None, with_error: bool = True, log=None, transport: str = "all_orders",
               all_orders=None, skylight: dict | None = None) -> Tables:
    """All tables for one volume, camera and sun (see the module docstring); ``extinctions`` in 1/m."""
    from natscene.scatter.allorders import AllOrdersSettings
    from natscene.scatter.medium import make_medium
    from natscene.scatter.single import march_view

    if transport not in TRANSPORTS:
        raise InputError(f"config key 'precompute.transport': unknown transport {transport!r} "
                         f"(one of {', '.join(TRANSPORTS)})")
    extinctions = check_grid(extinctions, "extinction", 0.0, np.inf)   # the physical range: config_checks
    sigmas = extinctions / float(volume.extinction_scale)          # the tracers' unitless sigma_t
    gs = check_grid(gs, "g", -1.0, 1.0, hi_open=True)
    if n_m < 1:
        raise InputError(f"config key 'precompute.n_m': must be >= 1, got {n_m}")
    if spp < 1:
        raise InputError(f"config key 'precompute.spp': must be >= 1, got {spp}")
    if transport == "all_orders" and all_orders is not None:
        check_noise_target(all_orders)
    log = log or (lambda msg: None)
    t0 = time.perf_counter()
    med = make_medium(volume, sun_dir)
    single = march_view(med, camera, sigmas, step_voxels=step_voxels, supersample=supersample,
                        rho_threshold=rho_threshold)
    log(f"single scattering + transmittance marched for {len(sigmas)} extinctions in {time.perf_counter() - t0:.1f} s")
    H, W = camera.height, camera.width
    t_c, cos_t, footprint = geometry_images(camera, volume, med.sun_dir, single["t_hit"])
    meta = {"transport": transport, "extinction": extinctions.tolist(), "g": gs.tolist(), "seed": int(seed),
            "step_voxels": float(step_voxels), "supersample": int(supersample),
            "rho_threshold": float(rho_threshold), "resolution": [W, H],
            "camera": {"position": list(camera.position), "look_at": list(camera.look_at), "up": list(camera.up),
                       "fov": camera.fov},
            "sun_dir": med.sun_dir.tolist(), "extinction_scale": float(volume.extinction_scale),
            "reference_distance": reference_distance(camera, volume), "footprint_pixels": int(footprint.sum()),
            # ∫ rho ds through the cloud in metres (times an extinction in 1/m: its optical depth)
            "column_m": cloud_columns(volume)}
    extra = {}
    if transport == "dobashi":
        orders, multiple, m = _dobashi_multiple(med, camera, sigmas, gs, single, n_m, spp, seed, batch_spp,
                                                with_error, log)
        meta.update(m)
    else:
        orders, multiple = [], np.zeros((0, len(gs), len(sigmas), H, W), np.float32)
        settings = all_orders if all_orders is not None else AllOrdersSettings()
        sun_ms, sky_ms, sun_r, sky_r, m = _all_orders_multiple(volume, camera, med.sun_dir, sigmas, gs, settings,
                                                               skylight, seed, log, single)
        meta.update(m)
        extra = {"transport": transport, "sun_bands": tuple(settings.sun_bands),
                 "sky_bands": tuple(settings.sky_bands), "sun_ms": sun_ms, "sky_ms": sky_ms,
                 "sun_ratios": sun_r, "sky_ratios": sky_r}
    log(f"precompute done in {time.perf_counter() - t0:.1f} s")
    return Tables(extinctions, gs, orders, single["S_sun"], single["S_amb"], single["T"], multiple, t_c, cos_t,
                  footprint, meta, **extra)


def table_files(transport: str) -> tuple[str, ...]:
    """The files :func:`save_tables` writes for ``transport`` (the precompute rule's outputs)."""
    return ("single.exr", "transmittance.exr", "allorders.exr" if transport == "all_orders" else "multiple.exr",
            "geometry.exr", "meta.yaml")


def _allorders_names(tables) -> list[str]:
    sig = [_tag(s) for s in tables.extinction]
    gt = [_tag(g) for g in tables.g]
    names = [f"sun.b{b}.g{g}.e{s}" for b in range(len(tables.sun_bands)) for g in gt for s in sig]
    names += [f"sky.{c}.b{b}.g{g}.e{s}" for c in SKY_CHANNELS for b in range(len(tables.sky_bands))
              for g in gt for s in sig]
    return names


def save_tables(directory, tables: Tables, extra_meta: dict | None = None) -> dict:
    """Write the files of the precompute (:func:`table_files`); returns the meta written (with file sizes)."""
    d = Path(directory)
    sig = [_tag(s) for s in tables.extinction]
    gt = [_tag(g) for g in tables.g]
    attrs = {"extinction": tables.extinction.tolist(), "g": tables.g.tolist(), "orders": list(tables.orders),
             "transport": tables.transport}
    write_exr(d / "single.exr", np.concatenate([tables.s_sun, tables.s_amb]).transpose(1, 2, 0),
              [f"sun.e{s}" for s in sig] + [f"amb.e{s}" for s in sig], attrs=attrs, stage="precompute")
    write_exr(d / "transmittance.exr", tables.transmittance.transpose(1, 2, 0), [f"T.e{s}" for s in sig],
              attrs=attrs, stage="precompute")
    H, W = tables.t_c.shape
    if tables.transport == "all_orders":
        data = np.concatenate([tables.sun_ms.reshape(-1, H, W), tables.sky_ms.reshape(-1, H, W)])
        scale = data.reshape(len(data), -1).max(1).astype(np.float64)
        scale[scale <= 0] = 1.0
        # each channel divided by its maximum: half floats then keep 4.9e-4 relative precision over 14 octaves
        write_exr(d / "allorders.exr", (data / scale[:, None, None]).transpose(1, 2, 0), _allorders_names(tables),
                  attrs={**attrs, "channel_scale": scale.tolist()}, half=True, stage="precompute")
    else:
        K, Ng, Ns = tables.multiple.shape[:3]
        names = [f"k{k}.g{g}.e{s}" for k in tables.orders for g in gt for s in sig]
        if K:
            write_exr(d / "multiple.exr", tables.multiple.reshape(K * Ng * Ns, H, W).transpose(1, 2, 0), names,
                      attrs=attrs, stage="precompute")
        else:
            write_exr(d / "multiple.exr", np.zeros((H, W, 1), np.float32), ["none"], attrs=attrs, stage="precompute")
    write_exr(d / "geometry.exr", np.stack([tables.t_c, tables.cos_theta, tables.footprint], -1),
              ["t_c", "cos_theta", "footprint"], attrs=attrs, stage="precompute")
    meta = dict(tables.meta)
    meta.update(extra_meta or {})
    meta["files_bytes"] = {f: (d / f).stat().st_size for f in table_files(tables.transport) if f != "meta.yaml"}
    meta["memory_bytes"] = tables.nbytes()
    write_yaml(d / "meta.yaml", meta)
    return meta


def _stack(img, names, H, W) -> np.ndarray:
    return np.moveaxis(img.channel(*names).reshape(H, W, -1), -1, 0)


def load_tables(directory) -> Tables:
    """Read the tables written by :func:`save_tables` (the ``precompute`` rule)."""
    d = Path(directory)
    meta = read_yaml(d / "meta.yaml")
    try:
        sigmas = np.asarray(meta["extinction"], np.float64)
        gs = np.asarray(meta["g"], np.float64)
        transport = meta.get("transport", "dobashi")
        orders = [int(k) for k in meta.get("orders", [])]
    except (KeyError, TypeError) as e:
        raise InputError(f"{d / 'meta.yaml'}: missing key {e}; rerun the precompute rule") from e
    if transport not in TRANSPORTS:
        raise InputError(f"{d / 'meta.yaml'}: unknown transport {transport!r}; rerun the precompute rule")
    sig = [_tag(s) for s in sigmas]
    gt = [_tag(g) for g in gs]
    single = read_exr(d / "single.exr")
    trans = read_exr(d / "transmittance.exr")
    geo = read_exr(d / "geometry.exr")
    extra = {}
    try:
        H, W = geo.pixels.shape[:2]
        s_sun = _stack(single, [f"sun.e{s}" for s in sig], H, W)
        s_amb = _stack(single, [f"amb.e{s}" for s in sig], H, W)
        T = _stack(trans, [f"T.e{s}" for s in sig], H, W)
        multiple = np.zeros((0, len(gs), len(sigmas), H, W), np.float32)
        if transport == "dobashi" and orders:
            mult = read_exr(d / "multiple.exr")
            names = [f"k{k}.g{g}.e{s}" for k in orders for g in gt for s in sig]
            multiple = np.ascontiguousarray(_stack(mult, names, H, W).reshape(len(orders), len(gs), len(sigmas), H, W))
        elif transport == "all_orders":
            sb = tuple((int(a), None if e is None else int(e)) for a, e in meta["sun_bands"])
            kb = tuple((int(a), None if e is None else int(e)) for a, e in meta["sky_bands"])
            ao = read_exr(d / "allorders.exr")
            probe = Tables(sigmas, gs, [], None, None, None, None, np.zeros((H, W)), None, None, {},
                           sun_bands=sb, sky_bands=kb)
            names = _allorders_names(probe)
            scale = np.asarray(ao.attrs.get("channel_scale"), np.float64)
            if scale.size != len(names):
                raise InputError(f"{d / 'allorders.exr'}: channel scales missing; rerun the precompute rule")
            data = _stack(ao, names, H, W).astype(np.float32) * scale[:, None, None].astype(np.float32)
            n_sun = len(sb) * len(gs) * len(sigmas)
            extra = {"transport": "all_orders", "sun_bands": sb, "sky_bands": kb,
                     "sun_ms": np.ascontiguousarray(data[:n_sun].reshape(len(sb), len(gs), len(sigmas), H, W)),
                     "sky_ms": np.ascontiguousarray(data[n_sun:].reshape(4, len(kb), len(gs), len(sigmas), H, W)),
                     "sun_ratios": np.asarray(meta["sun_ratios"], np.float64),
                     "sky_ratios": np.asarray(meta["sky_ratios"], np.float64)}
        t_c, cos_t, foot = (geo.channel(n) for n in ("t_c", "cos_theta", "footprint"))
    except KeyError as e:
        raise InputError(f"{d}: precompute images lack channels ({e}); rerun the precompute rule") from e
    return Tables(sigmas, gs, orders, np.ascontiguousarray(s_sun), np.ascontiguousarray(s_amb),
                  np.ascontiguousarray(T), multiple, t_c.copy(), cos_t.copy(), foot.copy(), meta, **extra)
