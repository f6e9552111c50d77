"""
Precomputed tables
==================

Defines the precomputed intermediate images for one volume, camera and sun (Dobashi et al. 2012, §4.3, Eqs. 5–9),
for either transport model (``precompute.transport``):

-   :class:`Tables`, :func:`precompute`: all tables of one view; :data:`EXTINCTION_RANGE`, the physical range
    of an extinction.
-   :func:`save_tables`, :func:`load_tables`, :func:`table_files`: the tables on disk.
-   :func:`geometry_images`, :func:`reference_distance`: t_c, cos θ_q and the footprint from the view march.

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
  without the albedo, with the bands' order distributions (``sun_orders`` (Ng, Ns, B, J, 2), ``sky_orders``
  (Ng, Ns, 2, B', J, 2): the dome's and the ground's) that make beta compose in closed form
  (:mod:`natscene.scatter.bands`);
- ``transport: dobashi`` (the paper): ``multiple`` (K, Ng, Ns, H, W), E_m^(k)(q, g, e) of Eq. 7 for k in
  ``orders`` = 2..n_m (:mod:`natscene.scatter.multiple`), plus the ambient term through ``s_amb``.

The tracers take the volume's unitless sigma_t = e / ``extinction_scale`` (mu_t = sigma_t k rho).

On disk (``results/precompute/{volume}/{view}/``): ``single.exr`` (channels ``sun.e<e>``, ``amb.e<e>``),
``transmittance.exr`` (``T.e<e>``), ``geometry.exr`` (``t_c``, ``cos_theta``, ``footprint``), then
``allorders.exr`` (``sun.b<i>.g<g>.e<e>``, ``sky.<R|G|B|ground>.b<i>.g<g>.e<e>``; half floats, each channel
divided by its maximum, the maxima and the bands' order distributions in the header) or ``multiple.exr``
(``k<k>.g<g>.e<e>``, float32), and ``meta.yaml`` (grids, bands, the sky dome, sample counts, noise). No
wall-clock time is written into any of them (timings go to the log): a rerun gives the same bytes.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from natscene.errors import InputError
from natscene.io import read_exr, read_yaml, write_exr, write_yaml

__all__ = ["EXTINCTION_RANGE", "Tables", "precompute", "save_tables", "load_tables", "table_files",
           "geometry_images", "reference_distance"]


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
    sun_orders: np.ndarray | None = None   # (Ng, Ns, B, J, 2)
    sky_orders: np.ndarray | None = None   # (Ng, Ns, 2, B', J, 2): the dome's R, G, B, the ground (SKY_GROUPS)

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


def precompute(volume, camera, sun_dir, extinctions=DEFAULT_EXTINCTIONS, gs=DEFAULT_GS, n_m: int = 4, spp: int = 256,
               seed: int = 0, step_voxels: float = 0.5, supersample: int = 4, rho_threshold: float = 0.01,
               batch_spp: int | None = None, with_error: bool = True, log=None, transport: str = "all_orders",
               all_orders=None, skylight: dict | None = None) -> Tables:
    """All tables for one volume, camera and sun (see the module docstring); ``extinctions`` in 1/m. The
    transport's part (its multiple scattering) comes from :mod:`natscene.scatter.transport`: ``n_m``, ``spp``,
    ``batch_spp``, ``with_error`` are the ``dobashi`` transport's, ``all_orders`` (its settings) and ``skylight``
    the ``all_orders`` transport's."""
    from natscene.scatter.medium import make_medium
    from natscene.scatter.single import march_view
    from natscene.scatter.transport import get

    model = get(transport)
    extinctions = check_grid(extinctions, "extinction", 0.0, np.inf)   # the physical range: config_checks
    sigmas = extinctions / float(volume.extinction_scale)          # the tracers' unitless sigma_t
    gs = check_grid(gs, "g", -1.0, 1.0, hi_open=True)
    if n_m < 1:
        raise InputError(f"config key 'precompute.n_m': must be >= 1, got {n_m}")
    if spp < 1:
        raise InputError(f"config key 'precompute.spp': must be >= 1, got {spp}")
    model.validate(all_orders)
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
    fields, m = model.precompute(volume, med, camera, sigmas, gs, single, settings=all_orders, skylight=skylight,
                                 n_m=n_m, spp=spp, seed=seed, batch_spp=batch_spp, with_error=with_error, log=log)
    meta.update(m)
    orders = fields.pop("orders", [])
    multiple = fields.pop("multiple", np.zeros((0, len(gs), len(sigmas), H, W), np.float32))
    log(f"precompute done in {time.perf_counter() - t0:.1f} s")
    return Tables(extinctions, gs, orders, single["S_sun"], single["S_amb"], single["T"], multiple, t_c, cos_t,
                  footprint, meta, transport=transport, **fields)


def table_files(transport: str) -> tuple[str, ...]:
    """The files :func:`save_tables` writes for ``transport`` (the precompute rule's outputs)."""
    from natscene.scatter.transport import get
    return ("single.exr", "transmittance.exr", get(transport).tables_file, "geometry.exr", "meta.yaml")


def save_tables(directory, tables: Tables, extra_meta: dict | None = None) -> dict:
    """Write the files of the precompute (:func:`table_files`); returns the meta written (with file sizes)."""
    from natscene.scatter.transport import of
    d = Path(directory)
    sig = [_tag(s) for s in tables.extinction]
    attrs = {"extinction": tables.extinction.tolist(), "g": tables.g.tolist(), "orders": list(tables.orders),
             "transport": tables.transport}
    write_exr(d / "single.exr", np.concatenate([tables.s_sun, tables.s_amb]).transpose(1, 2, 0),
              [f"sun.e{s}" for s in sig] + [f"amb.e{s}" for s in sig], attrs=attrs, stage="precompute")
    write_exr(d / "transmittance.exr", tables.transmittance.transpose(1, 2, 0), [f"T.e{s}" for s in sig],
              attrs=attrs, stage="precompute")
    of(tables).save(d, tables, attrs)
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
    from natscene.scatter.transport import TRANSPORTS, get
    d = Path(directory)
    meta = read_yaml(d / "meta.yaml")
    try:
        extinctions = np.asarray(meta["extinction"], np.float64)
        gs = np.asarray(meta["g"], np.float64)
        transport = meta.get("transport", "dobashi")
        orders = [int(k) for k in meta.get("orders", [])]
    except (KeyError, TypeError) as e:
        raise InputError(f"{d / 'meta.yaml'}: missing key {e}; rerun the precompute rule") from e
    if transport not in TRANSPORTS:
        raise InputError(f"{d / 'meta.yaml'}: unknown transport {transport!r}; rerun the precompute rule")
    sig = [_tag(s) for s in extinctions]
    single = read_exr(d / "single.exr")
    trans = read_exr(d / "transmittance.exr")
    geo = read_exr(d / "geometry.exr")
    try:
        H, W = geo.pixels.shape[:2]
        s_sun = _stack(single, [f"sun.e{s}" for s in sig], H, W)
        s_amb = _stack(single, [f"amb.e{s}" for s in sig], H, W)
        T = _stack(trans, [f"T.e{s}" for s in sig], H, W)
        fields = get(transport).load(d, meta, extinctions, gs, orders, (H, W))
        multiple = fields.pop("multiple", np.zeros((0, len(gs), len(extinctions), H, W), np.float32))
        t_c, cos_t, foot = (geo.channel(n) for n in ("t_c", "cos_theta", "footprint"))
    except KeyError as e:
        raise InputError(f"{d}: precompute images lack channels ({e}); rerun the precompute rule") from e
    return Tables(extinctions, gs, orders, np.ascontiguousarray(s_sun), np.ascontiguousarray(s_amb),
                  np.ascontiguousarray(T), multiple, t_c.copy(), cos_t.copy(), foot.copy(), meta, transport=transport,
                  **fields)
