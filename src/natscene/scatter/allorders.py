"""
All-orders images of one view
=============================

Defines the band images of the all-orders transport: every scattering order of the sun's light and the
skylight, per pixel, by bands (the remedies of Dobashi et al. 2012, §7):

-   :class:`AllOrdersSettings`, :func:`settings_from_config`, :func:`frame_settings`: the transport's settings
    (of the precompute, of a shot's frames); :func:`render_settings`: a shot's render section completed.
-   :class:`Lighting`, :class:`Scene`: what lights the cloud, and the volume prepared once for a view.
-   :func:`view_images`: the band images of one view at (sigma_t, g), as two independent halves
    (:class:`ViewImages`).
-   :func:`standard_error`, :func:`budget_scale`: the per-pixel noise of two halves, and the photon count a noise
    target needs.

Dobashi 2012 truncates multiple scattering at order 4 and adds a constant ambient term L_amb (§3); his §7
names both limits and the remedy (order bands after Bouthors et al. 2008, the skylight as a light source).
For one view (camera + sun), one sigma_t and one g this module computes, with photon tracing
(:mod:`.photons`) into an in-scatter cache gathered along the view rays (:mod:`.inscatter`):

- ``sun`` (B_sun, H, W): the light of each band of orders >= 2 of the sun's multiple scattering, per unit
  sun irradiance and without the albedo (order 1 is the ray-marched S_sun of Eq. 5);
- ``sky`` (4, B_sky, H, W): the light of each band of orders >= 1 of the skylight, without the albedo, for
  the dome's R, G, B radiance distributions and a unit-radiance ground (lower hemisphere); order 1 by shadow rays
  at the fine cache's cells (:mod:`natscene.scatter.sky_first`, ``sky_order1_points`` > 0: one set of points per
  view serves every node, :meth:`Scene.shadow_samples`) or from the sky photons' first flights;
- the bands' order distributions of the light in the camera's frame
  (:func:`natscene.scatter.bands.order_distribution`; the sky's dome and ground each their own), so that any
  albedo composes in closed form (:func:`natscene.scatter.bands.band_weights`,
  :func:`natscene.scatter.bands.channel_weights`);
- a noise estimate: the photons are traced as two independent halves, and the images of the halves give
  each pixel's standard error (the cache and the gather are linear in the tallies, so the mean of the two
  halves is exactly the result of tracing them together). A caller that needs no noise figure (a shot's frame)
  asks for the whole run: the halves' tallies are averaged before the gather, whose cost grows with the number
  of images it gathers, so one gather serves both.

Low orders vary over a mean free path near the lit surface and are cached in cells of ``fine_voxels``;
bands from order 5 on are smooth (they have diffused over several transport mean free paths) and use
cells of ``coarse_voxels``. Every tally is weighted by the camera transmittance at its point
(:func:`natscene.scatter.inscatter.visibility`), so a cell holds the in-scattered radiance of the part
of it the camera sees (:func:`natscene.scatter.inscatter.cache_fields`). With ``guide_width`` > 0 a cache is
smoothed along the surface seen by the camera (a cross-bilateral local-linear fit guided by the cells' optical
depth toward the camera).

Effort goes where the variance is: the number of photons is set from a collision budget (a short pilot run
measures the collisions per photon at this sigma_t, g), because the noise of a cell falls with the
collisions in it, and a thin cloud makes fewer collisions per photon than a thick one. With ``importance``
the photons split where the camera sees the cloud and its flux is low and are rouletted deep inside
(:func:`weight_window`, :mod:`natscene.scatter.importance`), and a share of the sky photons comes from a lobe of directions toward the camera (:meth:`natscene.scatter.photons.SkySource.toward`).
With a ``noise_target`` a node that misses it after its budget is topped up with more photons (:func:`view_images`);
a node can start from the photons its neighbour needed (``start``: the precompute passes each node those of the
node one extinction thinner at the same g, :data:`START_MIN` the least).

References
----------
-   Bouthors, A., Neyret, F., Max, N., Bruneton, E., & Crassin, C. (2008). Interactive multiple anisotropic
    scattering in clouds. Proceedings of the 2008 Symposium on Interactive 3D Graphics and Games, 173–182.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from natscene.scatter.bands import SKY_BANDS, SKY_HISTOGRAMS, SUN_BANDS, order_distribution

__all__ = ["AllOrdersSettings", "settings_from_config", "render_settings", "frame_settings", "Lighting", "Scene",
           "ViewImages", "view_images", "weight_window", "photons_for", "standard_error",
           "budget_scale", "source_scales", "START_MIN"]

FINE_UP_TO_ORDER = 4


@dataclass(kw_only=True)
class AllOrdersSettings:
    """Settings of the all-orders transport (config ``precompute.all_orders`` with the precompute's
    ``step_voxels`` and ``supersample``: :func:`settings_from_config`; a shot's frames: :func:`frame_settings`).
    A configurable field has no default here: the schema's (``workflow/schemas/precompute.schema.yaml``) are the
    only ones (:func:`natscene.config.default_settings` builds the default instance); the fields with a default
    are not configurable."""

    sun_collisions: int
    sky_collisions: int
    sun_photons_max: int                  # a thin cloud (few collisions per photon) is not traced forever
    sky_photons_max: int
    fine_voxels: int
    coarse_voxels: int
    guide_width: tuple                    # optical depth, fine and coarse cache (0: no smoothing)
    max_order: int
    similarity_order: int                 # high orders by similarity from this order on (0: every order exact)
    p1_order: int                         # the tallies' phase function in its P1 part from this order on (0: HG)
    diffusion_jumps: bool                 # photons cross homogeneous balls deep inside the cloud in one step
    tally_rate: float                     # tally samples per voxel length at least, along every flight in cloud
    sun_bands: tuple = SUN_BANDS
    sky_bands: tuple = SKY_BANDS
    majorant_voxels: int = 4
    step_voxels: float
    supersample: int
    p_ground: float = 0.25                # share of the sky photons that come from the ground
    importance: bool                      # weight windows: split / roulette photons toward what the camera sees
    importance_floor: float               # the window's visibility far behind the visible skin (relative)
    window_voxels: int = 4                # the window's cells
    split_max: int                        # most copies of one photon at one collision
    sky_lobe_share: float                 # sky photons drawn from a lobe of directions toward the camera
    sky_lobe_g: float = 0.7               # the lobe's HG asymmetry
    sky_order1_points: int                # the sky's order 1 by shadow rays: points per fine cell (0: photons)
    camera_lobe: float                    # share of the visible scatterings drawn around the direction to the
                                          # camera (angle biasing; the frames turn it off)
    noise_target: tuple                   # median, p95 of a node's relative standard error (0: fixed budget)
    max_budget_scale: float               # most photons a node gets, in units of the collision budget's

    SCHEMA = (("precompute.schema.yaml", ("all_orders",)), ("precompute.schema.yaml", ()))


def settings_from_config(precompute: dict) -> AllOrdersSettings:
    """The settings of a validated ``precompute`` config section: its ``all_orders`` keys plus the march's
    ``step_voxels`` and ``supersample`` (:func:`natscene.config.settings_from_section`)."""
    from natscene.config import settings_from_section
    section = dict(precompute.get("all_orders") or {})
    section.update({k: precompute[k] for k in ("step_voxels", "supersample") if k in precompute})
    return settings_from_section(AllOrdersSettings, section, "precompute.all_orders")


def render_settings(section: dict | None = None, key: str = "shots.<name>.render") -> dict:
    """A shot's render settings: ``section`` (a validated ``shots.<name>.render``, a part of one, or None) with each
    key it lacks the schema's default (:func:`natscene.config.complete_section`: the schema's defaults are the only
    ones; a bad key or value raises :class:`natscene.errors.ConfigError` naming ``key``)."""
    from natscene.config import complete_section
    return complete_section(section, "shots.schema.yaml", ("additionalProperties", "render"), key)


def frame_settings(render: dict | None) -> AllOrdersSettings:
    """The settings of a shot's frames, from its render section (a validated ``shots.<name>.render``, or a part of
    one: each key it lacks the schema's default): the precompute's defaults with the shot's collision budgets,
    cache cells (``fine_voxels``, ``coarse_voxels``), ``tally_rate``, ``ground_share`` (the share of the sky photons that come from the ground, ``p_ground``),
    ``similarity_order``, ``step_voxels`` and ``supersample``; the angle biasing toward the camera off (``camera_lobe`` 0: on the main
    job's day frame it cut the noise figure by 13 % for about 20 % more time; docs/stages/precompute.md); the sky's
    order 1 from the sky photons (``sky_order1_points`` 0: one node per frame, so the shadow rays' points serve one g
    and one extinction; on the main job's day and sunset frames they cost 5-8 s a frame and left the noise figure at
    1.43 % against 1.44 %, 1.35 % against 1.46 %); photon caps that follow the budgets (at most one photon per two collisions, or the precompute's caps where higher).
    The one place where a shot's render settings become the transport's."""
    from dataclasses import replace

    from natscene.config import default_settings
    r = render_settings(render)
    st = default_settings(AllOrdersSettings)
    return replace(st, sun_collisions=int(r["sun_collisions"]), sky_collisions=int(r["sky_collisions"]),
                   sky_order1_points=0,
                   tally_rate=float(r["tally_rate"]), p_ground=float(r["ground_share"]),
                   fine_voxels=int(r["fine_voxels"]), coarse_voxels=int(r["coarse_voxels"]),
                   step_voxels=r["step_voxels"], supersample=r["supersample"], camera_lobe=0.0,
                   similarity_order=int(r["similarity_order"]),
                   sun_photons_max=max(st.sun_photons_max, int(r["sun_collisions"]) // 2),
                   sky_photons_max=max(st.sky_photons_max, int(r["sky_collisions"]) // 2))


@dataclass
class Lighting:
    """What lights the cloud for one view: sun direction (toward the sun), the sky dome (or None) and the ground
    (None: the open ground of unit radiance; a :class:`natscene.scatter.skylight.GroundLight`: in the cloud's
    shadow)."""

    sun_dir: np.ndarray
    dome: object = None
    ground: object = None


@dataclass
class ViewImages:
    """Band images of the two independent halves of the photons: ``sun_halves`` (2, B_sun, H, W),
    ``sky_halves`` (2, 4, B_sky, H, W) or None (a leading 1 instead of 2: the whole run, no halves); the bands'
    order distributions; counts."""

    sun_halves: np.ndarray
    sky_halves: np.ndarray | None
    sun_orders: np.ndarray            # (B_sun, J, 2): natscene.scatter.bands.order_distribution
    sky_orders: np.ndarray | None     # (2, B_sky, J, 2): the dome's R, G, B and the ground's (bands.SKY_GROUPS)
    stats: dict = field(default_factory=dict)

    @property
    def sun(self) -> np.ndarray:
        return self.sun_halves.mean(0)

    @property
    def sky(self) -> np.ndarray | None:
        return None if self.sky_halves is None else self.sky_halves.mean(0)


class Scene:
    """The volume prepared once for a view: medium with the sun optical depth, majorant grid, emitters, and
    per camera position the voxels' optical depth to the camera. ``g_grid``, ``sigma_grid``: the nodes that one
    set of the sky's shadow rays serves (None: each node's own); ``shadow_seed``: their seed (a frame's render
    seed: two seeds, two independent runs); ``med``: the volume's medium made for the lighting's sun direction
    (:func:`natscene.scatter.medium.make_medium`) when the caller has it already (None: made here)."""

    def __init__(self, volume, lighting: Lighting, settings: AllOrdersSettings, g_grid=None, sigma_grid=None,
                 shadow_seed: int = 0, med=None):
        from natscene.scatter.majorant import majorant_grid
        from natscene.scatter.medium import make_medium
        from natscene.scatter.photons import SkySource, SunBeam
        self.settings = settings
        self.volume = volume
        self.med = med if med is not None else make_medium(volume, lighting.sun_dir)
        self.grid = majorant_grid(volume.density, volume.bbox_min, volume.bbox_max, settings.majorant_voxels)
        self.bounds = self.grid.occupied_bounds()
        self.sun = SunBeam(self.grid, volume.bbox_min, volume.bbox_max, self.med.sun_dir)
        ground = None if lighting.ground is None else (lighting.ground, self.med)
        self.sky = (SkySource(lighting.dome, *self.bounds, p_ground=settings.p_ground, ground=ground)
                    if lighting.dome is not None else None)
        self.factors = (int(settings.fine_voxels), int(settings.coarse_voxels))
        self.voxel_volume = float(np.prod(volume.voxel_size))
        self.g_grid = None if g_grid is None else tuple(float(x) for x in g_grid)
        self.sigma_grid = None if sigma_grid is None else tuple(float(x) for x in sigma_grid if x > 0)
        self.shadow_seed = int(shadow_seed)
        self._vox_depth = {}
        self._shadow = {}
        self._frame = {}

    def camera_depth_voxels(self, camera) -> np.ndarray:
        """The voxels' optical depth to the camera (:func:`natscene.scatter.inscatter.voxel_camera_depth`),
        marched once per camera position."""
        from natscene.scatter.inscatter import voxel_camera_depth
        key = tuple(float(x) for x in camera.position)
        if key not in self._vox_depth:
            self._vox_depth[key] = voxel_camera_depth(self.med, camera.position)
        return self._vox_depth[key]

    def frame_voxels(self, camera) -> np.ndarray:
        """The voxels in the camera's frame, each grown by a coarse cache cell (whose tallies the frame's pixels
        interpolate): where the order histogram counts the light (:func:`natscene.geometry.frame_voxels`)."""
        from natscene.geometry import frame_voxels
        key = (camera.position, camera.look_at, camera.up, camera.fov, camera.width, camera.height)
        if key not in self._frame:
            self._frame = {key: frame_voxels(camera, self.volume.bbox_min, self.volume.bbox_max,
                                             self.volume.density.shape, pad=self.factors[1])}
        return self._frame[key]

    def shadow_samples(self, camera, sigma: float, g: float):
        """The sky's order-1 shadow rays for ``camera`` (:func:`natscene.scatter.sky_first.shadow_samples`) over
        ``g_grid`` (or ``g`` alone), in the cells that the smallest of ``sigma_grid`` (or ``sigma``) lets the
        camera see; made once per camera position and grids."""
        from natscene.scatter.inscatter import VISIBLE_DEPTH
        from natscene.scatter.sky_first import shadow_samples
        gs = self.g_grid if self.g_grid is not None else (float(g),)
        sig = min(self.sigma_grid if self.sigma_grid is not None else (float(sigma),))
        key = (tuple(float(x) for x in camera.position), gs, sig, int(self.shadow_seed))
        if key not in self._shadow:
            self._shadow = {key: shadow_samples(self.med, self.camera_depth_voxels(camera), camera.position,
                                                self.sky, gs, self.factors[0],
                                                per_cell=self.settings.sky_order1_points,
                                                seed=7919 + int(self.shadow_seed),
                                                max_camera_depth=VISIBLE_DEPTH / (sig * self.volume.extinction_scale))}
        return self._shadow[key]

    def weighted_integrals(self, voxel_integrals: np.ndarray, sigma: float, factor: int) -> np.ndarray:
        """Q(cell) = ∫_cell w sigma_t dV for cells of ``factor`` voxels, from the voxels' ∫rho w dV / voxel
        volume (:func:`natscene.scatter.inscatter.weighted_voxel_integrals`): the denominator of the cache's
        ratio (:func:`natscene.scatter.inscatter.cache_fields`)."""
        from natscene.scatter.inscatter import block_sum
        sig_k = sigma * self.volume.extinction_scale
        return block_sum(voxel_integrals, factor) * (sig_k * self.voxel_volume)


def _split(bands, up_to: int) -> tuple[list, list]:
    """Indices of the bands that end at or below order ``up_to``, and of the others."""
    fine = [i for i, (a, e) in enumerate(bands) if e is not None and e <= up_to]
    coarse = [i for i in range(len(bands)) if i not in fine]
    return fine, coarse


def _caches(scene: Scene, bands) -> tuple:
    """(factor, band indices) of the fine cache (orders <= 4) and the coarse cache (the rest)."""
    fine, coarse = _split(bands, FINE_UP_TO_ORDER)
    out = []
    if fine:
        out.append((scene.factors[0], fine))
    if coarse:
        out.append((scene.factors[1], coarse))
    return tuple(out)


def _images(scene: Scene, camera, sigma: float, halves, bands, channels: int, voxel_integrals,
            k_min: int = 1, per_half: bool = True) -> np.ndarray:
    """(2 halves, channels, bands, H, W) images of the two halves' tallies (``per_half`` False: (1, ...), the image of
    their mean, gathered once: the gather is linear in the tallies); a cache whose bands all end below
    order ``k_min`` holds no tallies and is not gathered (zeros), nor is a band that begins past ``max_order``
    (the walks end there: the sun's band from 4097 without ``similarity_order``)."""
    from natscene.scatter.inscatter import cache_fields, gather
    st = scene.settings
    sig_k = sigma * scene.volume.extinction_scale
    m = 2 if per_half else 1
    out = np.zeros((m, channels, len(bands), camera.height, camera.width), np.float32)
    for ci, (f, sel) in enumerate(_caches(scene, bands)):
        if all(bands[i][1] is not None and bands[i][1] < k_min for i in sel):
            continue
        live = [j for j, i in enumerate(sel) if bands[i][0] <= st.max_order]
        if not live:
            continue
        width = st.guide_width[0 if f == scene.factors[0] and ci == 0 else 1]
        guide = None
        if width > 0:   # the cells' optical depth toward the camera: the mean of their voxels'
            from natscene.scatter.inscatter import block_sum
            guide = block_sum(scene.camera_depth_voxels(camera), f) / f ** 3 * sig_k
        q = scene.weighted_integrals(voxel_integrals, sigma, f)
        nums = [h.numerators[ci][:, live] for h in halves]
        if not per_half:
            nums = [(nums[0] + nums[1]) / 2]
        E = _gather_halves(scene, camera, sigma, nums, q, f, guide, width)
        out[:, :, [sel[j] for j in live]] = E.reshape(m, channels, len(live), camera.height, camera.width)
    return out


def _gather_halves(scene: Scene, camera, sigma: float, numerators, q, factor: int, guide=None,
                   width: float = 0.0) -> np.ndarray:
    """The view integrals (halves x fields, H, W) of the halves' cache ``numerators`` (each (..., cz, cy, cx)) over the
    cells' ``q`` (:func:`natscene.scatter.inscatter.cache_fields`, :func:`natscene.scatter.inscatter.gather`)."""
    from natscene.scatter.inscatter import cache_fields, gather
    st = scene.settings
    fields = [cache_fields(n, q, guide=guide, guide_width=width) for n in numerators]
    stack = np.concatenate([c.reshape(-1, *c.shape[-3:]) for c, _ in fields])       # (halves * fields, cz, cy, cx)
    return gather(scene.med, camera, sigma, stack, fields[0][1], factor, st.step_voxels, st.supersample,
                  scene.bounds, scene.grid)


def _sky_order1_images(scene: Scene, camera, sigma: float, g: float, voxel_integrals) -> np.ndarray:
    """(2 halves, 4 channels, H, W): the sky's order-1 band by shadow rays (:mod:`natscene.scatter.sky_first`),
    in the fine cache's cells and gathered as the photons' bands."""
    from natscene.scatter.sky_first import first_order_numerators
    f = scene.factors[0]
    q = scene.weighted_integrals(voxel_integrals, sigma, f)
    num = first_order_numerators(scene.shadow_samples(camera, sigma, g), sigma * scene.volume.extinction_scale, g, q)
    return _gather_halves(scene, camera, sigma, list(num), q, f).reshape(2, 4, camera.height, camera.width)


def weight_window(scene: Scene, source, sigma: float, g: float, camera, seed: int, pilot: int = 65536):
    """The weight window of ``source`` at (sigma, g) for ``camera`` (:mod:`natscene.scatter.importance`): a pilot
    run tallies the forward flux (phase-free, first flight apart) in cells of ``window_voxels``; returns the
    (factor, dims, targets) that :func:`natscene.scatter.photons.trace` takes."""
    import mitsuba as mi
    from natscene.scatter.importance import window_targets
    from natscene.scatter.inscatter import block_sum
    from natscene.scatter.photons import trace
    st = scene.settings
    f = int(st.window_voxels)
    t = trace(scene.med, scene.grid, source, sigma, g, camera.position, pilot, ((1, 1), (2, None)),
              caches=((f, None),), seed=seed + 65537, max_order=st.max_order, k_min=1,
              tally_rate=st.tally_rate, phase=False, similarity_order=st.similarity_order)
    tallies = t.numerators[0].sum(0)                        # (2 bands, cz, cy, cx): first flight, the rest
    rho = np.asarray(scene.volume.density, np.float64)
    mass = block_sum(rho, f)
    w = np.exp(-sigma * scene.volume.extinction_scale * scene.camera_depth_voxels(camera).astype(np.float64))
    occ = mass > 0
    flux = np.where(occ, tallies.sum(0) / np.where(occ, mass, 1.0), 0.0)
    vis = np.where(occ, block_sum(w * rho, f) / np.where(occ, mass, 1.0), 0.0)
    thickness = sigma * scene.volume.extinction_scale * mass / f ** 2 * float(np.min(scene.volume.voxel_size))
    targets = window_targets(flux, tallies[0], vis, occ, thickness, floor=st.importance_floor)
    cz, cy, cx = targets.shape
    return f, (cx, cy, cz), mi.Float(np.ascontiguousarray(targets).ravel())


def photons_for(scene: Scene, source, sigma: float, g: float, camera, collisions: int, k_min: int,
                seed: int, pilot: int = 32768, most: int | None = None, window=None, camera_depth=None) -> int:
    """Photons that make about ``collisions`` collisions at (sigma, g) (a short pilot run measures the rate,
    with the weight window ``window`` if any: splitting adds collisions, roulette removes them; with the
    diffusion jumps where ``camera_depth`` allows them, each jump one collision), at most ``most``."""
    from natscene.scatter.photons import trace
    t = trace(scene.med, scene.grid, source, sigma, g, camera.position, pilot, ((1, None),),
              caches=((scene.factors[1], None),), seed=seed + 104729, max_order=scene.settings.max_order,
              k_min=10 ** 9, window=window, split_max=scene.settings.split_max,
              similarity_order=scene.settings.similarity_order, camera_depth=camera_depth,
              jumps=scene.settings.diffusion_jumps)
    per = max(t.collisions / pilot, 1e-3)
    n = int(min(max(collisions / per, 4 * pilot), 64 * collisions))
    return n if most is None else min(n, int(most))


def _trace_halves(scene: Scene, source, sigma: float, g: float, camera, n_photons: int, bands, k_min: int,
                  seed: int, camera_depth, window=None):
    """Two independent halves of the photons, each tallied into the fine and the coarse cache."""
    from natscene.scatter.photons import trace
    return [trace(scene.med, scene.grid, source, sigma, g, camera.position, max(1, n_photons // 2), bands,
                  caches=_caches(scene, bands), seed=seed * 2 + h, max_order=scene.settings.max_order, k_min=k_min,
                  camera_depth=camera_depth, tally_rate=scene.settings.tally_rate, window=window,
                  split_max=scene.settings.split_max, camera_lobe=scene.settings.camera_lobe,
                  similarity_order=scene.settings.similarity_order, p1_order=scene.settings.p1_order,
                  jumps=scene.settings.diffusion_jumps, seen=scene.frame_voxels(camera))
            for h in range(2)]


def standard_error(half_a: np.ndarray, half_b: np.ndarray, window: int = 9) -> np.ndarray:
    """Per-pixel standard error of the mean of two independent halves (..., H, W).

    One difference gives a one-degree-of-freedom estimate of the variance, ((a - b) / 2)², whose square root reads
    the median error a third low and the tail high (|N(0, 1)| has median 0.67 and 95th percentile 1.96). The
    cache's noise is correlated over a cell, several pixels wide, so averaging the variance over 3x3 pixels adds
    few degrees of freedom; averaging it over a wider window mixes bright and dim pixels, and the dim ones
    inherit the bright ones' variance. So the relative variance ((a - b) / (a + b))² is averaged over
    ``window`` x ``window`` pixels, over the pixels with light only (a normalised average: the pixels outside
    the cloud do not dilute its edge), and scaled by each pixel's mean (a + b) / 2. On three of the main job's
    nodes (sigma_t 0.2, 0.5, 1) the median and 95th percentile of the relative error so estimated are within
    2-7 % of those of 5 independent repetitions of the node (10 halves); the 3x3 average of the variance read the
    median 20 % low and the 95th percentile 27-53 % high. Pixels without light get the plain difference."""
    from scipy.ndimage import uniform_filter
    a = np.asarray(half_a, np.float64)
    b = np.asarray(half_b, np.float64)
    m = (a + b) / 2
    lit = m > 0
    rel = np.where(lit, ((a - b) / 2) ** 2 / np.where(lit, m, 1.0) ** 2, 0.0)
    size = [1] * (m.ndim - 2) + [int(window), int(window)]
    share = uniform_filter(lit.astype(np.float64), size=size, mode="constant")
    avg = uniform_filter(rel, size=size, mode="constant") / np.maximum(share, 1e-12)
    se = np.where(lit, np.sqrt(np.maximum(avg, 0.0)) * m, np.abs(a - b) / 2)
    return se.astype(np.float32)


@dataclass
class _Part:
    """One source's band images of the two halves, with the photons, collisions, order histogram behind them."""

    halves: np.ndarray
    histogram: np.ndarray
    photons: int
    collisions: int
    truncated: float

    def merged(self, other: "_Part") -> "_Part":
        """The two runs as one: each image and the histogram are per unit source power, so they average
        weighted by photons (the cache and the gather are linear in the tallies)."""
        a, b = self.photons, other.photons
        return _Part(((a * self.halves.astype(np.float64) + b * other.halves) / (a + b)).astype(np.float32),
                     (a * self.histogram + b * other.histogram) / (a + b), a + b,
                     self.collisions + other.collisions, max(self.truncated, other.truncated))


def _part(scene: Scene, source, sigma: float, g: float, camera, n_photons: int, bands, k_min: int, seed: int,
          depth, window, channels: int, vint, per_half: bool = True) -> _Part:
    """``n_photons`` of ``source`` traced as two halves and gathered into band images (of each half, or of the
    whole run: ``per_half``)."""
    halves = _trace_halves(scene, source, sigma, g, camera, n_photons, bands, k_min, seed, depth, window)
    return _Part(_images(scene, camera, sigma, halves, bands, channels, vint, k_min, per_half),
                 sum(h.histogram for h in halves),
                 int(sum(h.photons for h in halves)), int(sum(h.collisions for h in halves)),
                 float(max(h.truncated for h in halves)))


def budget_scale(noise: tuple, target: tuple) -> float:
    """The photon count, as a multiple of the present one, at which a node's relative standard error (median,
    p95) meets ``target`` (0 = no target for that figure): the error falls as 1 / sqrt(photons)."""
    need = 1.0
    for x, t in zip(noise, target):
        if t > 0:
            need = max(need, (float(x) / float(t)) ** 2)
    return need


def source_scales(variances, costs, need: float, fixed: float = 0.0) -> list:
    """Factors (each >= 1) by which to multiply each source's photons so that the summed variance of a node's
    pixel, ``sum(variances) + fixed``, falls by ``need`` at the least cost (Neyman allocation; ``costs``: each
    source's cost so far, its variance falling as 1 / its photons; ``fixed``: variance that no source's photons
    lower, the sky's order 1 by shadow rays). Minimising sum c_i x_i under sum v_i / x_i = V* - fixed gives
    x_i = sqrt(v_i / c_i) sum_j sqrt(v_j c_j) / (V* - fixed); a source whose x_i would fall below 1 (its photons
    are traced already) keeps them, and the others share what remains. Where ``fixed`` alone exceeds V*, the
    sources' own variance falls by ``need``. Equal shares give ``need`` for every source; a source without
    variance gets no more photons."""
    v = [max(float(x), 0.0) for x in variances]
    c = [max(float(x), 1e-30) for x in costs]
    fixed = max(float(fixed), 0.0)
    target = (sum(v) + fixed) / float(need) - fixed
    if target <= 0:                                    # the fixed variance alone is over the wanted one
        target = sum(v) / float(need)
    if sum(v) <= 0 or need <= 1.0:
        return [1.0] * len(v)
    free = list(range(len(v)))
    x = [1.0] * len(v)
    while free:
        left = target - sum(v[i] for i in range(len(v)) if i not in free)
        if left <= 0:                                  # the fixed sources alone exceed the target: all of them
            return [float(need)] * len(v)
        total = sum(np.sqrt(v[i] * c[i]) for i in free)
        for i in free:
            x[i] = np.sqrt(v[i] / c[i]) * total / left
        low = [i for i in free if x[i] < 1.0]
        if not low:
            break
        for i in low:
            x[i] = 1.0
            free.remove(i)
    return [float(max(xi, 1.0)) for xi in x]


START_MIN = 0.25
"""The least first pass of a node started from its neighbour's need (``view_images(start=...)``), as a multiple of
the collision budget, and the first pass of the precompute's thinnest extinction, which has no thinner neighbour.
The main job's thin nodes meet the target at a quarter; a smaller first pass leaves the
top-up to an estimate from fewer photons, which over-asks (a thick node's sun started at 0.36x was topped up to
3.6x where 1.7x sufficed; docs/stages/precompute.md, "A noise target per node")."""


def view_images(scene: Scene, camera, sigma: float, g: float, seed: int = 0, noise=None,
                split=None, halves: bool = True, start=None) -> ViewImages:
    """Band images of the sun's and the sky's light at (sigma, g) for ``camera`` (see the module docstring).

    ``noise``: a function of the :class:`ViewImages` that returns the node's relative standard error (median,
    p95 over its cloud pixels). With it and a ``noise_target``, a node that misses the target is topped up (more
    photons, fresh seeds, merged into the halves), at most twice and to at most ``max_budget_scale`` times each
    source's budget: the noisy nodes (thick, strongly forward scattering) get the photons, a node within the
    target none. ``split``: a function of the :class:`ViewImages` that returns the sun's and the sky's shares
    of the pixel's variance; with it the top-up goes to the sources by :func:`source_scales` (costs: their
    collisions), without it both sources get the same factor. ``halves`` False: the images of the whole run
    (a leading axis of 1), gathered once instead of once per half; no noise figure then (``noise`` must be None).
    ``start``: each source's first pass as a multiple of its budget (clipped to [:data:`START_MIN`,
    ``max_budget_scale``], to [1, ``max_budget_scale``] without a noise target; None: 1), e.g. a neighbouring
    node's ``stats["need"]``: the multiples at which this node's last estimate meets the target (its photons scaled
    by (error / target)², above or below 1).
    """
    st = scene.settings
    H, W = camera.height, camera.width
    nb_sun, nb_sky = len(st.sun_bands), len(st.sky_bands)
    if noise is not None and not halves:
        raise ValueError("view_images: a noise target needs the two halves (halves=True)")
    m = 2 if halves else 1
    if sigma <= 0:
        sky = np.zeros((m, 4, nb_sky, H, W), np.float32) if scene.sky is not None else None
        sky_orders = None if sky is None else order_distribution(st.sky_bands, np.zeros((SKY_HISTOGRAMS, 0)))
        return ViewImages(np.zeros((m, nb_sun, H, W), np.float32), sky, order_distribution(st.sun_bands, np.zeros(0)),
                          sky_orders, {})
    from natscene.scatter.inscatter import weighted_voxel_integrals
    depth = scene.camera_depth_voxels(camera)
    vint = weighted_voxel_integrals(scene.med, depth, camera.position, sigma * scene.volume.extinction_scale)
    win = weight_window(scene, scene.sun, sigma, g, camera, seed) if st.importance else None
    n_sun = photons_for(scene, scene.sun, sigma, g, camera, st.sun_collisions, 10 ** 9, seed,
                        most=st.sun_photons_max, window=win, pilot=16384 if win else 32768, camera_depth=depth)
    jobs = [(scene.sun, n_sun, st.sun_bands, 2, seed, win, 1)]
    order1 = None
    if scene.sky is not None:
        sky = (scene.sky.toward(camera.position, st.sky_lobe_g, st.sky_lobe_share)
               if st.sky_lobe_share > 0 else scene.sky)
        win = weight_window(scene, sky, sigma, g, camera, seed + 7919) if st.importance else None
        n_sky = photons_for(scene, sky, sigma, g, camera, st.sky_collisions, 10 ** 9, seed + 7919,
                            most=st.sky_photons_max, window=win, pilot=16384 if win else 32768,
                            camera_depth=depth)
        shadow = st.sky_order1_points > 0
        jobs.append((sky, n_sky, st.sky_bands, 2 if shadow else 1, seed + 7919, win, 4))
        order1 = _sky_order1_images(scene, camera, sigma, g, vint) if shadow else None

    def run(scales, round_: int) -> list:
        return [None if sc <= 0 else
                _part(scene, src, sigma, g, camera, max(2, int(round(n * sc))), bands, k_min,
                      s + 1_000_003 * round_, depth, w, ch, vint, halves)
                for (src, n, bands, k_min, s, w, ch), sc in zip(jobs, scales)]

    def result(parts) -> ViewImages:
        sun, sky = parts[0], (parts[1] if len(parts) > 1 else None)
        sky_halves = None if sky is None else sky.halves
        if sky is not None and order1 is not None:      # band (1) by shadow rays, the photons' from order 2 on
            sky_halves = sky.halves.copy()
            sky_halves[:, :, 0] = order1 if halves else order1.mean(0, keepdims=True)
        stats = dict(sun_photons=sun.photons, sun_collisions=sun.collisions, sun_truncated=sun.truncated)
        if sky is not None:
            stats.update(sky_photons=sky.photons, sky_collisions=sky.collisions,
                         sky_order1="shadow_rays" if order1 is not None else "photons")
        return ViewImages(sun.halves[:, 0], sky_halves,
                          order_distribution(st.sun_bands, sun.histogram[0]),
                          None if sky is None else order_distribution(st.sky_bands, sky.histogram), stats)

    targeted = noise is not None and max(st.noise_target) > 0
    least = START_MIN if targeted else 1.0         # nothing tops a short first pass up without a noise target
    scales = ([1.0] * len(jobs) if start is None else
              [float(min(max(float(x), least), st.max_budget_scale)) for x in list(start)[:len(jobs)]])
    first = list(scales)
    parts = run(scales, 0)
    vi = result(parts)
    budget = [p.collisions / sc for p, sc in zip(parts, scales)]    # each source's cost at its budget
    if targeted:
        figure = noise(vi)
        for round_ in (1, 2):
            need = budget_scale(figure, st.noise_target)
            if need <= 1.0:
                break
            need *= 1.1
            if split is not None and len(parts) > 1:   # a share past the sources' (the sky's order 1 by shadow
                v = split(vi)                          # rays) is fixed: no photons lower it
                x = source_scales(v[:len(parts)], [p.collisions for p in parts], need, fixed=sum(v[len(parts):]))
            else:
                x = [need] * len(parts)
            want = [min(sc * xi, float(st.max_budget_scale)) for sc, xi in zip(scales, x)]
            extra = [w - sc if w > sc * 1.05 else 0.0 for w, sc in zip(want, scales)]
            if not any(extra):
                break
            parts = [p if q is None else p.merged(q) for p, q in zip(parts, run(extra, round_))]
            scales = [sc + e for sc, e in zip(scales, extra)]
            vi = result(parts)
            figure = noise(vi)
        ratio = max([(float(x) / float(t)) ** 2 for x, t in zip(figure, st.noise_target) if t > 0])
        vi.stats["need"] = [sc * ratio for sc in scales]
        vi.stats["first_pass"] = first
        vi.stats["budget_scale"] = float(np.dot(scales, budget) / max(sum(budget), 1))
        vi.stats["source_budget_scales"] = scales
    return vi
