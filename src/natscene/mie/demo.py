"""Demo views for the Mie shading (Reimschuessel 2011, Ch. 4, Fig. 11): one sun, three cameras placed
around the cloud so that the same point-cloud solution is reused (the thesis' view independence):

- ``glory``: camera between the sun and the cloud, the cloud centre at the antisolar point (θ = 180°);
- ``fogbow``: the cloud centre ``fogbow_angle`` degrees from the antisolar point (θ = 180° - that);
- ``silver_lining``: camera behind the cloud, the sun ``silver_offset`` degrees from the cloud centre
  (θ near 0°, the forward peak).

Also the R_i picture of Fig. 8 (a slice of the point cloud through the centre, along the light).

Where nature shows these effects (and so where the demo shoots them):

- glory and fogbow: on the tops of *thin, uniform-droplet* stratocumulus decks and fog banks, with the sun
  behind the observer. The rings need a narrow droplet spectrum (effective variance v_eff ≲ 0.05; at
  v_eff = 0.1 they wash out, Laven 2005) and a view where single scattering is a large share of the light
  (optical depth of a few, not the τ ≈ 70 of a towering cumulus). :func:`stratocumulus_deck` builds such a
  deck (a slab of given vertical optical depth with a gently textured top); :func:`deck_camera` looks at it
  from above;
- silver lining: toward the sun, the sun just hidden behind a cloud edge: the diffraction peak of the
  droplets (4π p(0°) in the thousands, ≈ 1–2° wide) lights the thin edge brilliantly within a degree or
  two of the sun. :func:`silver_lining_camera` finds such a line of sight (sun behind ≥ ``hide_tau`` of
  cloud, the nearest clear sky ``edge_deg`` away, on the cloud's upper edge) and frames it narrowly.
"""
from __future__ import annotations

import numpy as np

from natscene.geometry import Camera

SHOTS = ("glory", "fogbow", "silver_lining")


def _rotate(v, axis, angle_rad):
    axis = axis / np.linalg.norm(axis)
    return (v * np.cos(angle_rad) + np.cross(axis, v) * np.sin(angle_rad)
            + axis * np.dot(axis, v) * (1 - np.cos(angle_rad)))


def demo_camera(shot: str, volume, sun_dir, distance: float = 2.2, fov: float = 32.0, resolution=(480, 360),
                fogbow_angle: float = 39.0, silver_offset: float = 6.0) -> Camera:
    """The camera of one demo shot, looking at the centre of the volume's bounding box."""
    c = (np.asarray(volume.bbox_min, float) + np.asarray(volume.bbox_max, float)) / 2
    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    side = np.cross(s, [0.0, 1.0, 0.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.array([1.0, 0.0, 0.0])
    if shot == "glory":
        to_cam = s
    elif shot == "fogbow":
        to_cam = _rotate(s, side, np.radians(fogbow_angle))   # away from the antisolar direction
    elif shot == "silver_lining":
        to_cam = -_rotate(s, side, np.radians(silver_offset))
    else:
        raise ValueError(f"unknown demo shot '{shot}' (one of {SHOTS})")
    pos = c + distance * to_cam
    up = np.array([0.0, 1.0, 0.0]) if abs(to_cam[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    w, h = resolution
    return Camera(tuple(pos), tuple(c), tuple(up), float(fov), int(w), int(h))


def stratocumulus_deck(size: float = 2.0, resolution: int = 160, thickness: float = 0.06,
                       relief: float = 0.15, relief_scale: float = 0.15, optical_depth: float = 3.0,
                       sigma_t: float = 0.3, seed: int = 0):
    """A thin stratocumulus / fog deck: a horizontal slab ``size`` × ``size`` (world units, centred on
    x = z = 0) of cubic voxels (``resolution`` across), ``thickness`` thick above a base one voxel over
    the box floor, whose top is raised by ``relief`` × thickness × a smooth random field (Gaussian-filtered
    white noise of correlation length ``relief_scale``, unit standard deviation, clipped at ±2.5σ; seeded).
    Density is 1 inside with one-voxel soft surfaces and fades to 0 over the outer 5 % of the deck. The
    extinction scale is set so that the mean vertical optical depth (σ_e = ``sigma_t`` × extinction scale,
    the project convention) over the deck's interior is ``optical_depth``.
    -> :class:`~natscene.volume.grid.Volume`."""
    from scipy.ndimage import gaussian_filter

    from natscene.volume.grid import Volume

    if not (size > 0 and thickness > 0 and optical_depth > 0 and sigma_t > 0 and resolution >= 8):
        raise ValueError("stratocumulus_deck: size, thickness, optical_depth, sigma_t must be > 0, "
                         "resolution >= 8")
    vox = size / resolution
    ny = max(4, int(np.ceil(thickness * (1 + 2.5 * relief) / vox)) + 3)
    rng = np.random.default_rng(seed)
    noise = gaussian_filter(rng.standard_normal((resolution, resolution)), relief_scale / vox, mode="wrap")
    noise = np.clip(noise / max(float(noise.std()), 1e-12), -2.5, 2.5)
    top = vox + thickness * (1 + relief * noise)                 # (z, x) top height above the box floor
    y = (np.arange(ny) + 0.5) * vox                              # voxel centres
    # soft (one-voxel) top and base: the covered fraction of each voxel
    dens = np.clip((top[:, None, :] - y[None, :, None]) / vox + 0.5, 0, 1) \
        * np.clip((y[None, :, None] - vox) / vox + 0.5, 0, 1)
    c = (np.arange(resolution) + 0.5) / resolution
    edge = np.clip(np.minimum(c, 1 - c) / 0.05, 0, 1)            # fade over the outer 5 %
    dens = (dens * (edge[:, None, None] * edge[None, None, :])).astype(np.float32)
    inner = (edge[:, None] * edge[None, :]) >= 1
    column = float(dens.sum(axis=1)[inner].mean()) * vox         # mean ∫ D dy over the interior
    lo = np.array([-size / 2, 0.0, -size / 2])
    hi = np.array([size / 2, ny * vox, size / 2])
    return Volume(dens, lo, hi, float(optical_depth / (sigma_t * column)))


def deck_camera(shot: str, deck, sun_dir, distance: float = 1.5, fov: float = 10.0, resolution=(480, 360),
                angle: float = 0.0) -> Camera:
    """A camera above a deck with the sun behind it, aimed at the deck's top centre from ``distance``:
    ``glory`` looks at the antisolar point; ``fogbow`` ``angle`` degrees from it, sideways (same side of
    the sun's vertical plane for positive angles), so the side arc of the bow crosses the frame."""
    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    if s[1] <= 0.05:
        raise ValueError("deck_camera: the sun must be above the horizon to light the deck from above")
    vy = float(deck.voxel_size[1])
    col = deck.density.sum(axis=1) * vy                          # ∫ D dy per column
    top = float(deck.bbox_min[1]) + vy + float(np.median(col[col > 0.5 * col.max()]))  # base one voxel up
    c = np.array([(deck.bbox_min[0] + deck.bbox_max[0]) / 2, top, (deck.bbox_min[2] + deck.bbox_max[2]) / 2])
    to_cam = s
    if shot == "fogbow":
        # sideways (about the axis in the sun's vertical plane): the view still looks down at the deck,
        # at a shallower angle than the antisolar point, so the bow's side arc lies on the deck top
        axis = np.array([0.0, 1.0, 0.0]) - s[1] * s
        to_cam = _rotate(s, axis / np.linalg.norm(axis), np.radians(angle))
    elif shot != "glory":
        raise ValueError(f"deck_camera: shot must be 'glory' or 'fogbow', got '{shot}'")
    pos = c + distance * to_cam
    up = np.array([0.0, 1.0, 0.0]) if abs(to_cam[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    w, h = resolution
    return Camera(tuple(pos), tuple(c), tuple(up), float(fov), int(w), int(h))


def silver_lining_camera(volume, sun_dir, sigma_e: float, distance: float = 2.2, fov: float = 8.0,
                         resolution=(480, 360), edge_deg: float = 0.8, hide_tau: float = 10.0) -> Camera:
    """A camera behind the cloud looking straight at the sun, which is hidden behind ≥ ``hide_tau`` of
    cloud (optical depth along the sun's line of sight, σ_e = ``sigma_e``) and the cloud's upper edge
    (clear sky, τ < 0.05) ``edge_deg`` degrees above it (seen from ``distance`` behind the cloud's centre
    plane); of all such lines the one highest in the image (the top of the cloud), then the most central.
    Deterministic (no random search)."""
    from natscene.mie.points import sample_density

    s = np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    up0 = np.array([0.0, 1.0, 0.0]) if abs(s[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    ex = np.cross(s, up0)
    ex /= np.linalg.norm(ex)
    ey = np.cross(ex, s)                                         # image up, perpendicular to the sun line
    lo, hi = np.asarray(volume.bbox_min, float), np.asarray(volume.bbox_max, float)
    centre = (lo + hi) / 2
    rel = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) - centre
    px = float(np.min(volume.voxel_size)) * 1.5                  # map pixel (world units)
    xs = np.arange(np.min(rel @ ex), np.max(rel @ ex) + px, px)
    ys = np.arange(np.min(rel @ ey), np.max(rel @ ey) + px, px)
    zs = np.arange(np.min(rel @ s), np.max(rel @ s) + px, px)
    tau = np.zeros((len(ys), len(xs)))
    for k in range(0, len(ys), 32):                              # τ along the sun's line, in row blocks
        yy = ys[k:k + 32]
        p = centre + yy[:, None, None, None] * ey + xs[None, :, None, None] * ex + zs[None, None, :, None] * s
        tau[k:k + 32] = sample_density(volume, p).sum(axis=-1) * px * sigma_e
    hidden = tau >= min(hide_tau, 0.5 * float(tau.max()))          # a thin cloud: its thicker half
    if not hidden.any():
        raise ValueError("silver_lining_camera: the volume is empty (no optical depth toward the sun)")
    # distance (world) from each map pixel up (+ey) to the first clear-sky pixel of its column
    clear = tau < 0.05
    up = np.full(tau.shape, np.inf)
    nxt = np.full(len(xs), np.inf)
    for i in range(len(ys) - 1, -1, -1):
        nxt = np.where(clear[i], ys[i], nxt)
        up[i] = nxt - ys[i]
    target = distance * np.tan(np.radians(edge_deg))
    err = np.where(hidden, np.abs(up - target), np.inf)
    cand = err <= max(px, 0.15 * target, float(err.min()))       # else the nearest achievable edge distance
    iy, ix = np.nonzero(cand)
    k = int(np.argmax(ys[iy] * 1e6 - np.abs(xs[ix])))            # highest in the image, then most central
    p0 = centre + ys[iy[k]] * ey + xs[ix[k]] * ex
    pos = p0 - distance * s
    w, h = resolution
    return Camera(tuple(pos), tuple(pos + s), tuple(up0), float(fov), int(w), int(h))


def scattering_angle_at_centre(camera: Camera, sun_dir) -> float:
    """Phase angle (deg) of sunlight scattered toward the camera at its look-at point."""
    to_cam = np.subtract(camera.position, camera.look_at)
    to_cam = to_cam / np.linalg.norm(to_cam)
    w = -np.asarray(sun_dir, float) / np.linalg.norm(sun_dir)
    return float(np.degrees(np.arccos(np.clip(np.dot(w, to_cam), -1, 1))))


def ratio_slice(solution) -> np.ndarray:
    """Fig. 8: R_i on the lattice slice through the middle containing the light direction (rows: along
    the light, sun at the top; columns: across), NaN where there is no point. Returns (nc, na)."""
    p = solution.points
    nc, nb, na = p.shape
    b_mid = int(np.median(p.index[:, 1]))
    img = np.full((nc, na), np.nan, np.float32)
    sel = p.index[:, 1] == b_mid
    img[p.index[sel, 0], p.index[sel, 2]] = solution.ratio[sel]
    return img


def ratio_image(solution, scale: int = 4) -> np.ndarray:
    """Fig. 8 as a grey image (dark = isotropic, light = Mie), blue where there is no point."""
    r = ratio_slice(solution)
    rgb = np.where(np.isnan(r)[..., None], np.array([0.05, 0.08, 0.2], np.float32), np.nan_to_num(r)[..., None])
    return np.repeat(np.repeat(rgb, scale, 0), scale, 1).astype(np.float32)


# ------------------------------------------------------------------------------------ measurements
def angular_profile(img: np.ndarray, camera: Camera, direction, max_deg: float = 4.0, step_deg: float = 0.1):
    """Azimuthal mean of the RGB mean of ``img`` in rings of width ``step_deg`` around ``direction`` (a
    unit vector, e.g. the antisolar direction -sun): -> (ring centres (deg), profile); NaN for empty rings."""
    d = camera.ray_directions()
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    ang = np.degrees(np.arccos(np.clip(d @ u, -1, 1)))
    edges = np.arange(0.0, max_deg + 1e-9, step_deg)
    k = np.digitize(ang, edges) - 1
    y = np.asarray(img, np.float64).mean(axis=-1)
    ok = (k >= 0) & (k < len(edges) - 1)
    s = np.bincount(k[ok], y[ok], minlength=len(edges) - 1)
    n = np.bincount(k[ok], minlength=len(edges) - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (edges[:-1] + edges[1:]) / 2, s / n


def ring_contrast(centres: np.ndarray, profile: np.ndarray):
    """The first bright ring of a radial profile (around the antisolar point): the first local minimum
    outward from the centre, then the maximum beyond it -> (ring angle (deg), ring max / that minimum).
    A profile with no local minimum (monotone) gives (NaN, 1.0)."""
    p = np.asarray(profile, np.float64)
    ok = np.isfinite(p)
    c, p = np.asarray(centres)[ok], p[ok]
    for i in range(1, len(p) - 1):
        if p[i] < p[i - 1] and p[i] <= p[i + 1]:
            j = i + int(np.argmax(p[i:]))
            if j == i:
                break
            return float(c[j]), float(p[j] / p[i])
    return float("nan"), 1.0


def rim_peak(img: np.ndarray, fraction: float = 0.001) -> float:
    """Brightness of the brightest ``fraction`` of pixels (mean of their RGB means): the silver-lining
    rim's peak."""
    y = np.sort(np.asarray(img, np.float64).mean(axis=-1).ravel())
    return float(y[-max(1, int(round(fraction * y.size))):].mean())
