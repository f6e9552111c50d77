"""The precomputed intermediate images of Dobashi 2012 §4.3 for one volume, camera and sun.

For a sigma_t grid (default 0, 0.1, ..., 1) and a g grid (default 0, 0.1, ..., 0.9: HG with g -> 1 is a
delta lobe, 0.9 is the documented maximum), the tables hold, per pixel q:

- ``s_sun``, ``s_amb`` (Ns, H, W): the two integrals of Eq. 5 (:mod:`natscene.scatter.single`);
- ``transmittance`` (Ns, H, W): tau(x_v, x_b, sigma_t) of Eq. 9;
- ``multiple`` (K, Ng, Ns, H, W): E_m^(k)(q, g, sigma_t) of Eq. 7 for k in ``orders`` = 2..n_m
  (:mod:`natscene.scatter.multiple`, all g from the same paths, one path-tracing pass per sigma_t > 0);
- ``t_c`` (H, W): distance from the camera to the cloud (first sample with rho >= ``rho_threshold``)
  divided by the camera-to-volume distance (camera to bbox centre), DESIGN §3; 0 where no cloud;
- ``cos_theta`` (H, W): cosine of θ_q, the angle between the sun's propagation direction and the
  direction toward the camera (= dot(sun_dir, view_dir));
- ``footprint`` (H, W): 1 where the view ray meets the cloud.

On disk (``results/precompute/{volume}/{view}/``): ``single.exr`` (channels ``sun.s<σ>``, ``amb.s<σ>``),
``transmittance.exr`` (``T.s<σ>``), ``multiple.exr`` (``k<k>.g<g>.s<σ>``), ``geometry.exr``
(``t_c``, ``cos_theta``, ``footprint``), all float32, and ``meta.yaml`` (grids, spp, timings, view).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from natscene.io import InputError, read_exr, read_yaml, write_exr, write_yaml

DEFAULT_SIGMAS = tuple(np.round(np.arange(11) * 0.1, 6))
DEFAULT_GS = tuple(np.round(np.arange(10) * 0.1, 6))


@dataclass
class Tables:
    sigma_t: np.ndarray          # (Ns,)
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

    @property
    def shape(self) -> tuple[int, int]:
        return self.t_c.shape

    def nbytes(self) -> int:
        return int(sum(a.nbytes for a in (self.s_sun, self.s_amb, self.transmittance, self.multiple, self.t_c,
                                          self.cos_theta, self.footprint)))


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


def precompute(volume, camera, sun_dir, sigmas=DEFAULT_SIGMAS, gs=DEFAULT_GS, n_m: int = 4, spp: int = 256,
               seed: int = 0, step_voxels: float = 0.5, supersample: int = 4, rho_threshold: float = 0.01,
               batch_spp: int | None = None, with_error: bool = True, log=None) -> Tables:
    """All tables for one volume, camera and sun (see the module docstring)."""
    from natscene.scatter.medium import make_medium
    from natscene.scatter.multiple import trace_orders
    from natscene.scatter.single import march_view

    sigmas = check_grid(sigmas, "sigma_t", 0.0, 1e6)
    gs = check_grid(gs, "g", -1.0, 1.0, hi_open=True)
    if n_m < 1:
        raise InputError(f"config key 'precompute.n_m': must be >= 1, got {n_m}")
    log = log or (lambda msg: None)
    timings = {}
    t0 = time.perf_counter()
    med = make_medium(volume, sun_dir)
    timings["sun_depth_s"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    single = march_view(med, camera, sigmas, step_voxels=step_voxels, supersample=supersample,
                        rho_threshold=rho_threshold)
    timings["single_s"] = time.perf_counter() - t1
    log(f"single scattering + transmittance marched for {len(sigmas)} sigma_t in {timings['single_s']:.1f} s")
    orders = list(range(2, n_m + 1))
    H, W = camera.height, camera.width
    multiple = np.zeros((len(orders), len(gs), len(sigmas), H, W), np.float32)
    single_cos = camera.ray_directions() @ (med.sun_dir / np.linalg.norm(med.sun_dir))
    rel_se = {k: [] for k in orders}
    foot = single["footprint"] > 0
    # only pixels whose view rays meet any density can score (T < 1 at the largest sigma_t), dilated by
    # one pixel for jittered rays at the silhouette; the others are exactly 0 and are not traced
    from scipy.ndimage import binary_dilation
    traced = np.flatnonzero(binary_dilation(single["T"][-1] < 1, iterations=1)) if sigmas[-1] > 0 else None
    weighted = {k: [] for k in orders}
    weighted_sum = []
    t2 = time.perf_counter()
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
            from natscene.scatter.phase import hg
            L = hg(single_cos[foot][None], gs[:, None]) * single["S_sun"][i][foot][None] + est[1:][:, :, foot].sum(0)
            okL = L > 0
            for ki, k in enumerate(orders):
                weighted[k].append((se[k - 1][:, foot][okL] / L[okL]).astype(np.float32))
            tot = np.sqrt((se[1:][:, :, foot] ** 2).sum(0))
            weighted_sum.append((tot[okL] / L[okL]).astype(np.float32))
        log(f"multiple scattering sigma_t={s:g}: orders {orders[0]}..{n_m}, {len(gs)} g, {spp} spp "
            f"in {time.perf_counter() - ts:.1f} s")
    timings["multiple_s"] = time.perf_counter() - t2
    timings["total_s"] = time.perf_counter() - t0
    t_c, cos_t, footprint = geometry_images(camera, volume, med.sun_dir, single["t_hit"])
    meta = {"sigma_t": sigmas.tolist(), "g": gs.tolist(), "orders": orders, "n_m": int(n_m), "spp": int(spp),
            "seed": int(seed), "step_voxels": float(step_voxels), "supersample": int(supersample),
            "rho_threshold": float(rho_threshold), "resolution": [W, H],
            "camera": {"position": list(camera.position), "look_at": list(camera.look_at), "up": list(camera.up),
                       "fov": camera.fov},
            "sun_dir": med.sun_dir.tolist(), "extinction_scale": float(volume.extinction_scale),
            "reference_distance": reference_distance(camera, volume),
            "footprint_pixels": int(footprint.sum()), "timings": timings}
    if with_error and orders:
        meta["relative_standard_error"] = {
            f"k{k}": ({"median": float(np.median(np.concatenate(v))), "p95": float(np.percentile(np.concatenate(v), 95))}
                      if v and np.concatenate(v).size else None) for k, v in rel_se.items()}

        def stats(v):
            v = np.concatenate(v) if v else np.zeros(0)
            return {"median": float(np.median(v)), "p95": float(np.percentile(v, 95))} if v.size else None
        # standard error of E^(k) divided by the pixel's composed radiance (beta = 1, no ambient), and of
        # sum_k E^(k) (orders' errors combined in quadrature), over cloud pixels, all sigma_t > 0 and g
        meta["pixel_relative_standard_error"] = {**{f"k{k}": stats(v) for k, v in weighted.items()},
                                                 "sum": stats(weighted_sum)}
        meta["traced_pixels"] = int(H * W if traced is None else traced.size)
    return Tables(sigmas, gs, orders, single["S_sun"], single["S_amb"], single["T"], multiple, t_c, cos_t,
                  footprint, meta)


def save_tables(directory, tables: Tables, extra_meta: dict | None = None) -> dict:
    """Write the five files of the precompute; returns the meta written (with file sizes)."""
    d = Path(directory)
    sig = [_tag(s) for s in tables.sigma_t]
    gt = [_tag(g) for g in tables.g]
    attrs = {"sigma_t": tables.sigma_t.tolist(), "g": tables.g.tolist(), "orders": list(tables.orders)}
    write_exr(d / "single.exr", np.concatenate([tables.s_sun, tables.s_amb]).transpose(1, 2, 0),
              [f"sun.s{s}" for s in sig] + [f"amb.s{s}" for s in sig], attrs=attrs, stage="precompute")
    write_exr(d / "transmittance.exr", tables.transmittance.transpose(1, 2, 0), [f"T.s{s}" for s in sig],
              attrs=attrs, stage="precompute")
    K, Ng, Ns, H, W = tables.multiple.shape
    names = [f"k{k}.g{g}.s{s}" for k in tables.orders for g in gt for s in sig]
    if K:
        write_exr(d / "multiple.exr", tables.multiple.reshape(K * Ng * Ns, H, W).transpose(1, 2, 0), names,
                  attrs=attrs, stage="precompute")
    else:
        write_exr(d / "multiple.exr", np.zeros((H, W, 1), np.float32), ["none"], attrs=attrs, stage="precompute")
    write_exr(d / "geometry.exr", np.stack([tables.t_c, tables.cos_theta, tables.footprint], -1),
              ["t_c", "cos_theta", "footprint"], attrs=attrs, stage="precompute")
    meta = dict(tables.meta)
    meta.update(extra_meta or {})
    meta["files_bytes"] = {f: (d / f).stat().st_size for f in
                           ("single.exr", "transmittance.exr", "multiple.exr", "geometry.exr")}
    meta["memory_bytes"] = tables.nbytes()
    write_yaml(d / "meta.yaml", meta)
    return meta


def load_tables(directory) -> Tables:
    """Read the tables written by :func:`save_tables` (the ``precompute`` rule)."""
    d = Path(directory)
    meta = read_yaml(d / "meta.yaml")
    try:
        sigmas = np.asarray(meta["sigma_t"], np.float64)
        gs = np.asarray(meta["g"], np.float64)
        orders = [int(k) for k in meta["orders"]]
    except (KeyError, TypeError) as e:
        raise InputError(f"{d / 'meta.yaml'}: missing key {e}; rerun the precompute rule") from e
    sig = [_tag(s) for s in sigmas]
    gt = [_tag(g) for g in gs]
    single = read_exr(d / "single.exr")
    trans = read_exr(d / "transmittance.exr")
    geo = read_exr(d / "geometry.exr")
    try:
        s_sun = np.moveaxis(single.channel(*[f"sun.s{s}" for s in sig]).reshape(*single.pixels.shape[:2], -1), -1, 0)
        s_amb = np.moveaxis(single.channel(*[f"amb.s{s}" for s in sig]).reshape(*single.pixels.shape[:2], -1), -1, 0)
        T = np.moveaxis(trans.channel(*[f"T.s{s}" for s in sig]).reshape(*trans.pixels.shape[:2], -1), -1, 0)
        H, W = geo.pixels.shape[:2]
        if orders:
            mult = read_exr(d / "multiple.exr")
            names = [f"k{k}.g{g}.s{s}" for k in orders for g in gt for s in sig]
            m = mult.channel(*names).reshape(H, W, -1)
            multiple = np.ascontiguousarray(np.moveaxis(m, -1, 0).reshape(len(orders), len(gs), len(sigmas), H, W))
        else:
            multiple = np.zeros((0, len(gs), len(sigmas), H, W), np.float32)
        t_c, cos_t, foot = (geo.channel(n) for n in ("t_c", "cos_theta", "footprint"))
    except KeyError as e:
        raise InputError(f"{d}: precompute images lack channels ({e}); rerun the precompute rule") from e
    return Tables(sigmas, gs, orders, np.ascontiguousarray(s_sun), np.ascontiguousarray(s_amb),
                  np.ascontiguousarray(T), multiple, t_c.copy(), cos_t.copy(), foot.copy(), meta)
